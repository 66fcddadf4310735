// Cells of the CSV and Markdown tables that `compare` and `sweep` write.
#pragma once
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace crumble {

// A number with `prec` significant digits; NaN (no value) is empty, ±inf is `infinite`.
inline std::string table_number(double v, int prec = 4, const char* infinite = "") {
  if (std::isnan(v)) return "";
  if (std::isinf(v)) return infinite;
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

// RFC 4180 quoting when the text holds a comma, a quote or a newline (newlines become spaces).
inline std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
  return q + "\"";
}

// A Markdown table cell: `|` would end the cell and becomes `/`, a newline a space; empty is —.
inline std::string md_cell(std::string s) {
  for (auto& c : s)
    if (c == '|' || c == '\n') c = c == '|' ? '/' : ' ';
  return s.empty() ? "—" : s;
}

}  // namespace crumble
