// The options of a registered implementation, declared once: key,
// type, default, range and one line of documentation per option. Everything that needs to
// know an implementation's options reads its table: the implementation itself (through
// `Options`, which takes defaults and ranges from the table), the scenario factory (which
// keys of a sibling implementation to accept), `crumble list --options TYPE` and the option
// tables of docs/scenarios.md (generated from the table and checked by a test).
#pragma once
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "core/Config.h"

namespace crumble {

struct OptionSpec {
  enum class Kind { Number, Positive, Integer, Boolean, String, Choice };
  // No value (monostate): the default depends on other options and `default_doc` says how
  // (e.g. the stress model's strength, per criterion); the implementation passes it in.
  using Default = std::variant<std::monostate, double, long, bool, std::string>;

  std::string key;
  Kind kind = Kind::Number;
  Default def;
  // Number: [min, max]. Positive: (0, max], or (0, max) with max_open.
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool max_open = false;
  long int_min = std::numeric_limits<long>::min(), int_max = std::numeric_limits<long>::max();  // Integer
  std::vector<std::string> choices;  // Choice
  std::string unit;                  // SI unit of a number ("N/m", "Pa"), "" when dimensionless
  std::string doc;                   // one line; cites the paper and equation where it applies
  std::string default_doc;           // shown instead of the default when `def` is empty
};

using OptionTable = std::vector<OptionSpec>;

// Declaring a table reads best with these (one line per option).
namespace opt {
OptionSpec number(std::string key, double def, double min, double max, std::string unit, std::string doc);
OptionSpec positive(std::string key, double def, std::string unit, std::string doc);
// (0, max], or (0, max) with max_open.
OptionSpec positive_below(std::string key, double def, double max, bool max_open, std::string unit, std::string doc);
OptionSpec integer(std::string key, long def, long min, long max, std::string doc);
OptionSpec boolean(std::string key, bool def, std::string doc);
OptionSpec choice(std::string key, std::string def, std::vector<std::string> choices, std::string doc);
}  // namespace opt

// Reads one implementation's section of the scenario through its table. Every accessor
// takes the default, range and choices from the table; a key that is not in the table, or
// read as another kind than declared, is a programming error (std::logic_error), so no
// option can be read without being declared. Bad input stays a ConfigError naming the JSON
// path and the accepted range or values (Config's messages).
class Options {
 public:
  Options(const Config& cfg, const OptionTable& table);

  double number(const std::string& key) const;  // Number or Positive
  // For an option declared without a default (its default depends on other options).
  double number(const std::string& key, double def) const;
  long integer(const std::string& key) const;
  bool boolean(const std::string& key) const;
  std::string string(const std::string& key) const;  // String or Choice
  // True when the scenario gives the key (a declared key only).
  bool has(const std::string& key) const;

  [[noreturn]] void fail(const std::string& key, const std::string& msg) const { cfg_.fail(key, msg); }
  const Config& config() const { return cfg_; }

 private:
  const OptionSpec& spec(const std::string& key) const;
  double read_number(const OptionSpec& s, double def) const;
  const Config& cfg_;
  const OptionTable& table_;
};

// Reads one option as its spec says (the default written back, the range checked), for
// checking a value without the implementation that owns it (sibling options). Throws
// ConfigError like `Options`.
void check_option(const Config& cfg, const OptionSpec& spec);

// Words for `crumble list --options` and docs/scenarios.md.
std::string option_number_text(double v);              // %g written as docs write it: 4e7, 1e-9, 0.003
std::string option_kind_name(const OptionSpec& s);     // "number", "integer", "choice", ...
std::string option_default_text(const OptionSpec& s);  // "4e+07 N/m", "\"linear\"", "true"
std::string option_range_text(const OptionSpec& s);    // "[0, 10]", "> 0", "linear, hertz", ""

}  // namespace crumble
