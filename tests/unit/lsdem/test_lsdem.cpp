// lsdem engine: contact laws against closed forms, convergence with node refinement, energy
// conservation, static loads, 2D, determinism across thread counts, grain management, errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "backends/lsdem/LsdemEngine.h"
#include "scenarios/Registry.h"
#include "tests/support/EngineKit.h"

using namespace crumble;

using crumble::testing_support::grain;

namespace {

EngineContext context(int dim, Vec3 gravity = {}, int threads = 1) {
  EngineContext c;
  c.dimension = dim;
  c.gravity = gravity;
  Material m;
  m.density = 1000;
  m.friction = 0.5;
  m.wall_friction = 0.0;
  m.young = 1e9;
  m.poisson = 0.25;
  c.materials = {m};
  c.threads = threads;
  return c;
}

Shape::Ptr sphere(double r, double h, int nodes) {
  ShapeResolution res;
  res.level_set_spacing = h;
  res.surface_nodes = nodes;
  return Shape::sphere(r, res);
}

const Contact* find_pair(const std::vector<Contact>& cs) {
  for (const auto& c : cs)
    if (!c.is_wall()) return &c;
  return nullptr;
}

// Force between two unit spheres at overlap delta, head-on along `axis`, with the second
// sphere turned by q (so nodes do not line up with the axis by construction).
Contact pressed_pair(const LsdemSettings& s, const Shape::Ptr& sh, double delta, Vec3 axis, Quat q) {
  LsdemEngine e(s, context(3));
  e.add_grain(grain(0, sh, {0, 0, 0}, q));
  e.add_grain(grain(1, sh, normalized(axis) * (2.0 - delta), q.conjugate()));
  e.step(1e-9);
  const std::vector<Contact> all = e.contacts();  // find_pair points into it (AddressSanitizer)
  const Contact* c = find_pair(all);
  if (!c) return {};
  Contact r = *c;
  if (r.a == 1) {  // report as seen by grain 0
    r.force = -r.force;
    r.normal = -r.normal;
  }
  return r;
}

}  // namespace

// Linear law: |F| = k_n·δ with δ the overlap (tolerance 1 %: trilinear error ≈ h²/(4R) and
// the deepest node's distance from the axis ≈ s²/(8R*) with s the node spacing).
TEST(Lsdem, TwoSpheresLinearLaw) {
  auto sh = sphere(1.0, 0.025, 8000);
  LsdemSettings s;
  s.kn = 1e6;
  s.damping_ratio = 0;
  const Quat q = Quat::from_axis_angle({0.3, -0.5, 0.8}, 0.7);
  for (double delta : {0.05, 0.1, 0.2}) {
    const Contact c = pressed_pair(s, sh, delta, {1, 0.2, -0.1}, q);
    const Vec3 ax = normalized(Vec3{1, 0.2, -0.1});
    EXPECT_NEAR(norm(c.force) / (s.kn * delta), 1.0, 0.01) << delta;
    EXPECT_GT(dot(c.normal, -ax), 0.9999) << "normal from b to a";
    EXPECT_GT(dot(normalized(c.force), -ax), 0.9999) << "force on a pushes it away from b";
    EXPECT_LT(norm(c.point - ax * (1 - 0.5 * delta)), 0.02 * delta + 0.005) << "point mid-overlap";
  }
}

// sphere_representation "polyhedron": a sphere collides as the hull of its mesh (the 42-vertex
// icosphere Bullet and ODE collide). Two unit spheres face to face along a facet's normal,
// closer than two radii by half the facet's depth below the sphere: the exact spheres
// overlap by that much (|F| = k_n·δ within 2 %), the hulls do not touch. Vertex to vertex,
// both representations overlap by δ.
TEST(Lsdem, PolyhedronSphereRepresentationCollidesTheHull) {
  auto sh = sphere(1.0, 0.025, 8000);
  const TriMesh& hull = sh->convex_hull();
  ASSERT_EQ(hull.vertices.size(), 42u);
  const auto& t = hull.triangles.front();
  const Vec3 a = hull.vertices[t[0]], b = hull.vertices[t[1]], c = hull.vertices[t[2]];
  const Vec3 n = normalized(cross(b - a, c - a));
  const double depth = 1 - std::abs(dot(n, a));  // the facet's plane lies this far inside
  ASSERT_GT(depth, 0.04);
  const double delta = 0.5 * depth;
  LsdemSettings s;
  s.kn = 1e6;
  s.damping_ratio = 0;
  const Quat id{1, 0, 0, 0};
  EXPECT_NEAR(norm(pressed_pair(s, sh, delta, n, id).force) / (s.kn * delta), 1.0, 0.02) << "exact spheres";
  s.exact_spheres = false;
  EXPECT_EQ(norm(pressed_pair(s, sh, delta, n, id).force), 0.0) << "hulls a facet's depth apart";
  // Vertex to vertex (the icosphere is centrally symmetric, so -v is a vertex too).
  const Vec3 v = normalized(a);
  EXPECT_GT(norm(pressed_pair(s, sh, delta, v, id).force), 0.0) << "hull vertices overlap";
}

// Hertz: F = (4/3) E* √R* δ^{3/2}, E* = E / (2(1 − ν²)), R* = R/2 (tolerance 1 %; the law
// takes R from the equivalent radius, exact for spheres).
TEST(Lsdem, TwoSpheresHertzLaw) {
  auto sh = sphere(1.0, 0.025, 8000);
  LsdemSettings s;
  s.contact_law = "hertz";
  s.damping_ratio = 0;
  const auto ctx = context(3);
  const double estar = ctx.materials[0].young / (2 * (1 - 0.25 * 0.25));
  for (double delta : {0.05, 0.1}) {
    const Contact c = pressed_pair(s, sh, delta, {0, 0, 1}, Quat::from_axis_angle({1, 1, 0}, 0.3));
    const double f = 4.0 / 3.0 * estar * std::sqrt(0.5) * std::pow(delta, 1.5);
    EXPECT_NEAR(norm(c.force) / f, 1.0, 0.01) << delta;
  }
}

// Refining the nodes makes the force converge to the closed form: the worst error over
// several orientations (the deepest node misses the axis by up to half a node spacing s,
// so δ is under-estimated by up to ≈ s²/(8R*)) falls with the node count.
TEST(Lsdem, ContactForceConvergesWithNodeRefinement) {
  LsdemSettings s;
  s.kn = 1e6;
  s.damping_ratio = 0;
  const double delta = 0.05;
  std::vector<double> worst;
  for (int n : {500, 2000, 8000}) {
    const auto sh = sphere(1.0, 0.025, n);
    double w = 0;
    for (int k = 0; k < 6; ++k) {
      const Vec3 axis = normalized(Vec3{std::sin(1.3 * k), std::cos(0.7 * k), 0.5 - 0.2 * k});
      const Quat q = Quat::from_axis_angle({1, 2.0 * k, 3}, 0.4 + 0.9 * k);
      const Contact c = pressed_pair(s, sh, delta, axis, q);
      w = std::max(w, std::abs(norm(c.force) - s.kn * delta) / (s.kn * delta) + norm(normalized(c.force) + axis));
    }
    worst.push_back(w);
  }
  EXPECT_LT(worst[1], worst[0]);
  EXPECT_LT(worst[2], worst[1]);
  EXPECT_LT(worst[2], 0.015);
  EXPECT_LT(worst[2], 0.35 * worst[0]) << worst[0] << " " << worst[1] << " " << worst[2];
}

// No damping, no friction: a bouncing sphere keeps its apex height within 1 % of the drop
// height over 1e4 steps of the default stable step (dt_safety 0.1).
TEST(Lsdem, BouncingSphereConservesEnergy) {
  LsdemSettings s;
  s.kn = 1e8;
  s.damping_ratio = 0;
  LsdemEngine e(s, context(3, {0, 0, -9.81}));
  Container box;
  box.lx = 10;
  box.ly = 10;
  e.set_container(box);
  const double z0 = 1.5;
  e.add_grain(grain(0, sphere(1.0, 0.1, 1000), {5, 5, z0}));
  const double dt = e.max_stable_dt();
  EXPECT_NEAR(dt, 0.1 * std::sqrt(1000 * 4 * kPi / 3 / s.kn), 1e-15);
  std::vector<Grain> g(1);
  g[0].id = 0;
  double zmax = 0, vz_prev = 0;
  int apexes = 0;
  double worst = 0;
  for (int i = 0; i < 10000; ++i) {
    e.step(dt);
    e.read_state(g);
    zmax = std::max(zmax, g[0].position.z);
    if (vz_prev > 0 && g[0].velocity.z <= 0) {  // apex
      ++apexes;
      worst = std::max(worst, std::abs(zmax - z0) / (z0 - 1.0));
      zmax = 0;
    }
    vz_prev = g[0].velocity.z;
  }
  EXPECT_GE(apexes, 8);
  EXPECT_LT(worst, 0.01);
}

// The contact patch must hold several nodes (kn 1e7: overlap 4e-3, patch radius 0.09,
// node spacing 0.06) for the node-weighted point to sit under the centre.
TEST(Lsdem, SphereAtRestCarriesItsWeight) {
  LsdemSettings s;
  s.kn = 1e7;
  s.damping_ratio = 0.7;
  s.global_damping = 1;
  auto ctx = context(3, {0, 0, -9.81});
  ctx.materials[0].wall_friction = 0.5;
  LsdemEngine e(s, ctx);
  e.set_container({});
  e.add_grain(grain(0, sphere(1.0, 0.05, 4000), {0, 0, 1.0}));
  for (int i = 0; i < 4000; ++i) e.step(e.max_stable_dt());
  const double mg = 1000 * 4 * kPi / 3 * 9.81;
  EXPECT_NEAR(e.floor_force() / mg, 1.0, 0.01);
  ASSERT_EQ(e.contacts().size(), 1u);
  EXPECT_EQ(e.contacts()[0].wall, kFloor);
  EXPECT_NEAR(e.contacts()[0].normal.z, 1.0, 1e-9);
  // Under the centre, within the patch radius √(2 R δ) ≈ 0.09.
  EXPECT_LT(std::hypot(e.contacts()[0].point.x, e.contacts()[0].point.y), 0.09);
  EXPECT_NEAR(e.contacts()[0].point.z, 0.0, 0.01);
}

// packing.settle.global_damping_scale: Harmon et al. 2020 Table 2's global damping holds a
// falling grain to its terminal velocity g / C_g; scaled by 0 while settling, the grain falls
// freely (v = g t), and scale 1 restores it.
TEST(Lsdem, GlobalDampingScaleLetsAGrainFallFreely) {
  LsdemSettings s;
  s.kn = 1e7;
  s.global_damping = 100;  // 1/s
  const auto ctx = context(3, {0, 0, -9.81});
  const auto fall = [&](double scale) {
    LsdemEngine e(s, ctx);
    e.set_container({});
    e.add_grain(grain(0, sphere(0.1, 0.02, 1000), {0, 0, 10.0}));
    EXPECT_TRUE(e.set_global_damping_scale(scale));
    for (int i = 0; i < 500; ++i) e.step(1e-4);  // 0.05 s, far above the floor
    std::vector<Grain> st(1);
    st[0].id = 0;
    e.read_state(st);
    return -st[0].velocity.z;
  };
  EXPECT_NEAR(fall(0), 9.81 * 0.05, 1e-9);
  EXPECT_NEAR(fall(1), 9.81 / 100 * (1 - std::exp(-100 * 0.05)), 0.01 * 9.81 / 100);
}

TEST(Lsdem, MassScalingKeepsTheWeightAndLengthensTheStep) {
  // Zhu & Zhao 2019 §5 density scaling: inertia ×70, weight unchanged, stable step ×√70.
  LsdemSettings s;
  s.kn = 1e7;
  s.damping_ratio = 0.7;
  s.global_damping = 1;
  auto ctx = context(3, {0, 0, -9.81});
  LsdemEngine plain(s, ctx);
  s.mass_scale = 70;
  LsdemEngine e(s, ctx);
  const auto sh = sphere(1.0, 0.05, 4000);
  for (LsdemEngine* x : {&plain, &e}) {
    x->set_container({});
    x->add_grain(grain(0, sh, {0, 0, 1.0}));
  }
  EXPECT_NEAR(e.max_stable_dt() / plain.max_stable_dt(), std::sqrt(70.0), 1e-9);
  for (int i = 0; i < 4000; ++i) e.step(e.max_stable_dt());
  const double mg = 1000 * 4 * kPi / 3 * 9.81;
  EXPECT_NEAR(e.floor_force() / mg, 1.0, 0.01);
}

TEST(Lsdem, DiskAtRestCarriesItsWeight2D) {
  LsdemSettings s;
  s.kn = 1e8;
  s.damping_ratio = 0.7;
  LsdemEngine e(s, context(2, {0, -9.81, 0}));
  Container box;
  box.lx = 4;
  e.set_container(box);
  ShapeResolution res;
  res.level_set_spacing = 0.05;
  e.add_grain(grain(0, Shape::disk(1.0, res), {2, 1.0, 0}));
  for (int i = 0; i < 6000; ++i) e.step(e.max_stable_dt());
  const double mg = 1000 * kPi * 9.81;  // per metre of thickness
  EXPECT_NEAR(e.floor_force() / mg, 1.0, 0.01);
  std::vector<Grain> g(1);
  g[0].id = 0;
  e.read_state(g);
  EXPECT_NEAR(g[0].position.x, 2.0, 1e-9);
  EXPECT_EQ(g[0].position.z, 0.0);
}

// A box sliding on a frictional floor decelerates at μ g (Coulomb, per-node history).
TEST(Lsdem, SlidingBoxDeceleratesAtMuG) {
  LsdemSettings s;
  s.kn = 1e8;
  s.damping_ratio = 0.7;
  auto ctx = context(3, {0, 0, -9.81});
  ctx.materials[0].wall_friction = 0.3;
  LsdemEngine e(s, ctx);
  e.set_container({});
  ShapeResolution res;
  res.level_set_spacing = 0.05;
  auto box = Shape::box({0.5, 0.5, 0.5}, res);
  Grain g = grain(0, box, {0, 0, 0.5});
  e.add_grain(g);
  const double dt = e.max_stable_dt();
  for (int i = 0; i < 2000; ++i) e.step(dt);  // settle
  std::vector<Grain> st(1);
  st[0].id = 0;
  e.read_state(st);
  const double x0 = st[0].position.x;
  // Kick it: remove and re-add with a velocity (engine keeps no other state of it).
  st[0].velocity = {2.0, 0, 0};
  st[0].shape = box;
  e.remove_grain(0);
  e.add_grain(st[0]);
  for (int i = 0; i < 40000; ++i) e.step(dt);
  e.read_state(st);
  const double expected = 2.0 * 2.0 / (2 * 0.3 * 9.81);
  EXPECT_NEAR((st[0].position.x - x0) / expected, 1.0, 0.03);
  EXPECT_LT(norm(st[0].velocity), 1e-3);
}

TEST(Lsdem, ForceControlledPlatenBalancesTheGrain) {
  LsdemSettings s;
  s.kn = 1e8;
  s.damping_ratio = 0.7;
  s.global_damping = 5;
  LsdemEngine e(s, context(3, {0, 0, -9.81}));
  Container box;
  box.lx = 3;
  box.ly = 3;
  box.height = 2.05;
  box.platen_mass = 1000;
  e.set_container(box);
  e.add_grain(grain(0, sphere(1.0, 0.1, 1000), {1.5, 1.5, 1.0}));
  const double F = 1e5;
  e.set_platen({PlatenCommand::Mode::Force, F});
  for (int i = 0; i < 12000; ++i) e.step(e.max_stable_dt());
  const double mg = 1000 * 4 * kPi / 3 * 9.81;
  EXPECT_NEAR(e.platen_force() / F, 1.0, 0.01);
  EXPECT_NEAR(e.floor_force() / (F + mg), 1.0, 0.01);
  EXPECT_LT(e.platen_position(), 2.0);
  // Kinematic platen.
  const double p0 = e.platen_position();
  e.set_platen({PlatenCommand::Mode::Velocity, 0.01});
  for (int i = 0; i < 100; ++i) e.step(1e-3);
  EXPECT_NEAR(e.platen_position(), p0 + 1e-3, 1e-12);
}

namespace {
// A few superellipsoids and spheres falling into a box, colliding with each other.
void pile(LsdemEngine& e, int n) {
  Container box;
  box.lx = 0.6;
  box.ly = 0.6;
  box.height = 3;
  e.set_container(box);
  ShapeResolution res;
  res.level_set_spacing = 0.02;
  res.surface_nodes = 400;
  auto a = Shape::superellipsoid({0.12, 0.09, 0.07}, 0.6, 0.8, res);
  auto b = sphere(0.08, 0.02, 300);
  for (int i = 0; i < n; ++i) {
    const Vec3 x{0.15 + 0.3 * (i % 2), 0.15 + 0.3 * ((i / 2) % 2), 0.15 + 0.2 * (i / 4)};
    Grain g = grain(i, i % 3 ? a : b, x, Quat::from_axis_angle({1, 0.3 * i, 0.1}, 0.4 * i));
    g.velocity = {0.1 * std::sin(i), 0.1 * std::cos(i), 0};
    g.angular_velocity = {std::sin(2.0 * i), 0, std::cos(3.0 * i)};
    e.add_grain(g);
  }
}
}  // namespace

namespace {
// 12 spheres piled for 1200 steps: their final states, the floor force and the engine's stats.
struct PileRun {
  std::vector<Grain> grains;
  double floor_force = 0;
  LsdemStats stats;
};
PileRun run_pile(LsdemSettings s) {
  s.kn = 2e4;
  LsdemEngine e(s, context(3, {0, 0, -9.81}, s.threads));
  pile(e, 12);
  for (int i = 0; i < 1200; ++i) e.step(e.max_stable_dt());
  PileRun r;
  r.grains.resize(12);
  for (int i = 0; i < 12; ++i) r.grains[i].id = i;
  e.read_state(r.grains);
  r.floor_force = e.floor_force();
  r.stats = e.stats();
  return r;
}
void expect_bitwise_equal(const PileRun& a, const PileRun& b) {
  EXPECT_GT(a.stats.contact_pairs, 0) << "the test must exercise grain contacts";
  for (int i = 0; i < 12; ++i) {
    EXPECT_EQ(std::memcmp(&a.grains[i].position, &b.grains[i].position, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.grains[i].orientation, &b.grains[i].orientation, sizeof(Quat)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.grains[i].angular_velocity, &b.grains[i].angular_velocity, sizeof(Vec3)), 0) << i;
  }
  EXPECT_EQ(std::memcmp(&a.floor_force, &b.floor_force, sizeof(double)), 0);
}
}  // namespace

TEST(Lsdem, BitwiseIdenticalAcrossThreadCounts) {
  LsdemSettings one, two;
  two.threads = 2;
  expect_bitwise_equal(run_pile(one), run_pile(two));
}

TEST(Lsdem, AddRemoveReplaceMidRun) {
  LsdemSettings s;
  s.kn = 2e4;
  LsdemEngine e(s, context(3, {0, 0, -9.81}));
  pile(e, 8);
  for (int i = 0; i < 100; ++i) e.step(e.max_stable_dt());
  EXPECT_EQ(e.grain_count(), 8u);
  e.remove_grain(3);
  EXPECT_EQ(e.grain_count(), 7u);
  EXPECT_THROW(e.remove_grain(3), std::invalid_argument);
  std::vector<Grain> kids = {grain(100, sphere(0.05, 0.01, 200), {0.3, 0.3, 1.0}),
                             grain(101, sphere(0.05, 0.01, 200), {0.3, 0.3, 1.2})};
  e.replace_grain(4, kids);
  EXPECT_EQ(e.grain_count(), 8u);
  for (int i = 0; i < 100; ++i) e.step(e.max_stable_dt());
  for (const auto& c : e.contacts()) {
    EXPECT_NE(c.a, 3);
    EXPECT_NE(c.b, 3);
    EXPECT_TRUE(is_finite(c.force));
  }
  std::vector<Grain> g(2);
  g[0].id = 100;
  g[1].id = 101;
  e.read_state(g);
  EXPECT_LT(g[1].position.z, 1.2);  // falling
}

TEST(Lsdem, RegistryAndConfig) {
  nlohmann::json doc = {{"engine", {{"type", "lsdem"}, {"kn", 1e6}, {"contact_law", "linear"}}}};
  Config root(doc);
  const auto& entry = engines().find("lsdem", "/engine/type");
  EXPECT_EQ(entry.dimensions, (std::vector<int>{2, 3}));
  auto eng = entry.make(root.child("engine"), context(3));
  EXPECT_EQ(eng->name(), "lsdem");
  EXPECT_NO_THROW(root.check_unknown());
  EXPECT_EQ(doc["engine"]["ks_ratio"], 0.6);  // defaults recorded

  nlohmann::json bad = {{"engine", {{"type", "lsdem"}, {"contact_law", "hooke"}}}};
  Config r2(bad);
  EXPECT_THROW(make_lsdem_engine(r2.child("engine"), context(3)), ConfigError);
  nlohmann::json neg = {{"engine", {{"type", "lsdem"}, {"kn", -1}}}};
  Config r3(neg);
  EXPECT_THROW(make_lsdem_engine(r3.child("engine"), context(3)), ConfigError);
  nlohmann::json h2 = {{"engine", {{"type", "lsdem"}, {"contact_law", "hertz"}}}};
  Config r4(h2);
  EXPECT_THROW(make_lsdem_engine(r4.child("engine"), context(2)), ConfigError);
  nlohmann::json typo = {{"engine", {{"type", "lsdem"}, {"kn_typo", 1}}}};
  Config r5(typo);
  make_lsdem_engine(r5.child("engine"), context(3));
  EXPECT_THROW(r5.check_unknown(), ConfigError);
}

TEST(Lsdem, BadInput) {
  LsdemEngine e(LsdemSettings{}, context(3));
  ShapeResolution res;
  res.level_set_spacing = 0.1;
  EXPECT_THROW(e.add_grain(grain(0, Shape::disk(1.0, res), {})), std::invalid_argument);  // 2D shape
  Grain g = grain(0, sphere(1.0, 0.1, 300), {});
  g.material = 3;
  EXPECT_THROW(e.add_grain(g), std::invalid_argument);
  g.material = 0;
  e.add_grain(g);
  EXPECT_THROW(e.add_grain(g), std::invalid_argument);  // duplicate id
  EXPECT_THROW(e.step(0), std::invalid_argument);
  EXPECT_THROW(e.step(-1), std::invalid_argument);
  Grain thin = grain(1, Shape::ellipsoid({1, 1, 0.05}, res), {5, 0, 0});
  try {
    e.add_grain(thin);
    FAIL();
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("ellipsoid"), std::string::npos) << ex.what();
  }
  LsdemSettings s;
  s.kn = 0;
  EXPECT_THROW(LsdemEngine(s, context(3)), std::invalid_argument);
}

// 2D end to end: disks, ellipses and polygons (their level sets built from the shapes) fall
// into a box and settle; the floor then carries the total weight (tolerance 2 %: slow
// residual motion) and every grain stays inside the box.
TEST(Lsdem, MixedShapes2DSettleInABox) {
  LsdemSettings s;
  s.kn = 1e5;
  s.damping_ratio = 0.5;
  s.global_damping = 2;
  auto ctx = context(2, {0, -9.81, 0});
  ctx.materials[0].wall_friction = 0.3;
  LsdemEngine e(s, ctx);
  Container box;
  box.lx = 0.5;
  e.set_container(box);
  ShapeResolution res;
  res.level_set_spacing = 0.005;
  const std::vector<Shape::Ptr> shapes = {
      Shape::disk(0.04, res), Shape::ellipse(0.05, 0.03, res), Shape::superellipse(0.045, 0.035, 0.5, res),
      Shape::polygon({{-0.04, -0.03, 0}, {0.05, -0.035, 0}, {0.03, 0.04, 0}, {-0.045, 0.03, 0}}, res)};
  double mass = 0;
  const int n = 16;
  for (int i = 0; i < n; ++i) {
    Grain g = grain(i, shapes[i % 4], {0.06 + 0.125 * (i % 4), 0.06 + 0.11 * (i / 4), 0},
                    Quat::from_axis_angle({0, 0, 1}, 0.7 * i));
    g.velocity = {0.05 * std::sin(i), 0, 0};
    mass += 1000 * g.shape->volume();
    e.add_grain(g);
  }
  const double dt = e.max_stable_dt();
  for (int i = 0; i < 20000; ++i) e.step(dt);
  EXPECT_GT(e.stats().contact_pairs, 0);
  EXPECT_NEAR(e.floor_force() / (mass * 9.81), 1.0, 0.02);
  std::vector<Grain> g(n);
  for (int i = 0; i < n; ++i) g[i].id = i;
  e.read_state(g);
  for (const auto& x : g) {
    EXPECT_GT(x.position.x, 0.0);
    EXPECT_LT(x.position.x, box.lx);
    EXPECT_GT(x.position.y, 0.0);
    EXPECT_LT(x.position.y, 0.4);
    EXPECT_EQ(x.position.z, 0.0);
    EXPECT_NEAR(x.orientation.x, 0.0, 1e-15);  // rotation about z only
    EXPECT_NEAR(x.orientation.y, 0.0, 1e-15);
  }
  EXPECT_LT(e.kinetic_energy(), 1e-6 * mass * 9.81 * 0.1);
}

// Shape walls: a 2D polygon plate carries a disk (force on the wall = −m g within 1 %), then
// lifts it when it moves up; a 3D box plate tilted by θ lets a cube slide with acceleration
// g (sin θ − μ cos θ) (within 3 %).
TEST(Lsdem, ShapeWalls) {
  {
    LsdemSettings s;
    s.kn = 1e8;
    s.damping_ratio = 0.7;
    LsdemEngine e(s, context(2, {0, -9.81, 0}));
    ShapeResolution res;
    res.level_set_spacing = 0.02;
    auto plate = Shape::polygon({{-2, -0.1, 0}, {2, -0.1, 0}, {2, 0.1, 0}, {-2, 0.1, 0}}, res);
    const int w = e.add_shape_wall(plate, {0, -0.1, 0});
    res.level_set_spacing = 0.05;
    e.add_grain(grain(0, Shape::disk(1.0, res), {0.3, 1.0, 0}));
    for (int i = 0; i < 6000; ++i) e.step(e.max_stable_dt());
    const double mg = 1000 * kPi * 9.81;
    EXPECT_NEAR(e.shape_wall_force(w).y / -mg, 1.0, 0.01);
    ASSERT_EQ(e.contacts().size(), 1u);
    EXPECT_EQ(e.contacts()[0].wall, LsdemEngine::kFirstShapeWall + w);
    e.set_shape_wall_motion(w, {0, 0.5, 0}, {});
    for (int i = 0; i < 3000; ++i) e.step(e.max_stable_dt());
    std::vector<Grain> g(1);
    g[0].id = 0;
    e.read_state(g);
    EXPECT_NEAR(g[0].velocity.y, 0.5, 0.02);
    EXPECT_NEAR(e.shape_wall_position(w).y, -0.1 + 0.5 * 3000 * e.max_stable_dt(), 1e-9);
  }
  {
    LsdemSettings s;
    s.kn = 1e7;
    s.damping_ratio = 0.7;
    auto ctx = context(3, {0, 0, -9.81});
    ctx.materials[0].wall_friction = 0.1;
    LsdemEngine e(s, ctx);
    ShapeResolution res;
    res.level_set_spacing = 0.05;
    const double th = 0.2;
    const Quat tilt = Quat::from_axis_angle({0, 1, 0}, th);  // slope going down towards +x
    e.add_shape_wall(Shape::box({4, 1, 0.2}, res), {-2, 0, 0}, tilt);  // the cube stays on it
    const Vec3 up = tilt.rotate({0, 0, 1}), down_slope = tilt.rotate({1, 0, 0});
    EXPECT_LT(down_slope.z, 0);
    auto cube = Shape::box({0.25, 0.25, 0.25}, res);
    e.add_grain(grain(0, cube, Vec3{-2, 0, 0} + up * 0.45, tilt));
    const double dt = e.max_stable_dt();
    std::vector<Grain> g(1);
    g[0].id = 0;
    for (int i = 0; i < 2000; ++i) e.step(dt);  // lands, starts sliding
    e.read_state(g);
    const double s0 = dot(g[0].position, down_slope), v0 = dot(g[0].velocity, down_slope);
    const int n = 3000;
    for (int i = 0; i < n; ++i) e.step(dt);
    e.read_state(g);
    const double T = n * dt;
    const double a = 9.81 * (std::sin(th) - 0.1 * std::cos(th));
    const double travelled = dot(g[0].position, down_slope) - s0;
    EXPECT_NEAR(travelled / (v0 * T + 0.5 * a * T * T), 1.0, 0.03);
  }
  {
    // A rigid body given by a closed triangle mesh (crusher plates): a sphere rests on a
    // slab read as a TriMesh and carries its weight into it.
    LsdemSettings s;
    s.kn = 1e7;
    s.damping_ratio = 0.7;
    s.global_damping = 1;
    LsdemEngine e(s, context(3, {0, 0, -9.81}));
    ShapeResolution res;
    res.level_set_spacing = 0.05;
    TriMesh slab;
    for (int i = 0; i < 8; ++i) slab.vertices.push_back({(i & 1) ? 2.0 : -2.0, (i & 2) ? 2.0 : -2.0, (i & 4) ? 0.2 : -0.2});
    slab.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                      {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    const int w = e.add_shape_wall(Shape::polyhedron(slab, res), {0, 0, -0.2});
    e.add_grain(grain(0, sphere(1.0, 0.05, 4000), {0.1, -0.2, 1.0}));
    for (int i = 0; i < 4000; ++i) e.step(e.max_stable_dt());
    const double mg = 1000 * 4 * kPi / 3 * 9.81;
    EXPECT_NEAR(e.shape_wall_force(w).z / -mg, 1.0, 0.01);
  }
}

// The broad phase's Verlet list (pair_list_skin) changes only the speed: a pile run with the
// list kept while the grains stay within the skin ends bit for bit where a run rebuilding
// it every step ends, and it is rebuilt far less often than every step.
TEST(Lsdem, PairListReuseIsBitwiseIdenticalToRebuildingEveryStep) {
  LsdemSettings every, kept;
  every.pair_list_skin = 0;
  kept.pair_list_skin = 0.2;
  const PileRun a = run_pile(every), b = run_pile(kept);
  EXPECT_EQ(a.stats.pair_list_builds, 1200);
  EXPECT_LT(b.stats.pair_list_builds, 600);
  expect_bitwise_equal(a, b);
}
