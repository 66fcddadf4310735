// Runs the crumble binary (CRUMBLE_BINARY, set by tests/CMakeLists.txt) from a test.
#pragma once
#include <sys/wait.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace crumble::testing_support {

struct CliResult {
  int status;          // exit status, -1 when the process did not exit normally
  std::string output;  // stdout and stderr together
};

// `args` go after the binary's path, through the shell.
inline CliResult run_cli(const std::string& args) {
  const std::string cmd = std::string(CRUMBLE_BINARY) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  const int st = p ? pclose(p) : -1;
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

// Writes `text` to $TMPDIR/<suite>/<current test>/<name> and returns the path: one folder per
// test, because ctest runs the tests of one program in parallel.
inline std::string scenario_file(const std::string& suite, const std::string& name, const std::string& text) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / suite / (info ? info->name() : "any");
  std::filesystem::create_directories(dir);
  const std::filesystem::path f = dir / name;
  std::ofstream(f) << text;
  return f.string();
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// Index of column `name` in the header row of a CSV table (crumble::read_csv); a test
// failure when absent.
inline std::size_t column(const std::vector<std::vector<std::string>>& rows, const std::string& name) {
  for (std::size_t c = 0; !rows.empty() && c < rows[0].size(); ++c)
    if (rows[0][c] == name) return c;
  ADD_FAILURE() << "no column " << name;
  return 0;
}

}  // namespace crumble::testing_support
