#include "tools/Bench.h"

#include "scenarios/ScenarioFactory.h"

#include <cmath>
#include <fstream>
#include <map>
#include <iomanip>
#include <sstream>

#include <chrono>
#include <cstdlib>
#include <ctime>

#include "crumble_config.h"

#include "backends/lsdem/LsdemEngine.h"
#if CRUMBLE_WITH_BULLET
#include "backends/bullet/BulletEngine.h"
#include "tools/RawBulletBench.h"
#endif
#if CRUMBLE_WITH_ODE
#include "backends/ode/OdeEngine.h"
#include "tools/RawOdeBench.h"
#endif
#include "core/RawScene.h"
#include "breakage/peridynamics/Peridynamics.h"
#include "core/Measures.h"
#include "scenarios/Packing.h"
#include "geometry/ConvexHull.h"
#include "base/Format.h"
#include "geometry/LevelSetGrid.h"
#include "output/Checkpoint.h"
#include "tools/Compare.h"
#include "scenarios/Registry.h"
#include "core/ShapeSpec.h"
#include "output/VtkWriter.h"
#include "tools/Stages.h"
#include "output/LayerOutputs.h"
#include "output/Writers.h"


namespace crumble {

using Json = nlohmann::json;

namespace {

Json phase_json(const LsdemBenchResult& r) {
  return {{"steps", r.steps},
          {"wall_seconds", r.seconds},
          {"cpu_seconds", r.cpu_seconds},
          {"ms_per_step", r.ms_per_step},
          {"cpu_ms_per_step", r.cpu_ms_per_step},
          {"steps_per_second", r.steps_per_second},
          {"node_queries_per_second", r.node_queries_per_second},
          {"bbox_overlaps_per_step", r.mean_bbox_overlaps},
          {"contact_pairs_per_step", r.mean_contact_pairs},
          {"node_queries_per_step", r.mean_node_queries}};
}


// The loop phase of `bench engine` and `bench lsdem`: the same engine, from where the timed
// adapter steps left it, stepped `steps` times by the simulation's own loop (Simulation::run:
// the state read-out and scalar checks of every step, the guards of every sample; no
// observers, no output). The benchmarks replace the scenario's loading by "none" (platen held
// still, as in the adapter phase), so the two phases step the same scene. Its wall time per step against
// the adapter's is the loop overhead (goal: <= 10 % on every engine). The run's
// breakage checks are timed apart (they are the model's work, not the loop's).
Json loop_phase(Simulation& sim, long steps, double dt, double adapter_ms_per_step) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  RunSummary s;
  sim.set_time_step(dt);
  try {
    s = sim.run();
  } catch (const std::exception& e) {
    return Json{{"error", e.what()}};
  }
  const double wall = std::chrono::duration<double>(clock::now() - t0).count();
  const Timings& t = s.timings;
  const double breakage = t.contacts + t.screening + t.analyses + t.fragments;
  const double n = static_cast<double>(std::max(1L, s.steps));
  // The adapter again, after the loop, from where the loop left the scene: a scene that
  // slows down or speeds up as it settles falls on both sides of the loop phase alike.
  Engine& eng = sim.engine();
  const auto a0 = clock::now();
  for (long k = 0; k < s.steps; ++k) eng.step(dt);
  const double after_ms = 1e3 * std::chrono::duration<double>(clock::now() - a0).count() / n;
  const double adapter_ms = 0.5 * (adapter_ms_per_step + after_ms);
  Json j;
  j["steps"] = s.steps;
  j["ms_per_step"] = 1e3 * (wall - breakage) / n;
  j["engine_ms_per_step"] = 1e3 * t.engine / n;
  j["loop_ms_per_step"] = 1e3 * t.loop / n;
  j["guards_ms_per_step"] = 1e3 * t.guards / n;
  j["breakage_checks_s"] = breakage;
  j["adapter_after_ms_per_step"] = after_ms;
  j["loop_overhead_vs_adapter"] = adapter_ms > 0 ? 1e3 * (wall - breakage) / n / adapter_ms - 1 : 0.0;
  j["loop_overhead_vs_engine_in_loop"] = t.engine > 0 ? (t.loop + t.guards + t.observers) / t.engine : 0.0;
  if (s.steps < steps) j["note"] = "the scenario's loading ended after " + std::to_string(s.steps) + " steps";
  return j;
}

// `crumble bench lsdem --scenario F`: the loose phase (grains falling) and the settled
// packing of the scenario's scene, each over `steps` steps. YADE 2023.02a on the same scene
// was measured once on this kind of machine (scripts/bench-lsdem-vs-yade.sh, docs/performance.md):
// ≈ 12 ms/step loose, ≈ 82 ms/step settled at ≈ 2500 bounding-box overlaps.
Json bench_lsdem(long steps, int threads, const std::string& file) {
  if (file.empty()) throw ConfigError("--scenario", "bench lsdem needs --scenario (e.g. scenarios/lsdem_discharge.json)");
  BuildOptions opt;
  opt.threads = threads;
  opt.source_name = file;
  Json doc = load_scenario_file(file);
  doc["simulation"]["max_steps"] = steps;  // the loop phase: `steps` steps of Simulation::run,
  doc["loading"] = Json{{"mode", "none"}};  // with the platen held still as in the adapter phase
  Scenario sc = build_scenario(doc, opt);
  auto* eng = dynamic_cast<LsdemEngine*>(&sc.sim->engine());
  if (!eng) throw ConfigError(file + ": /engine/type", "bench lsdem needs an lsdem scenario");
  sc.packing.settle = false;
  build_packing(*sc.sim, sc.packing);
  const double dt = std::min(sc.sim->settings().time_steps.front().dt, eng->max_stable_dt());
  const LsdemBenchResult loose = lsdem_bench_phase(*eng, steps, dt);
  // Let the grains land and come to rest: until the kinetic energy per grain is below
  // 1e-6 of m g d of the mean grain, or the scenario's simulated duration.
  const auto& gs = sc.sim->grains();
  double md = 0, dmean = 0;
  for (const auto& g : gs) {
    md += g.mass(sc.sim->context().materials[g.material].density);
    dmean += g.shape->equivalent_diameter();
  }
  dmean /= gs.size();
  const double ke_rest = 1e-6 * md * 9.81 * dmean;
  const double t_max = sc.sim->loading().settings().duration > 0 ? sc.sim->loading().settings().duration : 1.0;
  long settle_steps = 0;
  for (double t = 0; t < t_max; t += dt, ++settle_steps) {
    eng->step(dt);
    if (settle_steps % 1000 == 999 && eng->kinetic_energy() < ke_rest) break;
  }
  const LsdemBenchResult settled = lsdem_bench_phase(*eng, steps, dt);
  Json j;
  j["benchmark"] = "lsdem";
  j["scenario"] = file;
  j["grains"] = gs.size();
  j["threads"] = threads;
  j["dt_s"] = dt;
  j["settle_steps"] = settle_steps;
  j["kinetic_energy_J"] = eng->kinetic_energy();
  j["loose"] = phase_json(loose);
  j["settled"] = phase_json(settled);
  j["yade_reference_ms_per_step"] = {{"loose", 12.0}, {"settled", 82.0}};
  j["speedup_vs_yade_reference"] = {{"loose", 12.0 / loose.ms_per_step}, {"settled", 82.0 / settled.ms_per_step}};
  j["loop"] = loop_phase(*sc.sim, steps, dt, settled.ms_per_step);
  return j;
}


// The grains of a simulation as library-neutral rigid bodies (SI), for the raw baselines.
RawScene raw_scene_of(const Simulation& sim, const Container& box, double dt) {
  RawScene r;
  const auto& mats = sim.context().materials;
  for (const Grain& g : sim.grains()) {
    const Material& m = mats[g.material];
    const MassProperties& mp = g.shape->mass_properties();
    RawBody b;
    b.hull = g.shape->convex_hull();
    b.hull.translate(Vec3{} - mp.centroid);
    b.mass = m.density * mp.volume;
    b.inertia = mp.inertia * m.density;
    const Quat q = g.orientation.normalized();
    b.com = g.position + q.rotate(mp.centroid);
    b.orientation = q;
    b.velocity = g.velocity;
    b.angular_velocity = g.angular_velocity;
    b.diameter = g.shape->equivalent_diameter();
    b.friction = m.friction;
    b.rolling_friction = m.rolling_friction;
    r.bodies.push_back(std::move(b));
  }
  r.lx = box.lx;
  r.ly = box.ly;
  r.platen_z = sim.engine().platen_position();
  r.wall_friction = mats.empty() ? 0 : mats.front().wall_friction;
  r.gravity = sim.context().gravity;
  r.dt = dt;
  return r;
}

// The scenario of `bench engine`: on engine E (Bullet with its tolerance exit off), the
// loop phase `steps` steps of Simulation::run with the platen held still as in the adapter
// phase.
Scenario bench_scenario(const std::string& engine, const std::string& file, long steps, int threads) {
  Json doc = load_scenario_file(file);
  if (!doc.contains("engine") || !doc["engine"].is_object()) doc["engine"] = Json::object();
  doc["engine"]["type"] = engine;
  if (engine == "bullet") {
    doc["engine"]["solver_tolerance"] = 0;
    doc["engine"]["solver_residual"] = 0;
  }
  doc["simulation"]["max_steps"] = steps;
  doc["loading"] = Json{{"mode", "none"}};
  BuildOptions opt;
  opt.threads = threads;
  opt.source_name = file;
  Scenario sc = build_scenario(doc, opt);
  if (sc.sim->context().dimension != 3 && engine != "lsdem")
    throw ConfigError(file + ": /dimension", "bench engine compares 3D scenes");
  return sc;
}

// The grains leave the engine and enter it again where they are, at their velocities: the
// adapter's world then starts, as the raw world does, without the contact points and impulses
// of the settling (Bullet's manifolds hold up to 4 points each, gathered one per step while
// the grains moved; a new world starts with none and a resting packing gathers few). Bullet
// only: ODE keeps no contacts between steps.
#if CRUMBLE_WITH_BULLET
void restart_contacts(Engine& eng, const std::vector<Grain>& grains) {
  for (const Grain& g : grains) eng.remove_grain(g.id);
  for (const Grain& g : grains) eng.add_grain(g);
}
#endif

// The raw library's world for a bullet or ode adapter (null for lsdem), with the adapter's
// solver settings and length scale.
std::unique_ptr<RawWorld> raw_world_for(Engine& eng, const Scenario& sc, RawScene& raw) {
  std::unique_ptr<RawWorld> raw_world;
  Json engine_section = sc.effective["engine"];
  const Config engine_cfg(engine_section);
  // The solver settings both rigid-body adapters share, read from the adapter's own options.
  auto shared_settings = [&](const auto& o, double length_scale) {
    raw.solver_iterations = o.solver_iterations;
    raw.erp = o.erp;
    raw.mass_scale = o.mass_scale;
    raw.length_scale = length_scale;
  };
#if CRUMBLE_WITH_BULLET
  if (auto* b = dynamic_cast<BulletEngine*>(&eng)) {
    const auto o = BulletEngine::read_options(engine_cfg);
    shared_settings(o, b->length_scale());
    raw.margin_fraction = o.margin_fraction;
    restart_contacts(eng, sc.sim->grains());
    raw_world = make_raw_bullet_world(raw);
  }
#endif
#if CRUMBLE_WITH_ODE
  if (auto* e = dynamic_cast<OdeEngine*>(&eng)) {
    const auto o = OdeEngine::read_options(engine_cfg);
    shared_settings(o, e->length_scale());
    raw.contacts_per_pair = o.contacts_per_pair;
    raw_world = make_raw_ode_world(raw);
  }
#endif
  return raw_world;
}

// Wall time (s) of the adapter's steps, of its read-out and of the raw world's steps, and
// the contacts each counted, over `steps` alternate steps.
struct StepTimes {
  double step = 0, read = 0, raw = 0, contacts = 0, raw_contacts = 0;
  std::map<std::string, double> work, raw_work;  // contact work summed over the steps (untimed)
};

// The contact work of the adapter's last step (Bullet: backends/bullet/BulletWorldReport.h);
// empty for an engine that does not report it.
std::map<std::string, double> adapter_contact_work([[maybe_unused]] const Engine& eng) {
#if CRUMBLE_WITH_BULLET
  if (auto* b = dynamic_cast<const BulletEngine*>(&eng)) return b->contact_work();
#endif
  return {};
}

std::map<std::string, double> adapter_settings([[maybe_unused]] const Engine& eng) {
#if CRUMBLE_WITH_BULLET
  if (auto* b = dynamic_cast<const BulletEngine*>(&eng)) return b->world_settings();
#endif
  return {};
}

void add_to(std::map<std::string, double>& sum, const std::map<std::string, double>& v) {
  for (const auto& [k, x] : v) sum[k] += x;
}

Json per_step(const std::map<std::string, double>& sum, long steps) {
  Json j = Json::object();
  for (const auto& [k, x] : sum) j[k] = x / static_cast<double>(steps);
  return j;
}

// The settings in which the two worlds differ, by name (relative tolerance 1e-9).
Json settings_differences(const std::map<std::string, double>& a, const std::map<std::string, double>& b) {
  Json d = Json::array();
  std::map<std::string, std::pair<double, double>> both;
  for (const auto& [k, x] : a) both[k] = {x, b.count(k) ? b.at(k) : std::nan("")};
  for (const auto& [k, x] : b)
    if (!a.count(k)) both[k] = {std::nan(""), x};
  for (const auto& [k, v] : both)
    if (!(std::abs(v.first - v.second) <= 1e-9 * std::max(std::abs(v.first), std::abs(v.second))))
      d.push_back(k);
  return d;
}

StepTimes time_steps(Engine& eng, RawWorld* raw_world, std::vector<Grain>& grains, long steps, double dt) {
  using clock = std::chrono::steady_clock;
  auto seconds = [](clock::time_point a, clock::time_point b) { return std::chrono::duration<double>(b - a).count(); };
  StepTimes t;
  for (long k = 0; k < steps; ++k) {
    const auto a = clock::now();
    eng.step(dt);
    const auto b = clock::now();
    eng.read_state(grains);
    t.contacts += static_cast<double>(eng.contacts().size());
    const auto c = clock::now();
    t.step += seconds(a, b);
    t.read += seconds(b, c);
    add_to(t.work, adapter_contact_work(eng));
    if (raw_world) {
      const auto d = clock::now();
      raw_world->step();
      t.raw += seconds(d, clock::now());
      t.raw_contacts += raw_world->contact_pairs();
      add_to(t.raw_work, raw_world->contact_work());
    }
  }
  return t;
}

// `crumble bench engine --engine E [--scenario F]`: the scenario's packing (placed, not
// settled) on engine E; `settle` steps let the grains fall into contact, then `steps` steps
// are timed through the adapter (Engine::step, and separately the read-out the Simulation
// does: read_state + contacts) and, for bullet and ode, through the raw library on the same
// bodies from the same state (RawBulletBench / RawOdeBench). The adapter runs with the raw
// baseline's solver settings (fixed iterations: Bullet's tolerance exit off; ODE the
// scenario's contact points per pair in both), so both do the same solver work. Then the
// same number of steps through the simulation's loop (loop_phase).
Json bench_engine(const std::string& engine, long steps, long settle, int threads, const std::string& file_in) {
  const std::string file = file_in.empty() ? "scenarios/oedometer_rigid_quick.json" : file_in;
  Scenario sc = bench_scenario(engine, file, steps, threads);
  // settle < 0: the scenario's own packing procedure (settled under the platen, as `run`
  // does); otherwise the grains are placed and fall for `settle` steps.
  if (settle >= 0) sc.packing.settle = false;
  const auto t_settle = std::chrono::steady_clock::now();
  build_packing(*sc.sim, sc.packing);
  Engine& eng = sc.sim->engine();
  const double dt = std::min(sc.sim->settings().time_steps.front().dt, eng.max_stable_dt());
  eng.set_platen(PlatenCommand{});
  for (long k = 0; k < settle; ++k) eng.step(dt);
  const double settle_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_settle).count();
  sc.sim->sync_grains();
  RawScene raw = raw_scene_of(*sc.sim, sc.sim->container(), dt);
  // The raw world starts from this state; the two are stepped alternately, so the machine's
  // load falls on both alike.
  const std::unique_ptr<RawWorld> raw_world = raw_world_for(eng, sc, raw);
  std::vector<Grain> grains = sc.sim->grains();
  double load[3] = {0, 0, 0}, load_after[3] = {0, 0, 0};
  getloadavg(load, 3);
  const StepTimes t = time_steps(eng, raw_world.get(), grains, steps, dt);
  getloadavg(load_after, 3);
  Json j;
  j["benchmark"] = "engine";
  j["engine"] = engine;
  j["scenario"] = file;
  j["grains"] = sc.sim->grains().size();
  j["threads"] = threads;
  j["dt_s"] = dt;
  j["settle"] = settle < 0 ? Json("scenario packing procedure") : Json(settle);
  j["settle_wall_s"] = settle_s;
  j["steps"] = steps;
  j["load_average_1min"] = {{"before", load[0]}, {"after", load_after[0]}};
  j["adapter"] = {{"ms_per_step", 1e3 * t.step / steps},
                  {"readout_ms_per_step", 1e3 * t.read / steps},
                  {"contacts_per_step", t.contacts / steps},
                  {"contact_work_per_step", per_step(t.work, steps)}};
  if (raw_world) {
    const double raw_ms = 1e3 * t.raw / steps;
    j["raw"] = {{"ms_per_step", raw_ms},
                {"contacts_per_step", t.raw_contacts / steps},
                {"contact_work_per_step", per_step(t.raw_work, steps)}};
    // What each world was set up to do, and where the two differ (a like-for-like comparison
    // has no difference but the ones the bench names: docs/performance.md).
    const auto a = adapter_settings(eng), r = raw_world->settings();
    j["settings"] = {{"adapter", a}, {"raw", r}, {"differences", settings_differences(a, r)}};
    j["adapter_overhead"] = t.step / t.raw - 1;
    j["adapter_overhead_with_readout"] = (t.step + t.read) / t.raw - 1;
  } else {
    j["raw"] = nullptr;
    j["note"] = engine + " is crumble's own engine: there is no raw library to compare with";
  }
  j["loop"] = loop_phase(*sc.sim, steps, dt, 1e3 * t.step / steps);
  return j;
}

// `crumble bench pd-analysis [--scenario F] [--steps R] [--threads N]`: the breakage analysis
// that crushes a grain, alone. The scenario (default scenarios/single_grain_pd.json) gives the
// peridynamic options, the material and the size (scene.diameter, else d0); the grain, of G_c
// gc0 scaled by eq. 15 to that size, is pressed by two opposite contacts at 1.5 × the load of
// the reference grain scaled as √G_c·d² (Zhu & Zhao 2019, eq. 14), so the analysis ramps the
// load until the grain splits, as the analysis of a breakage check that crushes it does. R
// repeats; wall and CPU time per analysis, with the crushing force and the steps. breakage.threads
// is set from --threads.
Json bench_pd_analysis(long repeats, int threads, const std::string& file_in) {
  const std::string file = file_in.empty() ? "scenarios/single_grain_pd.json" : file_in;
  Json doc = load_scenario_file(file);
  if (!doc.contains("breakage") || !doc["breakage"].is_object() || doc["breakage"].value("type", "") != "peridynamics")
    throw ConfigError(file + ": /breakage/type", "bench pd-analysis needs a peridynamics scenario");
  doc["breakage"]["threads"] = threads;
  BuildOptions opt;
  opt.threads = 1;
  opt.source_name = file;
  Scenario sc = build_scenario(doc, opt);
  const auto& model = sc.sim->model();
  const Json& b = sc.effective["breakage"];
  const double gc0 = b.value("gc0", 30.0), d0 = b.value("d0", 2e-3);
  double d = d0;
  if (doc.contains("scene") && doc["scene"].is_object() && doc["scene"].contains("diameter"))
    d = doc["scene"]["diameter"].get<double>();
  const Material& m = sc.sim->context().materials.front();
  Json breakage_section = b;
  const PdOptions o = pd_options_from_config(Config(breakage_section));
  Grain g;
  g.id = 1;
  g.shape = Shape::sphere(d / 2);
  g.strength.set(PeridynamicsModel::kGc, pd_child_gc(o, gc0, d, d0));
  const double load = 1.5 * 180.0 * std::sqrt(g.strength.get_or(PeridynamicsModel::kGc, gc0) / gc0) * (d / d0) * (d / d0);
  std::vector<Contact> c(2);
  c[0].a = c[1].a = g.id;
  c[0].wall = kPlaten, c[0].point = {0, 0, d / 2}, c[0].force = {0, 0, -load};
  c[1].wall = kFloor, c[1].point = {0, 0, -d / 2}, c[1].force = {0, 0, load};
  auto cpu_now = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
  };
  double wall = 0, wall_min = 1e300, cpu = 0;
  BreakageAnalysis a;
  for (long k = 0; k < repeats; ++k) {
    const double c0 = cpu_now();
    const auto t0 = std::chrono::steady_clock::now();
    a = model.analyse(g, m, c);
    const double w = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    cpu += cpu_now() - c0;
    wall += w;
    wall_min = std::min(wall_min, w);
  }
  Json j;
  j["benchmark"] = "pd-analysis";
  j["scenario"] = file;
  j["diameter_m"] = d;
  j["gc_J_m2"] = g.strength.get_or(PeridynamicsModel::kGc, gc0);
  j["density_scale"] = o.density_scale;
  j["threads"] = threads;
  j["load_N"] = load;
  j["outcome"] = a.outcome;
  j["force_at_split_N"] = a.figure("force_at_split_N");
  j["points"] = a.figure("points");
  j["bonds"] = a.figure("bonds");
  j["steps"] = a.figure("steps");
  j["repeats"] = repeats;
  j["wall_s_per_analysis"] = wall / repeats;
  j["wall_s_min"] = wall_min;
  j["cpu_s_per_analysis"] = cpu / repeats;
  double la[3] = {0, 0, 0};
  if (getloadavg(la, 3) == 3) j["load_average"] = {la[0], la[1], la[2]};
  return j;
}

}  // namespace

Json run_benchmark(const std::string& what, long steps, int threads, const std::string& scenario,
                   const std::string& engine, long settle_steps) {
  if (steps <= 0) steps = what == "pd-analysis" ? 3 : 1000;
  if (what == "engine") {
    if (engine.empty()) throw ConfigError("--engine", "bench engine needs --engine (known: " + engines().names() + ")");
    engines().find(engine, "--engine");
    return bench_engine(engine, steps, settle_steps, threads, scenario);
  }
  if (engine != "") throw ConfigError("--engine", "only `bench engine` takes --engine");
  if (what == "lsdem") return bench_lsdem(steps, threads, scenario);
  if (what == "pd-kernel") {
    // The LPS kernel on the lattice of LAMMPS's examples/peri cylinder (3487 points). LAMMPS
    // peri/lps on this machine kind: 13.8–19.4 s per 1000 steps
    // (scripts/bench-pd-vs-lammps.sh), ≈ 1.7e7 bond visits/s per core.
    Json j = Json::parse(pd_kernel_bench(steps, threads));
    j["benchmark"] = "pd-kernel";
    return j;
  }
  if (what == "pd-analysis") return bench_pd_analysis(steps, threads, scenario);
  throw ConfigError("bench " + what, "unknown benchmark; known: engine, lsdem, pd-kernel, pd-analysis");
}

}  // namespace crumble

#include <iostream>

#include "tools/Subcommand.h"

namespace crumble {
namespace {

class BenchCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c = app.add_subcommand("bench", "benchmarks (one JSON line on stdout)");
    c->add_option("what", what_, "engine | pd-kernel | pd-analysis | lsdem")->required();
    c->add_option("--steps", steps_, "steps (default 1000); pd-analysis: repeats (default 3)")
        ->check(CLI::Range(1L, 100000000L));
    c->add_option("--threads", threads_, "threads")->check(CLI::Range(1, 1024));
    c->add_option("--scenario", scenario_,
                  "scenario file (lsdem; engine: default scenarios/oedometer_rigid_quick.json)");
    c->add_option("--engine", engine_, "engine for `bench engine` (bullet, ode, lsdem, ...)");
    c->add_option("--settle-steps", settle_,
                  "engine: steps the placed grains fall before timing (default: settle them as the scenario's "
                  "packing does)")
        ->check(CLI::Range(-1L, 100000000L));
    return c;
  }

  int run(const CommandContext&) override {
    std::cout << run_benchmark(what_, steps_, threads_, scenario_, engine_, settle_).dump() << "\n";
    return 0;
  }

 private:
  std::string what_, scenario_, engine_;
  long steps_ = 0, settle_ = -1;  // steps 0: the benchmark's default
  int threads_ = 1;
};

}  // namespace

std::unique_ptr<Subcommand> make_bench_command() { return std::make_unique<BenchCommand>(); }

}  // namespace crumble
