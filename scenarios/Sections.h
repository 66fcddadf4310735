// The scenario-level sections (top level, materials, container, packing, settle, loading,
// simulation, guards, schedule, screening, output, the scenes, walls): each section's options
// declared once in a table bound to the struct it fills (core/Options.h), so the readers
// (ScenarioFactory, Packing, Walls), `crumble list --options NAME` and the generated blocks of
// docs/scenarios.md share one default, range and meaning per key.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/Engine.h"
#include "core/Options.h"
#include "output/VtkWriter.h"

namespace crumble {

// The implementation a scenario gets when its section names none, per dimension.
struct DefaultImplementations {
  std::string engine, breakage, fragments;
};
const DefaultImplementations& default_implementations(int dimension);
const OptionTable& implementation_options();  // engine.type, breakage.type, fragments.type

// The top level ("name", "dimension", "seed", ...); "time_step" is read by hand (a number
// or a list of rules) with the default of its row.
struct ScenarioSettings {
  std::string name = "scenario";
  std::string description;
  long dimension = 3;
  std::uint64_t seed = 1;
  long threads = 1;
  Vec3 gravity{0, 0, -9.81};  // m/s²; 2D: along −y
};
const OptionTable& scenario_options();

const OptionTable& material_options();  // one entry of "materials" (core/Grain.h Material)

// "container": the box; `dimension` is set by the caller (ly is 0 in 2D).
struct ContainerSettings {
  Container box;
  long dimension = 3;
};
const OptionTable& container_options();

// "packing": what each type reads (cloud: count, sizes, fill fraction, material; grains: the
// list and whether it settles; file: the path). psd, shape and grains are read by hand.
struct PackingSettings {
  std::string type = "cloud";
  long count = 100;
  bool keep_template_size = false;
  double diameter = 0;        // m; 0 = from the psd
  double fill_fraction = 0.2;  // 2D: 0.35
  long material = 0;
  bool settle = false;  // type "grains"
  std::string path;     // type "file"
  std::string relax = "auto";  // type "file": "auto" | "on" | "off" (Packing.h, relaxation)
  long dimension = 3;   // set by the caller
};
const OptionTable& packing_options();

// One entry of packing.grains (or of a packing.json); its shape is read by hand.
struct GrainEntrySettings {
  Vec3 position;
  std::vector<double> orientation{1, 0, 0, 0};
  long material = 0;
};
const OptionTable& grain_entry_options();

// Settling is measured in simulated time so that engines with very different time steps
// (Bullet's 8e-5 s, an explicit DEM's 1e-6 s) settle the same physical way.
struct SettleSettings {
  bool enabled = true;        // a generated cloud settles before loading
  double stress = 10e3;       // Pa pushed by the platen while settling
  double max_time = 0.5;      // s of simulated time at most
  double dt = 0;              // s; 0 = the scenario's first time step (capped by the engine's bound)
  double tolerance = 1e-3;    // platen travel per window, relative to the mean diameter
  double window = 0.01;       // s between checks
  double friction_scale = 1;  // friction × this while settling (0: frictionless, a denser packing)
  double global_damping_scale = 1;  // engine.global_damping × this while settling
};
const OptionTable& settle_options();  // packing.settle
// Of packing.settle, what a file packing's relaxation reads (it is not settled again, so
// enabled and the friction and global-damping scales are not among them); also what
// effective_scenario.json keeps, which must run again as it is.
const OptionTable& relax_options();

const OptionTable& loading_options();     // core/Loading.h LoadingSettings
const OptionTable& simulation_options();  // core/Simulation.h SimulationSettings (but time_steps, threads, guards)
const OptionTable& guard_options();       // simulation.guards (core/Guards.h)
const OptionTable& schedule_options();    // core/Schedule.h; the defaults are the breakage model's

struct OutputSettings : VtkOutputSettings {
  long series_every = 0;              // steps between series rows (0 = simulation.sample_every)
  std::vector<double> psd_at_stress;  // Pa: PSD tables written when the stress first passes these
  std::vector<double> psd_at_strain;  // axial strains: PSD tables written when the strain first passes these
  bool shape_metrics = true;          // shape.csv (means of the grains' shape descriptors per sample)
  bool intact_analyses = true;        // events.csv rows for analyses that left their grain whole
  long checkpoint_every = 0;          // steps between checkpoint.json writes (0 = none)
  bool plots = true;                  // PNG figures at the end of `crumble run` (output/Plots.h)
  // Wall-time seconds between checkpoint.json writes (0 = none): a run killed after hours
  // loses minutes. Scenes with moving walls or a feed cannot be checkpointed: 0 there.
  double checkpoint_every_s = 300;
  long psd_layers = 0;  // psd_layers.csv: sieve curves per layer of the initial packing (0 = none)
};
const OptionTable& output_options();

// "scene" of type single_grain (the type is read here for both scenes).
struct SceneSettings {
  std::string type = "single_grain";
  double diameter = 2e-3;  // m
  long material = 0;
  double platen_mass = 0;  // kg; 0 = the grain's mass
};
const OptionTable& scene_options();

// "scene" of type jaw_crusher: Harmon et al. 2020 Table 1 (after Johansson et al. 2017).
struct JawCrusherSettings {
  double css = 0.05;                   // m, closed side setting
  double throw_ = 0.05;                // m, OSS − CSS
  double rpm = 300;
  double nip_angle = 22;               // degrees
  double nip_angle_variation = 1.7;    // degrees
  double cycles = 40;
  double plate_thickness = 0.1;        // m
  double plate_level_set_spacing = 0.007;  // m
  double phase = 0;                    // rad
  double hopper_height = 1.5;          // m; 0 = none
  double discharge_depth = 0.2;        // m
};
const OptionTable& jaw_crusher_options();

// scene.rocks of the jaw crusher (Harmon et al. 2020 §4.1, Table 1).
struct RockFeedSettings {
  long count = 40;
  std::vector<double> diameter{0.15, 0.25};  // m, [d_min, d_max]
  double level_set_spacing = 0.007;           // m
  double surface_points_per_cell = 2;
  long material = 0;
  double spawn_height = 0.3;  // m
};
const OptionTable& rock_options();

// One entry of "walls" (its shape is read by hand) and its "motion" (core/MovingWall.h).
struct WallSettings {
  std::string name;  // default "wall_INDEX", set by the caller
  Vec3 position;
  std::vector<double> orientation{1, 0, 0, 0};
};
const OptionTable& wall_options();
const OptionTable& motion_options();

// Every table above with its section's name (for `crumble list --options NAME` and the
// generated blocks of docs/scenarios.md).
struct SectionOptions {
  std::string name, description;
  const OptionTable* options;
};
std::vector<SectionOptions> scenario_sections();

}  // namespace crumble
