// What the conformance suites and the cross product are instantiated for: every entry of
// the registration tables (scenarios/Registry.h) that this build contains, per dimension the
// entry declares. A new registration is tested without editing a test.
//
// Plugins: CRUMBLE_TEST_PLUGINS=/path/a.so:/path/b.so loads those libraries (as
// `crumble --plugin` does) before the parameter lists are generated, so their engines,
// models and builders are tested too; the CLI runs of the cross product get the same
// `--plugin` arguments. Example:
//   CRUMBLE_TEST_PLUGINS=$PWD/build/tests/integration/plugin/libcrumble_test_plugin.so
//     ./build/tests/test_models          (one line)
// (ctest runs exactly that as conformance.plugin_*; tests/CMakeLists.txt.)
#pragma once
#include <cctype>
#include <cstdlib>
#include <ostream>
#include <string>
#include <vector>

#include "scenarios/Plugins.h"
#include "scenarios/Registry.h"

namespace crumble::testing_support {

inline std::vector<std::string> test_plugins() {
  std::vector<std::string> out;
  const char* env = std::getenv("CRUMBLE_TEST_PLUGINS");
  if (!env) return out;
  std::string s = env;
  std::size_t start = 0;
  while (start <= s.size()) {
    const std::size_t end = s.find(':', start);
    const std::string p = s.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (!p.empty()) out.push_back(p);
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

// Loads the plugins once (the parameter generators call it before reading the tables). A
// plugin that cannot be loaded aborts the test program with the loader's message: a
// plugin that is asked for and silently missing would test nothing.
inline void load_test_plugins() {
  static const bool loaded = [] {
    for (const auto& p : test_plugins()) load_plugin(p);
    return true;
  }();
  (void)loaded;
}

// " --plugin a.so --plugin b.so" for CLI runs.
inline std::string plugin_args() {
  std::string a;
  for (const auto& p : test_plugins()) a += " --plugin " + p;
  return a;
}

// One registered implementation in one dimension it supports.
struct Registered {
  std::string name;
  int dimension = 3;
};

// A GoogleTest parameter name (letters, digits, underscores).
inline std::string sanitized(std::string s) {
  for (auto& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}
inline std::string param_name(const Registered& r) { return sanitized(r.name) + "_" + std::to_string(r.dimension) + "d"; }
inline void PrintTo(const Registered& r, std::ostream* os) { *os << param_name(r); }

template <class Table>
std::vector<Registered> registered(const Table& t) {
  load_test_plugins();
  std::vector<Registered> out;
  for (const auto& e : t.entries())
    for (int d : e.dimensions) out.push_back({e.name, d});
  return out;
}

inline std::vector<Registered> registered_engines() { return registered(engines()); }
inline std::vector<Registered> registered_models() { return registered(breakage_models()); }
inline std::vector<Registered> registered_builders() { return registered(fragment_builders()); }

}  // namespace crumble::testing_support
