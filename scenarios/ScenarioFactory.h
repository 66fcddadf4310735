// JSON scenario → Simulation with its observers (the composition root).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/Simulation.h"
#include "scenarios/Packing.h"

namespace crumble {

// output.checkpoint_every_s when the scenario does not say (s of wall time).
inline constexpr double kDefaultCheckpointSeconds = 300;

struct OutputSettings {
  long series_every = 0;                 // steps between series rows (0 = simulation.sample_every)
  std::vector<double> psd_at_stress;     // Pa: PSD tables written when the stress first passes these
  std::vector<double> psd_at_strain;     // axial strains: PSD tables written when the strain first passes these
  bool shape_metrics = true;             // shape.csv (means of the grains' shape descriptors per sample)
  bool intact_analyses = true;           // events.csv rows for analyses that left their grain whole
  long vtk_every = 0;                    // steps between VTK snapshots (0 = none)
  bool vtk_final = true;                 // write the final state as VTK
  bool vtk_contacts = false;             // contact-force lines in each VTK snapshot
  bool vtk_analyses = false;             // per-point data of breakage analyses (vtk/analysis_*.vtp)
  long checkpoint_every = 0;             // steps between checkpoint.json writes (0 = none)
  bool plots = true;                     // PNG figures at the end of `crumble run` (output/Plots.h)
  double checkpoint_every_s = 0;         // wall-time seconds between checkpoint.json writes (0 = none)
  long psd_layers = 0;                   // psd_layers.csv: sieve curves per layer of the initial packing (0 = none)
};

struct Scenario {
  std::string name;
  nlohmann::json effective;    // the scenario with every default filled in
  std::unique_ptr<Simulation> sim;
  PackingSpec packing;
  OutputSettings output;
  std::uint64_t seed = 1;
  int threads = 1;
  std::string engine_name, breakage_name, fragments_name;
  std::vector<std::string> notes;  // options accepted but not used (see build_scenario)
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
