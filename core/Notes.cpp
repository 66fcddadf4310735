#include "core/Notes.h"

#include <iostream>

#include <nlohmann/json.hpp>

#include "core/Config.h"

namespace crumble {

namespace {

// True when `path` names a value in `doc` (a JSON pointer; a malformed one names none).
bool names_a_value(const nlohmann::json& doc, const std::string& path) {
  try {
    return doc.contains(nlohmann::json::json_pointer(path));
  } catch (const nlohmann::json::exception&) {
    return false;
  }
}

// Whether setting the override path `o` changes what the declared path `p` means: its value
// or a value around it, or the `type` of a section holding it (another implementation reads it).
bool touches(const std::string& p, const std::string& o) {
  if (p == o || p.rfind(o + "/", 0) == 0 || o.rfind(p + "/", 0) == 0) return true;
  for (std::size_t cut = p.find('/', 1); cut != std::string::npos; cut = p.find('/', cut + 1))
    if (o == p.substr(0, cut) + "/type") return true;
  return false;
}

}  // namespace

DeliberateSettings read_deliberate(const nlohmann::json& doc) {
  DeliberateSettings out;
  if (!doc.is_object() || !doc.contains("deliberate")) return out;
  const nlohmann::json& d = doc["deliberate"];
  if (!d.is_object())
    throw ConfigError("/deliberate", "expected an object {\"/json/path\": \"why this setting is deliberate\"}");
  for (auto it = d.begin(); it != d.end(); ++it) {
    const std::string& path = it.key();
    if (path.empty() || path[0] != '/' || path.rfind("/deliberate", 0) == 0 || !names_a_value(doc, path))
      throw ConfigError("/deliberate", "'" + path +
                                           "' is not the JSON path of a setting of this scenario (e.g. "
                                           "\"/engine/solver_iterations\")");
    if (!it.value().is_string() || it.value().get<std::string>().empty())
      throw ConfigError("/deliberate", "'" + path + "': expected the reason, a non-empty string");
    out[path] = it.value().get<std::string>();
  }
  return out;
}

Note make_note(const DeliberateSettings& deliberate, std::string setting, std::string text) {
  const auto it = deliberate.find(setting);
  return Note{std::move(setting), std::move(text), it == deliberate.end() ? std::string() : it->second};
}

void print_note(const Note& n) {
  if (n.deliberate.empty()) std::cerr << "crumble: note: " << n.text << "\n";
}

nlohmann::json notes_json(const std::vector<Note>& notes) {
  nlohmann::json out = nlohmann::json::array();
  for (const Note& n : notes) {
    nlohmann::json j = {{"note", n.text}};
    if (!n.setting.empty()) j["setting"] = n.setting;
    if (!n.deliberate.empty()) j["deliberate"] = n.deliberate;
    out.push_back(std::move(j));
  }
  return out;
}

void apply_override_lapsing(nlohmann::json& doc, const std::string& assignment) {
  apply_override(doc, assignment);
  if (!doc.is_object() || !doc.contains("deliberate") || !doc["deliberate"].is_object()) return;
  std::string o(1, '/');  // the override's JSON path
  o += assignment.substr(0, assignment.find('='));
  for (char& c : o)
    if (c == '.') c = '/';
  nlohmann::json& d = doc["deliberate"];
  for (auto it = d.begin(); it != d.end();) it = touches(it.key(), o) ? d.erase(it) : std::next(it);
  if (d.empty()) doc.erase("deliberate");
}

}  // namespace crumble
