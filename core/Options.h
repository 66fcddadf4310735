// The options of a registered implementation or of a scenario section, declared once: key,
// type, default, range, one line of documentation, and the settings member the option
// fills. Everything that needs to know the options reads the table: `read_options` (which
// fills the settings struct, with the table's defaults and ranges), `check_options` (the
// same ranges for settings built in code), the scenario factory (which keys of a sibling
// implementation to accept), `crumble list --options NAME` and the option tables of
// docs/scenarios.md (generated from the table and checked by a test).
//
//   struct S { double kn = 4e7; };
//   const OptionTable t{opt::positive("kn", &S::kn, "N/m", "normal stiffness")};
//   S s;  read_options(cfg, t, s);   // s.kn = cfg's "kn", or 4e7 (from S{}), checked > 0
#pragma once
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <typeindex>
#include <typeinfo>
#include <utility>
#include <variant>
#include <vector>

#include "core/Config.h"

namespace crumble {

struct OptionBinding;

struct OptionSpec {
  // Numbers: an array of numbers; Vector3: an array of 3 numbers; Unsigned: [0, 2^64 − 1].
  enum class Kind { Number, Positive, Integer, Boolean, String, Choice, Numbers, Vector3, Unsigned };
  // No value (monostate): the default depends on other options or on the caller and
  // `default_doc` says how (e.g. the stress model's strength, per criterion).
  using Default = std::variant<std::monostate, double, long, bool, std::string, std::vector<double>, std::uint64_t>;

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
  bool required = false;             // no default: the scenario must give it
  bool optional = false;             // read only when the scenario gives it (no default written)
  // The settings member the option fills (set by the opt:: overloads that take a member
  // pointer); null for an option read by hand through `Options`.
  std::shared_ptr<const OptionBinding> binding;

  // Modifiers for a table entry (each returns the changed copy):
  // the default is the member's value when `read_options` is called (the caller fills it in,
  // e.g. the breakage model's schedule); `doc` says what it is.
  OptionSpec depends(std::string doc) const;
  // The default follows from the members read before this option (in table order).
  template <class S, class F>
  OptionSpec depends(std::string doc, F default_of) const;
  // Read only when `f` holds for the members read before it; otherwise the key is not read
  // (and so unknown to the scenario).
  template <class S, class F>
  OptionSpec when(F f) const;
  // The scenario must give the key.
  OptionSpec required_key() const;
  // Read only when the scenario gives the key; the member keeps its value otherwise.
  OptionSpec if_given(std::string doc) const;
};

using OptionTable = std::vector<OptionSpec>;

// How `read_options` reaches the member an option names: the owner's type (checked when a
// table is read into a struct), the member as an option value and back, and the optional
// condition and computed default of the modifiers above.
struct OptionBinding {
  std::type_index owner = typeid(void);
  std::function<OptionSpec::Default(const void*)> get;
  std::function<void(void*, const OptionSpec::Default&)> set;
  std::function<bool(const void*)> when;                        // empty: always read
  std::function<OptionSpec::Default(const void*)> default_of;  // empty: the declared default
};

namespace option_detail {

template <class M>
OptionSpec::Default to_value(const M& v) {
  if constexpr (std::is_same_v<M, bool>) return v;
  else if constexpr (std::is_same_v<M, std::uint64_t>) return v;
  else if constexpr (std::is_integral_v<M>) return static_cast<long>(v);
  else if constexpr (std::is_floating_point_v<M>) return static_cast<double>(v);
  else if constexpr (std::is_same_v<M, Vec3>) return std::vector<double>{v.x, v.y, v.z};
  else return v;  // std::string, std::vector<double>
}

template <class M>
M from_value(const OptionSpec::Default& v) {
  if constexpr (std::is_same_v<M, bool>) return std::get<bool>(v);
  else if constexpr (std::is_same_v<M, std::uint64_t>) return std::get<std::uint64_t>(v);
  else if constexpr (std::is_integral_v<M>) return static_cast<M>(std::get<long>(v));
  else if constexpr (std::is_floating_point_v<M>) return static_cast<M>(std::get<double>(v));
  else if constexpr (std::is_same_v<M, Vec3>) {
    const auto& a = std::get<std::vector<double>>(v);
    return Vec3{a[0], a[1], a[2]};
  } else return std::get<M>(v);
}

// A member of a member (`AlphaShapeBuilderOptions::alpha.start_spacings`): opt::nested.
template <class S, class Mid, class M>
struct Nested {
  Mid S::*outer;
  M Mid::*inner;
};

// What an option names: a member pointer or a Nested; Owner is the settings struct.
template <class P>
struct Access;
template <class S, class M>
struct Access<M S::*> {
  using Owner = S;
  using Type = M;
  static const M& get(const S& s, M S::*p) { return s.*p; }
  static M& ref(S& s, M S::*p) { return s.*p; }
};
template <class S, class Mid, class M>
struct Access<Nested<S, Mid, M>> {
  using Owner = S;
  using Type = M;
  static const M& get(const S& s, Nested<S, Mid, M> p) { return (s.*p.outer).*p.inner; }
  static M& ref(S& s, Nested<S, Mid, M> p) { return (s.*p.outer).*p.inner; }
};
template <class P>
using OwnerOf = typename Access<P>::Owner;
template <class P>
using TypeOf = typename Access<P>::Type;

// The member's value in a default-constructed owner: the option's default.
template <class P>
TypeOf<P> initial(P p) {
  const OwnerOf<P> s{};
  return Access<P>::get(s, p);
}

template <class P>
std::shared_ptr<OptionBinding> bind(P p) {
  using A = Access<P>;
  using S = OwnerOf<P>;
  auto b = std::make_shared<OptionBinding>();
  b->owner = typeid(S);
  b->get = [p](const void* s) { return to_value(A::get(*static_cast<const S*>(s), p)); };
  b->set = [p](void* s, const OptionSpec::Default& v) { A::ref(*static_cast<S*>(s), p) = from_value<TypeOf<P>>(v); };
  return b;
}

// A choice stored as another type (a bool, an enum): each choice names its value.
template <class P>
std::shared_ptr<OptionBinding> bind_choice(P p, std::vector<std::pair<std::string, TypeOf<P>>> map) {
  using A = Access<P>;
  using S = OwnerOf<P>;
  auto b = std::make_shared<OptionBinding>();
  b->owner = typeid(S);
  b->get = [p, map](const void* s) -> OptionSpec::Default {
    for (const auto& [name, value] : map)
      if (value == A::get(*static_cast<const S*>(s), p)) return name;
    return std::string();
  };
  b->set = [p, map](void* s, const OptionSpec::Default& v) {
    for (const auto& [name, value] : map)
      if (name == std::get<std::string>(v)) A::ref(*static_cast<S*>(s), p) = value;
  };
  return b;
}

inline OptionSpec bound(OptionSpec spec, std::shared_ptr<OptionBinding> b) {
  spec.binding = std::move(b);
  return spec;
}

}  // namespace option_detail

// Declaring a table reads best with these (one line per option).
namespace opt {
OptionSpec number(std::string key, double def, double min, double max, std::string unit, std::string doc);
OptionSpec positive(std::string key, double def, std::string unit, std::string doc);
// (0, max], or (0, max) with max_open.
OptionSpec positive_below(std::string key, double def, double max, bool max_open, std::string unit, std::string doc);
OptionSpec integer(std::string key, long def, long min, long max, std::string doc);
OptionSpec boolean(std::string key, bool def, std::string doc);
OptionSpec choice(std::string key, std::string def, std::vector<std::string> choices, std::string doc);
OptionSpec string(std::string key, std::string def, std::string doc);
OptionSpec numbers(std::string key, std::vector<double> def, std::string unit, std::string doc);
OptionSpec vec3(std::string key, Vec3 def, std::string unit, std::string doc);
OptionSpec unsigned_integer(std::string key, std::uint64_t def, std::string doc);

// A member of a member, for the overloads below: opt::nested(&S::alpha, &Alpha::max_steps).
template <class S, class Mid, class M>
option_detail::Nested<S, Mid, M> nested(Mid S::*outer, M Mid::*inner) {
  return {outer, inner};
}

// The same, bound to the member of the settings struct that the option fills (a member
// pointer or opt::nested); the default is the member's initialiser (its value in a
// default-constructed struct).
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec number(std::string key, P m, double min, double max, std::string unit, std::string doc) {
  return option_detail::bound(number(std::move(key), static_cast<double>(option_detail::initial(m)), min, max,
                                     std::move(unit), std::move(doc)),
                              option_detail::bind(m));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec positive(std::string key, P m, std::string unit, std::string doc) {
  return option_detail::bound(
      positive(std::move(key), static_cast<double>(option_detail::initial(m)), std::move(unit), std::move(doc)),
      option_detail::bind(m));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec positive_below(std::string key, P m, double max, bool max_open, std::string unit, std::string doc) {
  return option_detail::bound(positive_below(std::move(key), static_cast<double>(option_detail::initial(m)), max,
                                             max_open, std::move(unit), std::move(doc)),
                              option_detail::bind(m));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec integer(std::string key, P m, long min, long max, std::string doc) {
  return option_detail::bound(
      integer(std::move(key), static_cast<long>(option_detail::initial(m)), min, max, std::move(doc)),
      option_detail::bind(m));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec boolean(std::string key, P m, std::string doc) {
  return option_detail::bound(boolean(std::move(key), option_detail::initial(m), std::move(doc)), option_detail::bind(m));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec choice(std::string key, P m, std::vector<std::string> choices, std::string doc) {
  return option_detail::bound(choice(std::move(key), option_detail::initial(m), std::move(choices), std::move(doc)),
                              option_detail::bind(m));
}
// A choice stored as another type: {{"load", true}, {"body", false}}.
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec mapped_choice(std::string key, P m, std::vector<std::pair<std::string, option_detail::TypeOf<P>>> map,
                         std::string doc) {
  std::vector<std::string> names;
  for (const auto& c : map) names.push_back(c.first);
  auto b = option_detail::bind_choice(m, std::move(map));
  const option_detail::OwnerOf<P> d{};
  OptionSpec spec = choice(std::move(key), std::get<std::string>(b->get(&d)), std::move(names), std::move(doc));
  return option_detail::bound(std::move(spec), std::move(b));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec string(std::string key, P m, std::string doc) {
  return option_detail::bound(string(std::move(key), option_detail::initial(m), std::move(doc)), option_detail::bind(m));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec numbers(std::string key, P m, std::string unit, std::string doc) {
  return option_detail::bound(numbers(std::move(key), option_detail::initial(m), std::move(unit), std::move(doc)),
                              option_detail::bind(m));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec vec3(std::string key, P m, std::string unit, std::string doc) {
  return option_detail::bound(vec3(std::move(key), option_detail::initial(m), std::move(unit), std::move(doc)),
                              option_detail::bind(m));
}
template <class P, class = option_detail::OwnerOf<P>>
OptionSpec unsigned_integer(std::string key, P m, std::string doc) {
  return option_detail::bound(unsigned_integer(std::move(key), option_detail::initial(m), std::move(doc)),
                              option_detail::bind(m));
}
}  // namespace opt

template <class S, class F>
OptionSpec OptionSpec::depends(std::string doc, F default_of) const {
  OptionSpec c = depends(std::move(doc));
  auto b = std::make_shared<OptionBinding>(*c.binding);
  b->default_of = [default_of](const void* s) -> Default { return default_of(*static_cast<const S*>(s)); };
  c.binding = std::move(b);
  return c;
}

template <class S, class F>
OptionSpec OptionSpec::when(F f) const {
  OptionSpec c = *this;
  auto b = std::make_shared<OptionBinding>(*c.binding);
  b->when = [f](const void* s) { return static_cast<bool>(f(*static_cast<const S*>(s))); };
  c.binding = std::move(b);
  return c;
}

// Reads every option of `table` that is bound to a member of S into `s`, in the table's
// order: the scenario's value, or the default (written back into the scenario), checked
// against the declared range or choices (ConfigError naming the JSON path, as Config's reads).
// Options without a member are left to the caller (`Options`).
void read_bound_options(const Config& cfg, const OptionTable& table, void* settings, std::type_index type);
template <class S>
void read_options(const Config& cfg, const OptionTable& table, S& s) {
  read_bound_options(cfg, table, &s, typeid(S));
}
template <class S>
S read_options(const Config& cfg, const OptionTable& table) {
  S s{};
  read_options(cfg, table, s);
  return s;
}

// The declared ranges and choices checked on settings built in code: std::invalid_argument
// "WHO: KEY must lie in RANGE, got V" for the first member outside its option's range.
void check_bound_options(const OptionTable& table, const void* settings, std::type_index type, const std::string& who);
template <class S>
void check_options(const OptionTable& table, const S& s, const std::string& who) {
  check_bound_options(table, &s, typeid(S), who);
}

// The option of `table` called `key` (std::logic_error when there is none).
const OptionSpec& find_option(const OptionTable& table, const std::string& key);

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
