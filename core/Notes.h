// Notes of a run: what it tells about one setting of the scenario that the user may want to
// act on (an option the chosen engine ignores, a contact solver that stops at its iteration
// limit). A scenario file may declare settings deliberate, with a reason:
//   "deliberate": {"/engine/solver_iterations": "300 iterations for speed; ..."}
// A note about a declared setting is not printed on stderr; summary.json keeps it, with the
// reason. A --set that touches a declared setting (its value, a section holding it or the
// `type` of such a section) lapses the declaration: the file's reason no longer applies.
#pragma once
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace crumble {

using DeliberateSettings = std::map<std::string, std::string>;  // JSON path -> the file's reason

struct Note {
  std::string setting;     // JSON path of the setting it is about ("/engine/kn"); empty: none
  std::string text;        // what stderr shows after "crumble: note: "
  std::string deliberate;  // the scenario's reason when it declares `setting` deliberate
};

// The scenario's "deliberate" object, checked: each key a JSON path ("/engine/kn") of a value
// the scenario sets, each reason a non-empty string; errors name /deliberate. Empty without it.
DeliberateSettings read_deliberate(const nlohmann::json& doc);

// The note, with the scenario's reason when it declares `setting` deliberate.
Note make_note(const DeliberateSettings& deliberate, std::string setting, std::string text);

// "crumble: note: TEXT" on stderr, unless the note's setting is declared deliberate.
void print_note(const Note& n);

// summary.json's notes: [{"note": text, "setting": path, "deliberate": reason}], "setting"
// when known and "deliberate" when declared.
nlohmann::json notes_json(const std::vector<Note>& notes);

// apply_override (core/Config.h) of a --set `assignment` ("engine.type=lsdem"), then the
// declarations it touches dropped from the document's "deliberate".
void apply_override_lapsing(nlohmann::json& doc, const std::string& assignment);

}  // namespace crumble
