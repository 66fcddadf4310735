// Numbers in words a user reads (errors, notes, reports): %g, so 1e-12 m reads "1e-12 m"
// and not std::to_string's "0.000000". Header-only and in geometry/, the lowest layer, so
// every layer prints numbers the same way.
#pragma once
#include <cstdio>
#include <string>
#include <utility>

namespace crumble {

inline std::string fmt_num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Two numbers printed with the fewest significant digits (at least %g's 6, at most 17)
// that tell them apart: a value compared with a limit, where %g would print both alike
// (an overlap of 2.0000000000000003e-05 m against a tolerance of 2e-05 m).
inline std::pair<std::string, std::string> fmt_apart(double a, double b) {
  char x[40], y[40];
  for (int p = 6; p <= 17; ++p) {
    std::snprintf(x, sizeof x, "%.*g", p, a);
    std::snprintf(y, sizeof y, "%.*g", p, b);
    if (std::string(x) != y) break;
  }
  return {x, y};
}

}  // namespace crumble
