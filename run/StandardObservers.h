// The observers every run attaches: the CSV writers, ParaView output, the stage table, the
// recorders of summary.json figures and the checkpoint writer, chosen by the scenario's
// output section.
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

}  // namespace crumble
