// Packings are data: generated (a cloud drawn from a PSD, pushed down by the platen until
// stable, Zhu & Zhao 2019 §5), listed explicitly, or loaded from a packing.json written by an
// earlier run, so different engines and models start from the identical packing.
#pragma once
#include <atomic>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "core/Simulation.h"
#include "scenarios/Sections.h"

namespace crumble {

struct PsdPoint {
  double diameter;  // m
  double passing;   // fraction by mass in [0, 1]
};

// Draw `count` equivalent diameters whose mass distribution follows the PSD (number
// density within each bin ∝ mass fraction / d³, uniform in d inside a bin).
std::vector<double> sample_psd(const std::vector<PsdPoint>& psd, std::size_t count, Rng& rng);

struct PlacedGrain {
  Shape::Ptr shape;
  nlohmann::json shape_spec;  // to save the packing
  Vec3 position;
  Quat orientation;
  int material = 0;
  std::string source;  // JSON path of the entry it came from (errors: source + "/material")
};

struct PackingSpec {
  std::string type;  // "cloud" | "grains" | "file"
  std::vector<PlacedGrain> grains;
  bool settle = false;
  SettleSettings settle_settings;
  Container container;
  // Moving walls (top-level "walls" and those a scene builds), rocks fed during the run and
  // the run's length a scene fixes (s; 0 = the loading decides), figures for summary.json.
  std::vector<MovingWall> walls;
  FeedSettings feed;
  double duration = 0;
  std::map<std::string, double> scene_figures;
  // A file packing: the engine that built it (packing.json's "engine"; empty in files written
  // before 0.2.0) and packing.relax. Relaxing is settling (settle_packing) on this scenario's
  // engine; decide_relaxation sets `settle` once the engine is known.
  std::string built_by;
  std::string relax = "off";
};


// Reads the "packing" and "container" objects; for "cloud" draws the grains now.
PackingSpec packing_from_config(const Config& packing, const Config& container, int dimension, Rng& rng);

// The unit quaternion of `q` (read at `key` of `c`; the errors name it): [w, x, y, z], not zero.
Quat quaternion_from(const Config& c, const std::string& key, const std::vector<double>& q);

// The shape spec of a template (JSON) scaled by `factor`.
nlohmann::json scaled_spec(const nlohmann::json& tmpl, double factor);

struct SettleResult {
  long steps = 0;
  bool interrupted = false;  // `stop` was raised before the packing was stable
  bool converged = true;     // false: settle.max_time ran out before the platen came to rest
  double stress_first = 0, stress_max = 0;  // Pa (SettleProgress)
};

// A file packing relaxes (spec.settle) when packing.relax is "on", or "auto" and packing.json
// was built by another engine than `engine`. Nothing for other packing types.
void decide_relaxation(PackingSpec& spec, const std::string& engine);

// What relaxing a file packing did, after settle_packing returned `r` for it: the engine that
// built the packing, steps, the platen stress after the first step, its largest value and at
// the end (Pa), how far the grains moved from the file's positions (m, largest and mean), and
// the void ratio of the file and after.
nlohmann::json relaxation_report(const Simulation& sim, const PackingSpec& spec, const SettleResult& r);

// What the run pipeline adds to a settling: a stop flag (a signal), where to go on from
// (a checkpoint's progress; the grains are already in the simulation), and a call after
// every step, and once more when `stop` ends the settling (`stopping` true), with the engine
// as the next step would find it (checkpoints).
struct SettleControl {
  const std::atomic<bool>* stop = nullptr;
  std::optional<SettleProgress> from;
  std::function<void(const SettleProgress&, bool stopping)> after_step;
};

// The container, the moving walls, the feed and (`add_grains`) the grains of the packing
// put into the simulation.
void place_packing(Simulation& sim, const PackingSpec& spec, bool add_grains = true);

// For generated clouds: pushes the platen down until the packing is stable (the initial
// state of the run). `ctl.stop` ends the settling early; the result says so, and such a
// packing is not a valid start of a run (a checkpoint of it is: SettleControl).
// The settling's friction and global-damping scales (packing.settle) set on the engine; a
// ConfigError naming the option when the engine cannot scale it. reset: both back to 1.
void apply_settle_scales(Engine& e, const SettleSettings& ss);
void reset_settle_scales(Engine& e);

SettleResult settle_packing(Simulation& sim, const PackingSpec& spec, const SettleControl& ctl = {});

// place_packing, then settle_packing.
SettleResult build_packing(Simulation& sim, const PackingSpec& spec, const std::atomic<bool>* stop = nullptr);

// packing.json of the current grains (shape specs, poses) for reuse by another scenario.
nlohmann::json packing_to_json(const Simulation& sim, const PackingSpec& spec);

}  // namespace crumble
