// Fidelity presets: a scenario may say "fidelity": "fast" | "balanced" | "accurate", and each
// preset sets the knobs of the engine, breakage model and fragment builder the scenario uses to
// values read off the measured speed–accuracy fronts (studies/*.json, docs/speed-accuracy.md).
// A preset only fills in what the scenario leaves out: a value in the file or a --set wins.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scenarios/Methods.h"

namespace crumble {

struct FidelityKnob {
  std::string seam;            // engine | breakage | fragments
  std::string implementation;  // the registry name the preset applies to (e.g. "bullet")
  std::string path;            // dotted scenario path, as --set takes it (e.g. "engine.solver_iterations")
  nlohmann::json fast, balanced, accurate;
  std::string measured;        // what the front measured for it (one line; docs/speed-accuracy.md)
};

// "fast", "balanced", "accurate".
const std::vector<std::string>& fidelity_presets();

// Every knob of every preset, per implementation.
const std::vector<FidelityKnob>& fidelity_knobs();

// The value of `knob` under `preset` (one of fidelity_presets()).
const nlohmann::json& fidelity_value(const FidelityKnob& knob, const std::string& preset);

// Applies the preset `doc["fidelity"]` names (nothing when the key is absent): for each knob of
// the engine, breakage model and fragment builder the document selects (their defaults when it
// names none), the value is written at the knob's path unless the document already has one there.
// Call it after --set overrides are in the document and before anything reads it, so explicit
// values win. Returns "path=value" for each value it wrote. Throws ConfigError at /fidelity when
// the value is not a string or not a preset (the message lists the presets).
std::vector<std::string> apply_fidelity(nlohmann::json& doc);

// The same, reporting also the knobs of the selected implementations it left because a value
// was there: `left` those the scenario or --set gave, `left_by_method` those `method` (what
// apply_method did to the document just before) set. `governed` counts the knobs of the
// selected implementations; set + left + left_by_method is all of them.
PresetReport apply_fidelity_report(nlohmann::json& doc, const PresetReport& method);

// The presets for a person (`crumble list`): each preset's knobs per implementation.
std::string fidelity_text();

}  // namespace crumble
