// The physical guards (core/Guards.h) on hand-made states: each invariant fails on a state
// that breaks it, with a message that names it, and passes on a sane state.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/Guards.h"

using namespace crumble;

namespace {

Grain sphere_at(GrainId id, Vec3 p, double r = 1e-3) {
  Grain g;
  g.id = id;
  g.shape = Shape::sphere(r);
  g.position = p;
  return g;
}

GuardContext ctx(double budget = 1.0) {
  GuardContext at;
  at.step = 42;
  at.advice = "Raise engine.solver_iterations.";
  at.energy_budget = budget;
  return at;
}

Container box() {
  Container c;
  c.lx = 0.01;
  c.ly = 0.01;
  c.height = 0.01;
  return c;
}

template <class F>
std::string failure_of(F&& f) {
  try {
    f();
  } catch (const PhysicsGuardError& e) {
    return e.what();
  }
  return "";
}

const std::vector<Material> kMat{Material{}};

}  // namespace

TEST(Guards, SaneStatePassesAndReportsItsMargins) {
  std::vector<Grain> gs{sphere_at(0, {0.002, 0.002, 0.001}), sphere_at(1, {0.004, 0.002, 0.001})};
  gs[0].velocity = {0.1, 0, 0};  // ½ m v² = ½ · 2650 · 4.19e-9 · 0.01 = 5.55e-8 J
  Contact c;
  c.a = 0;
  c.b = 1;
  c.overlap = 1e-5;  // 0.5 % of 2 mm
  const std::vector<Contact> cs{c};
  const GuardReading r = check_invariants(GuardSettings{}, ctx(1e-6), box(), 3, 0.01, gs, kMat, cs);
  EXPECT_NEAR(r.max_overlap_fraction, 0.005, 1e-12);
  const double ke = 0.5 * 2650 * (4.0 / 3.0) * M_PI * 1e-9 * 0.01;
  EXPECT_NEAR(r.energy_ratio, ke / 1e-6, 1e-9);
  EXPECT_NEAR(kinetic_energy(gs, kMat, 3), ke, 1e-15);
}

TEST(Guards, GrainOutsideTheContainerFails) {
  for (Vec3 p : {Vec3{-1e-4, 0.005, 0.002}, Vec3{0.0101, 0.005, 0.002}, Vec3{0.005, 0.011, 0.002},
                 Vec3{0.005, 0.005, -1e-4}, Vec3{0.005, 0.005, 0.0081}}) {
    std::vector<Grain> gs{sphere_at(7, p)};
    const std::string msg = failure_of(
        [&] { check_invariants(GuardSettings{}, ctx(), box(), 3, /*platen*/ 0.008, gs, kMat, {}); });
    EXPECT_NE(msg.find("grain 7"), std::string::npos) << msg;
    EXPECT_NE(msg.find("outside the container"), std::string::npos) << msg;
    EXPECT_NE(msg.find("step 42"), std::string::npos) << msg;
  }
  // 2D: the vertical axis is y; z is not checked.
  std::vector<Grain> gs{sphere_at(3, {0.005, 0.009, 5.0})};
  EXPECT_NE(failure_of([&] { check_invariants(GuardSettings{}, ctx(), box(), 2, 0.008, gs, kMat, {}); }), "");
  gs[0].position.y = 0.007;
  EXPECT_EQ(failure_of([&] { check_invariants(GuardSettings{}, ctx(), box(), 2, 0.008, gs, kMat, {}); }), "");
}

// An open scene (a jaw crusher): a grain beyond any face of the domain fails, except below its
// bottom (the vertical axis: y in 2D, z in 3D), where it is leaving through the discharge —
// the state after a run's last step, whose grains the Simulation has not yet taken out as
// product when the final check runs.
TEST(Guards, OpenSceneGrainBelowTheBottomIsLeavingThroughTheDischarge) {
  Container open;
  open.open = true;
  open.domain = {{-1, -0.2, -1}, {1, 2, 1}};
  open.height = 2.2;
  const auto check = [&](int dim, Vec3 p) {
    std::vector<Grain> gs{sphere_at(5, p)};
    return failure_of([&] { check_invariants(GuardSettings{}, ctx(), open, dim, 0, gs, kMat, {}); });
  };
  EXPECT_EQ(check(2, {0.03, -0.2001, 0}), "");
  EXPECT_EQ(check(3, {0.03, 0.5, -1.0001}), "");
  for (Vec3 p : {Vec3{-1.0001, -0.15, 0}, Vec3{1.0001, 0.5, 0}, Vec3{0.03, 2.0001, 0}}) {
    const std::string msg = check(2, p);
    EXPECT_NE(msg.find("outside the scene's domain"), std::string::npos) << p.x << " " << p.y << ": " << msg;
  }
  EXPECT_NE(check(3, {0.03, -0.2001, 0}), "");  // in 3D y is a side
  // Below the discharge level a grain out sideways has passed the discharge; above eject_above
  // it was thrown out of the top: both are taken out by the Simulation, neither fails.
  open.discharge_level = 0;
  open.eject_above = 1.5;
  EXPECT_EQ(check(2, {-1.0001, -0.05, 0}), "");
  EXPECT_EQ(check(2, {1.0001, -0.05, 0}), "");
  EXPECT_EQ(check(2, {-1.0001, 1.6, 0}), "");
  EXPECT_NE(check(2, {-1.0001, 0.05, 0}), "");  // between the two: through a wall
  EXPECT_NE(check(2, {1.0001, 1.4, 0}), "");
}

TEST(Guards, DeepOverlapFailsAndNamesTheLimit) {
  std::vector<Grain> gs{sphere_at(0, {0.002, 0.002, 0.001}), sphere_at(1, {0.003, 0.002, 0.001}, 0.5e-3)};
  Contact c;
  c.a = 0;
  c.b = 1;
  c.overlap = 0.6e-3;  // 0.6 of the smaller (1 mm) diameter
  const std::vector<Contact> cs{c};
  const std::string msg = failure_of([&] { check_invariants(GuardSettings{}, ctx(), box(), 3, 0.01, gs, kMat, cs); });
  EXPECT_NE(msg.find("overlaps grain 1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("max_overlap_fraction"), std::string::npos) << msg;
  EXPECT_NE(msg.find("solver_iterations"), std::string::npos) << msg;  // the engine's advice
  // Fragments of one grain (same origin) are born overlapping: not a failure.
  gs[0].origin = gs[1].origin = 5;
  EXPECT_EQ(failure_of([&] { check_invariants(GuardSettings{}, ctx(), box(), 3, 0.01, gs, kMat, cs); }), "");
  gs[1].origin = 6;
  EXPECT_NE(failure_of([&] { check_invariants(GuardSettings{}, ctx(), box(), 3, 0.01, gs, kMat, cs); }), "");
  // A grain below small_grain_fraction of the reference diameter is counted, not fatal.
  GuardContext big = ctx();
  big.reference_diameter = 5e-3;  // 0.25 × 5 mm = 1.25 mm > the 1 mm grain
  GuardReading counted;
  EXPECT_EQ(failure_of([&] { counted = check_invariants(GuardSettings{}, big, box(), 3, 0.01, gs, kMat, cs); }), "");
  EXPECT_EQ(counted.small_grain_overlaps, 1);
  GuardSettings loose;
  loose.max_overlap_fraction = 0.65;
  EXPECT_EQ(failure_of([&] { check_invariants(loose, ctx(), box(), 3, 0.01, gs, kMat, cs); }), "");
}

TEST(Guards, KineticEnergyAboveTheBudgetFails) {
  std::vector<Grain> gs{sphere_at(0, {0.005, 0.005, 0.002})};
  gs[0].angular_velocity = {0, 0, 1e4};  // ½ I ω², I = 0.4 m r²
  const double m = 2650 * (4.0 / 3.0) * M_PI * 1e-9;
  const double ke = 0.5 * 0.4 * m * 1e-6 * 1e8;
  EXPECT_NEAR(kinetic_energy(gs, kMat, 3), ke, 1e-9 * ke);
  const std::string msg =
      failure_of([&] { check_invariants(GuardSettings{}, ctx(ke / 20), box(), 3, 0.01, gs, kMat, {}); });
  EXPECT_NE(msg.find("kinetic energy"), std::string::npos) << msg;
  EXPECT_EQ(failure_of([&] { check_invariants(GuardSettings{}, ctx(ke / 5), box(), 3, 0.01, gs, kMat, {}); }), "");
}

TEST(Guards, ScalarInvariants) {
  const GuardSettings s;
  EXPECT_NE(failure_of([&] { check_scalar_invariants(s, ctx(), -1e-4, 0.5, 10); }).find("below the floor"),
            std::string::npos);
  EXPECT_NE(failure_of([&] { check_scalar_invariants(s, ctx(), 0.01, -0.2, 10); }).find("void ratio"),
            std::string::npos);
  EXPECT_NE(failure_of([&] { check_scalar_invariants(s, ctx(), 0.01, 0.5, std::nan("")); }).find("non-finite"),
            std::string::npos);
  EXPECT_EQ(failure_of([&] { check_scalar_invariants(s, ctx(), 0.01, 0.5, 10); }), "");
  // Switched off, only non-finite states still stop a run.
  GuardSettings off;
  off.enabled = false;
  EXPECT_EQ(failure_of([&] { check_scalar_invariants(off, ctx(), -1, -1, 10); }), "");
  EXPECT_NE(failure_of([&] { check_scalar_invariants(off, ctx(), std::nan(""), 1, 10); }), "");
}

TEST(Guards, TinyGrainOutsideTheContainerIsListedForRemovalNotFatal) {
  // A 0.2 mm grain below the floor, reference diameter 2 mm: 0.1 < small_grain_fraction 0.25.
  std::vector<Grain> gs{sphere_at(4, {0.005, 0.005, -1e-6}, 0.1e-3), sphere_at(5, {0.005, 0.005, 0.002})};
  GuardContext at = ctx();
  at.reference_diameter = 2e-3;
  GuardReading r;
  EXPECT_EQ(failure_of([&] { r = check_invariants(GuardSettings{}, at, box(), 3, 0.008, gs, kMat, {}); }), "");
  ASSERT_EQ(r.escaped_small.size(), 1u);
  EXPECT_EQ(r.escaped_small[0], 4);
  // A grain above the limit still stops the run; so does the tiny one without a reference.
  gs[1].position.z = -1e-4;
  EXPECT_NE(failure_of([&] { check_invariants(GuardSettings{}, at, box(), 3, 0.008, gs, kMat, {}); }).find("grain 5"),
            std::string::npos);
  gs[1].position.z = 0.002;
  EXPECT_NE(failure_of([&] { check_invariants(GuardSettings{}, ctx(), box(), 3, 0.008, gs, kMat, {}); }), "");
}

// The end of a stress ramp: the packing must carry at least half the commanded stress.
TEST(Guards, AStressRampEndsWithItsStressCarried) {
  const GuardSettings s;
  GuardContext at = ctx();
  at.platen_stress = 0.6e9;
  EXPECT_EQ(failure_of([&] { check_stress_carried(s, at, 1e9); }), "");
  at.platen_stress = 0;  // the platen touches nothing
  const std::string why = failure_of([&] { check_stress_carried(s, at, 1e9); });
  EXPECT_NE(why.find("carries 0 Pa of the 1e+09 Pa"), std::string::npos) << why;
  EXPECT_NE(why.find("loading.ramp_time"), std::string::npos) << why;
  at.platen_stress = 0.49e9;
  EXPECT_NE(failure_of([&] { check_stress_carried(s, at, 1e9); }), "");
  EXPECT_EQ(failure_of([&] { check_stress_carried(s, at, 0); }), "");  // nothing commanded
  GuardSettings off;
  off.enabled = false;
  EXPECT_EQ(failure_of([&] { check_stress_carried(off, at, 1e9); }), "");
}

// The kinetic energy of mass an engine added for its stable step (GuardContext::
// added_kinetic_energy) counts against the budget: a state within it at the true masses
// fails once the added mass's energy is counted, and the message says how much was added.
TEST(Guards, AddedMassKineticEnergyCountsAgainstTheBudget) {
  std::vector<Grain> gs{sphere_at(0, {0.005, 0.005, 0.002})};
  gs[0].velocity = {0.1, 0, 0};
  const double ke = kinetic_energy(gs, kMat, 3);
  GuardContext at = ctx(ke / 5);  // limit 10 × budget = 2 ke
  EXPECT_EQ(failure_of([&] { check_invariants(GuardSettings{}, at, box(), 3, 0.01, gs, kMat, {}); }), "");
  at.added_kinetic_energy = 3 * ke;  // a grain scaled ×4: 4 ke in all
  const std::string msg = failure_of([&] { check_invariants(GuardSettings{}, at, box(), 3, 0.01, gs, kMat, {}); });
  EXPECT_NE(msg.find("mass added for the stable step"), std::string::npos) << msg;
  at.added_kinetic_energy = 0.5 * ke;
  const GuardReading r = check_invariants(GuardSettings{}, at, box(), 3, 0.01, gs, kMat, {});
  EXPECT_NEAR(r.energy_ratio, 1.5 * ke / (ke / 5), 1e-12);
}
