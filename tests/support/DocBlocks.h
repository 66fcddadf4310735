// For the tests that hold a document against the code that generates part of it
// (tests/integration/option_docs, tests/integration/output_reference).
#pragma once
#include <sstream>
#include <string>

namespace crumble::testing_support {

// The first line where a generated block (`code`) and what a document holds (`docs`) differ,
// both shown.
inline std::string first_difference(const std::string& code, const std::string& docs) {
  std::istringstream a(code), b(docs);
  std::string la, lb;
  for (int n = 1;; ++n) {
    const bool ha = static_cast<bool>(std::getline(a, la)), hb = static_cast<bool>(std::getline(b, lb));
    if (!ha && !hb) return "(no difference)";
    if (!ha || !hb || la != lb)
      return "line " + std::to_string(n) + " of the block:\n  code: " + (ha ? la : "(end)") + "\n  docs: " + (hb ? lb : "(end)");
  }
}

}  // namespace crumble::testing_support
