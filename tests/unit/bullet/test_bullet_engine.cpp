// Engine `bullet`: what is Bullet's own — precision, option checks, the principal inertia
// frame, the velocity platen, rolling friction in Bullet's internal unit. What every engine
// must pass (weight, stack of three, platen = floor − weight, free fall, determinism,
// mid-run replacement, Coulomb sliding, mass scaling) is in tests/conformance/engines.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "backends/bullet/BulletEngine.h"
#include "geometry/SymmetricEigen.h"
#include "core/Config.h"
#include "scenarios/Registry.h"
#include "tests/support/CupDrop.h"
#include "tests/support/EngineKit.h"
#include "tests/support/RollingCouple.h"

using namespace crumble;
using nlohmann::json;

using namespace crumble::testing_support;

namespace {

std::unique_ptr<BulletEngine> make_engine(json opts = json::object(), Vec3 gravity = {0, 0, -kG}, Material mat = Material{}) {
  return make_engine_as<BulletEngine>("bullet", make_bullet_engine, std::move(opts), gravity, mat);
}

}  // namespace

// (f) Double precision throughout (mixing builds corrupts memory).
TEST(BulletEngine, UsesDoublePrecisionBullet) {
  std::string why;
  EXPECT_TRUE(bullet_double_precision_ok(&why)) << why;
}

// (g) Options are checked: bad values and unknown keys are ConfigErrors naming the key.
TEST(BulletEngine, BadOptionsAreConfigErrors) {
  auto expect_error = [](json opts, const std::string& key) {
    opts["type"] = "bullet";
    Config cfg(opts);
    EngineContext ctx;
    try {
      auto e = make_bullet_engine(cfg, ctx);
      cfg.check_unknown();
      FAIL() << "no error for " << opts.dump();
    } catch (const ConfigError& err) {
      EXPECT_NE(std::string(err.what()).find(key), std::string::npos) << err.what();
    }
  };
  expect_error({{"margin_fraction", -0.01}}, "margin_fraction");
  expect_error({{"margin_fraction", 0.5}}, "margin_fraction");
  expect_error({{"solver_iterations", 0}}, "solver_iterations");
  expect_error({{"length_scale", -1}}, "length_scale");
  expect_error({{"mass_scale", 0}}, "mass_scale");
  expect_error({{"erp", 2}}, "erp");
  expect_error({{"sphere_representation", "cube"}}, "sphere_representation");
  expect_error({{"solver_iteration", 10}}, "solver_iteration");  // misspelt key
  // Defaults are recorded in the effective scenario; the registry knows the name.
  json opts = {{"type", "bullet"}};
  Config cfg(opts);
  auto e = engines().find("bullet", "/engine").make(cfg, EngineContext{});
  cfg.check_unknown();
  EXPECT_EQ(e->name(), "bullet");
  EXPECT_EQ(opts["solver_iterations"], 100);
  EXPECT_EQ(opts["erp"], 0.003);
  EXPECT_EQ(opts["sphere_representation"], "polyhedron");
  // A 2D scenario is refused.
  EngineContext flat;
  flat.dimension = 2;
  json o2 = {{"type", "bullet"}};
  Config c2(o2);
  EXPECT_THROW(make_bullet_engine(c2, flat), ConfigError);
}

// Poses in the shape's own frame although the body lives in its principal frame, and
// the same dynamics as the identical body described in its principal frame.
TEST(BulletEngine, NonDiagonalInertiaUsesThePrincipalFrame) {
  // A 4:2:1 box given as a rotated mesh: its inertia is not diagonal in the shape frame.
  const Quat tilt = Quat::from_axis_angle({1, 1, 0}, 0.6);
  const auto plain = Shape::box({2e-3, 1e-3, 0.5e-3});
  TriMesh m = plain->mesh();
  for (auto& v : m.vertices) v = tilt.rotate(v);
  const auto tilted = Shape::polyhedron(m);
  const Mat3& I = tilted->mass_properties().inertia;
  EXPECT_GT(std::abs(I(0, 1)), 1e-2 * I.trace());
  const auto pa = principal_axes(I);
  for (int k = 0; k < 3; ++k) {
    const Vec3 axis{pa.axes(0, k), pa.axes(1, k), pa.axes(2, k)};
    EXPECT_NEAR(norm(I * axis - axis * pa.moments[k]), 0, 1e-12 * I.trace());
  }

  // Round trip of pose and velocities through the engine.
  const Quat q = Quat::from_axis_angle({0.2, -1, 0.5}, 1.1);
  Grain g = grain(3, tilted, {10e-3, 10e-3, 6e-3}, q);
  g.velocity = {0.01, 0, -0.02};
  g.angular_velocity = {30, -20, 10};
  auto e1 = make_engine();
  e1->set_container({20e-3, 20e-3, 20e-3, 0});
  e1->add_grain(g);
  Grain r = state_of(*e1, g);
  EXPECT_NEAR(norm(r.position - g.position), 0, 1e-15);
  EXPECT_NEAR(std::abs(r.orientation.w * q.w + r.orientation.x * q.x + r.orientation.y * q.y + r.orientation.z * q.z),
              1.0, 1e-14);
  EXPECT_NEAR(norm(r.velocity - g.velocity), 0, 1e-15);
  EXPECT_NEAR(norm(r.angular_velocity - g.angular_velocity), 0, 1e-12);

  // Twin: the plain box at orientation q·tilt is the same body. Both tumble onto the
  // floor; a wrong inertia frame would make them part within the first impact.
  Grain h = grain(3, plain, g.position, q * tilt);
  h.velocity = g.velocity;
  h.angular_velocity = g.angular_velocity;
  auto e2 = make_engine();
  e2->set_container({20e-3, 20e-3, 20e-3, 0});
  e2->add_grain(h);
  for (int k = 0; k < 600; ++k) {
    e1->step(kDt);
    e2->step(kDt);
  }
  r = state_of(*e1, g);
  const Grain rh = state_of(*e2, h);
  EXPECT_LT(r.position.z, 5e-3);  // it has hit the floor
  EXPECT_NEAR(norm(r.position - rh.position), 0, 1e-3 * 2e-3);
  const Quat rq = r.orientation * tilt;  // the tilted grain's box axes in the world
  EXPECT_NEAR(std::abs(rq.w * rh.orientation.w + rq.x * rh.orientation.x + rq.y * rh.orientation.y +
                       rq.z * rh.orientation.z),
              1.0, 1e-6);
  EXPECT_NEAR(norm(r.angular_velocity - rh.angular_velocity), 0, 1e-3 * norm(rh.angular_velocity) + 1e-6);
}

// The kinematic platen moves at the commanded velocity and pushes grains.
TEST(BulletEngine, VelocityPlatenMovesAtCommandedSpeed) {
  auto e = make_engine();
  e->set_container({10e-3, 10e-3, 4e-3, 0});
  EXPECT_DOUBLE_EQ(e->platen_position(), 4e-3);
  const auto s = Shape::sphere(1e-3);
  e->add_grain(grain(0, s, {5e-3, 5e-3, 1e-3}));
  e->set_platen({PlatenCommand::Mode::Velocity, -0.01});
  run(*e, 1000);  // 0.5 mm down: the platen has not reached the grain (gap 2 mm)
  EXPECT_NEAR(e->platen_position(), 3.5e-3, 1e-12);
  EXPECT_EQ(e->platen_force(), 0.0);
  e->set_platen({PlatenCommand::Mode::Velocity, -0.1});
  run(*e, 400);  // 2 mm more: pressing on the grain
  EXPECT_NEAR(e->platen_position(), 1.5e-3, 1e-12);
  EXPECT_GT(e->platen_force(), 0.0);
  EXPECT_TRUE(std::isfinite(e->floor_force()));
}

// Rolling friction in Bullet's convention: a lever arm μr in the internal length unit
// (here 1/length_scale = 2 mm), so a rolling ball decelerates at μr·L·g / (1.4 r).
TEST(BulletEngine, RollingFrictionIsALeverArmInTheInternalUnit) {
  Material mat;
  mat.rolling_friction = 0.05;
  mat.wall_friction = 0.5;  // rolls without slipping
  auto e = make_engine({{"sphere_representation", "sphere"}, {"length_scale", 500}}, {0, 0, -kG}, mat);
  EXPECT_EQ(e->length_scale(), 0.0);  // fixed at the first grain
  e->set_container({40e-3, 20e-3, 10e-3, 0});
  const double r = 1e-3, v0 = 0.02;
  Grain g = grain(0, Shape::sphere(r), {5e-3, 10e-3, r});
  g.velocity = {v0, 0, 0};
  g.angular_velocity = {0, v0 / r, 0};
  e->add_grain(g);
  EXPECT_EQ(e->length_scale(), 500.0);
  run(*e, 200);  // rolling: the couple at its limit against the spin
  testing_support::expect_rolling_couple_against_y_spin(e->contacts(), mat.rolling_friction / 500.0);
  run(*e, 1000);
  const Grain s = state_of(*e, g);
  const double a = mat.rolling_friction * (1 / 500.0) * kG / (1.4 * r);
  const double expect = v0 * v0 / (2 * a);
  EXPECT_NEAR(s.position.x - g.position.x, expect, 0.03 * expect);
  EXPECT_NEAR(s.velocity.x, 0.0, 1e-4);
}


// The solver report (Engine::solver_report): a column of five spheres on the floor needs many
// projected Gauss-Seidel sweeps to pass its weight down. Two sweeps stop at the limit with the
// tolerance unmet; 2000 sweeps reach a loose tolerance before the limit. No contact: no report.
TEST(BulletEngine, SolverReportSaysWhenTheIterationLimitCameFirst) {
  auto column = [](int iterations, double tolerance) {
    auto e = make_engine({{"solver_iterations", iterations}, {"solver_tolerance", tolerance}});
    e->set_container({4e-3, 4e-3, 20e-3, 0});
    const auto s = Shape::sphere(1e-3);
    for (int i = 0; i < 5; ++i) e->add_grain(grain(i, s, {2e-3, 2e-3, 1e-3 + 2e-3 * i}));
    run(*e, 200);
    return e->solver_report();
  };
  const Engine::SolverReport few = column(2, 1e-9);
  EXPECT_EQ(few.iterations, 2);
  EXPECT_TRUE(few.limit_before_tolerance);
  EXPECT_GT(few.change, 1e-9);
  const Engine::SolverReport many = column(2000, 1e-3);
  EXPECT_GT(many.iterations, 2);
  EXPECT_LT(many.iterations, 2000);
  EXPECT_FALSE(many.limit_before_tolerance);
  // Without a tolerance every step runs all its sweeps, by request: not reported as limited.
  const Engine::SolverReport fixed = column(50, 0);
  EXPECT_EQ(fixed.iterations, 50);
  EXPECT_FALSE(fixed.limit_before_tolerance);
  auto empty = make_engine();
  empty->set_container({4e-3, 4e-3, 4e-3, 0});
  empty->add_grain(grain(0, Shape::sphere(1e-3), {2e-3, 2e-3, 2e-3}));
  run(*empty, 2);
  EXPECT_LT(empty->solver_report().iterations, 0);
}

// engine.deep_penetration: two spheres born 0.4 mm into each other (d = 2 mm), no gravity.
// Eq. 8 alone (β = 0.003) corrects 0.3 % of the depth per step and turns it into velocity;
// past 0.1 d the split impulse at deep_erp 0.2 pushes them apart within a few steps without
// giving them speed. The depth left below 0.1 d keeps eq. 8.
TEST(BulletEngine, DeepPenetrationIsPushedApartWithoutSpeed) {
  auto pair = [](double deep) {
    auto e = make_engine({{"deep_penetration", deep}, {"solver_iterations", 50}}, Vec3{0, 0, 0});
    e->set_container({20e-3, 20e-3, 20e-3, 0});
    const auto s = Shape::sphere(1e-3);
    const Grain a = grain(0, s, {9.2e-3, 10e-3, 10e-3}), b = grain(1, s, {10.8e-3, 10e-3, 10e-3});
    e->add_grain(a);
    e->add_grain(b);
    run(*e, 20);
    const Grain ga = state_of(*e, a), gb = state_of(*e, b);
    const double overlap = 2e-3 - norm(gb.position - ga.position);
    return std::pair{overlap, std::max(norm(ga.velocity), norm(gb.velocity))};
  };
  const auto [plain_overlap, plain_speed] = pair(0);
  EXPECT_GT(plain_overlap, 0.35e-3);  // 20 steps of eq. 8 at β = 0.003: ≈ 6 % of 0.4 mm corrected
  EXPECT_GT(plain_speed, 1e-3);       // ... and turned into velocity, β·Δd/Δt ≈ 0.01 m/s
  const auto [deep_overlap, deep_speed] = pair(0.1);
  // Down to about the 0.1 d threshold (0.2 mm; the icosphere hulls and their margins put
  // Bullet's depth a few µm from the centre distance's).
  EXPECT_LT(deep_overlap, 0.22e-3) << "plain " << plain_overlap;
  // The speed comes from eq. 8 on the depth left below the threshold (half of it): the deep
  // correction itself adds none (as a velocity bias at β = 0.2 it would give ≈ 0.8 m/s).
  EXPECT_LT(deep_speed, 0.6 * plain_speed) << deep_speed << " against " << plain_speed;
}

// A concave grain collides as convex pieces that cover it, not as its hull (Zhu & Zhao 2019
// §3.2 keep such fragments concave in the engine): a 0.6 mm sphere dropped into the notch of a
// U-shaped grain (3 × 3 × 2 mm, a 1 mm notch 1 mm deep) comes to rest on the notch's bottom,
// and its contact point lies on the grain's surface. As the hull, it rests on the hull's top
// face, 1 mm higher, over the notch: no material of the grain is there.
TEST(BulletEngine, AConcaveGrainCollidesAsConvexPieces) {
  auto drop = [](const char* mode) {
    auto e = make_engine({{"concave_shapes", mode}, {"solver_iterations", 50}});
    const auto r = testing_support::drop_ball_into_u_notch(*e, 4000, kDt);
    EXPECT_EQ(e->summary_figures().at("compound_shapes"), std::string(mode) == "convex_pieces" ? 1.0 : 0.0);
    return r;
  };
  const auto pieces = drop("convex_pieces"), hull = drop("convex_hull");
  EXPECT_NEAR(pieces.ball_height, 1.3e-3, 0.05e-3);  // notch bottom (1 mm) + radius
  EXPECT_NEAR(hull.ball_height, 2.3e-3, 0.05e-3);    // hull top (2 mm) + radius
  EXPECT_GE(pieces.contact_offset, 0);
  EXPECT_LT(pieces.contact_offset, 0.03e-3);  // on the grain's surface, within the margins
  EXPECT_GT(hull.contact_offset, 0.4e-3);     // over the notch: 0.5 mm from its walls
}
