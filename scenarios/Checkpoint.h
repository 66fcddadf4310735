// Checkpoints of long runs (checkpoint.json in the output directory) and resuming from them
// (`crumble run SCENARIO --out DIR --resume`). A checkpoint holds the loop's state and every
// grain (shape, pose, velocities, strength, lineage); the engine is rebuilt from it, so
// contact history and solver warm starts begin afresh at the resume point.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "core/Observer.h"
#include "core/Simulation.h"

namespace crumble {

// A shape as scenario JSON (analytic parameters, the closed mesh / polygon, or the
// level-set grid with its surface nodes).
nlohmann::json shape_to_json(const Shape& s);

nlohmann::json checkpoint_json(Simulation& sim, const std::string& scenario_name);

struct Checkpoint {
  SimulationState state;
  std::vector<Grain> grains;
};
// Reads DIR/checkpoint.json; errors name the file and what is wrong.
Checkpoint read_checkpoint(const std::string& path, const std::string& scenario_name, int dimension);

// Writes checkpoint.json every `every` steps (atomically) and at the end of the run.
class CheckpointWriter : public Observer {
 public:
  CheckpointWriter(std::string dir, std::string scenario, long every)
      : dir_(std::move(dir)), scenario_(std::move(scenario)), every_(every) {}
  void on_start(const Simulation& sim, const RunState& s) override { last_ = s.step; }
  void on_sample(const Simulation& sim, const RunState& s) override;
  void on_finish(const Simulation& sim, const RunState& s, RunSummary&) override;

 private:
  std::string dir_, scenario_;
  long every_;
  long last_ = 0;
};

}  // namespace crumble
