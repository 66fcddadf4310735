// Checked access to a scenario's JSON. Every read names its key, a default and the
// accepted range; the default is written back so the effective scenario (all defaults
// filled in) can be saved. After construction, `check_unknown()` turns every key that no
// component asked for into an error naming its JSON path — a misspelt key never falls
// back silently to a default.
#pragma once
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "geometry/Vec3.h"

namespace crumble {

class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& path, const std::string& msg)
      : std::runtime_error(path + ": " + msg), path_(path) {}
  // `where` (a file and line) in front of the JSON path.
  ConfigError(const std::string& where, const std::string& path, const std::string& msg)
      : std::runtime_error(where + ": " + path + ": " + msg), path_(path) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

class Config {
 public:
  // Wraps (and edits in place: defaults are filled in) the given document.
  explicit Config(nlohmann::json& root);
  ~Config();
  Config(const Config&);

  const std::string& path() const { return path_; }
  bool has(const std::string& key) const;
  bool is_object(const std::string& key) const;

  double number(const std::string& key, double def,
                double min = -std::numeric_limits<double>::infinity(),
                double max = std::numeric_limits<double>::infinity()) const;
  double number(const std::string& key) const;  // required
  // Strictly positive finite number.
  double positive(const std::string& key, double def) const;
  double positive(const std::string& key) const;
  long integer(const std::string& key, long def, long min = std::numeric_limits<long>::min(),
               long max = std::numeric_limits<long>::max()) const;
  // The full unsigned 64-bit range (seeds).
  std::uint64_t unsigned_integer(const std::string& key, std::uint64_t def) const;
  bool boolean(const std::string& key, bool def) const;
  std::string string(const std::string& key, const std::string& def) const;
  std::string string(const std::string& key) const;
  // String restricted to `choices`; error lists them.
  std::string choice(const std::string& key, const std::string& def,
                     const std::vector<std::string>& choices) const;
  Vec3 vec3(const std::string& key, const Vec3& def) const;
  std::vector<double> numbers(const std::string& key, const std::vector<double>& def) const;
  std::vector<double> numbers(const std::string& key) const;

  // Sub-object (created empty if absent, so its defaults get recorded).
  Config child(const std::string& key) const;
  // Required sub-object.
  Config required_child(const std::string& key) const;
  // Array of objects.
  std::vector<Config> children(const std::string& key) const;
  // The raw JSON at key (for components that take free-form data); marks it read whole.
  const nlohmann::json& raw(const std::string& key) const;

  // Keys of this object read so far; mark a key as read without using it.
  std::set<std::string> read_keys() const;
  void accept(const std::string& key) const { mark(key); }

  // Throw ConfigError at `path()/key`.
  [[noreturn]] void fail(const std::string& key, const std::string& msg) const;

  // Errors on the first key (depth-first, sorted) that nobody read.
  void check_unknown() const;

  const nlohmann::json& doc() const;

 private:
  struct State;
  Config(std::shared_ptr<State> st, nlohmann::json* node, std::string path);
  nlohmann::json* node_;
  std::string path_;
  std::shared_ptr<State> st_;
  nlohmann::json* at(const std::string& key) const;
  void mark(const std::string& key) const;
};

// Parse text as JSON. Every error is a ConfigError naming the source, line and column:
// malformed JSON, a number outside the range of a double (1e999), and a key given twice in
// one object (which JSON parsers otherwise resolve silently to the last value), the
// latter two with the JSON path.
nlohmann::json parse_json_text(const std::string& text, const std::string& source_name);

// Apply `--set a.b.c=value`: value is parsed as JSON when it is valid JSON, otherwise
// taken as a string (a number outside the range of a double is an error). Intermediate
// objects are created; array indices are numbers.
void apply_override(nlohmann::json& doc, const std::string& assignment);

}  // namespace crumble
