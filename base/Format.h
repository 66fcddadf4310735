// Numbers in words a user reads (errors, notes, reports): %g, so 1e-12 m reads "1e-12 m"
// and not std::to_string's "0.000000". Header-only and in geometry/, the lowest layer, so
// every layer prints numbers the same way.
#pragma once
#include <cstdio>
#include <string>

namespace crumble {

inline std::string fmt_num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace crumble
