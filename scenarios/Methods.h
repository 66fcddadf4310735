// Named methods: a scenario may say "method": "zhu_zhao_2019" | "harmon_2020" (or a name a
// plugin registers), and the method sets the engine, breakage model, fragment builder,
// screening and time-step schedule the paper uses. Like a fidelity preset (Fidelity.h) a
// method only fills in what the scenario leaves out: a value in the file or a --set wins.
// It is applied after --set and before the fidelity preset, so the preset sees the engine and
// breakage model the method selects, and a key the method sets is left alone by the preset.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace crumble {

struct MethodSetting {
  std::string path;  // dotted scenario path, as --set takes it (e.g. "engine.type", "time_step")
  nlohmann::json value;
  std::string source;  // where the value comes from, for a person (e.g. "Zhu & Zhao 2019 §5")
};

struct Method {
  std::string name;
  std::string description;
  std::vector<MethodSetting> settings;
};

class MethodTable {
 public:
  // Throws std::invalid_argument for an empty or duplicate name or an empty path component.
  void add(Method m);
  // nullptr when `name` is not registered.
  const Method* find(const std::string& name) const;
  const std::vector<Method>& entries() const { return entries_; }
  std::string names() const;

 private:
  std::vector<Method> entries_;
};

// The built-in methods ("zhu_zhao_2019", "harmon_2020") and those plugins add.
MethodTable& methods();

// What a method or a fidelity preset did to a scenario.
struct PresetReport {
  std::string name;                         // the method or preset; empty when none is selected
  std::vector<std::string> set;             // "path=value" for each value it wrote
  std::vector<std::string> left;            // paths it governs that the scenario or --set already gave
  std::vector<std::string> left_by_method;  // (fidelity) paths the method had already set
  int governed = 0;                         // paths it governs for the selected implementations
};

// Writes `value` at the dotted `path` of `doc` unless a value is already there (or a non-object
// sits on the way, which the scenario factory reports). True when it wrote.
bool fill_missing(nlohmann::json& doc, const std::string& path, const nlohmann::json& value);

// Applies the method `doc["method"]` names (nothing when the key is absent). Call it after
// --set overrides are in the document and before anything reads it. Throws ConfigError at
// /method when the value is not a string or not a registered method (the message lists them).
PresetReport apply_method(nlohmann::json& doc);

// The methods for a person (`crumble list`): each method's settings and their sources.
std::string methods_text();

}  // namespace crumble
