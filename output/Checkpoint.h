// Checkpoints of long runs (checkpoint.json in the output directory) and resuming from them
// (`crumble run SCENARIO --out DIR --resume`). A checkpoint holds the loop's state (with an
// open scene's feed count and the product collected so far), every grain (shape, pose,
// velocities, strength, lineage) and, when the engine can save it (Engine::save_state:
// lsdem), the engine's own state (contact history, half-step velocities, platen and moving
// walls' motion), so that a resumed lsdem run is bit-identical to an
// uninterrupted one. Other engines are rebuilt from the grains: their contact history and
// solver warm starts begin afresh at the resume point (docs/scenarios.md, output). A
// checkpoint written while the packing settles also holds where the settling stands.
#pragma once
#include <chrono>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "core/Observer.h"
#include "core/Simulation.h"

namespace crumble {

// A shape as scenario JSON (analytic parameters, the closed mesh / polygon, or the
// level-set grid with its surface nodes).
nlohmann::json shape_to_json(const Shape& s);
// shape_to_json plus the figures the run computed ("saved": mass properties, bounds,
// recentring), so that shape_from_saved_config gives back a shape that computes with the
// same numbers, bit for bit (checkpoints; shapes sent to other MPI ranks, parallel/).
nlohmann::json shape_saved_json(const Shape& s);
// Reads shape_saved_json's object (or a plain shape object); errors name the JSON path.
Shape::Ptr shape_from_saved_config(const Config& sc, int dimension);

// `run_info`: the run pipeline's own figures, stored as "run" (omitted when empty).
// `settling`: written while the packing settles (before the loading began), where the
// settling stands ("settling"; absent once the loading runs).
nlohmann::json checkpoint_json(Simulation& sim, const std::string& scenario_name,
                               const nlohmann::json& run_info = nlohmann::json::object(),
                               const SettleProgress* settling = nullptr);

struct Checkpoint {
  SimulationState state;
  std::vector<Grain> grains;
  nlohmann::json engine_state;  // null when the engine saved none
  nlohmann::json run_info = nlohmann::json::object();  // checkpoint_json's run_info
  std::optional<SettleProgress> settling;  // a checkpoint of the settling, not of the loading
};
// Restores the engine part of a checkpoint into an engine holding its grains; errors name
// `path`/engine_state (ConfigError). Does nothing for a checkpoint without one.
void restore_engine_state(Engine& engine, const Checkpoint& cp, const std::string& path);
// Reads DIR/checkpoint.json; errors name the file and what is wrong.
Checkpoint read_checkpoint(const std::string& path, const std::string& scenario_name, int dimension);

// Writes checkpoint.json (atomically: temporary file + rename) at the first series sample
// `every` steps or `every_s` seconds of wall time after the last one (0 = not by that
// measure), and at the end of the run. Attach it after the CSV writers: they flush a
// sample's rows before it runs, so a run killed at any moment leaves CSV rows up to (at
// least) the checkpoint's step and a resume keeps exactly those.
class CheckpointWriter : public Observer {
 public:
  std::string name() const override { return "checkpoint"; }
  CheckpointWriter(std::string dir, std::string scenario, long every, double every_s = 0,
                   nlohmann::json run_info = nlohmann::json::object());
  void on_start(const Simulation& sim, const RunState& s) override;
  void on_sample(const Simulation& sim, const RunState& s) override;
  void on_finish(const Simulation& sim, const RunState& s, RunSummary&) override;

 private:
  void write(const Simulation& sim);
  std::string dir_, scenario_;
  long every_;
  double every_s_;
  nlohmann::json info_;
  long last_ = 0;
  std::chrono::steady_clock::time_point last_time_;
};

}  // namespace crumble
