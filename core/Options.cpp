#include "core/Options.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "base/Format.h"

namespace crumble {

using Kind = OptionSpec::Kind;

namespace opt {

OptionSpec number(std::string key, double def, double min, double max, std::string unit, std::string doc) {
  OptionSpec s;
  s.key = std::move(key);
  s.kind = Kind::Number;
  s.def = def;
  s.min = min;
  s.max = max;
  s.unit = std::move(unit);
  s.doc = std::move(doc);
  return s;
}

OptionSpec positive(std::string key, double def, std::string unit, std::string doc) {
  return positive_below(std::move(key), def, std::numeric_limits<double>::infinity(), false, std::move(unit),
                        std::move(doc));
}

OptionSpec positive_below(std::string key, double def, double max, bool max_open, std::string unit, std::string doc) {
  OptionSpec s;
  s.key = std::move(key);
  s.kind = Kind::Positive;
  s.def = def;
  s.min = 0;
  s.max = max;
  s.max_open = max_open;
  s.unit = std::move(unit);
  s.doc = std::move(doc);
  return s;
}

OptionSpec integer(std::string key, long def, long min, long max, std::string doc) {
  OptionSpec s;
  s.key = std::move(key);
  s.kind = Kind::Integer;
  s.def = def;
  s.int_min = min;
  s.int_max = max;
  s.doc = std::move(doc);
  return s;
}

OptionSpec boolean(std::string key, bool def, std::string doc) {
  OptionSpec s;
  s.key = std::move(key);
  s.kind = Kind::Boolean;
  s.def = def;
  s.doc = std::move(doc);
  return s;
}

OptionSpec choice(std::string key, std::string def, std::vector<std::string> choices, std::string doc) {
  OptionSpec s;
  s.key = std::move(key);
  s.kind = Kind::Choice;
  s.def = std::move(def);
  s.choices = std::move(choices);
  s.doc = std::move(doc);
  return s;
}

}  // namespace opt

namespace {

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

[[noreturn]] void programming_error(const std::string& msg) { throw std::logic_error("options: " + msg); }

bool is_number(Kind k) { return k == Kind::Number || k == Kind::Positive; }

// The same checked reads as Config's, with the table's default and range. A default that
// depends on other options comes in as `def`.
double read_number(const Config& cfg, const OptionSpec& s, double def) {
  if (s.kind == Kind::Number) return cfg.number(s.key, def, s.min, s.max);
  const double v = cfg.positive(s.key, def);
  if (v > s.max || (s.max_open && v >= s.max))
    cfg.fail(s.key, "expected a number in (0, " + fmt_num(s.max) + (s.max_open ? ")" : "]") + ", got " + fmt_num(v));
  return v;
}

}  // namespace

Options::Options(const Config& cfg, const OptionTable& table) : cfg_(cfg), table_(table) {}

const OptionSpec& Options::spec(const std::string& key) const {
  for (const auto& s : table_)
    if (s.key == key) return s;
  programming_error("'" + key + "' is read at " + cfg_.path() + " but not declared in the option table");
}

double Options::read_number(const OptionSpec& s, double def) const { return crumble::read_number(cfg_, s, def); }

double Options::number(const std::string& key) const {
  const OptionSpec& s = spec(key);
  if (!is_number(s.kind) || !std::holds_alternative<double>(s.def))
    programming_error("'" + key + "' is not declared as a number with a default");
  return read_number(s, std::get<double>(s.def));
}

double Options::number(const std::string& key, double def) const {
  const OptionSpec& s = spec(key);
  if (!is_number(s.kind) || !std::holds_alternative<std::monostate>(s.def))
    programming_error("'" + key + "' has a declared default; read it without one");
  return read_number(s, def);
}

long Options::integer(const std::string& key) const {
  const OptionSpec& s = spec(key);
  if (s.kind != Kind::Integer || !std::holds_alternative<long>(s.def))
    programming_error("'" + key + "' is not declared as an integer");
  return cfg_.integer(key, std::get<long>(s.def), s.int_min, s.int_max);
}

bool Options::boolean(const std::string& key) const {
  const OptionSpec& s = spec(key);
  if (s.kind != Kind::Boolean || !std::holds_alternative<bool>(s.def))
    programming_error("'" + key + "' is not declared as a boolean");
  return cfg_.boolean(key, std::get<bool>(s.def));
}

std::string Options::string(const std::string& key) const {
  const OptionSpec& s = spec(key);
  if ((s.kind != Kind::String && s.kind != Kind::Choice) || !std::holds_alternative<std::string>(s.def))
    programming_error("'" + key + "' is not declared as a string");
  if (s.kind == Kind::Choice) return cfg_.choice(key, std::get<std::string>(s.def), s.choices);
  return cfg_.string(key, std::get<std::string>(s.def));
}

bool Options::has(const std::string& key) const {
  spec(key);
  return cfg_.has(key);
}

void check_option(const Config& cfg, const OptionSpec& s) {
  switch (s.kind) {
    case Kind::Number:
    case Kind::Positive:
      // A default that depends on other options: any value in the range will do here.
      read_number(cfg, s, std::holds_alternative<double>(s.def) ? std::get<double>(s.def) : 1.0);
      return;
    case Kind::Integer: cfg.integer(s.key, std::get<long>(s.def), s.int_min, s.int_max); return;
    case Kind::Boolean: cfg.boolean(s.key, std::get<bool>(s.def)); return;
    case Kind::String: cfg.string(s.key, std::get<std::string>(s.def)); return;
    case Kind::Choice: cfg.choice(s.key, std::get<std::string>(s.def), s.choices); return;
  }
}

namespace {
// %g without the exponent's plus sign and leading zero: 4e7, 1e-9 (how docs/scenarios.md
// writes numbers).
std::string short_num(double v) { return option_number_text(v); }
}  // namespace

std::string option_number_text(double v) {
  // %g, or the shortest exact mantissa–exponent form when that is at least two characters
  // shorter (4e5 rather than 400000, 1e-4 rather than 0.0001; 0.002 stays).
  auto strip = [](std::string t) {
    const auto e = t.find('e');
    if (e == std::string::npos) return t;
    std::string mant = t.substr(0, e), ex = t.substr(e + 1), sign;
    if (!ex.empty() && (ex[0] == '+' || ex[0] == '-')) {
      if (ex[0] == '-') sign = "-";
      ex.erase(0, 1);
    }
    while (ex.size() > 1 && ex[0] == '0') ex.erase(0, 1);
    return mant + "e" + sign + ex;
  };
  const std::string plain = strip(fmt_num(v));
  if (!std::isfinite(v) || v == 0) return plain;
  for (int p = 0; p <= 16; ++p) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*e", p, v);
    if (std::strtod(buf, nullptr) != v) continue;
    const std::string exp = strip(buf);
    return exp.size() + 2 <= plain.size() ? exp : plain;
  }
  return plain;
}

namespace {

// Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "[" + a + ...
std::string interval(const char* open, const std::string& lo, const std::string& hi, const char* close) {
  std::string r = open;
  r += lo;
  r += ", ";
  r += hi;
  r += close;
  return r;
}

std::string long_text(long v) {
  if (v == std::numeric_limits<long>::max()) return "∞";
  return std::to_string(v);
}
}  // namespace

std::string option_kind_name(const OptionSpec& s) {
  switch (s.kind) {
    case Kind::Number: return "number";
    case Kind::Positive: return "number";
    case Kind::Integer: return "integer";
    case Kind::Boolean: return "boolean";
    case Kind::String: return "string";
    case Kind::Choice: return "choice";
  }
  return "?";
}

std::string option_default_text(const OptionSpec& s) {
  if (std::holds_alternative<std::monostate>(s.def)) return s.default_doc;
  if (auto* d = std::get_if<double>(&s.def)) return short_num(*d) + (s.unit.empty() ? "" : " " + s.unit);
  if (auto* l = std::get_if<long>(&s.def)) return std::to_string(*l);
  if (auto* b = std::get_if<bool>(&s.def)) return *b ? "true" : "false";
  return "\"" + std::get<std::string>(s.def) + "\"";
}

std::string option_range_text(const OptionSpec& s) {
  const double inf = std::numeric_limits<double>::infinity();
  switch (s.kind) {
    case Kind::Number:
      if (s.min == -inf && s.max == inf) return "any";
      if (s.max == inf) return "≥ " + short_num(s.min);
      if (s.min == -inf) return "≤ " + short_num(s.max);
      return interval("[", short_num(s.min), short_num(s.max), "]");
    case Kind::Positive:
      if (s.max == inf) return "> 0";
      return interval("(", "0", short_num(s.max), s.max_open ? ")" : "]");
    case Kind::Integer:
      if (s.int_max == std::numeric_limits<long>::max()) return "≥ " + std::to_string(s.int_min);
      return interval("[", std::to_string(s.int_min), long_text(s.int_max), "]");
    case Kind::Boolean: return "true, false";
    case Kind::String: return "";
    case Kind::Choice: return joined(s.choices);
  }
  return "";
}

}  // namespace crumble
