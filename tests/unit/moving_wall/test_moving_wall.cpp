// Moving walls: the motion laws against their closed forms, the jaw-crusher scene's
// geometry against Harmon et al. 2020 Table 1, a moving wall pushing a grain in lsdem
// (momentum and velocity against the rigid-wall collision), sieve sizes, and JSON errors.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "backends/lsdem/LsdemEngine.h"
#include "core/Measures.h"
#include "core/MovingWall.h"
#include "scenarios/ScenarioFactory.h"

using namespace crumble;
using Json = nlohmann::json;

namespace {

MovingWall eccentric_wall() {
  MovingWall w;
  w.name = "swing";
  w.shape = Shape::polygon({{-0.05, -0.4, 0}, {0.05, -0.4, 0}, {0.05, 0.4, 0}, {-0.05, 0.4, 0}});
  w.position = {0.3, 0.5, 0};
  w.orientation = Quat::from_axis_angle({0, 0, 1}, -0.3);
  w.motion.type = WallMotion::Type::Eccentric;
  w.motion.pivot = {0.4, 0.9, 0};
  w.motion.lever = 0.909;
  w.motion.throw_ = 0.054;
  w.motion.rpm = 300;
  w.motion.phase = 0.2;
  return w;
}

}  // namespace

TEST(MotionLaw, EccentricMatchesClosedForm) {
  const MovingWall w = eccentric_wall();
  const double A = std::asin(0.054 / (2 * 0.909));
  const double om = 2 * kPi * 300 / 60;  // 31.4159 rad/s
  EXPECT_NEAR(w.motion.amplitude(), A, 1e-15);
  EXPECT_NEAR(w.motion.omega(), om, 1e-12);
  const Vec3 r0 = w.position - w.motion.pivot;
  for (double t : {0.0, 0.013, 0.05, 0.1234, 0.2, 1.77}) {
    const double th = A * std::sin(om * t + 0.2), thd = A * om * std::cos(om * t + 0.2);
    const WallKinematics k = wall_kinematics(w, t);
    // x = pivot + R(θ) r0, v = θ' ẑ × (x − pivot), ω = θ' ẑ
    const Vec3 r{std::cos(th) * r0.x - std::sin(th) * r0.y, std::sin(th) * r0.x + std::cos(th) * r0.y, 0};
    EXPECT_NEAR(k.position.x, w.motion.pivot.x + r.x, 1e-14) << t;
    EXPECT_NEAR(k.position.y, w.motion.pivot.y + r.y, 1e-14) << t;
    EXPECT_NEAR(k.velocity.x, -thd * r.y, 1e-13) << t;
    EXPECT_NEAR(k.velocity.y, thd * r.x, 1e-13) << t;
    EXPECT_NEAR(k.angular_velocity.z, thd, 1e-13) << t;
    // The orientation turns by θ too: the wall's body x axis.
    const Vec3 ex = k.orientation.rotate({1, 0, 0});
    EXPECT_NEAR(std::atan2(ex.y, ex.x), -0.3 + th, 1e-13) << t;
    // Periodic with 60/rpm = 0.2 s.
    EXPECT_NEAR(norm(wall_kinematics(w, t + 0.2).position - k.position), 0, 1e-13) << t;
  }
  // The point at the lever travels a chord of exactly `throw` between θ = −A and θ = +A.
  const Vec3 tip = w.motion.pivot + Vec3{0, -0.909, 0};
  auto at = [&](double th) {
    const Vec3 d = tip - w.motion.pivot;
    return Vec3{std::cos(th) * d.x - std::sin(th) * d.y, std::sin(th) * d.x + std::cos(th) * d.y, 0};
  };
  EXPECT_NEAR(norm(at(A) - at(-A)), 0.054, 1e-15);
}

TEST(MotionLaw, StepKinematicsLandOnTheExactPose) {
  const MovingWall w = eccentric_wall();
  const double dt = 1e-4;
  for (double t : {0.0, 0.031, 0.09}) {
    const WallKinematics k = wall_step_kinematics(w, t, dt);
    const WallKinematics k1 = wall_kinematics(w, t + dt);
    EXPECT_NEAR(norm(k.position + k.velocity * dt - k1.position), 0, 1e-15);
    const double dth = k.angular_velocity.z * dt;
    EXPECT_NEAR(dth, w.motion.angle(t + dt) - w.motion.angle(t), 1e-17);
    // Mean velocity = the exact one at mid-step to O(dt²).
    EXPECT_NEAR(norm(k.velocity - wall_kinematics(w, t + 0.5 * dt).velocity), 0, 1e-6);
  }
}

TEST(MotionLaw, VelocityAndFixed) {
  MovingWall w = eccentric_wall();
  w.motion = WallMotion{};
  WallKinematics k = wall_kinematics(w, 3.0);
  EXPECT_EQ(k.position.x, w.position.x);
  EXPECT_EQ(norm(k.velocity), 0);
  w.motion.type = WallMotion::Type::Velocity;
  w.motion.velocity = {0.1, -0.2, 0};
  w.motion.angular_velocity = {0, 0, 0.5};
  k = wall_kinematics(w, 2.0);
  EXPECT_NEAR(k.position.x, 0.3 + 0.2, 1e-15);
  EXPECT_NEAR(k.position.y, 0.5 - 0.4, 1e-15);
  const Vec3 ex = k.orientation.rotate({1, 0, 0});
  EXPECT_NEAR(std::atan2(ex.y, ex.x), -0.3 + 1.0, 1e-14);
}

// The scene's plates reproduce Table 1 of Harmon et al. 2020: the gap at the discharge is
// css when closed and css + throw when open, the swing jaw turns ±1.7° about the nip angle 22°.
TEST(JawScene, GeometryFollowsTable1) {
  for (double css : {0.05, 0.08, 0.1}) {
    Json doc = {{"dimension", 2},
                {"engine", {{"type", "lsdem"}}},
                {"scene",
                 {{"type", "jaw_crusher"},
                  {"css", css},
                  {"cycles", 1},
                  {"rocks", {{"count", 1}, {"shapes", Json::array({{{"type", "disk"}}})}}}}}};
    Scenario sc = build_scenario(doc, {});
    ASSERT_EQ(sc.packing.walls.size(), 4u);  // fixed jaw, swing jaw, two hopper walls
    const MovingWall& sw = sc.packing.walls[1];
    ASSERT_EQ(sw.name, "swing_jaw");
    EXPECT_EQ(sc.packing.walls[0].motion.type, WallMotion::Type::Fixed);
    EXPECT_NEAR(sw.motion.amplitude() * 180 / kPi, 1.7, 1e-12);
    // Bottom inner corner of the swing plate (body frame −t/2, −L/2), fixed face at x = 0.
    const Aabb b = sw.shape->bounds();
    const Vec3 corner{b.lo.x, b.lo.y, 0};
    const double T = 60.0 / 300;
    auto gap = [&](double t) {
      const WallKinematics k = wall_kinematics(sw, t);
      return (k.position + k.orientation.rotate(corner)).x;
    };
    EXPECT_NEAR(gap(0.75 * T), css, 1e-12);          // θ = −A: closed side setting
    EXPECT_NEAR(gap(0.25 * T), css + 0.05, 1e-12);   // θ = +A: open side setting = css + throw
    // Nip angle: the swing face is 22° from the vertical fixed face on average.
    const Vec3 ey = sw.orientation.rotate({0, 1, 0});
    EXPECT_NEAR(std::atan2(ey.x, ey.y) * 180 / kPi, 22.0, 1e-12);
    EXPECT_NEAR(sc.sim->loading().settings().duration, T, 1e-15);
  }
}

// A wall moving at constant speed u hits a free disk (no gravity, no damping): in the wall's
// frame an elastic bounce, so the disk leaves at 2u; the impulse on the wall is −m·2u.
TEST(LsdemMovingWall, PushesAGrainConsistently) {
  EngineContext ctx;
  ctx.dimension = 2;
  ctx.gravity = {};
  Material m;
  m.density = 2650;
  m.friction = 0;
  m.wall_friction = 0;
  ctx.materials = {m};
  LsdemSettings s;
  s.kn = 1e7;
  s.damping_ratio = 0;
  LsdemEngine e(s, ctx);
  ShapeResolution res;
  res.level_set_spacing = 0.002;
  Grain g;
  g.id = 0;
  g.shape = Shape::disk(0.05, res);
  g.position = {0.2, 0, 0};
  e.add_grain(g);
  MovingWall w;
  w.name = "pusher";
  w.shape = Shape::polygon({{-0.05, -0.2, 0}, {0.05, -0.2, 0}, {0.05, 0.2, 0}, {-0.05, 0.2, 0}}, res);
  w.position = {0.095, 0, 0};
  w.motion.type = WallMotion::Type::Velocity;
  w.motion.velocity = {0.5, 0, 0};
  ASSERT_EQ(e.add_moving_wall(w), 0);
  const double mass = 2650 * g.shape->volume();
  const double dt = 0.05 * std::sqrt(mass / s.kn);
  double impulse = 0, t = 0;
  for (int i = 0; i < 4000; ++i) {
    e.set_moving_wall(0, wall_step_kinematics(w, t, dt));
    e.step(dt);
    impulse += e.moving_wall_force(0).x * dt;
    t += dt;
  }
  Grain out = g;
  e.read_state(std::span<Grain>(&out, 1));
  // The wall has moved on and the disk left it: 2u, to the integrator's energy error (< 1 %).
  EXPECT_NEAR(out.velocity.x, 1.0, 0.01);
  EXPECT_NEAR(out.velocity.y, 0.0, 1e-9);
  // Force on the wall = −force on the grain at every step: the impulses balance exactly.
  EXPECT_NEAR(impulse, -mass * out.velocity.x, 1e-9 * mass);
  EXPECT_LT(impulse, 0);
}

TEST(MovingWallEngines, BulletRefusesNamingItself) {
  Json doc = {{"engine", {{"type", "bullet"}}},
              {"container", {{"lx", 0.01}, {"ly", 0.01}, {"height", 0.01}}},
              {"packing", {{"type", "grains"}, {"grains", Json::array({{{"shape", {{"type", "sphere"}, {"radius", 1e-3}}}, {"position", {0.005, 0.005, 0.002}}}})}}},
              {"walls", Json::array({{{"shape", {{"type", "box"}, {"half_extents", {0.001, 0.001, 0.001}}}}, {"position", {0.005, 0.005, 0.008}}}})}};
  try {
    build_scenario(doc, {});
    FAIL() << "bullet accepted a moving wall";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.path(), "/engine/type");
    EXPECT_NE(std::string(e.what()).find("'bullet' does not support moving walls"), std::string::npos) << e.what();
  }
}

namespace {
std::string error_path(Json doc) {
  try {
    build_scenario(std::move(doc), {});
  } catch (const ConfigError& e) {
    return e.path();
  }
  return "(no error)";
}
Json wall_doc(Json motion) {
  return {{"dimension", 2},
          {"engine", {{"type", "lsdem"}}},
          {"container", {{"lx", 1.0}, {"height", 1.0}}},
          {"packing", {{"type", "grains"}, {"grains", Json::array({{{"shape", {{"type", "disk"}, {"radius", 0.05}}}, {"position", {0.5, 0.05, 0}}}})}}},
          {"walls", Json::array({{{"shape", {{"type", "polygon"}, {"vertices", {{-0.1, -0.1}, {0.1, -0.1}, {0.1, 0.1}, {-0.1, 0.1}}}}},
                                  {"position", {0.5, 0.5, 0}},
                                  {"motion", motion}}})}};
}
}  // namespace

TEST(MovingWallJson, ErrorsNameThePath) {
  EXPECT_EQ(error_path(wall_doc({{"type", "eccentric"}, {"pivot", {0.5, 1, 0}}, {"lever", 0.1}, {"throw", 0.3}, {"rpm", 60}})),
            "/walls/0/motion/throw");
  EXPECT_EQ(error_path(wall_doc({{"type", "eccentric"}, {"lever", 0.1}, {"throw", 0.05}})), "/walls/0/motion/rpm");
  EXPECT_EQ(error_path(wall_doc({{"type", "swing"}})), "/walls/0/motion/type");
  EXPECT_EQ(error_path(wall_doc({{"type", "velocity"}, {"velocity", {0, 0, 1}}})), "/walls/0/motion/velocity");
  EXPECT_EQ(error_path(wall_doc({{"type", "fixed"}, {"speed", 1}})), "/walls/0/motion/speed");
  Json no_shape = wall_doc({{"type", "fixed"}});
  no_shape["walls"][0].erase("shape");
  EXPECT_EQ(error_path(no_shape), "/walls/0/shape");
  Json ok = wall_doc({{"type", "eccentric"}, {"pivot", {0.5, 1, 0}}, {"lever", 0.5}, {"throw", 0.05}, {"rpm", 60}});
  EXPECT_EQ(error_path(ok), "(no error)");
  // The jaw crusher: 2D only, its duration is the scene's.
  Json jaw = {{"dimension", 2},
              {"engine", {{"type", "lsdem"}}},
              {"scene", {{"type", "jaw_crusher"}, {"rocks", {{"shapes", Json::array({{{"type", "disk"}}})}}}}}};
  EXPECT_EQ(error_path(jaw), "(no error)");
  Json j3 = jaw;
  j3["dimension"] = 3;
  EXPECT_EQ(error_path(j3), "/scene/type");
  Json jd = jaw;
  jd["loading"] = {{"mode", "none"}, {"duration", 1.0}};
  EXPECT_EQ(error_path(jd), "/loading/duration");
  Json jr = jaw;
  jr["scene"]["rocks"]["diameter"] = {0.2, 0.1};
  EXPECT_EQ(error_path(jr), "/scene/rocks/diameter");
  Json jbig = jaw;
  jbig["scene"]["rocks"]["diameter"] = {0.6, 0.7};
  EXPECT_EQ(error_path(jbig), "/scene/rocks/diameter");
  Json jn = jaw;
  jn["scene"]["rocks"].erase("shapes");
  EXPECT_EQ(error_path(jn), "/scene/rocks/shapes");
  // Checkpoints record the feed, the product and the walls: accepted.
  Json jc = jaw;
  jc["output"] = {{"checkpoint_every", 100}};
  EXPECT_EQ(error_path(jc), "(no error)");
}

// Harmon et al. 2020 §4.2: sieve size = chord through the centroid towards the closest
// surface point: a disk's diameter, a rectangle's shorter side.
TEST(SieveSize, MinorAxisOfSimpleShapes) {
  ShapeResolution res;
  res.level_set_spacing = 0.002;
  EXPECT_NEAR(sieve_size(*Shape::disk(0.05, res)), 0.1, 1e-9);
  EXPECT_NEAR(sieve_size(*Shape::polygon({{-0.1, -0.03, 0}, {0.1, -0.03, 0}, {0.1, 0.03, 0}, {-0.1, 0.03, 0}}, res)), 0.06,
              0.06 * 0.01);
  EXPECT_NEAR(mass_quantile({1, 2, 3}, {1, 1, 1}, 0.5), 2.0, 1e-15);
  EXPECT_TRUE(std::isnan(mass_quantile({}, {}, 0.5)));
}
