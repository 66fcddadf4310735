// Seeded mutation fuzzing of the untrusted inputs (scenario JSON, SHAPE JSON, OBJ meshes),
// bounded so it runs in the suite: every corpus file under tests/fuzz/corpus/<target>/ and
// CRUMBLE_FUZZ_INPUTS (default 200) mutants of them per target, each in a child process with
// a limit of 60 s of CPU and 4 GiB. A crash or a hang fails the test and prints the input (saved
// under $TMPDIR/crumble_fuzz_findings/); an exception that is not an input error (the CLI's
// exit 1 "failed") is listed as a finding. CRUMBLE_FUZZ_SEED picks another mutation stream.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "tests/fuzz/FuzzTargets.h"

// Built with AddressSanitizer (scripts/sanitize.sh)? GCC defines __SANITIZE_ADDRESS__, clang
// answers __has_feature(address_sanitizer).
#if defined(__SANITIZE_ADDRESS__)
#define CRUMBLE_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CRUMBLE_ASAN 1
#endif
#endif
#ifndef CRUMBLE_ASAN
#define CRUMBLE_ASAN 0
#endif

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::fuzz::Outcome;

namespace {

long env_long(const char* name, long def) {
  const char* v = std::getenv(name);
  return v ? std::strtol(v, nullptr, 10) : def;
}

std::vector<std::string> corpus(const std::string& target) {
  std::vector<std::string> out;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(fs::path(CRUMBLE_SOURCE_DIR) / "tests/fuzz/corpus" / target))
    files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    out.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return out;
}

// Values that break careless input handling.
Json hostile_value(std::mt19937_64& rng) {
  static const std::vector<Json> values = {0, -1, 1, -0.0, 0.5, 1e308, -1e308, 1e-308, 4.9e-324,
                                           9007199254740993.0, 2147483648, -2147483649, 1e9, 1e-9,
                                           "", "x", "\xff", nullptr, true, Json::array(), Json::object(),
                                           Json::array({0}), Json::array({1e308, -1e308, 0}), 3, 100000000};
  return values[rng() % values.size()];
}

// Every node of a document, by JSON pointer.
void collect(const Json& j, const Json::json_pointer& at, std::vector<Json::json_pointer>& out) {
  out.push_back(at);
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it) collect(*it, at / it.key(), out);
  else if (j.is_array())
    for (std::size_t i = 0; i < j.size(); ++i) collect(j[i], at / i, out);
}

std::string mutate_json(Json doc, std::mt19937_64& rng) {
  const int edits = 1 + static_cast<int>(rng() % 3);
  for (int e = 0; e < edits; ++e) {
    std::vector<Json::json_pointer> nodes;
    collect(doc, Json::json_pointer(), nodes);
    const auto& p = nodes[rng() % nodes.size()];
    Json& n = doc[p];
    switch (rng() % 6) {
      case 0:  // a hostile value in place of whatever was there
      case 1:
        n = hostile_value(rng);
        break;
      case 2:  // scale a number by a wild factor
        if (n.is_number()) n = n.get<double>() * std::pow(10.0, static_cast<int>(rng() % 41) - 20);
        else n = hostile_value(rng);
        break;
      case 3:  // drop a key or an element
        if (n.is_object() && !n.empty()) {
          auto it = n.begin();
          std::advance(it, rng() % n.size());
          n.erase(it.key());
        } else if (n.is_array() && !n.empty()) {
          n.erase(n.begin() + static_cast<long>(rng() % n.size()));
        }
        break;
      case 4:  // duplicate an element / add an unknown key
        if (n.is_array() && !n.empty()) n.push_back(n[rng() % n.size()]);
        else if (n.is_object()) n["fuzz_key"] = hostile_value(rng);
        break;
      case 5:  // negate a number
        if (n.is_number()) n = -n.get<double>();
        break;
    }
  }
  return doc.dump();
}

std::string mutate_bytes(std::string s, std::mt19937_64& rng) {
  if (s.empty()) return "{";
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits && !s.empty(); ++e) {
    const std::size_t i = rng() % s.size();
    switch (rng() % 4) {
      case 0: s[i] = static_cast<char>(rng() & 0xff); break;
      case 1: s.insert(s.begin() + static_cast<long>(i), "0123456789-.e[]{}\",:"[rng() % 20]); break;
      case 2: s.erase(i, 1 + rng() % 8); break;
      case 3: s.resize(i); break;
    }
  }
  return s;
}

std::string mutate(const std::string& seed, bool json, std::mt19937_64& rng) {
  if (json && rng() % 5 != 0) {
    try {
      return mutate_json(Json::parse(seed), rng);
    } catch (const std::exception&) {
    }
  }
  return mutate_bytes(seed, rng);
}

struct Tally {
  long accepted = 0, input_errors = 0, other_errors = 0, crashes = 0, hangs = 0;
  std::vector<std::string> findings;
};

// Runs one input in a child: 60 s of CPU and 4 GiB of address space at most.
void run_one(const std::function<Outcome(const std::string&, std::string*)>& target, const std::string& input,
             const std::string& label, Tally& t) {
  int pipefd[2];
  if (pipe(pipefd) != 0) throw std::runtime_error("pipe");
  const pid_t pid = fork();
  if (pid == 0) {
    close(pipefd[0]);
    rlimit cpu{60, 61};
    setrlimit(RLIMIT_CPU, &cpu);
#if !CRUMBLE_ASAN
    // AddressSanitizer reserves terabytes of address space for its shadow memory: under it the
    // address-space cap would fail every allocation; ASan reports runaway allocations itself.
    rlimit mem{4ul << 30, 4ul << 30};
    setrlimit(RLIMIT_AS, &mem);
#endif
    std::string what;
    const Outcome o = target(input, &what);
    what = what.substr(0, 300);
    (void)!write(pipefd[1], what.data(), what.size());
    _exit(o == Outcome::Accepted ? 0 : o == Outcome::InputError ? 2 : 1);
  }
  close(pipefd[1]);
  std::string what;
  char buf[512];
  ssize_t n;
  while ((n = read(pipefd[0], buf, sizeof buf)) > 0) what.append(buf, static_cast<std::size_t>(n));
  close(pipefd[0]);
  int st = 0;
  waitpid(pid, &st, 0);
  auto save = [&](const std::string& kind) {
    const fs::path dir = fs::temp_directory_path() / "crumble_fuzz_findings";
    fs::create_directories(dir);
    const fs::path f = dir / (label + "." + kind);
    std::ofstream(f, std::ios::binary) << input;
    t.findings.push_back(kind + " " + f.string() + (what.empty() ? "" : ": " + what));
  };
  if (WIFEXITED(st)) {
    const int code = WEXITSTATUS(st);
    if (code == 0) ++t.accepted;
    else if (code == 2) ++t.input_errors;
    else {
      ++t.other_errors;
      save("error");
    }
  } else if (WIFSIGNALED(st) && WTERMSIG(st) == SIGXCPU) {
    ++t.hangs;
    save("hang");
  } else {
    ++t.crashes;
    save("crash");
  }
}

Tally fuzz(const std::string& name, const std::function<Outcome(const std::string&, std::string*)>& target,
           bool json) {
  const auto seeds = corpus(name);
  EXPECT_FALSE(seeds.empty()) << "no corpus for " << name;
  Tally t;
  std::mt19937_64 rng(static_cast<std::uint64_t>(env_long("CRUMBLE_FUZZ_SEED", 1)));
  for (std::size_t i = 0; i < seeds.size(); ++i) run_one(target, seeds[i], name + "-seed" + std::to_string(i), t);
  // Every corpus input is a valid one: it must be accepted.
  EXPECT_EQ(t.accepted, static_cast<long>(seeds.size())) << name << ": a corpus input was rejected";
  const long n = env_long("CRUMBLE_FUZZ_INPUTS", 200);
  for (long k = 0; k < n; ++k)
    run_one(target, mutate(seeds[rng() % seeds.size()], json, rng), name + "-" + std::to_string(k), t);
  std::cout << name << ": " << seeds.size() + n << " inputs: " << t.accepted << " accepted, " << t.input_errors
            << " input errors, " << t.other_errors << " other errors, " << t.crashes << " crashes, " << t.hangs
            << " hangs\n";
  for (const auto& f : t.findings) std::cout << "  " << f << "\n";
  EXPECT_EQ(t.crashes, 0) << name << ": crashes (inputs saved, listed above)";
  EXPECT_EQ(t.hangs, 0) << name << ": inputs that ran out of CPU time (listed above)";
  EXPECT_EQ(t.other_errors, 0) << name << ": inputs that failed with an error that is not an input error";
  return t;
}

}  // namespace

TEST(Fuzz, ScenarioJson) { fuzz("scenario", crumble::fuzz::scenario, true); }
TEST(Fuzz, ShapeJson) { fuzz("shape", crumble::fuzz::shape, true); }
TEST(Fuzz, ObjMesh) { fuzz("obj", crumble::fuzz::obj, false); }
