#include "core/Config.h"

#include <cmath>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "base/Format.h"

namespace crumble {

using Json = nlohmann::json;

struct Config::State {
  Json* root = nullptr;
  std::map<std::string, std::set<std::string>> read;  // object path -> keys read
  std::set<std::string> whole;                        // paths read as raw
};

namespace {
std::string join(const std::string& path, const std::string& key) { return path + "/" + key; }

std::string type_name(const Json& j) {
  switch (j.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::object: return "an object";
    case Json::value_t::array: return "an array";
    case Json::value_t::string: return "a string";
    case Json::value_t::boolean: return "a boolean";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned: return "an integer";
    case Json::value_t::number_float: return "a number";
    default: return "an unsupported value";
  }
}

std::string fmt(double v) { return fmt_num(v); }

// A document built in code (or edited by --set) may hold inf or NaN, which JSON text cannot:
// reject it wherever it is, with its path, before any component reads it.
void check_finite_numbers(const Json& node, const std::string& path) {
  if (node.is_number_float() && !std::isfinite(node.get<double>()))
    throw ConfigError(path.empty() ? "/" : path, "expected a finite number, got " + fmt(node.get<double>()));
  if (node.is_object())
    for (auto& [k, v] : node.items()) check_finite_numbers(v, path + "/" + k);
  else if (node.is_array())
    for (std::size_t i = 0; i < node.size(); ++i) check_finite_numbers(node[i], path + "/" + std::to_string(i));
}
}  // namespace

Config::Config(Json& root) : node_(&root), path_(""), st_(std::make_shared<State>()) {
  st_->root = &root;
  if (!root.is_object()) throw ConfigError("/", "the scenario must be a JSON object, got " + type_name(root));
  check_finite_numbers(root, "");
}
Config::Config(std::shared_ptr<State> st, Json* node, std::string path)
    : node_(node), path_(std::move(path)), st_(std::move(st)) {}
Config::Config(const Config&) = default;
Config::~Config() = default;

const Json& Config::doc() const { return *node_; }

void Config::fail(const std::string& key, const std::string& msg) const {
  throw ConfigError(key.empty() ? (path_.empty() ? "/" : path_) : join(path_, key), msg);
}

void Config::mark(const std::string& key) const { st_->read[path_].insert(key); }

std::set<std::string> Config::read_keys() const {
  auto it = st_->read.find(path_);
  return it == st_->read.end() ? std::set<std::string>{} : it->second;
}

bool Config::has(const std::string& key) const {
  mark(key);
  return node_->contains(key) && !(*node_)[key].is_null();
}

bool Config::is_object(const std::string& key) const {
  return node_->contains(key) && (*node_)[key].is_object();
}

Json* Config::at(const std::string& key) const {
  mark(key);
  auto it = node_->find(key);
  if (it == node_->end() || it->is_null()) return nullptr;
  return &*it;
}

double Config::number(const std::string& key, double def, double min, double max) const {
  Json* j = at(key);
  double v = def;
  if (!j) {
    (*node_)[key] = def;
  } else {
    if (!j->is_number()) fail(key, "expected a number, got " + type_name(*j));
    v = j->get<double>();
  }
  if (!std::isfinite(v)) fail(key, "expected a finite number");
  if (v < min || v > max)
    fail(key, "expected a number in [" + fmt(min) + ", " + fmt(max) + "], got " + fmt(v));
  return v;
}

double Config::number(const std::string& key) const {
  if (!at(key)) fail(key, "required number is missing");
  return number(key, 0);
}

double Config::positive(const std::string& key, double def) const {
  const double v = number(key, def);
  if (!(v > 0)) fail(key, "expected a number > 0, got " + fmt(v));
  return v;
}

double Config::positive(const std::string& key) const {
  if (!at(key)) fail(key, "required number (> 0) is missing");
  return positive(key, 0);
}

long Config::integer(const std::string& key, long def, long min, long max) const {
  Json* j = at(key);
  long v = def;
  if (!j) {
    (*node_)[key] = def;
  } else {
    if (j->is_number_float()) {
      const double d = j->get<double>();
      if (!std::isfinite(d) || std::floor(d) != d) fail(key, "expected an integer, got " + fmt(d));
      if (d < static_cast<double>(min) || d > static_cast<double>(max))
        fail(key, "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "], got " + fmt(d));
      v = static_cast<long>(d);
    } else if (j->is_number_unsigned()) {
      // Above LONG_MAX get<long>() would wrap to a negative number.
      const auto u = j->get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(max))
        fail(key, "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "], got " +
                      std::to_string(u));
      v = static_cast<long>(u);
    } else if (j->is_number_integer()) {
      v = j->get<long>();
    } else {
      fail(key, "expected an integer, got " + type_name(*j));
    }
  }
  if (v < min || v > max)
    fail(key, "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "], got " +
                  std::to_string(v));
  return v;
}

std::uint64_t Config::unsigned_integer(const std::string& key, std::uint64_t def) const {
  Json* j = at(key);
  if (!j) {
    (*node_)[key] = def;
    return def;
  }
  const std::string range = "expected an integer in [0, " + std::to_string(std::numeric_limits<std::uint64_t>::max()) + "]";
  if (j->is_number_unsigned()) return j->get<std::uint64_t>();
  if (j->is_number_integer()) fail(key, range + ", got " + std::to_string(j->get<long>()));
  if (j->is_number_float()) {
    // Doubles hold integers exactly only up to 2^53: larger ones were rounded already.
    const double d = j->get<double>();
    if (!std::isfinite(d) || std::floor(d) != d || d < 0 || d > 9007199254740992.0)
      fail(key, range + " (written without exponent or fraction above 2^53), got " + fmt(d));
    return static_cast<std::uint64_t>(d);
  }
  fail(key, range + ", got " + type_name(*j));
}

bool Config::boolean(const std::string& key, bool def) const {
  Json* j = at(key);
  if (!j) {
    (*node_)[key] = def;
    return def;
  }
  if (!j->is_boolean()) fail(key, "expected true or false, got " + type_name(*j));
  return j->get<bool>();
}

std::string Config::string(const std::string& key, const std::string& def) const {
  Json* j = at(key);
  if (!j) {
    (*node_)[key] = def;
    return def;
  }
  if (!j->is_string()) fail(key, "expected a string, got " + type_name(*j));
  return j->get<std::string>();
}

std::string Config::string(const std::string& key) const {
  if (!at(key)) fail(key, "required string is missing");
  return string(key, "");
}

std::string Config::choice(const std::string& key, const std::string& def,
                           const std::vector<std::string>& choices) const {
  const std::string v = string(key, def);
  for (const auto& c : choices)
    if (c == v) return v;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  fail(key, "unknown value '" + v + "'; expected one of: " + list);
}

Vec3 Config::vec3(const std::string& key, const Vec3& def) const {
  auto v = numbers(key, {def.x, def.y, def.z});
  if (v.size() != 3) fail(key, "expected an array of 3 numbers, got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

std::vector<double> Config::numbers(const std::string& key, const std::vector<double>& def) const {
  Json* j = at(key);
  if (!j) {
    (*node_)[key] = def;
    return def;
  }
  if (!j->is_array()) fail(key, "expected an array of numbers, got " + type_name(*j));
  std::vector<double> out;
  for (std::size_t i = 0; i < j->size(); ++i) {
    const auto& e = (*j)[i];
    if (!e.is_number())
      fail(key + "/" + std::to_string(i), "expected a number, got " + type_name(e));
    const double d = e.get<double>();
    if (!std::isfinite(d)) fail(key + "/" + std::to_string(i), "expected a finite number");
    out.push_back(d);
  }
  return out;
}

std::vector<double> Config::numbers(const std::string& key) const {
  if (!at(key)) fail(key, "required array of numbers is missing");
  return numbers(key, {});
}

Config Config::child(const std::string& key) const {
  Json* j = at(key);
  if (!j) {
    (*node_)[key] = Json::object();
    j = &(*node_)[key];
  }
  if (!j->is_object()) fail(key, "expected an object, got " + type_name(*j));
  return Config(st_, j, join(path_, key));
}

Config Config::required_child(const std::string& key) const {
  if (!at(key)) fail(key, "required object is missing");
  return child(key);
}

std::vector<Config> Config::children(const std::string& key) const {
  Json* j = at(key);
  std::vector<Config> out;
  if (!j) return out;
  if (!j->is_array()) fail(key, "expected an array of objects, got " + type_name(*j));
  for (std::size_t i = 0; i < j->size(); ++i) {
    auto& e = (*j)[i];
    const std::string p = join(path_, key) + "/" + std::to_string(i);
    if (!e.is_object()) throw ConfigError(p, "expected an object, got " + type_name(e));
    out.push_back(Config(st_, &e, p));
  }
  return out;
}

const Json& Config::raw(const std::string& key) const {
  Json* j = at(key);
  if (!j) fail(key, "required value is missing");
  st_->whole.insert(join(path_, key));
  return *j;
}

namespace {
void walk(const Json& node, const std::string& path, const std::map<std::string, std::set<std::string>>& read,
          const std::set<std::string>& whole) {
  if (whole.count(path)) return;
  if (node.is_object()) {
    auto it = read.find(path);
    for (auto& [k, v] : node.items()) {
      const std::string p = path + "/" + k;
      if (it == read.end() || !it->second.count(k)) {
        std::string known;
        if (it != read.end())
          for (const auto& s : it->second) known += (known.empty() ? "" : ", ") + s;
        throw ConfigError(p, "unknown key '" + k + "'" +
                                 (known.empty() ? std::string(" (this object takes no keys)")
                                                : "; known keys here: " + known));
      }
      walk(v, p, read, whole);
    }
  } else if (node.is_array()) {
    for (std::size_t i = 0; i < node.size(); ++i) walk(node[i], path + "/" + std::to_string(i), read, whole);
  }
}
}  // namespace

void Config::check_unknown() const { walk(*node_, path_, st_->read, st_->whole); }

namespace {

// Line and column (1-based) of byte `pos` of `text`.
std::string line_column(const std::string& text, std::size_t pos) {
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < pos && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(col);
}

// nlohmann's DOM builder with the JSON path of every value tracked, so that a duplicate key
// or a number overflow can be reported where it is.
class CheckingSax {
 public:
  CheckingSax(Json& result, const std::string& text, const std::string& source)
      : dom_(result, true), text_(text), source_(source) {}

  bool null() { return value(dom_.null()); }
  bool boolean(bool v) { return value(dom_.boolean(v)); }
  bool number_integer(Json::number_integer_t v) { return value(dom_.number_integer(v)); }
  bool number_unsigned(Json::number_unsigned_t v) { return value(dom_.number_unsigned(v)); }
  bool number_float(Json::number_float_t v, const std::string& s) { return value(dom_.number_float(v, s)); }
  bool string(std::string& v) { return value(dom_.string(v)); }
  bool binary(Json::binary_t& v) { return value(dom_.binary(v)); }
  bool start_object(std::size_t n) {
    frames_.push_back({true, {}, {}, 0});
    return dom_.start_object(n);
  }
  bool key(std::string& k) {
    Frame& f = frames_.back();
    if (!f.keys.insert(k).second)
      throw ConfigError(source_, path_with(k),
                        "duplicate key '" + k + "' in one object (JSON keeps only one of the values); give it once");
    f.key = k;
    return dom_.key(k);
  }
  bool end_object() {
    frames_.pop_back();
    return value(dom_.end_object());
  }
  bool start_array(std::size_t n) {
    frames_.push_back({false, {}, {}, 0});
    return dom_.start_array(n);
  }
  bool end_array() {
    frames_.pop_back();
    return value(dom_.end_array());
  }
  bool parse_error(std::size_t pos, const std::string& token, const nlohmann::detail::exception& ex) {
    const std::string where = source_ + " " + line_column(text_, pos);
    if (ex.id == 406)  // out_of_range: number overflow (e.g. 1e999)
      throw ConfigError(where, path_of_next(),
                        "number '" + token + "' is outside the range of a double; expected a finite number");
    throw ConfigError(source_, std::string("malformed JSON: ") + ex.what());
  }

 private:
  struct Frame {
    bool object;
    std::set<std::string> keys;
    std::string key;
    std::size_t index;
  };
  bool value(bool ok) {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().index;
    return ok;
  }
  std::string path() const {
    std::string p;
    for (const auto& f : frames_) p += "/" + (f.object ? f.key : std::to_string(f.index));
    return p;
  }
  std::string path_with(const std::string& k) const {
    std::string p;
    for (std::size_t i = 0; i + 1 < frames_.size(); ++i)
      p += "/" + (frames_[i].object ? frames_[i].key : std::to_string(frames_[i].index));
    return p + "/" + k;
  }
  std::string path_of_next() const {
    const std::string p = path();
    return p.empty() ? "/" : p;
  }

  nlohmann::detail::json_sax_dom_parser<Json> dom_;
  const std::string& text_;
  const std::string& source_;
  std::vector<Frame> frames_;
};

}  // namespace

Json parse_json_text(const std::string& text, const std::string& source_name) {
  Json result;
  CheckingSax sax(result, text, source_name);
  try {
    Json::sax_parse(text, &sax);
  } catch (const Json::parse_error& e) {
    throw ConfigError(source_name, std::string("malformed JSON: ") + e.what());
  } catch (const Json::exception& e) {
    throw ConfigError(source_name, std::string("unreadable JSON: ") + e.what());
  }
  return result;
}

void apply_override(Json& doc, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ConfigError("--set " + assignment, "expected path=value (e.g. engine.type=lsdem)");
  const std::string path = assignment.substr(0, eq), value = assignment.substr(eq + 1);
  std::string json_path;
  for (char ch : path) json_path += ch == '.' ? '/' : ch;
  json_path = "/" + json_path;
  Json v;
  try {
    v = Json::parse(value);
  } catch (const Json::parse_error&) {
    v = value;
  } catch (const Json::out_of_range&) {
    throw ConfigError("--set " + assignment, json_path,
                      "number '" + value + "' is outside the range of a double; expected a finite number");
  }
  if (v.is_structured()) {
    // Valid JSON: check it as a file would be (duplicate keys), paths from the --set target.
    try {
      parse_json_text(value, "--set " + assignment);
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      const std::string prefix = "--set " + assignment + ": " + e.path() + ": ";
      throw ConfigError("--set " + assignment, json_path + e.path(),
                        what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what);
    }
  }
  Json* node = &doc;
  std::string seen;
  std::size_t start = 0;
  while (true) {
    const auto dot = path.find('.', start);
    const std::string key = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (key.empty()) throw ConfigError("--set " + assignment, "empty path component");
    seen += "/" + key;
    const bool last = dot == std::string::npos;
    if (node->is_array()) {
      std::size_t idx = 0;
      try {
        idx = std::stoul(key);
      } catch (...) {
        throw ConfigError(seen, "is an array: expected a numeric index");
      }
      if (idx >= node->size()) throw ConfigError(seen, "index out of range");
      node = &(*node)[idx];
    } else {
      if (node->is_null()) *node = Json::object();
      if (!node->is_object()) throw ConfigError(seen, "cannot descend into a non-object value");
      node = &(*node)[key];
    }
    if (last) {
      *node = v;
      return;
    }
    start = dot + 1;
  }
}

}  // namespace crumble
