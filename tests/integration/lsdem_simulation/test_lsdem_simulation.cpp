// The lsdem engine inside the Simulation loop: a force-controlled platen compresses a small
// 2D column of disks; the Simulation enforces the engine's stable step.
#include <gtest/gtest.h>

#include "backends/lsdem/LsdemEngine.h"
#include "breakage/none/NoBreakage.h"
#include "core/Simulation.h"

using namespace crumble;

TEST(LsdemSimulation, StressRampOnA2DColumn) {
  EngineContext ctx;
  ctx.dimension = 2;
  ctx.gravity = {0, -9.81, 0};
  Material m;
  m.density = 2650;
  m.friction = 0.4;
  ctx.materials = {m};
  LsdemSettings s;
  s.kn = 1e6;
  s.damping_ratio = 0.5;
  s.global_damping = 20;
  SimulationSettings ss;
  ss.time_steps = {{1e300, 1.0}};  // far above the stable step: the Simulation must reduce it
  ss.max_steps = 6000;
  LoadingSettings ls;
  ls.mode = "stress_ramp";
  ls.max_stress = 2e4;  // Pa·m / m: 2D stress = force per metre / width
  ls.ramp_time = 0.05;
  ls.hold_time = 1.0;
  Simulation sim(std::make_unique<LsdemEngine>(s, ctx), std::make_unique<NoBreakage>(), nullptr, ctx, ss, ls, {}, {},
                 1);
  Container box;
  box.lx = 0.02;
  box.height = 0.041;
  box.platen_mass = 0.05;
  sim.set_container(box);
  ShapeResolution res;
  res.level_set_spacing = 0.0005;
  auto disk = Shape::disk(0.005, res);
  for (int i = 0; i < 8; ++i) {
    Grain g;
    g.shape = disk;
    g.position = {0.005 + 0.01 * (i % 2), 0.005 + 0.01 * (i / 2), 0};
    sim.add_grain(g);
  }
  const RunSummary sum = sim.run();
  EXPECT_EQ(sum.steps, 6000);
  EXPECT_GT(sum.dt_reductions, 0);
  EXPECT_LE(sim.state().dt, sim.engine().max_stable_dt());
  // Force control reached the target: platen force ≈ stress × width, floor adds the weight.
  const double F = ls.max_stress * box.lx;
  EXPECT_NEAR(sim.engine().platen_force() / F, 1.0, 0.02);
  const double W = 8 * 2650 * disk->volume() * 9.81;
  EXPECT_NEAR(sim.engine().floor_force() / (F + W), 1.0, 0.02);
  EXPECT_LT(sim.engine().platen_position(), 0.041);
}
