// JSON scenario → Simulation with its observers (the composition root).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/Simulation.h"
#include "scenarios/Packing.h"
#include "scenarios/Sections.h"

namespace crumble {

struct Scenario {
  std::string name;
  nlohmann::json effective;    // the scenario with every default filled in
  std::unique_ptr<Simulation> sim;
  PackingSpec packing;
  OutputSettings output;
  std::uint64_t seed = 1;
  int threads = 1;
  std::string engine_name, breakage_name, fragments_name;
  std::vector<std::string> notes;  // printed: options accepted but not used, what a method or preset set (see build_scenario)
  // The notes about one setting, printed or not (declared deliberate: core/Notes.h), for summary.json.
  std::vector<Note> setting_notes;
  // What the method ("method": name, sets, left_as_given) and the fidelity preset ("fidelity":
  // preset, sets, left_as_given, left_as_method_set, changes_nothing[, note]) did; summary.json records it.
  nlohmann::json presets = nlohmann::json::object();
};

struct BuildOptions {
  std::vector<std::string> overrides;  // --set path=value
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  std::string source_name = "scenario";
};

// Reads a scenario file (errors name the file and JSON path).
nlohmann::json load_scenario_file(const std::string& path);

// Builds everything (engine, model, builder, packing spec) and checks for unknown keys.
// Throws ConfigError for any input problem.
Scenario build_scenario(nlohmann::json doc, const BuildOptions& opt);

}  // namespace crumble
