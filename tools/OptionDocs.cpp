#include "tools/OptionDocs.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "output/OutputReference.h"

namespace crumble {

namespace {

std::string escape_pipes(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

std::string choices_markdown(const OptionSpec& s) {
  std::string out;
  for (const auto& c : s.choices) out += (out.empty() ? "`" : ", `") + c + "`";
  return out;
}

// Characters on a terminal (UTF-8 continuation bytes take no column).
std::size_t columns(const std::string& s) {
  return static_cast<std::size_t>(std::count_if(s.begin(), s.end(), [](char c) { return (c & 0xC0) != 0x80; }));
}

// A unit as the reference shows it: "text" for a word, "–" for a number without unit.
std::string unit_cell(const std::string& u) { return u.empty() ? "text" : u == "1" ? "–" : u; }

std::string pad(const std::string& s, std::size_t width) {
  const std::size_t n = columns(s);
  return s + std::string(n < width ? width - n : 1, ' ');
}

}  // namespace

std::string option_table_markdown(const OptionTable& table) {
  std::string out = "| key | type | default | range | meaning |\n|---|---|---|---|---|\n";
  for (const auto& s : table) {
    std::string def = option_default_text(s);
    if (!std::holds_alternative<std::monostate>(s.def)) def = "`" + def + "`";
    const std::string range = s.kind == OptionSpec::Kind::Choice ? choices_markdown(s) : option_range_text(s);
    out += "| `" + s.key + "` | " + option_kind_name(s) + " | " + escape_pipes(def) + " | " + escape_pipes(range) +
           " | " + escape_pipes(s.doc) + " |\n";
  }
  return out;
}

std::string option_table_text(const OptionTable& table) {
  if (table.empty()) return "  (no declared options)\n";
  std::size_t wk = 3, wt = 4, wd = 7;
  for (const auto& s : table) {
    wk = std::max(wk, columns(s.key));
    wt = std::max(wt, columns(option_kind_name(s)));
    if (!std::holds_alternative<std::monostate>(s.def)) wd = std::max(wd, columns(option_default_text(s)));
  }
  std::string out = "  " + pad("key", wk + 2) + pad("type", wt + 2) + pad("default", wd + 2) + "range\n";
  for (const auto& s : table) {
    const bool dependent = std::holds_alternative<std::monostate>(s.def);
    out += "  " + pad(s.key, wk + 2) + pad(option_kind_name(s), wt + 2) +
           pad(dependent ? "(see below)" : option_default_text(s), wd + 2) + option_range_text(s) + "\n";
    if (dependent) out += "      default: " + s.default_doc + "\n";
    out += "      " + s.doc + "\n";
  }
  return out;
}

std::string output_reference_markdown() {
  std::string out;
  for (const auto& f : output_csv_files()) {
    std::string when = escape_pipes(f.when);
    if (!when.empty() && when[0] >= 'a' && when[0] <= 'z') when[0] = static_cast<char>(when[0] - 'a' + 'A');
    out += "### `" + f.file + "`\n\n" + when + ".\n\n| column | unit | meaning |\n|---|---|---|\n";
    for (const auto& c : f.columns)
      out += "| `" + escape_pipes(c.name) + "` | " + unit_cell(c.unit) + " | " + (c.only.empty() ? "" : "(" + c.only + ") ") +
             escape_pipes(c.meaning) + " |\n";
    out += "\n";
  }
  out += "### `summary.json`\n\nEvery run, at the end; nested keys by their path with dots.\n\n"
         "| key | unit | meaning | written |\n|---|---|---|---|\n";
  for (const auto& k : summary_keys())
    out += "| `" + escape_pipes(k.name) + "` | " + unit_cell(k.unit) + " | " + escape_pipes(k.meaning) + " | " +
           (k.when.empty() ? "always" : escape_pipes(k.when)) + " |\n";
  return out;
}

std::string output_reference_text() {
  std::string out;
  for (const auto& f : output_csv_files()) {
    out += f.file + ": " + f.when + "\n";
    for (const auto& c : f.columns)
      out += "  " + c.name + " [" + unit_cell(c.unit) + "]" + (c.only.empty() ? "" : " (" + c.only + ")") + "\n      " +
             c.meaning + "\n";
  }
  out += "summary.json: every run, at the end\n";
  for (const auto& k : summary_keys())
    out += "  " + k.name + " [" + unit_cell(k.unit) + "]" + (k.when.empty() ? "" : " (" + k.when + ")") + "\n      " +
           k.meaning + "\n";
  return out;
}

std::vector<OptionDocBlock> option_doc_blocks(const std::string& markdown) {
  static const std::string open = "<!-- options:", close = "<!-- /options -->";
  std::vector<OptionDocBlock> out;
  std::istringstream in(markdown);
  std::string line;
  int n = 0;
  OptionDocBlock* cur = nullptr;
  while (std::getline(in, line)) {
    ++n;
    if (line.rfind(open, 0) == 0) {
      if (cur) throw std::invalid_argument("line " + std::to_string(cur->line) + ": options block without " + close);
      const auto end = line.find(" -->");
      if (end == std::string::npos) throw std::invalid_argument("line " + std::to_string(n) + ": malformed marker");
      out.push_back({line.substr(open.size(), end - open.size()), "", n});
      cur = &out.back();
    } else if (line == close) {
      if (!cur) throw std::invalid_argument("line " + std::to_string(n) + ": " + close + " without an opening marker");
      cur = nullptr;
    } else if (cur) {
      cur->content += line + "\n";
    }
  }
  if (cur) throw std::invalid_argument("line " + std::to_string(cur->line) + ": options block without " + close);
  return out;
}

}  // namespace crumble
