// Engine `ode`: statics against closed forms (weights, load paths), free fall, Coulomb
// friction, conventions of contacts(), determinism, mid-run replacement, option checks.
// Mirrors tests/unit/bullet/test_bullet_engine.cpp.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <random>

#include "backends/ode/OdeEngine.h"
#include "core/Config.h"
#include "scenarios/Registry.h"

using namespace crumble;
using nlohmann::json;

namespace {

constexpr double kG = 9.81;
constexpr double kDensity = 2650;
constexpr double kDt = 5e-5;

std::unique_ptr<OdeEngine> make_engine(json opts = json::object(), Vec3 gravity = {0, 0, -kG},
                                       Material mat = Material{}) {
  opts["type"] = "ode";
  Config cfg(opts);
  EngineContext ctx;
  ctx.gravity = gravity;
  ctx.materials = {mat};
  auto e = make_ode_engine(cfg, ctx);
  cfg.check_unknown();
  return std::unique_ptr<OdeEngine>(static_cast<OdeEngine*>(e.release()));
}

Grain grain(GrainId id, Shape::Ptr s, Vec3 pos, Quat q = {}) {
  Grain g;
  g.id = id;
  g.shape = std::move(s);
  g.position = pos;
  g.orientation = q;
  return g;
}

double mass_of(const Shape::Ptr& s) { return kDensity * s->volume(); }

void run(Engine& e, int steps, double dt = kDt) {
  for (int i = 0; i < steps; ++i) e.step(dt);
}

Grain state_of(const Engine& e, const Grain& g0) {
  Grain g = g0;
  e.read_state(std::span<Grain>(&g, 1));
  return g;
}

}  // namespace

// One 2 mm grain at rest on the floor carries its weight through one floor contact.
class OdeRestingSphere : public ::testing::TestWithParam<const char*> {};

TEST_P(OdeRestingSphere, FloorCarriesTheWeight) {
  Material mat;
  mat.rolling_friction = 0;
  auto e = make_engine({{"sphere_representation", GetParam()}}, {0, 0, -kG}, mat);
  const auto s = Shape::sphere(1e-3);
  e->set_container({10e-3, 10e-3, 10e-3, 0});
  const Grain g0 = grain(0, s, {5e-3, 5e-3, 1.05e-3}, Quat::from_axis_angle({1, 2, 0}, 0.3));
  e->add_grain(g0);
  run(*e, 3000);  // 0.15 s: fall 0.05 mm, tip onto a face, settle
  const double mg = mass_of(s) * kG;
  EXPECT_NEAR(e->floor_force(), mg, 0.01 * mg);
  EXPECT_NEAR(e->platen_force(), 0.0, 1e-12);
  const auto cs = e->contacts();
  ASSERT_EQ(cs.size(), 1u);
  const Contact& c = cs[0];
  EXPECT_EQ(c.a, 0);
  EXPECT_EQ(c.b, -1);
  EXPECT_EQ(c.wall, kFloor);
  EXPECT_NEAR(c.force.z, mg, 0.01 * mg);
  EXPECT_NEAR(c.force.x, 0, 1e-3 * mg);
  EXPECT_NEAR(c.force.y, 0, 1e-3 * mg);
  EXPECT_NEAR(c.normal.z, 1.0, 1e-9);  // from the floor (b) towards the grain (a)
  EXPECT_GE(c.overlap, 0.0);
  EXPECT_LT(c.overlap, 0.01e-3);
  const Grain g = state_of(*e, g0);
  EXPECT_NEAR(c.point.z, 0.0, 0.03e-3);
  EXPECT_NEAR(c.point.x, g.position.x, 0.02e-3);
  EXPECT_NEAR(c.point.y, g.position.y, 0.02e-3);
  EXPECT_LT(norm(g.velocity), 1e-4);
  EXPECT_NEAR(g.position.z, 1e-3, 0.1e-3);
}

INSTANTIATE_TEST_SUITE_P(Representations, OdeRestingSphere, ::testing::Values("polyhedron", "sphere"));

// A stack of three cubes at rest: the floor carries 3mg, the contacts below the top and
// middle cubes mg and 2mg. Flat-on-flat contacts need several points (libccd gives one).
TEST(OdeEngine, StackOfThreeCubesAtRest) {
  auto e = make_engine();
  const auto s = Shape::box({1e-3, 1e-3, 1e-3});
  e->set_container({10e-3, 10e-3, 10e-3, 0});
  // ids: bottom 5, middle 2, top 9 (a = the smaller id in grain pairs)
  // Shape::box takes half extents: 2 mm cubes.
  e->add_grain(grain(5, s, {5e-3, 5e-3, 1.005e-3}));
  e->add_grain(grain(2, s, {5.2e-3, 4.9e-3, 3.01e-3}, Quat::from_axis_angle({0, 0, 1}, 0.4)));
  e->add_grain(grain(9, s, {5.0e-3, 5.1e-3, 5.02e-3}, Quat::from_axis_angle({0, 0, 1}, -0.3)));
  run(*e, 4000);
  const double mg = mass_of(s) * kG;
  EXPECT_NEAR(e->floor_force(), 3 * mg, 0.01 * 3 * mg);
  int seen = 0;
  for (const auto& c : e->contacts()) {
    if (c.is_wall()) {
      EXPECT_EQ(c.a, 5);
      EXPECT_EQ(c.wall, kFloor);
      EXPECT_NEAR(c.force.z, 3 * mg, 0.01 * 3 * mg);
      seen |= 1;
    } else if (c.a == 2 && c.b == 5) {  // middle on bottom: force on the middle is up
      EXPECT_NEAR(c.force.z, 2 * mg, 0.01 * 2 * mg);
      EXPECT_NEAR(c.normal.z, 1.0, 1e-6);
      EXPECT_NEAR(c.point.z, 2e-3, 0.05e-3);
      seen |= 2;
    } else if (c.a == 2 && c.b == 9) {  // top on middle: force on the middle is down
      EXPECT_NEAR(c.force.z, -mg, 0.01 * mg);
      EXPECT_NEAR(c.normal.z, -1.0, 1e-6);
      EXPECT_NEAR(c.point.z, 4e-3, 0.05e-3);
      seen |= 4;
    } else {
      ADD_FAILURE() << "unexpected contact " << c.a << "-" << c.b;
    }
  }
  EXPECT_EQ(seen, 7);
  const Grain top = state_of(*e, grain(9, s, {}));
  EXPECT_NEAR(top.position.z, 5e-3, 0.02e-3);
  EXPECT_LT(norm(top.velocity), 1e-4);
  EXPECT_LT(norm(top.angular_velocity), 1e-2);
}

// Free fall: semi-implicit Euler, v_n = −a·n·Δt and z_n = z0 − a·Δt²·n(n+1)/2 exactly (up
// to round-off) with a = g/mass_scale (the weight stays m·g, the mass is scaled: Zhu &
// Zhao's mass scaling slows the dynamics); the kinetic energy ms·m·v²/2 equals the work of
// the weight up to the integrator's offset.
TEST(OdeEngine, FreeFallMatchesTheClosedForm) {
  for (double ms : {1.0, 70.0}) {
    auto e = make_engine({{"mass_scale", ms}});
    const auto s = Shape::sphere(1e-3);
    e->set_container({10e-3, 10e-3, 100e-3, 0});
    const Grain g0 = grain(0, s, {5e-3, 5e-3, 50e-3});
    e->add_grain(g0);
    const int n = 1000;  // 0.05 s: falls 12 mm
    run(*e, n);
    const Grain g = state_of(*e, g0);
    const double acc = kG / ms;
    const double v = -acc * n * kDt, z = 50e-3 - acc * kDt * kDt * n * (n + 1) / 2;
    EXPECT_NEAR(g.velocity.z, v, 1e-9 * std::abs(v)) << "mass_scale " << ms;
    EXPECT_NEAR(g.position.z, z, 1e-9 * 50e-3) << "mass_scale " << ms;
    EXPECT_NEAR(g.velocity.x, 0, 1e-15);
    // Energy: the kinetic energy gained is the potential energy lost, up to the
    // integrator's O(Δt) offset (m·g·v·Δt/2).
    const double m = mass_of(s);
    const double ke = 0.5 * ms * m * g.velocity.z * g.velocity.z, pe = m * kG * (50e-3 - g.position.z);
    EXPECT_NEAR(ke, pe, 0.5 * m * kG * std::abs(v) * kDt * 1.01);
    EXPECT_TRUE(e->contacts().empty());
  }
}

namespace {

struct Packing {
  std::vector<Grain> grains;
  double weight = 0;
  Container box;
};

// A jittered 4x4x3 lattice of spheres (d 1.8–1.9 mm) in a 8.8 mm square box.
Packing lattice_packing(Engine& e, std::uint64_t seed) {
  Packing p;
  const int nx = 4, nz = 3;
  const double sp = 2.2e-3;
  p.box = {nx * sp, nx * sp, nz * sp + 0.3e-3, 0};
  e.set_container(p.box);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  GrainId id = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < nx; ++j)
      for (int i = 0; i < nx; ++i) {
        const auto s = Shape::sphere(0.5 * (1.85e-3 + 0.05e-3 * u(rng)));
        Grain g = grain(id++, s,
                        {sp * (i + 0.5) + 0.1e-3 * u(rng), sp * (j + 0.5) + 0.1e-3 * u(rng), sp * (k + 0.5)},
                        Quat::from_axis_angle({u(rng), u(rng), u(rng)}, 3 * u(rng)));
        e.add_grain(g);
        p.grains.push_back(g);
        p.weight += mass_of(s) * kG;
      }
  return p;
}

int load_packing(Engine& e, double force, int hold_steps) {
  int steps = 0;
  for (; steps < 1000; ++steps) e.step(kDt);
  e.set_platen({PlatenCommand::Mode::Velocity, -0.1});
  for (int k = 0; k < 4000 && !(e.platen_force() > 0); ++k, ++steps) e.step(kDt);
  const int ramp = 500;
  for (int k = 1; k <= ramp; ++k, ++steps) {
    e.set_platen({PlatenCommand::Mode::Force, force * k / ramp});
    e.step(kDt);
  }
  for (int k = 0; k < hold_steps; ++k, ++steps) e.step(kDt);
  return steps;
}

}  // namespace

// Quasi-static packing under a force-controlled platen: the platen carries the command,
// the floor carries the platen force plus the weight (frictionless side walls).
TEST(OdeEngine, LoadedPackingBalancesPlatenFloorAndWeight) {
  auto e = make_engine();
  const Packing p = lattice_packing(*e, 11);
  const double F = 1e5 * p.box.lx * p.box.ly;  // 0.1 MPa
  load_packing(*e, F, 800);
  double fp = 0, ff = 0;
  const int n = 50;
  for (int k = 0; k < n; ++k) {
    e->step(kDt);
    fp += e->platen_force() / n;
    ff += e->floor_force() / n;
  }
  EXPECT_NEAR(fp, F, 0.02 * F);
  EXPECT_NEAR(ff - p.weight, fp, 0.02 * fp);
  double sum_floor = 0, sum_platen = 0;
  for (const auto& c : e->contacts()) {
    if (c.wall == kFloor) sum_floor += c.force.z;
    if (c.wall == kPlaten) sum_platen -= c.force.z;
    EXPECT_TRUE(is_finite(c.force) && is_finite(c.point) && is_finite(c.normal));
    if (c.wall == kWallXMin) { EXPECT_GT(c.normal.x, 0.99); }
    if (c.wall == kWallYMax) { EXPECT_LT(c.normal.y, -0.99); }
    if (c.wall == kPlaten) { EXPECT_LT(c.normal.z, -0.99); }
  }
  EXPECT_NEAR(sum_floor, e->floor_force(), 1e-9 * F);
  EXPECT_NEAR(sum_platen, e->platen_force(), 1e-9 * F);
  EXPECT_LT(e->platen_position(), p.box.height);
  std::vector<Grain> gs = p.grains;
  e->read_state(gs);
  for (const auto& g : gs) {
    EXPECT_GT(g.position.z, 0.5e-3);
    EXPECT_LT(g.position.z, e->platen_position());
    EXPECT_GT(g.position.x, 0.5e-3);
    EXPECT_LT(g.position.x, p.box.lx - 0.5e-3);
  }
}

// Two identical runs are bit-identical.
TEST(OdeEngine, IdenticalRunsAreBitIdentical) {
  auto once = [](std::vector<Grain>& out, std::vector<Contact>& cs, double& fp) {
    auto e = make_engine();
    Packing p = lattice_packing(*e, 5);
    load_packing(*e, 5.0, 100);
    out = p.grains;
    e->read_state(out);
    cs = e->contacts();
    fp = e->platen_force();
  };
  std::vector<Grain> g1, g2;
  std::vector<Contact> c1, c2;
  double f1 = 0, f2 = 0;
  once(g1, c1, f1);
  once(g2, c2, f2);
  ASSERT_EQ(g1.size(), g2.size());
  for (std::size_t i = 0; i < g1.size(); ++i) {
    EXPECT_EQ(std::memcmp(&g1[i].position, &g2[i].position, sizeof(Vec3)), 0);
    EXPECT_EQ(std::memcmp(&g1[i].orientation, &g2[i].orientation, sizeof(Quat)), 0);
    EXPECT_EQ(std::memcmp(&g1[i].velocity, &g2[i].velocity, sizeof(Vec3)), 0);
  }
  ASSERT_EQ(c1.size(), c2.size());
  ASSERT_GT(c1.size(), 10u);
  for (std::size_t i = 0; i < c1.size(); ++i) {
    EXPECT_EQ(c1[i].a, c2[i].a);
    EXPECT_EQ(c1[i].b, c2[i].b);
    EXPECT_EQ(std::memcmp(&c1[i].force, &c2[i].force, sizeof(Vec3)), 0);
  }
  EXPECT_EQ(std::memcmp(&f1, &f2, sizeof(double)), 0);
}

// A grain replaced mid-run by its two halves: no NaN, the halves settle and the floor
// carries the same weight.
TEST(OdeEngine, ReplacingAGrainByTwoHalvesMidRun) {
  auto e = make_engine();
  e->set_container({10e-3, 10e-3, 10e-3, 0});
  const auto whole = Shape::box({2e-3, 1e-3, 1e-3});
  const auto half = Shape::box({1e-3, 1e-3, 1e-3});
  const auto ball = Shape::sphere(0.9e-3);
  const Quat q = Quat::from_axis_angle({0, 0, 1}, 0.3);
  Grain parent = grain(7, whole, {5e-3, 5e-3, 1.01e-3}, q);  // half extents
  e->add_grain(parent);
  e->add_grain(grain(8, ball, {5e-3, 5e-3, 3.2e-3}));
  run(*e, 1000);
  parent = state_of(*e, parent);
  std::vector<Grain> kids;
  for (int k = 0; k < 2; ++k) {
    const Vec3 r = parent.orientation.rotate({k == 0 ? -1e-3 : 1e-3, 0, 0});
    Grain c = grain(20 + k, half, parent.position + r, parent.orientation);
    c.parent = parent.id;
    c.velocity = parent.velocity + cross(parent.angular_velocity, r);
    c.angular_velocity = parent.angular_velocity;
    kids.push_back(c);
  }
  e->replace_grain(parent.id, kids);
  EXPECT_EQ(e->grain_count(), 3u);
  EXPECT_THROW(e->remove_grain(parent.id), std::invalid_argument);
  for (const auto& c : e->contacts()) EXPECT_NE(c.a, 7);
  for (int k = 0; k < 2000; ++k) {
    e->step(kDt);
    ASSERT_TRUE(std::isfinite(e->floor_force())) << "step " << k;
  }
  const double W = (mass_of(whole) + mass_of(ball)) * kG;
  EXPECT_NEAR(e->floor_force(), W, 0.01 * W);
  for (auto& c : kids) {
    c = state_of(*e, c);
    EXPECT_TRUE(is_finite(c.position) && is_finite(c.velocity));
    EXPECT_NEAR(c.position.z, 1e-3, 0.05e-3);
  }
}

// The kinematic platen moves at the commanded velocity and pushes grains; a force-driven
// platen with nothing below falls at F/M with the mass rule of core/Platen.h.
TEST(OdeEngine, PlatenFollowsTheSharedCommandRules) {
  {
    auto e = make_engine();
    e->set_container({10e-3, 10e-3, 4e-3, 0});
    EXPECT_DOUBLE_EQ(e->platen_position(), 4e-3);
    const auto s = Shape::sphere(1e-3);
    e->add_grain(grain(0, s, {5e-3, 5e-3, 1e-3}));
    e->set_platen({PlatenCommand::Mode::Velocity, -0.01});
    run(*e, 1000);
    EXPECT_NEAR(e->platen_position(), 3.5e-3, 1e-12);
    EXPECT_EQ(e->platen_force(), 0.0);
    e->set_platen({PlatenCommand::Mode::Velocity, -0.1});
    run(*e, 400);
    EXPECT_NEAR(e->platen_position(), 1.5e-3, 1e-12);
    EXPECT_GT(e->platen_force(), 0.0);
  }
  for (double platen_mass : {0.0, 1e-3}) {
    auto e = make_engine({{"mass_scale", 10}});
    e->set_container({10e-3, 10e-3, 8e-3, platen_mass});
    const auto s = Shape::sphere(1e-3);
    e->add_grain(grain(0, s, {5e-3, 5e-3, 1e-3}));
    const double F = 1e-3;  // N
    e->set_platen({PlatenCommand::Mode::Force, F});
    const int n = 200;
    run(*e, n);
    const double M = (platen_mass > 0 ? platen_mass : mass_of(s)) * 10;
    const double a = F / M;
    const double expect = 8e-3 - a * kDt * kDt * n * (n + 1) / 2;
    EXPECT_NEAR(e->platen_position(), expect, 1e-6 * (8e-3 - expect)) << "platen_mass " << platen_mass;
  }
}

// Coulomb friction (dContactApprox1): a sliding cube stops after v²/(2μg), μ the wall
// friction on the floor and the grain friction on another grain.
TEST(OdeEngine, SlidingFrictionStopsAtTheCoulombDistance) {
  Material mat;
  mat.friction = 0.5;
  mat.wall_friction = 0.3;
  mat.rolling_friction = 0;
  const double v0 = 0.05;
  const auto cube = Shape::box({1e-3, 1e-3, 1e-3});
  {
    auto e = make_engine({}, {0, 0, -kG}, mat);
    e->set_container({20e-3, 20e-3, 10e-3, 0});
    Grain s = grain(0, cube, {5e-3, 10e-3, 1e-3});  // half extents: touching the floor
    s.velocity = {v0, 0, 0};
    e->add_grain(s);
    run(*e, 800);
    const Grain r = state_of(*e, s);
    const double expect = v0 * v0 / (2 * mat.wall_friction * kG) - 0.5 * v0 * kDt;
    EXPECT_NEAR(r.position.x - s.position.x, expect, 0.01 * expect);
    EXPECT_NEAR(r.velocity.x, 0.0, 1e-5);
  }
  {
    auto e = make_engine({}, {0, 0, -kG}, mat);
    e->set_container({20e-3, 20e-3, 10e-3, 0});
    const auto slab = Shape::box({8e-3, 8e-3, 1e-3});
    e->add_grain(grain(0, slab, {10e-3, 10e-3, 1e-3}));
    Grain s = grain(1, cube, {5e-3, 10e-3, 3e-3});
    s.velocity = {v0, 0, 0};
    e->add_grain(s);
    run(*e, 800);
    const Grain r = state_of(*e, s);
    const double expect = v0 * v0 / (2 * mat.friction * kG) - 0.5 * v0 * kDt;
    EXPECT_NEAR(r.position.x - s.position.x, expect, 0.02 * expect);
  }
}

// Mass scaling keeps the weights physical.
TEST(OdeEngine, MassScalingKeepsWeightsPhysical) {
  auto e = make_engine({{"mass_scale", 70}});
  const auto s = Shape::box({1e-3, 1e-3, 1e-3});
  e->set_container({10e-3, 10e-3, 10e-3, 0});
  e->add_grain(grain(0, s, {5e-3, 5e-3, 1.02e-3}));
  run(*e, 1500);
  const double mg = mass_of(s) * kG;
  EXPECT_NEAR(e->floor_force(), mg, 0.01 * mg);
}

// Rolling friction (dContactRolling) as a lever arm μr in the internal length unit, like
// Bullet: a rolling ball decelerates at μr·L·g / (1.4 r).
TEST(OdeEngine, RollingFrictionIsALeverArmInTheInternalUnit) {
  Material mat;
  mat.rolling_friction = 0.05;
  mat.wall_friction = 0.5;
  auto e = make_engine({{"sphere_representation", "sphere"}, {"length_scale", 500}}, {0, 0, -kG}, mat);
  e->set_container({40e-3, 20e-3, 10e-3, 0});
  const double r = 1e-3, v0 = 0.02;
  Grain g = grain(0, Shape::sphere(r), {5e-3, 10e-3, r});
  g.velocity = {v0, 0, 0};
  g.angular_velocity = {0, v0 / r, 0};
  e->add_grain(g);
  EXPECT_EQ(e->length_scale(), 500.0);
  run(*e, 1200);
  const Grain s = state_of(*e, g);
  const double a = mat.rolling_friction * (1 / 500.0) * kG / (1.4 * r);
  const double expect = v0 * v0 / (2 * a);
  EXPECT_NEAR(s.position.x - g.position.x, expect, 0.03 * expect);
  EXPECT_NEAR(s.velocity.x, 0.0, 1e-4);
}

TEST(OdeEngine, UsesDoublePrecisionOde) {
  std::string why;
  EXPECT_TRUE(ode_double_precision_ok(&why)) << why;
}

TEST(OdeEngine, BadOptionsAreConfigErrors) {
  auto expect_error = [](json opts, const std::string& key) {
    opts["type"] = "ode";
    Config cfg(opts);
    EngineContext ctx;
    try {
      auto e = make_ode_engine(cfg, ctx);
      cfg.check_unknown();
      FAIL() << "no error for " << opts.dump();
    } catch (const ConfigError& err) {
      EXPECT_NE(std::string(err.what()).find(key), std::string::npos) << err.what();
    }
  };
  expect_error({{"solver_iterations", 0}}, "solver_iterations");
  expect_error({{"length_scale", -1}}, "length_scale");
  expect_error({{"mass_scale", 0}}, "mass_scale");
  expect_error({{"erp", 2}}, "erp");
  expect_error({{"cfm", -1}}, "cfm");
  expect_error({{"sor_w", 2.5}}, "sor_w");
  expect_error({{"contacts_per_pair", 0}}, "contacts_per_pair");
  expect_error({{"sphere_representation", "cube"}}, "sphere_representation");
  expect_error({{"solver_iteration", 10}}, "solver_iteration");
  json opts = {{"type", "ode"}};
  Config cfg(opts);
  auto e = engines().find("ode", "/engine").make(cfg, EngineContext{});
  cfg.check_unknown();
  EXPECT_EQ(e->name(), "ode");
  EXPECT_EQ(opts["solver_iterations"], 100);
  EXPECT_EQ(opts["contacts_per_pair"], 4);
  EngineContext flat;
  flat.dimension = 2;
  json o2 = {{"type", "ode"}};
  Config c2(o2);
  EXPECT_THROW(make_ode_engine(c2, flat), ConfigError);
}
