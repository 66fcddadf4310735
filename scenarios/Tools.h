// Helpers of the command line that belong to the composition root.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "scenarios/ScenarioFactory.h"

namespace crumble {

// series.csv, events.csv, breakage_per_mpa.csv, psd.csv, VTK, and for single-grain scenes
// the crushing figures in summary.json.
// `checkpoint_info` goes into every checkpoint.json as "run" (what the run pipeline needs on
// resume, e.g. the packing's settling figures) and comes back in Checkpoint::run_info.
void attach_standard_observers(Scenario& sc, const std::string& out_dir,
                               const nlohmann::json& checkpoint_info = nlohmann::json::object());

// `crumble shape`: volume, centroid, inertia, surface area (2D perimeter), grid, nodes of a
// shape under one representation.
nlohmann::json shape_report(const std::string& spec, const std::string& representation, double spacing,
                            long nodes);

// `crumble bench WHAT`: engine (adapter against raw library, --engine), lsdem, pd-kernel.
nlohmann::json run_benchmark(const std::string& what, long steps, int threads, const std::string& scenario,
                             const std::string& engine = "", long settle_steps = -1);

}  // namespace crumble
