// The Simulation loop with stand-in engine, model and builder: schedule, screening,
// replacement of broken grains (v + ω × r), fines removal and the mass budget, and
// independence of the thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <map>
#include <stdexcept>
#include <string_view>
#include <thread>


#include "core/Simulation.h"
#include "output/Checkpoint.h"
#include "output/VtkWriter.h"
#include "output/Writers.h"
#include "tests/support/VtkArrays.h"

using namespace crumble;
using crumble::test::vtp_array;
namespace fs = std::filesystem;

namespace {

// Each grain is squeezed between two opposite contacts whose force grows with the platen
// travel; no dynamics beyond that.
class SqueezeEngine : public Engine {
 public:
  std::string name() const override { return "squeeze"; }
  void set_container(const Container& c) override { z_ = c.height; }
  void add_grain(const Grain& g) override { grains_[g.id] = g; }
  void remove_grain(GrainId id) override { grains_.erase(id); }
  std::size_t grain_count() const override { return grains_.size(); }
  void step(double dt) override { z_ += v_ * dt; }
  void read_state(std::span<Grain> gs) const override {
    for (auto& g : gs) {
      auto it = grains_.find(g.id);
      if (it != grains_.end()) {
        g.position = it->second.position;
        g.velocity = it->second.velocity;
        g.angular_velocity = it->second.angular_velocity;
      }
    }
  }
  std::vector<Contact> contacts() const override {
    std::vector<Contact> cs;
    const double f = 1e6 * (0.01 - z_);  // N
    for (const auto& [id, g] : grains_) {
      const double r = 0.5 * g.shape->equivalent_diameter();
      cs.push_back({id, -1, kPlaten, g.position + Vec3{0, 0, r}, {0, 0, -1}, {0, 0, -f}});
      cs.push_back({id, -1, kFloor, g.position - Vec3{0, 0, r}, {0, 0, 1}, {0, 0, f}});
    }
    return cs;
  }
  void set_platen(const PlatenCommand& c) override { v_ = c.mode == PlatenCommand::Mode::Velocity ? c.value : -0.01; }
  double platen_position() const override { return z_; }
  double platen_force() const override { return 1e6 * (0.01 - z_); }
  double floor_force() const override { return platen_force(); }
  std::map<GrainId, Grain> grains_;
  double z_ = 0, v_ = 0;
};

// Breaks a grain when the largest contact force exceeds its strength.
class ThresholdModel : public BreakageModel {
 public:
  // Children get `child_factor` × their parent's limit (1000: they never break here).
  explicit ThresholdModel(double delay_s = 0, double child_factor = 1000) : delay_(delay_s), child_factor_(child_factor) {}
  std::string name() const override { return "threshold"; }
  void assign_strength(Grain& g, const Material&, Rng& rng) const override { g.strength.set("limit_N", 50 + 50 * rng.uniform()); }
  void inherit_strength(const Grain& p, Grain& c, const Material&, Rng&) const override {
    c.strength.set("limit_N", child_factor_ * p.strength.get("limit_N"));
  }
  BreakageAnalysis analyse(const Grain& g, const Material&, std::span<const Contact> cs) const override {
    if (delay_ > 0) std::this_thread::sleep_for(std::chrono::duration<double>(delay_));
    BreakageAnalysis a;
    for (const auto& c : cs) a.load = std::max(a.load, norm(c.force));
    a.broken = a.load > g.strength.get("limit_N");
    a.outcome = a.broken ? "split" : "intact";
    if (a.broken) a.fracture = CuttingSurfaces{{CutPlane{{1, 0, 0}, 0}}};
    return a;
  }

 private:
  double delay_, child_factor_;
};

// Returns the parent whole (one piece): the Simulation reports no_split and keeps the grain.
class WholeBuilder : public FragmentBuilder {
 public:
  std::string name() const override { return "whole"; }
  FragmentResult build(const Shape& parent, const Fracture&) const override {
    return {{{Shape::sphere(std::cbrt(parent.volume() * 3 / (4 * kPi))), {0, 0, 0}}}, "whole", 0};
  }
};

// Cannot cut the grain into a piece it resolves (FragmentResult::unresolved): no child, no
// removed volume. The Simulation reports unresolved and keeps the grain.
class UnresolvedBuilder : public FragmentBuilder {
 public:
  std::string name() const override { return "unresolved"; }
  FragmentResult build(const Shape&, const Fracture&) const override {
    FragmentResult r;
    r.method = "level_set_unresolved";
    r.unresolved = true;
    return r;
  }
};

// A sphere → one sphere of 7/8 of the volume at +x and one of 1/8 at −x (volume exact).
// With `chip`, the 1/8 piece is dropped by the builder itself (FragmentResult::removed_volume).
class EighthBuilder : public FragmentBuilder {
 public:
  explicit EighthBuilder(bool chip = false, double delay_s = 0) : chip_(chip), delay_(delay_s) {}
  std::string name() const override { return "eighth"; }
  FragmentResult build(const Shape& parent, const Fracture&) const override {
    if (delay_ > 0) std::this_thread::sleep_for(std::chrono::duration<double>(delay_));
    const double V = parent.volume();
    auto big = Shape::sphere(std::cbrt(0.875 * V * 3 / (4 * kPi)));
    auto small = Shape::sphere(std::cbrt(0.125 * V * 3 / (4 * kPi)));
    // centroid preserved: 0.875 a = 0.125 b
    const double a = 1e-4, b = 0.875 * a / 0.125;
    if (chip_) {
      FragmentResult r{{{big, {a, 0, 0}}}, "chip", 0};
      r.removed_volume = small->volume();
      return r;
    }
    return {{{big, {a, 0, 0}}, {small, {-b, 0, 0}}}, "eighth", 0};
  }

 private:
  bool chip_;
  double delay_;
};

struct Outcome {
  RunSummary sum;
  std::vector<Grain> grains;
  std::size_t events = 0;
};

// The squeeze loop: 1 ms steps sampled every step, a strain-rate platen stopped at 400 N,
// breakage checked every 5 steps with every grain screened in (the fake engine has no walls).
struct SqueezeSetup {
  SimulationSettings ss;
  LoadingSettings ls;
  ScheduleSettings sch;
  ScreeningSettings scr;
};
SqueezeSetup squeeze_setup() {
  SqueezeSetup u;
  u.ss.time_steps = {{1e300, 1e-3}};
  u.ss.sample_every = 1;
  u.ss.guards.containment = false;
  u.ls.mode = "strain_rate";
  u.ls.strain_rate = 1.0;
  u.ls.stop_force = 400;
  u.sch.every_steps = 5;
  u.scr.force_threshold = false;
  u.scr.min_diameter = 0;
  return u;
}

Outcome run_with(int threads, double fines, bool chip = false, double model_delay = 0, double build_delay = 0) {
  EngineContext ctx;
  SqueezeSetup u = squeeze_setup();
  u.ss.threads = threads;
  u.ss.fines_diameter = fines;
  Simulation sim(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(model_delay),
                 std::make_unique<EighthBuilder>(chip, build_delay), ctx, u.ss, u.ls, u.sch, u.scr, 123);
  sim.set_container({0.01, 0.01, 0.01, 0});
  for (int i = 0; i < 8; ++i) {
    Grain g;
    g.shape = Shape::sphere(1e-3);
    g.position = {1e-3 * i, 0, 0};
    g.angular_velocity = {0, 0, 10.0 * i};
    g.velocity = {0.1, 0, 0};
    sim.add_grain(g);
  }
  Outcome r;
  struct Count : Observer {
    std::size_t* n;
    void on_breakage(const Simulation&, const BreakageEvent&) override { ++*n; }
  };
  auto c = std::make_shared<Count>();
  c->n = &r.events;
  sim.add_observer(c);
  r.sum = sim.run();
  r.grains = sim.grains();
  return r;
}

}  // namespace

TEST(SimulationLoop, BrokenGrainsAreReplacedAndMassIsConserved) {
  const Outcome r = run_with(1, 0);
  EXPECT_EQ(r.sum.breakage_events, 8);  // every grain broke once
  EXPECT_EQ(r.events, static_cast<std::size_t>(r.sum.breakage_events));
  EXPECT_EQ(r.sum.grains_final, 8 + static_cast<std::size_t>(r.sum.breakage_events));
  EXPECT_NEAR(r.sum.mass_final + r.sum.mass_removed, r.sum.mass_initial, 1e-9 * r.sum.mass_initial);
  EXPECT_EQ(r.sum.mass_removed, 0);
}

TEST(SimulationLoop, ChildVelocityIsRigidBodyField) {
  const Outcome r = run_with(1, 0);
  // First-generation children of grain 3 (ω = 30 rad/s about z): v = v0 + ω × r.
  int checked = 0;
  for (const auto& g : r.grains) {
    if (g.parent != 3 || g.generation != 1) continue;
    const Vec3 rr = g.position - Vec3{3e-3, 0, 0};
    const Vec3 expect = Vec3{0.1, 0, 0} + cross(Vec3{0, 0, 30}, rr);
    EXPECT_NEAR(norm(g.velocity - expect), 0, 1e-12);
    ++checked;
  }
  EXPECT_EQ(checked, 2);
}

TEST(SimulationLoop, FinesLeaveTheEngineButStayInTheBudget) {
  const Outcome r = run_with(1, 1.05e-3);  // the 1/8 children (d = 1 mm) are fines
  EXPECT_GT(r.sum.mass_removed, 0);
  EXPECT_NEAR(r.sum.mass_final + r.sum.mass_removed, r.sum.mass_initial, 1e-9 * r.sum.mass_initial);
  for (const auto& g : r.grains) EXPECT_GE(g.shape->equivalent_diameter(), 1.05e-3);
  // All of it went through simulation.fines_diameter (summary.json mass_removed_<path>_kg).
  EXPECT_NEAR(r.sum.extra.at("mass_removed_fines_diameter_kg"), r.sum.mass_removed, 1e-12 * r.sum.mass_initial);
  EXPECT_EQ(r.sum.extra.at("mass_removed_chip_kg"), 0);
  EXPECT_NEAR(r.sum.extra.at("fines_mass_fraction"), r.sum.mass_removed / r.sum.mass_initial, 1e-12);
}

// A builder's removed pieces (one child + removed volume, e.g. a level-set sliver thinner
// than a cell) make a breakage whose removed mass enters the budget.
TEST(SimulationLoop, BuilderRemovedVolumeCountsAsRemovedMass) {
  const Outcome r = run_with(1, 0, /*chip=*/true);
  EXPECT_EQ(r.sum.breakage_events, 8);
  EXPECT_EQ(r.sum.grains_final, 8u);
  const double rho = Material{}.density, V = 4.0 / 3 * kPi * 1e-9;
  EXPECT_NEAR(r.sum.mass_removed, 8 * 0.125 * V * rho, 1e-9 * r.sum.mass_initial);
  EXPECT_NEAR(r.sum.mass_final + r.sum.mass_removed, r.sum.mass_initial, 1e-9 * r.sum.mass_initial);
  // One child and removed pieces: the chip path (summary.json mass_removed_chip_kg).
  EXPECT_NEAR(r.sum.extra.at("mass_removed_chip_kg"), r.sum.mass_removed, 1e-12 * r.sum.mass_initial);
  EXPECT_EQ(r.sum.extra.at("mass_removed_split_pieces_kg"), 0);
  EXPECT_EQ(r.sum.extra.at("mass_removed_fines_diameter_kg"), 0);
}

TEST(SimulationLoop, ResultsDoNotDependOnThreads) {
  const Outcome a = run_with(1, 0), b = run_with(2, 0);
  ASSERT_EQ(a.grains.size(), b.grains.size());
  for (std::size_t i = 0; i < a.grains.size(); ++i) {
    EXPECT_EQ(a.grains[i].id, b.grains[i].id);
    EXPECT_EQ(a.grains[i].position, b.grains[i].position);
    EXPECT_EQ(a.grains[i].strength.values, b.grains[i].strength.values);
  }
}

// summary.json time_breakdown_s: fragment building has its own entry, apart from the
// analyses (they run in one parallel loop; its wall time is split by what each task measured).
TEST(SimulationLoop, FragmentBuildingIsTimedApartFromAnalyses) {
  // 8 builds of 30 ms, analyses instant: ≥ 0.24 s under fragments, analyses near 0.
  const Outcome slow_build = run_with(1, 0, false, 0, 0.03);
  ASSERT_EQ(slow_build.sum.breakage_events, 8);
  EXPECT_GE(slow_build.sum.timings.fragments, 8 * 0.03);
  EXPECT_LT(slow_build.sum.timings.analyses, 0.3 * slow_build.sum.timings.fragments);
  // Slow analyses (every screened grain, ≥ 8 of them), instant building: the other way round.
  const Outcome slow_model = run_with(1, 0, false, 0.03, 0);
  ASSERT_EQ(slow_model.sum.breakage_events, 8);
  EXPECT_GE(slow_model.sum.timings.analyses, 8 * 0.03);
  EXPECT_LT(slow_model.sum.timings.fragments, 0.3 * slow_model.sum.timings.analyses);
}

namespace {
// Observers of known names and costs, for the per-writer timing.
struct NamedObserver : Observer {
  std::string label;
  double sample_s = 0;  // s slept per sample
  explicit NamedObserver(std::string l, double s = 0) : label(std::move(l)), sample_s(s) {}
  std::string name() const override { return label; }
  void on_sample(const Simulation&, const RunState&) override {
    if (sample_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(sample_s));
  }
};
struct Unnamed : Observer {};

// The squeeze loop on one sphere of 1 mm radius, broken by `builder`.
std::unique_ptr<Simulation> one_grain_squeeze(std::unique_ptr<FragmentBuilder> builder, long max_steps = 0) {
  SqueezeSetup u = squeeze_setup();
  u.ss.max_steps = max_steps;
  auto sim = std::make_unique<Simulation>(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(),
                                          std::move(builder), EngineContext{}, u.ss, u.ls, u.sch, u.scr, 123);
  sim->set_container({0.01, 0.01, 0.01, 0});
  Grain g;
  g.shape = Shape::sphere(1e-3);
  sim->add_grain(g);
  return sim;
}
}  // namespace

// summary.json time_breakdown_s.output_by_writer: each observer's seconds under its name,
// observers of one name summed, and the parts summing to output.
TEST(SimulationLoop, OutputIsTimedPerWriterAndSumsToOutput) {
  const auto sim = one_grain_squeeze(std::make_unique<EighthBuilder>(), 20);
  sim->add_observer(std::make_shared<NamedObserver>("slow", 2e-3));
  sim->add_observer(std::make_shared<NamedObserver>("twice", 1e-3));
  sim->add_observer(std::make_shared<NamedObserver>("twice", 1e-3));
  sim->add_observer(std::make_shared<Unnamed>());
  const RunSummary sum = sim->run();
  const auto& by = sum.timings.output_by_writer;
  ASSERT_EQ(by.size(), 3u);  // slow, twice, other
  // 20 samples in the loop and one at the end.
  EXPECT_GE(by.at("slow"), 21 * 2e-3);
  EXPECT_GE(by.at("twice"), 2 * 21 * 1e-3);
  EXPECT_LT(by.at("other"), by.at("twice"));
  const auto j = summary_json(sum, "s", "squeeze", "threshold", "eighth", 1, 1);
  const auto& t = j.at("time_breakdown_s");
  double parts = 0;
  for (const auto& [name, seconds] : t.at("output_by_writer").items()) parts += seconds.get<double>();
  EXPECT_NEAR(parts, t.at("output").get<double>(), 1e-12);
  EXPECT_NEAR(t.at("output").get<double>(), sum.timings.observers, 1e-12);
}

namespace {
// A sphere → two boxes of half its volume each (2:1:1, at ±x): fragments whose shape
// descriptors differ from their parent's.
class BoxesBuilder : public FragmentBuilder {
 public:
  std::string name() const override { return "boxes"; }
  FragmentResult build(const Shape& parent, const Fracture&) const override {
    const double c = std::cbrt(parent.volume() / 32);  // 8 · 2c · c · c = V / 2
    return {{{Shape::box({2 * c, c, c}), {2 * c, 0, 0}}, {Shape::box({2 * c, c, c}), {-2 * c, 0, 0}}}, "boxes", 0};
  }
};

}  // namespace

// The shape descriptors are computed once per shape and kept between samples: after a
// breakage, shape.csv and the VTK snapshot report the fragments' descriptors, not the parent's.
TEST(SimulationLoop, CachedShapeDescriptorsFollowTheFragments) {
  const fs::path dir = fs::temp_directory_path() / "crumble_simulation_loop" / "shape_cache";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto sim = one_grain_squeeze(std::make_unique<BoxesBuilder>());
  sim->add_observer(std::make_shared<ShapeWriter>(dir.string(), 3));
  sim->add_observer(std::make_shared<VtkWriter>(dir.string(), VtkWriter::Settings{1, true, false, 0}));
  const RunSummary sum = sim->run();
  ASSERT_EQ(sum.breakage_events, 1);
  const double sphere = grain_shape_metrics(*Shape::sphere(1e-3)).sphericity;
  const double box = grain_shape_metrics(*sim->grains().front().shape).sphericity;
  ASSERT_GT(std::abs(sphere - box), 0.1);
  const auto rows = read_csv((dir / "shape.csv").string());
  ASSERT_GT(rows.size(), 3u);
  EXPECT_NEAR(std::stod(rows[1][5]), sphere, 1e-9);       // before the breakage
  EXPECT_NEAR(std::stod(rows.back()[5]), box, 1e-9);      // after it: the fragments
  EXPECT_EQ(rows.back()[4], "2");
  std::ifstream in(dir / "vtk" / ("grains_" + std::string(8 - std::to_string(sum.steps).size(), '0') +
                                  std::to_string(sum.steps) + ".vtp"));
  const std::string last((std::istreambuf_iterator<char>(in)), {});
  const auto values = vtp_array(last, "sphericity");
  ASSERT_FALSE(values.empty());
  for (double v : values) EXPECT_NEAR(v, box, 1e-9);
}

// output.vtk_format: the compressed binary snapshot (the default) holds the values of the
// ascii one (its 10 significant digits; 17 for the pose and mass) in every array, and is smaller.
TEST(SimulationLoop, BinaryVtkSnapshotsHoldTheAsciiValues) {
  const fs::path dir = fs::temp_directory_path() / "crumble_simulation_loop" / "vtk_formats";
  fs::remove_all(dir);
  const auto sim = one_grain_squeeze(std::make_unique<BoxesBuilder>());
  VtkWriter::Settings ascii{1, true, false, 0};
  ascii.binary = false;
  sim->add_observer(std::make_shared<VtkWriter>((dir / "binary").string(), VtkWriter::Settings{1, true, false, 0}));
  sim->add_observer(std::make_shared<VtkWriter>((dir / "ascii").string(), ascii));
  const RunSummary sum = sim->run();
  ASSERT_EQ(sum.breakage_events, 1);
  const std::string name = "grains_" + std::string(8 - std::to_string(sum.steps).size(), '0') +
                           std::to_string(sum.steps) + ".vtp";
  std::ifstream ib(dir / "binary" / "vtk" / name), ia(dir / "ascii" / "vtk" / name);
  const std::string b((std::istreambuf_iterator<char>(ib)), {}), a((std::istreambuf_iterator<char>(ia)), {});
  ASSERT_NE(b.find("compressor=\"vtkZLibDataCompressor\""), std::string::npos);
  EXPECT_EQ(a.find("format=\"binary\""), std::string::npos);
  EXPECT_LT(b.size(), a.size());
  for (const char* n : {"grain", "parent", "diameter", "velocity", "position", "orientation", "mass", "sphericity",
                        "connectivity", "offsets"}) {
    const auto x = vtp_array(b, n), y = vtp_array(a, n);
    ASSERT_EQ(x.size(), y.size()) << n;
    ASSERT_FALSE(x.empty()) << n;
    for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(x[i], y[i], 1e-9 * std::abs(y[i]) + 1e-300) << n << ' ' << i;
  }
}

namespace {
// The squeeze engine with one absurd platen-force reading at step `spike_at` (the start-up
// transient of an explicit engine loading a packing settled by another).
class SpikeEngine : public SqueezeEngine {
 public:
  void step(double dt) override {
    SqueezeEngine::step(dt);
    ++steps_;
  }
  double platen_force() const override { return steps_ == spike_at ? 1e9 : SqueezeEngine::platen_force(); }
  long steps_ = 0, spike_at = 30;
};
}  // namespace

// Under a stress ramp the schedule follows the commanded stress: a peak in the measured
// platen stress does not postpone the later checks (it used to: one check at the peak,
// then none until the stress came back to it).
TEST(SimulationLoop, StressRampChecksFollowTheCommandNotAMeasuredPeak) {
  const auto run = [](long spike_at) {
    EngineContext ctx;
    SimulationSettings ss;
    ss.time_steps = {{1e300, 1e-4}};
    ss.sample_every = 0;
    ss.guards.containment = false;
    ss.guards.enabled = false;  // the absurd reading would (rightly) trip a guard
    LoadingSettings ls;
    ls.mode = "stress_ramp";
    ls.max_stress = 1e5;   // Pa
    ls.ramp_time = 0.004;  // 40 steps; the squeeze reaches 40 N, below every grain's strength
    ScheduleSettings sch;
    sch.every_stress = 1e4;
    ScreeningSettings scr;
    scr.force_threshold = false;
    auto engine = std::make_unique<SpikeEngine>();
    engine->spike_at = spike_at;
    Simulation sim(std::move(engine), std::make_unique<ThresholdModel>(), std::make_unique<EighthBuilder>(), ctx, ss,
                   ls, sch, scr, 1);
    sim.set_container({0.01, 0.01, 0.01, 0});
    Grain g;
    g.shape = Shape::sphere(1e-3);
    sim.add_grain(g);
    return sim.run();
  };
  const RunSummary calm = run(-1), spiked = run(15);
  EXPECT_EQ(calm.breakage_events, 0);
  // About one check per 0.01 MPa of the 0.1 MPa ramp, each analysing the one grain, with or
  // without the peak at step 15 (3 checks done by then).
  EXPECT_GE(calm.analyses, 9);
  EXPECT_EQ(spiked.analyses, calm.analyses);
}

namespace {
struct Lineage {
  std::vector<Grain> grains;
  std::map<GrainId, int> no_split;  // no_split records per grain
  std::map<GrainId, int> unresolved;  // unresolved records per grain
  long events = 0;
  RunSummary sum;
};

// `count` 1 mm spheres on the x axis, `spacing` apart.
void add_spheres(Simulation& sim, int count, double spacing) {
  for (int i = 0; i < count; ++i) {
    Grain g;
    g.shape = Shape::sphere(1e-3);
    g.position = {spacing * i, 0, 0};
    sim.add_grain(g);
  }
}

Lineage run_lineage(std::unique_ptr<FragmentBuilder> builder, double child_factor) {
  EngineContext ctx;
  const SqueezeSetup u = squeeze_setup();
  Simulation sim(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(0, child_factor),
                 std::move(builder), ctx, u.ss, u.ls, u.sch, u.scr, 7);
  sim.set_container({0.01, 0.01, 0.01, 0});
  add_spheres(sim, 4, 2e-3);
  Lineage r;
  struct Rec : Observer {
    Lineage* r;
    void on_analysis(const Simulation&, const AnalysisRecord& a) override {
      if (a.analysis.outcome == "no_split") ++r->no_split[a.grain];
      if (a.analysis.outcome == "unresolved") ++r->unresolved[a.grain];
    }
  };
  auto o = std::make_shared<Rec>();
  o->r = &r;
  sim.add_observer(o);
  r.sum = sim.run();
  r.events = r.sum.breakage_events;
  r.grains = sim.grains();
  return r;
}
}  // namespace

// Grain::crush_count counts the breakage verdicts of the lineage: a child starts at its
// parent's count + 1, so with every verdict splitting the grain it equals the generation.
TEST(SimulationLoop, CrushCountFollowsTheLineage) {
  // Children as strong as their parent (factor 1.01): they break again as the load grows.
  const Lineage r = run_lineage(std::make_unique<EighthBuilder>(), 1.01);
  ASSERT_GT(r.events, 4);
  int second = 0;
  for (const auto& g : r.grains) {
    EXPECT_EQ(g.crush_count, g.generation) << "grain " << g.id;
    if (g.generation >= 2) ++second;
  }
  EXPECT_GT(second, 0) << "no grandchild: the test would not see the count carried over";
}

// The four grains unbroken (generation 0), each with a crush_count equal to its records in
// `verdicts`; returns their sum.
static int unsplit_verdicts(const Lineage& r, const std::map<GrainId, int>& verdicts) {
  EXPECT_EQ(r.grains.size(), 4u);
  int total = 0;
  for (const auto& g : r.grains) {
    EXPECT_EQ(g.generation, 0);
    const auto it = verdicts.find(g.id);
    const int expect = it == verdicts.end() ? 0 : it->second;
    EXPECT_EQ(g.crush_count, expect) << "grain " << g.id;
    total += expect;
  }
  return total;
}

// A verdict the builder cannot split (no_split) keeps the grain and still counts: the
// count is the number of no_split records of that grain.
TEST(SimulationLoop, CrushCountCountsUnsplitVerdicts) {
  const Lineage r = run_lineage(std::make_unique<WholeBuilder>(), 1000);
  EXPECT_EQ(r.events, 0);
  EXPECT_GE(unsplit_verdicts(r, r.no_split), 4) << "every grain is loaded past its limit; each must have been judged broken";
}

// Harmon et al. 2020 §3.4, first method: a verdict the builder cannot turn into a resolved
// piece (unresolved) is not a breakage. Each grain stays whole with all of its mass, and
// summary.json's fragment_unresolved counts the verdicts (crush_count too, as for no_split).
TEST(SimulationLoop, UnresolvedSplitLeavesTheGrainWholeAndCounted) {
  const Lineage r = run_lineage(std::make_unique<UnresolvedBuilder>(), 1000);
  EXPECT_EQ(r.events, 0);
  EXPECT_EQ(r.sum.mass_removed, 0.0);
  EXPECT_EQ(r.sum.extra.at("mass_removed_crushed_kg"), 0.0);
  EXPECT_NEAR(r.sum.mass_final, r.sum.mass_initial, 1e-12 * r.sum.mass_initial);
  EXPECT_TRUE(r.no_split.empty());
  const int total = unsplit_verdicts(r, r.unresolved);
  EXPECT_GE(total, 4) << "every grain is loaded past its limit; each must have been judged broken";
  EXPECT_EQ(r.sum.extra.at("fragment_unresolved"), static_cast<double>(total));
}

namespace {
// A grain that never breaks, squeezed by a force growing 10 N per step, checked every step.
struct SkipRun {
  RunSummary sum;
  std::vector<double> loads;  // of grain 0's analyses
};
SkipRun run_skipping(double tolerance) {
  class Unbreakable : public ThresholdModel {
   public:
    void assign_strength(Grain& g, const Material&, Rng&) const override { g.strength.set("limit_N", 1e9); }
  };
  EngineContext ctx;
  SqueezeSetup u = squeeze_setup();
  u.sch.every_steps = 1;
  u.scr.skip_intact_tolerance = tolerance;
  Simulation sim(std::make_unique<SqueezeEngine>(), std::make_unique<Unbreakable>(), std::make_unique<EighthBuilder>(),
                 ctx, u.ss, u.ls, u.sch, u.scr, 123);
  sim.set_container({0.01, 0.01, 0.01, 0});
  for (int i = 0; i < 3; ++i) {
    Grain g;
    g.shape = Shape::sphere(1e-3);
    g.position = {3e-3 * i, 0, 0};
    sim.add_grain(g);
  }
  SkipRun r;
  struct Rec : Observer {
    std::vector<double>* loads;
    void on_analysis(const Simulation&, const AnalysisRecord& a) override {
      if (a.grain == 0) loads->push_back(a.analysis.load);
    }
  };
  auto rec = std::make_shared<Rec>();
  rec->loads = &r.loads;
  sim.add_observer(rec);
  r.sum = sim.run();
  return r;
}
}  // namespace

// The skip rule (Screening.h) in the loop: without it every check analyses every grain (a
// check every 10 N up to 400 N); with tolerance 0.35 a grain analysed whole is analysed again
// only at the first check whose force is more than 1.35 times that of its last analysis (no
// product of the sequence lands within 0.5 N of a check's force).
TEST(SimulationLoop, SkipRuleAnalysesAgainOnlyWhenTheLoadGrew) {
  const SkipRun off = run_skipping(0), on = run_skipping(0.35);
  // 40 or 41 checks: the platen force reaches 400 N at step 40 give or take round-off.
  ASSERT_GE(off.loads.size(), 40u);
  ASSERT_LE(off.loads.size(), 41u);
  EXPECT_EQ(off.sum.analyses, 3 * static_cast<long>(off.loads.size()));
  EXPECT_EQ(off.sum.analyses_skipped, 0);
  const std::vector<double> expect{10, 20, 30, 50, 70, 100, 140, 190, 260, 360};
  ASSERT_EQ(on.loads.size(), expect.size());
  for (std::size_t k = 0; k < expect.size(); ++k) EXPECT_NEAR(on.loads[k], expect[k], 1e-6) << k;
  EXPECT_EQ(on.sum.analyses, 3 * static_cast<long>(expect.size()));
  EXPECT_EQ(on.sum.analyses + on.sum.analyses_skipped, off.sum.analyses);  // every screened-in check is one or the other
  // The screening tally counts the grains that passed the rules, analysed or skipped.
  EXPECT_EQ(off.sum.extra.at("screening_selected"), static_cast<double>(off.sum.analyses));
  EXPECT_EQ(on.sum.extra.at("screening_selected"), static_cast<double>(on.sum.analyses + on.sum.analyses_skipped));
}

namespace {
// The squeeze engine whose platen read-out (called by the loop every step, outside
// Engine::step) takes `delay` seconds, and whose steps take `step_delay`.
class SlowReadoutEngine : public SqueezeEngine {
 public:
  SlowReadoutEngine(double delay, double step_delay) : delay_(delay), step_delay_(step_delay) {}
  void step(double dt) override {
    SqueezeEngine::step(dt);
    std::this_thread::sleep_for(std::chrono::duration<double>(step_delay_));
  }
  double platen_force() const override {
    std::this_thread::sleep_for(std::chrono::duration<double>(delay_));
    return SqueezeEngine::platen_force();
  }
  double delay_, step_delay_;
};
}  // namespace

// summary.json time_breakdown_s.loop: what the loop spends outside the parts it times
// (engine, guards, checks, output) — the loop overhead `crumble bench engine` reports. Work
// done between engine steps lands there, the engine's own stepping does not.
TEST(SimulationLoop, LoopOverheadIsTimedApartFromTheEngine) {
  const auto run = [](double readout_delay, double step_delay) {
    EngineContext ctx;
    SimulationSettings ss;
    ss.time_steps = {{1e300, 1e-4}};
    ss.sample_every = 0;
    ss.max_steps = 40;
    ss.guards.enabled = false;
    LoadingSettings ls;
    ls.mode = "none";
    ScheduleSettings sch;
    ScreeningSettings scr;
    Simulation sim(std::make_unique<SlowReadoutEngine>(readout_delay, step_delay), std::make_unique<ThresholdModel>(),
                   std::make_unique<EighthBuilder>(), ctx, ss, ls, sch, scr, 1);
    sim.set_container({0.01, 0.01, 0.01, 0});
    Grain g;
    g.shape = Shape::sphere(1e-3);
    sim.add_grain(g);
    return sim.run();
  };
  // 40 steps, each reading the platen force at least once: >= 40 ms of read-out in `loop`.
  const RunSummary slow_loop = run(1e-3, 0);
  EXPECT_EQ(slow_loop.steps, 40);
  EXPECT_GE(slow_loop.timings.loop, 40 * 1e-3);
  EXPECT_LT(slow_loop.timings.engine, 0.5 * slow_loop.timings.loop);
  // Slow steps, instant read-out: the other way round.
  const RunSummary slow_engine = run(0, 1e-3);
  EXPECT_GE(slow_engine.timings.engine, 40 * 1e-3);
  EXPECT_LT(slow_engine.timings.loop, 0.5 * slow_engine.timings.engine);
}

// Guards.h (containment): a grain below small_grain_fraction of the initial mean diameter
// that has left the container is taken out as fines — mass to mass_removed, counted in the
// summary — instead of stopping the run; a grain above the limit still stops it.
TEST(SimulationLoop, TinyGrainOutsideTheContainerLeavesAsFines) {
  auto run = [](double tiny_radius) {
    EngineContext ctx;
    SqueezeSetup u = squeeze_setup();
    u.ss.guards.containment = true;
    u.ls.stop_force = 50;
    Simulation sim(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(), std::make_unique<EighthBuilder>(false, 0),
                   ctx, u.ss, u.ls, u.sch, u.scr, 123);
    sim.set_container({0.01, 0.01, 0.01, 0});
    for (int i = 0; i < 4; ++i) {
      Grain g;
      g.shape = Shape::sphere(1e-3);
      g.position = {2e-3 * (i + 1), 5e-3, 2e-3};
      sim.add_grain(g);
    }
    Grain tiny;
    tiny.shape = Shape::sphere(tiny_radius);
    tiny.position = {5e-3, 5e-3, -1e-6};  // 1 µm below the floor
    const GrainId id = sim.add_grain(tiny);
    const RunSummary s = sim.run();
    for (const auto& g : sim.grains()) EXPECT_NE(g.id, id);
    return s;
  };
  const RunSummary s = run(0.05e-3);  // d = 0.1 mm against a mean of 1.6 mm
  EXPECT_EQ(s.extra.at("guard_small_grains_removed"), 1);
  const double m_tiny = Material{}.density * (4.0 / 3.0) * M_PI * std::pow(0.05e-3, 3);
  EXPECT_NEAR(s.mass_removed, m_tiny, 1e-9 * m_tiny);
  EXPECT_NEAR(s.mass_final + s.mass_removed, s.mass_initial, 1e-9 * s.mass_initial);
  EXPECT_THROW(run(0.5e-3), PhysicsGuardError);  // d = 1 mm: not tiny, the run stops
}

// An open scene's frame (Container::discharge_level, eject_above): a grain below the discharge
// level out of the domain sideways leaves as product, one above eject_above is ejected; both
// leave the engine, the summary counts them apart and the mass budget closes.
TEST(SimulationLoop, OpenSceneGrainsLeaveAsProductOrEjected) {
  EngineContext ctx;
  SqueezeSetup u = squeeze_setup();
  u.ss.guards.containment = true;
  u.ss.max_steps = 3;
  u.ls.mode = "none";
  Simulation sim(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(), std::make_unique<WholeBuilder>(),
                 ctx, u.ss, u.ls, u.sch, u.scr, 123);
  Container c;
  c.open = true;
  c.domain = {{-1, -1, -0.2}, {1, 1, 2}};
  c.height = 2.2;
  c.discharge_level = 0;
  c.eject_above = 1.5;
  sim.set_container(c);
  const auto add = [&](Vec3 p, double r) {
    Grain g;
    g.shape = Shape::sphere(r);
    g.position = p;
    return sim.add_grain(g);
  };
  const GrainId stays = add({0.5, 0, 0.5}, 1e-2);
  add({0.2, 1.2, -0.05}, 2e-2);  // below the discharge level, out sideways (y)
  add({0.1, 0.1, 1.6}, 3e-2);    // above the frame's top
  const RunSummary s = sim.run();
  ASSERT_EQ(sim.grains().size(), 1u);
  EXPECT_EQ(sim.grains()[0].id, stays);
  const double rho = Material{}.density, k = rho * 4.0 / 3.0 * M_PI;
  EXPECT_EQ(s.extra.at("product_grains"), 1);
  EXPECT_NEAR(s.extra.at("product_mass_kg"), k * std::pow(2e-2, 3), 1e-12);
  EXPECT_EQ(s.extra.at("ejected_grains"), 1);
  EXPECT_NEAR(s.extra.at("mass_ejected_kg"), k * std::pow(3e-2, 3), 1e-12);
  EXPECT_NEAR(s.extra.at("mass_budget_error_kg"), 0, 1e-15);
  // A checkpoint carries them: the resumed run reports what the first one discharged.
  const auto dir = fs::temp_directory_path() / "crumble_simulation_loop" / "ejected";
  fs::create_directories(dir);
  const std::string file = (dir / "checkpoint.json").string();
  write_file_atomic(file, checkpoint_json(sim, "open").dump());
  const Checkpoint cp = read_checkpoint(file, "open", 3);
  Simulation resumed(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(),
                     std::make_unique<WholeBuilder>(), ctx, u.ss, u.ls, u.sch, u.scr, 123);
  resumed.set_container(c);
  resumed.resume(cp.state, cp.grains);
  const RunSummary r = resumed.run();
  EXPECT_EQ(r.extra.at("ejected_grains"), 1);
  EXPECT_EQ(r.extra.at("mass_ejected_kg"), s.extra.at("mass_ejected_kg"));
  EXPECT_EQ(r.extra.at("product_grains"), 1);
  // Between the two levels, out sideways: through a wall, the run stops.
  Simulation bad(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(), std::make_unique<WholeBuilder>(),
                 ctx, u.ss, u.ls, u.sch, u.scr, 123);
  bad.set_container(c);
  Grain g;
  g.shape = Shape::sphere(1e-2);
  g.position = {0.2, 1.2, 0.5};
  bad.add_grain(g);
  EXPECT_THROW(bad.run(), PhysicsGuardError);
}

// An analysis or a fragment build that throws (a degenerate geometry) is not fatal: the
// grain stays as it was, summary.json counts the failure by the error's leading word, and
// the mass budget holds.
TEST(SimulationLoop, AFailedAnalysisLeavesTheGrainIntactAndIsCounted) {
  class FailsOnGrain2 : public ThresholdModel {
   public:
    BreakageAnalysis analyse(const Grain& g, const Material& m, std::span<const Contact> cs) const override {
      if (g.id == 2) throw std::invalid_argument("degenerate shape: no lattice");
      return ThresholdModel::analyse(g, m, cs);
    }
  };
  class FailsThreeTimes : public EighthBuilder {
   public:
    FragmentResult build(const Shape& parent, const Fracture& f) const override {
      if (builds_++ < 3) throw std::runtime_error("convex_hull: internal error (test)");
      return EighthBuilder::build(parent, f);
    }
    mutable int builds_ = 0;
  };
  EngineContext ctx;
  SqueezeSetup u = squeeze_setup();
  Simulation sim(std::make_unique<SqueezeEngine>(), std::make_unique<FailsOnGrain2>(),
                 std::make_unique<FailsThreeTimes>(), ctx, u.ss, u.ls, u.sch, u.scr, 123);
  sim.set_container({0.01, 0.01, 0.01, 0});
  add_spheres(sim, 8, 1e-3);
  struct Rec : Observer {
    long failed = 0;
    void on_analysis(const Simulation&, const AnalysisRecord& a) override { failed += a.analysis.outcome == "failed"; }
  };
  auto rec = std::make_shared<Rec>();
  sim.add_observer(rec);
  const RunSummary sum = sim.run();
  EXPECT_EQ(sum.breakage_events, 7);  // every grain but grain 2, three of them at a later check
  EXPECT_EQ(sum.extra.at("analyses_failed_convex_hull"), 3);
  const double on_grain_2 = sum.extra.at("analyses_failed_degenerate_shape");
  EXPECT_GE(on_grain_2, 1);
  EXPECT_EQ(sum.extra.at("analyses_failed"), 3 + on_grain_2);
  EXPECT_EQ(rec->failed, 3 + on_grain_2);
  EXPECT_EQ(sum.grains_final, 8u + 7u);
  EXPECT_NEAR(sum.mass_final + sum.mass_removed, sum.mass_initial, 1e-12 * sum.mass_initial);
}

// The failure counters are part of a checkpoint: a run resumed from it (here, from the
// checkpoint at the end of a run with failures, by models that no longer fail) reports the
// failures of the run it continues, analyses_failed and analyses_failed_<word>.
TEST(SimulationLoop, FailedAnalysisCountsSurviveACheckpoint) {
  class FailsOnGrain2 : public ThresholdModel {
   public:
    BreakageAnalysis analyse(const Grain& g, const Material& m, std::span<const Contact> cs) const override {
      if (g.id == 2) throw std::invalid_argument("degenerate shape: no lattice");
      return ThresholdModel::analyse(g, m, cs);
    }
  };
  EngineContext ctx;
  SqueezeSetup u = squeeze_setup();
  Simulation a(std::make_unique<SqueezeEngine>(), std::make_unique<FailsOnGrain2>(), std::make_unique<EighthBuilder>(),
               ctx, u.ss, u.ls, u.sch, u.scr, 123);
  a.set_container({0.01, 0.01, 0.01, 0});
  add_spheres(a, 8, 1e-3);
  const RunSummary sa = a.run();
  const double failed = sa.extra.at("analyses_failed_degenerate_shape");
  ASSERT_GE(failed, 1);
  const auto dir = std::filesystem::temp_directory_path() / "crumble_simulation_loop" / "failures";
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "checkpoint.json").string();
  write_file_atomic(file, checkpoint_json(a, "squeeze").dump());
  const Checkpoint cp = read_checkpoint(file, "squeeze", 3);
  Simulation b(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(), std::make_unique<EighthBuilder>(),
               ctx, u.ss, u.ls, u.sch, u.scr, 123);
  b.set_container({0.01, 0.01, 0.01, 0});
  b.resume(cp.state, cp.grains);
  const RunSummary sb = b.run();
  EXPECT_EQ(sb.extra.at("analyses_failed_degenerate_shape"), failed);
  EXPECT_EQ(sb.extra.at("analyses_failed"), sa.extra.at("analyses_failed"));
}

namespace {
// The names of the grains snapshots in dir/vtk, sorted (the step is in the name).
std::vector<std::string> grains_snapshots(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir / "vtk")) {
    const std::string n = e.path().filename().string();
    if (n.rfind("grains_", 0) == 0 && n.size() > 4 && n.compare(n.size() - 4, 4, ".vtp") == 0) names.push_back(n);
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string file_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// At every sample, a new VtkWriter (no cached text, no cached shape descriptors) writes the
// state into its own folder.
struct FreshWriterEverySample : Observer {
  explicit FreshWriterEverySample(fs::path d) : dir(std::move(d)) {}
  void on_sample(const Simulation& sim, const RunState& s) override {
    VtkWriter fresh(dir.string(), VtkWriter::Settings{1, true, false, 0});
    fresh.on_start(sim, s);
  }
  fs::path dir;
};

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "crumble_simulation_loop" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}
}  // namespace

// The writer keeps text and descriptors between snapshots (VtpTextCache, ShapeMetricsCache);
// after a grain splits, every snapshot it writes is byte for byte the one a writer without
// any cache writes of the same state: no surface, cell or field of the parent survives.
TEST(SimulationLoop, CachedVtkSnapshotsEqualAFreshWritersAcrossASplit) {
  const fs::path cached = fresh_dir("vtk_cached"), fresh = fresh_dir("vtk_fresh");
  const auto sim = one_grain_squeeze(std::make_unique<BoxesBuilder>());
  // The descriptors' cache shared with shape.csv's writer, as a run shares it.
  const auto metrics = std::make_shared<ShapeMetricsCache>();
  sim->add_observer(std::make_shared<ShapeWriter>(cached.string(), 3, -1, metrics));
  sim->add_observer(std::make_shared<VtkWriter>(cached.string(), VtkWriter::Settings{1, true, false, 0}, -1, metrics));
  sim->add_observer(std::make_shared<FreshWriterEverySample>(fresh));
  const RunSummary sum = sim->run();
  ASSERT_EQ(sum.breakage_events, 1);
  ASSERT_EQ(sim->grains().size(), 2u);
  const auto names = grains_snapshots(fresh);
  ASSERT_GT(names.size(), 10u);
  std::size_t one = 0, two = 0;  // snapshots of the sphere, of its two boxes
  for (const auto& n : names) {
    const std::string a = file_text(cached / "vtk" / n), b = file_text(fresh / "vtk" / n);
    ASSERT_FALSE(a.empty()) << n;
    EXPECT_EQ(a, b) << n;
    const auto ids = vtp_array(b, "grain");
    (std::set<double>(ids.begin(), ids.end()).size() == 1 ? one : two) += 1;
    const std::string walls = "walls" + n.substr(6);
    EXPECT_EQ(file_text(cached / "vtk" / walls), file_text(fresh / "vtk" / walls)) << walls;
  }
  EXPECT_GT(one, 2u);
  EXPECT_GT(two, 2u);
  // One shared cache: the descriptors of the sphere and of each box (two shapes), each
  // computed once for both writers.
  EXPECT_EQ(metrics->computed(), 3u);
}

namespace {
// grains_*.vtp files of the squeeze (strain rate, 1e-3 strain a step) stopped at stop_strain
// (0: at its stop force only, a loading without progress), a snapshot wanted every step.
std::size_t squeeze_snapshots(const std::string& name, double stop_strain, long max_frames) {
  const fs::path dir = fresh_dir(name);
  SqueezeSetup u = squeeze_setup();
  if (stop_strain > 0) u.ls.stop_force = 0;
  u.ls.stop_strain = stop_strain;
  Simulation sim(std::make_unique<SqueezeEngine>(), std::make_unique<ThresholdModel>(),
                 std::make_unique<EighthBuilder>(), EngineContext{}, u.ss, u.ls, u.sch, u.scr, 123);
  sim.set_container({0.01, 0.01, 0.01, 0});
  Grain g;
  g.shape = Shape::sphere(1e-3);
  sim.add_grain(g);
  sim.add_observer(std::make_shared<VtkWriter>(dir.string(), VtkWriter::Settings{1, false, false, 0, max_frames}));
  const RunSummary sum = sim.run();
  EXPECT_GT(sum.steps, 25);
  return grains_snapshots(dir).size();
}
}  // namespace

// output.vtk_max_frames: with a snapshot wanted at every step (vtk_every 1), 5 frames over a
// loading of 30 steps give the start and the first sample in each fifth of the strain (and
// the end, at 1); without the limit, or without a progress to count (a stop force only),
// every step.
TEST(SimulationLoop, VtkMaxFramesLimitsSnapshotsToPartsOfTheLoading) {
  const std::size_t every = squeeze_snapshots("frames_unlimited", 0.03, 0);
  const std::size_t five = squeeze_snapshots("frames_five", 0.03, 5);
  EXPECT_GE(every, 30u);
  EXPECT_GE(five, 5u);
  EXPECT_LE(five, 7u);
  const std::size_t force_only = squeeze_snapshots("frames_force_only", 0, 5);
  EXPECT_EQ(force_only, squeeze_snapshots("frames_force_only_unlimited", 0, 0));
  EXPECT_GE(force_only, 30u);
}
