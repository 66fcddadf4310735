#include "core/Options.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "base/Format.h"

namespace crumble {

using Kind = OptionSpec::Kind;

namespace opt {

namespace {
// Every helper below: one spec of `kind` with its key, default, unit and line of doc.
OptionSpec spec(std::string key, Kind kind, OptionSpec::Default def, std::string unit, std::string doc) {
  OptionSpec s;
  s.key = std::move(key);
  s.kind = kind;
  s.def = std::move(def);
  s.unit = std::move(unit);
  s.doc = std::move(doc);
  return s;
}
}  // namespace

OptionSpec number(std::string key, double def, double min, double max, std::string unit, std::string doc) {
  OptionSpec s = spec(std::move(key), Kind::Number, def, std::move(unit), std::move(doc));
  s.min = min;
  s.max = max;
  return s;
}

OptionSpec positive(std::string key, double def, std::string unit, std::string doc) {
  return positive_below(std::move(key), def, std::numeric_limits<double>::infinity(), false, std::move(unit),
                        std::move(doc));
}

OptionSpec positive_below(std::string key, double def, double max, bool max_open, std::string unit, std::string doc) {
  OptionSpec s = spec(std::move(key), Kind::Positive, def, std::move(unit), std::move(doc));
  s.min = 0;
  s.max = max;
  s.max_open = max_open;
  return s;
}

OptionSpec integer(std::string key, long def, long min, long max, std::string doc) {
  OptionSpec s = spec(std::move(key), Kind::Integer, def, "", std::move(doc));
  s.int_min = min;
  s.int_max = max;
  return s;
}

OptionSpec boolean(std::string key, bool def, std::string doc) {
  return spec(std::move(key), Kind::Boolean, def, "", std::move(doc));
}

OptionSpec choice(std::string key, std::string def, std::vector<std::string> choices, std::string doc) {
  OptionSpec s = spec(std::move(key), Kind::Choice, std::move(def), "", std::move(doc));
  s.choices = std::move(choices);
  return s;
}

OptionSpec string(std::string key, std::string def, std::string doc) {
  return spec(std::move(key), Kind::String, std::move(def), "", std::move(doc));
}

OptionSpec numbers(std::string key, std::vector<double> def, std::string unit, std::string doc) {
  return spec(std::move(key), Kind::Numbers, std::move(def), std::move(unit), std::move(doc));
}

OptionSpec vec3(std::string key, Vec3 def, std::string unit, std::string doc) {
  return spec(std::move(key), Kind::Vector3, std::vector<double>{def.x, def.y, def.z}, std::move(unit), std::move(doc));
}

OptionSpec unsigned_integer(std::string key, std::uint64_t def, std::string doc) {
  return spec(std::move(key), Kind::Unsigned, def, "", std::move(doc));
}

}  // namespace opt

OptionSpec OptionSpec::depends(std::string doc) const {
  OptionSpec c = *this;
  c.def = std::monostate{};
  c.default_doc = std::move(doc);
  return c;
}

OptionSpec OptionSpec::required_key() const {
  OptionSpec c = depends("required");
  c.required = true;
  return c;
}

OptionSpec OptionSpec::if_given(std::string doc) const {
  OptionSpec c = depends(std::move(doc));
  c.optional = true;
  return c;
}

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

template <class T>
const T& default_as(const OptionSpec& s, const OptionSpec::Default& def) {
  if (const T* v = std::get_if<T>(&def)) return *v;
  programming_error("'" + s.key + "' is read without a default of its type");
}

// One option's value as the scenario gives it, or `def` (written back); a required option
// without a value is Config's "required ... is missing".
OptionSpec::Default read_value(const Config& cfg, const OptionSpec& s, const OptionSpec::Default& def) {
  if (s.required && !cfg.has(s.key)) {
    switch (s.kind) {
      case Kind::Positive: cfg.positive(s.key); break;
      case Kind::Number: cfg.number(s.key); break;
      case Kind::String:
      case Kind::Choice: cfg.string(s.key); break;
      default: cfg.numbers(s.key); break;
    }
  }
  const bool given = cfg.has(s.key);
  switch (s.kind) {
    case Kind::Number:
    case Kind::Positive: return read_number(cfg, s, given ? 0.0 : default_as<double>(s, def));
    case Kind::Integer:
      return cfg.integer(s.key, given ? 0L : default_as<long>(s, def), s.int_min, s.int_max);
    case Kind::Unsigned: return cfg.unsigned_integer(s.key, given ? 0 : default_as<std::uint64_t>(s, def));
    case Kind::Boolean: return cfg.boolean(s.key, given ? false : default_as<bool>(s, def));
    case Kind::String: return cfg.string(s.key, given ? std::string() : default_as<std::string>(s, def));
    case Kind::Choice: return cfg.choice(s.key, given ? s.choices.front() : default_as<std::string>(s, def), s.choices);
    case Kind::Numbers:
      return cfg.numbers(s.key, given ? std::vector<double>() : default_as<std::vector<double>>(s, def));
    case Kind::Vector3: {
      const auto& d = given ? std::vector<double>{0, 0, 0} : default_as<std::vector<double>>(s, def);
      const Vec3 v = cfg.vec3(s.key, {d[0], d[1], d[2]});
      return std::vector<double>{v.x, v.y, v.z};
    }
  }
  return {};
}

// The text of a value in an error message.
std::string value_text(const OptionSpec::Default& v) {
  if (auto* d = std::get_if<double>(&v)) return fmt_num(*d);
  if (auto* l = std::get_if<long>(&v)) return std::to_string(*l);
  if (auto* u = std::get_if<std::uint64_t>(&v)) return std::to_string(*u);
  if (auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (auto* t = std::get_if<std::string>(&v)) return "'" + *t + "'";
  return "(a list)";
}

// Whether a value lies in the option's declared range or choices.
bool in_range(const OptionSpec& s, const OptionSpec::Default& v) {
  switch (s.kind) {
    case Kind::Number: {
      const double x = std::get<double>(v);
      return std::isfinite(x) && x >= s.min && x <= s.max;
    }
    case Kind::Positive: {
      const double x = std::get<double>(v);
      return std::isfinite(x) && x > 0 && (s.max_open ? x < s.max : x <= s.max);
    }
    case Kind::Integer: {
      const long x = std::get<long>(v);
      return x >= s.int_min && x <= s.int_max;
    }
    case Kind::Choice:
      for (const auto& c : s.choices)
        if (c == std::get<std::string>(v)) return true;
      return false;
    default: return true;
  }
}

const OptionBinding& binding_of(const OptionSpec& s, std::type_index type) {
  if (s.binding->owner != type)
    programming_error("'" + s.key + "' is bound to a member of another settings struct than the one read");
  return *s.binding;
}

}  // namespace

void read_bound_options(const Config& cfg, const OptionTable& table, void* settings, std::type_index type) {
  for (const auto& s : table) {
    if (!s.binding) continue;
    const OptionBinding& b = binding_of(s, type);
    if (b.when && !b.when(settings)) continue;
    if (s.optional && !cfg.has(s.key)) continue;
    OptionSpec::Default def = s.def;
    if (b.default_of) def = b.default_of(settings);
    else if (std::holds_alternative<std::monostate>(def)) def = b.get(settings);
    b.set(settings, read_value(cfg, s, def));
  }
}

void check_bound_options(const OptionTable& table, const void* settings, std::type_index type, const std::string& who) {
  for (const auto& s : table) {
    if (!s.binding) continue;
    const OptionBinding& b = binding_of(s, type);
    if (b.when && !b.when(settings)) continue;
    const OptionSpec::Default v = b.get(settings);
    if (in_range(s, v)) continue;
    const std::string range = option_range_text(s);
    const std::string must = s.kind == Kind::Choice                     ? "must be one of: "
                             : range[0] == '[' || range[0] == '(' ? "must lie in "
                                                                   : "must be ";
    throw std::invalid_argument(who + ": " + s.key + " " + must + range + ", got " + value_text(v));
  }
}

const OptionSpec& find_option(const OptionTable& table, const std::string& key) {
  for (const auto& s : table)
    if (s.key == key) return s;
  programming_error("'" + key + "' is not declared in the option table");
}

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
  // A default that depends on other options: any value in the range will do here.
  if (std::holds_alternative<std::monostate>(s.def) && !cfg.has(s.key)) return;
  read_value(cfg, s, s.def);
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
    case Kind::Numbers: return "numbers";
    case Kind::Vector3: return "vector";
    case Kind::Unsigned: return "integer";
  }
  return "?";
}

std::string option_default_text(const OptionSpec& s) {
  if (std::holds_alternative<std::monostate>(s.def)) return s.default_doc;
  if (auto* d = std::get_if<double>(&s.def)) return short_num(*d) + (s.unit.empty() ? "" : " " + s.unit);
  if (auto* l = std::get_if<long>(&s.def)) return std::to_string(*l);
  if (auto* b = std::get_if<bool>(&s.def)) return *b ? "true" : "false";
  if (auto* u = std::get_if<std::uint64_t>(&s.def)) return std::to_string(*u);
  if (auto* v = std::get_if<std::vector<double>>(&s.def)) {
    std::string t = "[";
    for (std::size_t i = 0; i < v->size(); ++i) t += (i ? ", " : "") + short_num((*v)[i]);
    return t + "]" + (s.unit.empty() ? "" : " " + s.unit);
  }
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
    case Kind::Numbers: return "";
    case Kind::Vector3: return "3 numbers";
    case Kind::Unsigned: return "[0, 2^64 − 1]";
  }
  return "";
}

}  // namespace crumble
