// lsdem selective mass scaling (engine.selective_dt / selective_dt_fraction):
// a grain below the target step gets mass and inertia × (target / own step)² — its own step
// is then the target (closed form); its acceleration under a force is F/(s·m) and its weight
// stays m·g, and global damping acts on m; the added mass and its kinetic energy are
// reported; an inactive target changes no bit; the state survives save_state / restore_state exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>

#include "backends/lsdem/LsdemEngine.h"
#include "core/Config.h"
#include "tests/support/EngineKit.h"

using namespace crumble;

using crumble::testing_support::grain;

namespace {

constexpr double kRho = 1000;

EngineContext context(Vec3 gravity = {}) {
  EngineContext c;
  c.dimension = 3;
  c.gravity = gravity;
  Material m;
  m.density = kRho;
  m.friction = 0.5;
  m.wall_friction = 0.0;
  c.materials = {m};
  return c;
}

Shape::Ptr sphere(double r, double h, int nodes) { return crumble::testing_support::level_set_sphere(r, h, nodes); }

// A grain's own stable step at its true mass: dt_safety·√(ρV/k).
double own_step(const LsdemSettings& s, const Shape::Ptr& sh) { return s.dt_safety * std::sqrt(kRho * sh->volume() / s.kn); }

}  // namespace

// Two grains, one above the target and one below: the stable step is the target (closed
// form: the small grain's mass × (target/own step)²), the large grain is untouched (the step
// of the two without scaling is the small one's), and the figures name one grain, its
// factor and its added mass.
TEST(LsdemSelective, ScaledGrainStepEqualsTheTarget) {
  LsdemSettings s;
  s.kn = 1e6;
  const auto big = sphere(1.0, 0.1, 1000), small = sphere(0.2, 0.02, 400);
  const double target = 0.5 * (own_step(s, big) + own_step(s, small));
  ASSERT_LT(own_step(s, small), target);
  ASSERT_GT(own_step(s, big), target);
  LsdemEngine plain(s, context());
  s.selective_dt = target;
  LsdemEngine e(s, context());
  for (LsdemEngine* x : {&plain, &e}) {
    x->add_grain(grain(0, big, {0, 0, 5}));
    x->add_grain(grain(1, small, {5, 0, 5}));
  }
  EXPECT_NEAR(plain.max_stable_dt() / own_step(s, small), 1.0, 1e-12);
  EXPECT_NEAR(e.max_stable_dt() / target, 1.0, 1e-12);
  EXPECT_EQ(e.selective_target_dt(), target);
  const auto f = e.summary_figures();
  const double factor = std::pow(target / own_step(s, small), 2);
  const double m_small = kRho * small->volume(), m_big = kRho * big->volume();
  EXPECT_EQ(f.at("selective_scaling_grains_scaled"), 1);
  EXPECT_NEAR(f.at("selective_scaling_max_factor") / factor, 1.0, 1e-12);
  EXPECT_NEAR(f.at("selective_scaling_added_mass_kg") / ((factor - 1) * m_small), 1.0, 1e-12);
  EXPECT_NEAR(f.at("selective_scaling_added_mass_fraction") / ((factor - 1) * m_small / (m_small + m_big)), 1.0, 1e-12);
  EXPECT_NEAR(f.at("selective_scaling_target_dt_s"), target, 0);
  EXPECT_TRUE(plain.summary_figures().empty()) << "off: no figures";
}

// Mass and inertia are both scaled by s: a scaled grain spinning and moving freely has the
// engine's kinetic energy s × its physical one, and the added mass carries (s − 1) × it
// (added_kinetic_energy, what the energy guard adds).
TEST(LsdemSelective, AddedKineticEnergyIsTheScaledInertias) {
  LsdemSettings s;
  s.kn = 1e6;
  const auto small = sphere(0.2, 0.02, 400);
  const double target = 3 * own_step(s, small), factor = 9;
  s.selective_dt = target;
  LsdemEngine e(s, context());
  Grain g = grain(0, small, {0, 0, 5}, Quat::from_axis_angle({1, 2, 3}, 0.4));
  g.velocity = {0.3, -0.2, 0.1};
  g.angular_velocity = {2, -1, 0.5};
  e.add_grain(g);
  const Mat3 I = g.orientation.matrix() * (small->mass_properties().inertia * kRho) * g.orientation.matrix().transposed();
  const double ke = 0.5 * kRho * small->volume() * norm2(g.velocity) + 0.5 * dot(g.angular_velocity, I * g.angular_velocity);
  EXPECT_NEAR(e.kinetic_energy() / (factor * ke), 1.0, 1e-9);
  EXPECT_NEAR(e.added_kinetic_energy() / ((factor - 1) * ke), 1.0, 1e-9);
}

// Equations of motion with the scaled inertia: a grain pressed into the floor (no gravity)
// gains v = F·dt/(s·m) in its first step, F the floor's force on it as the engine reports
// it (to rounding), and F ≈ k_n·δ (3 %: the deepest node's depth against δ on this grid).
TEST(LsdemSelective, ContactAccelerationUsesTheScaledMass) {
  LsdemSettings s;
  s.kn = 1e6;
  s.damping_ratio = 0;
  const auto sh = sphere(1.0, 0.025, 8000);
  const double delta = 0.02, factor = 16;
  s.selective_dt = 4 * own_step(s, sh);
  LsdemEngine e(s, context());
  Container box;
  box.lx = box.ly = 10;
  e.set_container(box);
  e.add_grain(grain(0, sh, {5, 5, 1.0 - delta}));
  const double dt = 1e-6;
  e.step(dt);
  std::vector<Grain> g(1);
  g[0].id = 0;
  e.read_state(g);
  const std::vector<Contact> cs = e.contacts();
  ASSERT_EQ(cs.size(), 1u);
  const double f = cs[0].a == 0 ? cs[0].force.z : -cs[0].force.z;
  EXPECT_NEAR(f / (s.kn * delta), 1.0, 0.03);
  EXPECT_NEAR(g[0].velocity.z / (f * dt / (factor * kRho * sh->volume())), 1.0, 1e-12);
}

// Weight is the true mass's: weight m·g on the inertia s·m gives the first step from rest
// v = g·dt/s; at rest on the floor the grain pushes the floor with m·g, not s·m·g (1 %: the
// floor force once the damped bounce settled).
TEST(LsdemSelective, WeightUsesTheTrueMass) {
  LsdemSettings s;
  s.kn = 1e7;
  s.damping_ratio = 0.7;
  s.global_damping = 1;
  const auto sh = sphere(1.0, 0.05, 4000);
  const double factor = 25;
  s.selective_dt = 5 * own_step(s, sh);
  LsdemEngine e(s, context({0, 0, -9.81}));
  e.set_container({});
  e.add_grain(grain(0, sh, {0, 0, 1.5}));
  const double dt = e.max_stable_dt();
  EXPECT_NEAR(dt / s.selective_dt, 1.0, 1e-12);
  std::vector<Grain> g(1);
  g[0].id = 0;
  e.step(dt);
  e.read_state(g);
  // One step from rest (the global damping acts on v = 0): v = (m·g/(s·m))·dt.
  EXPECT_NEAR(g[0].velocity.z / (-9.81 / factor * dt), 1.0, 1e-12);
  for (int i = 0; i < 20000; ++i) e.step(dt);
  EXPECT_NEAR(e.floor_force() / (kRho * sh->volume() * 9.81), 1.0, 0.01);
}

// Global damping acts on the mass before the factor: a free grain loses C_g·Δt/s of its
// velocity and spin per step (closed form of the leapfrog update with a = −(C_g/s)·v), so
// that under a steady force it drifts at F/(C_g·m) as unscaled; the unscaled grain loses
// C_g·Δt. (Damping the added mass too held the fragments of the 2D Harmon oedometer back.)
TEST(LsdemSelective, GlobalDampingActsOnTheMassBeforeScaling) {
  LsdemSettings s;
  s.kn = 1e6;
  s.global_damping = 50;
  const auto sh = sphere(0.2, 0.02, 400);
  const double factor = 9;
  LsdemEngine plain(s, context());
  s.selective_dt = 3 * own_step(s, sh);
  LsdemEngine e(s, context());
  const double dt = 1e-4;
  for (LsdemEngine* x : {&plain, &e}) {
    Grain g = grain(0, sh, {0, 0, 5});
    g.velocity = {0.3, -0.2, 0.1};
    g.angular_velocity = {0, 0, 2};
    x->add_grain(g);
    x->step(dt);
  }
  std::vector<Grain> a(1), b(1);
  a[0].id = b[0].id = 0;
  plain.read_state(a);
  e.read_state(b);
  EXPECT_NEAR(a[0].velocity.x / 0.3, 1 - s.global_damping * dt, 1e-12);
  EXPECT_NEAR(b[0].velocity.x / 0.3, 1 - s.global_damping * dt / factor, 1e-12);
  EXPECT_NEAR(b[0].velocity.y / -0.2, 1 - s.global_damping * dt / factor, 1e-12);
  EXPECT_NEAR(b[0].angular_velocity.z / 2, 1 - s.global_damping * dt / factor, 1e-6);
}

// A target below every grain's own step scales nothing, and the run is the unscaled run bit
// for bit (the weight, the platen's mass rule and the inertia take the same values).
TEST(LsdemSelective, AnInactiveTargetChangesNoBit) {
  LsdemSettings s;
  s.kn = 2e4;
  auto run = [](const LsdemSettings& st) {
    LsdemEngine e(st, context({0, 0, -9.81}));
    Container box;
    box.lx = box.ly = 1;
    box.height = 3;
    e.set_container(box);
    e.set_platen({PlatenCommand::Mode::Force, 50});
    for (int i = 0; i < 8; ++i)
      e.add_grain(grain(i, sphere(0.1 + 0.01 * i, 0.02, 300), {0.2 + 0.2 * (i % 4), 0.3 + 0.3 * (i / 4), 0.3 + 0.25 * i}));
    for (int i = 0; i < 300; ++i) e.step(e.max_stable_dt());
    nlohmann::json st_out;
    e.save_state(st_out);
    st_out.erase("selective_scaling");
    return st_out.dump() + std::to_string(e.platen_position()) + std::to_string(e.platen_force());
  };
  const std::string off = run(s);
  s.selective_dt = 1e-12;
  EXPECT_EQ(off, run(s));
  s.selective_dt = 0;
  s.selective_dt_fraction = 1;  // the initial packing's own step: nothing below it
  EXPECT_EQ(off, run(s));
}

// Fraction mode: the target is fixed at the first step from the grains then (no grain scaled);
// a fragment added later below it is scaled to it.
TEST(LsdemSelective, FractionOfTheInitialStep) {
  LsdemSettings s;
  s.kn = 1e6;
  s.selective_dt_fraction = 0.5;
  LsdemEngine e(s, context());
  const auto big = sphere(1.0, 0.1, 1000), small = sphere(0.2, 0.02, 400);
  e.add_grain(grain(0, big, {0, 0, 5}));
  EXPECT_EQ(e.selective_target_dt(), 0) << "not fixed before the first step";
  e.step(1e-6);
  EXPECT_NEAR(e.selective_target_dt() / (0.5 * own_step(s, big)), 1.0, 1e-12);
  EXPECT_EQ(e.summary_figures().at("selective_scaling_grains_scaled"), 0);
  e.add_grain(grain(1, small, {5, 0, 5}));
  EXPECT_NEAR(e.max_stable_dt() / (0.5 * own_step(s, big)), 1.0, 1e-12);
  EXPECT_EQ(e.summary_figures().at("selective_scaling_grains_scaled"), 1);
}

// save_state / restore_state carry the target and the factors: an engine rebuilt from the
// grains and restored steps on as the original does, bit for bit.
TEST(LsdemSelective, StateRoundTripIsExact) {
  LsdemSettings s;
  s.kn = 2e4;
  s.selective_dt_fraction = 0.8;
  const auto big = sphere(0.15, 0.02, 300), tiny = sphere(0.04, 0.01, 200);
  std::vector<Grain> grains;
  auto fill = [&](LsdemEngine& e, bool with_tiny) {
    Container box;
    box.lx = box.ly = 1;
    e.set_container(box);
    for (int i = 0; i < 6; ++i) e.add_grain(grain(i, big, {0.2 + 0.3 * (i % 3), 0.3 + 0.4 * (i / 3), 0.2 + 0.2 * i}));
    if (with_tiny) e.add_grain(grain(10, tiny, {0.5, 0.5, 1.8}));
  };
  LsdemEngine a(s, context({0, 0, -9.81}));
  fill(a, false);
  for (int i = 0; i < 100; ++i) a.step(a.max_stable_dt());
  a.add_grain(grain(10, tiny, {0.5, 0.5, 1.8}));  // a fragment born after the target was fixed
  ASSERT_EQ(a.summary_figures().at("selective_scaling_grains_scaled"), 1);
  for (int i = 0; i < 100; ++i) a.step(a.max_stable_dt());
  nlohmann::json saved;
  ASSERT_TRUE(a.save_state(saved));
  ASSERT_TRUE(saved.contains("selective_scaling"));
  LsdemEngine b(s, context({0, 0, -9.81}));
  fill(b, true);  // the checkpoint's grains, added before the target is known
  b.restore_state(saved);
  EXPECT_EQ(a.max_stable_dt(), b.max_stable_dt());
  for (int i = 0; i < 200; ++i) {
    a.step(a.max_stable_dt());
    b.step(b.max_stable_dt());
  }
  nlohmann::json sa, sb;
  a.save_state(sa);
  b.save_state(sb);
  EXPECT_EQ(sa.dump(), sb.dump());
  // A state without the scaling for a scenario with it, and the reverse, are refused.
  nlohmann::json stripped = saved;
  stripped.erase("selective_scaling");
  EXPECT_THROW(b.restore_state(stripped), std::invalid_argument);
  LsdemSettings off = s;
  off.selective_dt_fraction = 0;
  LsdemEngine c(off, context({0, 0, -9.81}));
  fill(c, true);
  EXPECT_THROW(c.restore_state(saved), std::invalid_argument);
}

// Both targets at once is a configuration error naming the key.
TEST(LsdemSelective, BothTargetsAreRefused) {
  nlohmann::json doc = {{"engine", {{"type", "lsdem"}, {"selective_dt", 1e-7}, {"selective_dt_fraction", 0.5}}}};
  Config root(doc);
  try {
    make_lsdem_engine(root.child("engine"), context());
    FAIL() << "accepted both targets";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("selective_dt_fraction"), std::string::npos) << e.what();
  }
  nlohmann::json neg = {{"engine", {{"type", "lsdem"}, {"selective_dt_fraction", 1.5}}}};
  Config r2(neg);
  EXPECT_THROW(make_lsdem_engine(r2.child("engine"), context()), ConfigError);
}

// Size-following stiffness (engine.kn_reference_radius): a contact's force is the constant-kn
// contact's × R_min/R_ref (the same nodes penetrate: exact to rounding), grain–grain and on a
// wall; the stable step is the smallest dt_safety·√(m·R_ref/(k·R)) over the grains.
TEST(LsdemSizeStiffness, ForceAndStepFollowTheRadius) {
  LsdemSettings s;
  s.kn = 1e6;
  s.damping_ratio = 0;
  const auto big = sphere(1.0, 0.05, 2000), small = sphere(0.5, 0.025, 1000);
  const double rref = 0.8;
  auto forces = [&](const LsdemSettings& st) {
    LsdemEngine e(st, context());
    Container box;
    box.lx = box.ly = 10;
    e.set_container(box);
    e.add_grain(grain(0, big, {5, 5, 3}));
    e.add_grain(grain(1, small, {5, 5, 3 + 1.5 - 0.02}));  // pressed into the big one
    e.add_grain(grain(2, small, {2, 2, 0.5 - 0.01}));      // pressed into the floor
    e.step(1e-9);
    std::map<std::pair<GrainId, GrainId>, double> f;
    for (const auto& c : e.contacts()) f[{std::min(c.a, c.b), std::max(c.a, c.b)}] = norm(c.force);
    return std::make_pair(f, e.max_stable_dt());
  };
  const auto [f0, dt0] = forces(s);
  s.kn_reference_radius = rref;
  const auto [f1, dt1] = forces(s);
  ASSERT_EQ(f0.size(), 2u);
  ASSERT_EQ(f1.size(), 2u);
  const double r_small = 0.5 * small->equivalent_diameter(), r_big = 0.5 * big->equivalent_diameter();
  for (const auto& [k, v] : f0) EXPECT_NEAR(f1.at(k) / v, r_small / rref, 1e-12) << k.first << " " << k.second;
  const double q = std::min(kRho * small->volume() / r_small, kRho * big->volume() / r_big);
  EXPECT_NEAR(dt1 / (s.dt_safety * std::sqrt(q * rref / s.kn)), 1.0, 1e-12);
  EXPECT_NEAR(dt0 / own_step(s, small), 1.0, 1e-12);
  // Hertz already follows the radius: refused.
  nlohmann::json doc = {{"engine", {{"type", "lsdem"}, {"contact_law", "hertz"}, {"kn_reference_radius", 1e-3}}}};
  Config root(doc);
  EXPECT_THROW(make_lsdem_engine(root.child("engine"), context()), ConfigError);
}
