// Conformance of the engine seam (core/Engine.h): every registered engine, in every
// dimension it declares, passes the same statics and dynamics against closed forms.
//   - a grain at rest on the floor carries its weight m·g (1 %), through floor contacts
//     that follow contacts()'s conventions;
//   - a stack of three: the floor carries 3mg, the contacts below the middle and the top
//     grain 2mg and mg (1 %);
//   - a force-controlled platen on the stack: platen force = command and
//     platen force = floor force − weight (2 %);
//   - gravity turned towards each side wall: wall_force() of that wall is m·g (1 %), every
//     other wall's is zero, and it equals the sum of the wall's contacts;
//   - free fall: velocity, height and kinetic energy against g·t, g·t²/2 and the work of the
//     weight, within one time step's worth of the integrator's offset;
//   - the same scene run twice with one thread gives bitwise the same state;
//   - a grain replaced mid-run by its two halves: no NaN, the floor carries the weight (1 %);
//   - Coulomb friction: a sliding cube stops after v0²/(2μg) on the floor and on a grain;
//   - mass scaling (engines with a `mass_scale` option) keeps the weights physical.
// The engines come from the registration table (tests/support/Registered.h): a new engine,
// or a plugin's (CRUMBLE_TEST_PLUGINS), is tested by registering it. Engine-specific checks
// (Bullet margins, ODE contact clipping, lsdem contact laws) stay in tests/unit/<engine>.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <map>
#include <random>

#include "core/Config.h"
#include "core/Platen.h"
#include "scenarios/Registry.h"
#include "tests/support/EngineKit.h"
#include "tests/support/Registered.h"

using namespace crumble;
using namespace crumble::testing_support;
using nlohmann::json;

namespace {

constexpr double kG = 9.81;
constexpr double kDensity = 2650;  // Material{} default
constexpr double kDt = 5e-5;       // Zhu & Zhao 2019 §5's smallest step; explicit engines go below

// Test profile: the options an engine needs to handle 1–2 mm grains in these scenes at an
// affordable cost, and the damping that brings the static scenes to rest sooner (it does not
// change a state at rest; the dynamic tests run without it). Unknown engines (plugins) run
// with their defaults.
struct Profile {
  json options = json::object();
  json statics = json::object();  // added for the scenes that must come to rest
};

Profile profile(const std::string& engine, int dim) {
  if (engine == "lsdem") {
    // Explicit: the stable step is 0.1·√(m/k_n); Harmon et al. 2020 Table 2's 4e7 N/m would
    // need 5e-8 s steps for a 2 mm grain. k_n = 1e3 N/m (2D: 1e6 N/m per metre of
    // thickness) gives ≈ 1e-5 s steps and overlaps below 0.2 % of a grain under these loads.
    return {{{"kn", dim == 3 ? 1e4 : 1e7}, {"damping_ratio", 0.7}}, {{"global_damping", 100}}};
  }
  return {};
}

class EngineConformance : public ::testing::TestWithParam<Registered> {
 protected:
  int dim() const { return GetParam().dimension; }
  Vec3 gravity() const { return dim() == 3 ? Vec3{0, 0, -kG} : Vec3{0, -kG, 0}; }
  // The vertical component (z in 3D, y in 2D).
  double up(const Vec3& v) const { return dim() == 3 ? v.z : v.y; }
  // A point at lateral position x (and y = 5 mm in 3D) and height h.
  Vec3 at(double x, double h) const { return dim() == 3 ? Vec3{x, 5e-3, h} : Vec3{x, h, 0}; }
  Quat turn(double angle) const { return Quat::from_axis_angle({0, 0, 1}, angle); }

  std::unique_ptr<Engine> make(Material mat = Material{}, bool statics = false, const json& extra = json::object()) const {
    return make_with_gravity(gravity(), mat, statics, extra);
  }
  std::unique_ptr<Engine> make_with_gravity(Vec3 g, Material mat = Material{}, bool statics = false,
                                            const json& extra = json::object()) const {
    const Profile p = profile(GetParam().name, dim());
    json opts = p.options;
    if (statics) opts.update(p.statics);
    opts.update(extra);
    opts["type"] = GetParam().name;
    Config cfg(opts);
    EngineContext ctx;
    ctx.dimension = dim();
    ctx.gravity = g;
    ctx.materials = {mat};
    ctx.threads = 1;
    auto e = engines().find(GetParam().name, "/engine/type").make(cfg, ctx);
    cfg.check_unknown();
    return e;
  }

  Container box(double height) const {
    Container c;
    c.lx = 10e-3;
    c.ly = dim() == 3 ? 10e-3 : 0;
    c.height = height;
    return c;
  }

  // 2 mm sphere / disk, 2 mm cube / square.
  Shape::Ptr ball() const { return dim() == 3 ? Shape::sphere(1e-3) : Shape::disk(1e-3); }
  Shape::Ptr cube() const {
    if (dim() == 3) return Shape::box({1e-3, 1e-3, 1e-3});
    return Shape::polygon({{-1e-3, -1e-3, 0}, {1e-3, -1e-3, 0}, {1e-3, 1e-3, 0}, {-1e-3, 1e-3, 0}});
  }
  static double mass(const Shape::Ptr& s) { return kDensity * s->volume(); }  // 2D: per metre

  static Grain grain(GrainId id, Shape::Ptr s, Vec3 pos, Quat q = {}) {
    return testing_support::grain(id, std::move(s), pos, q);
  }

  // The engine's step: kDt, or its stable bound when that is smaller (explicit engines).
  static double step_of(const Engine& e) { return std::min(kDt, e.max_stable_dt()); }
  static long run(Engine& e, double time) {
    const double dt = step_of(e);
    const long n = std::lround(time / dt);
    for (long i = 0; i < n; ++i) e.step(dt);
    return n;
  }
  static Grain state_of(const Engine& e, const Grain& g0) {
    Grain g = g0;
    e.read_state(std::span<Grain>(&g, 1));
    return g;
  }

  // Forces averaged over `window` seconds of further steps. A state at rest has mean
  // acceleration zero, so the mean forces balance the weights; single steps of a PGS solver
  // fluctuate a little and the springs of an explicit engine ring at √(k/m) (lsdem's
  // face-on-face contacts of these cubes keep an oscillation of several per cent).
  struct Mean {
    double floor = 0, platen = 0, floor_contacts = 0, platen_contacts = 0;
    std::map<std::pair<GrainId, GrainId>, double> pair;  // vertical force on first from second
  };
  Mean average(Engine& e, double window) const {
    const double dt = step_of(e);
    const long n = std::max(50L, std::lround(window / dt));
    Mean m;
    for (long k = 0; k < n; ++k) {
      e.step(dt);
      m.floor += e.floor_force() / n;
      m.platen += e.platen_force() / n;
      for (const auto& c : e.contacts()) {
        if (c.wall == kFloor) m.floor_contacts += up(c.force) / n;
        if (c.wall == kPlaten) m.platen_contacts -= up(c.force) / n;  // the force on the grain is downward
        if (!c.is_wall()) {
          m.pair[{c.a, c.b}] += up(c.force) / n;
          m.pair[{c.b, c.a}] -= up(c.force) / n;
        }
      }
    }
    return m;
  }
  static double pair_of(const Mean& m, GrainId on, GrainId from) {
    const auto it = m.pair.find({on, from});
    return it == m.pair.end() ? 0.0 : it->second;
  }

  // Bottom (id 5), middle (id 2) and top (id 9) cubes, a little apart and turned.
  std::vector<Grain> add_stack(Engine& e, const Shape::Ptr& s) const {
    // In 2D a turn about z would tilt the squares: they stay upright, shifted sideways.
    const double a = dim() == 3 ? 1 : 0;
    std::vector<Grain> gs = {grain(5, s, at(5e-3, 1.005e-3)), grain(2, s, at(5.2e-3, 3.01e-3), turn(0.4 * a)),
                             grain(9, s, at(5.0e-3, 5.02e-3), turn(-0.3 * a))};
    if (dim() == 3) gs[1].position.y = 4.9e-3, gs[2].position.y = 5.1e-3;
    for (const auto& g : gs) e.add_grain(g);
    return gs;
  }
};

TEST_P(EngineConformance, WeightOnTheFloorAtRest) {
  Material mat;
  mat.rolling_friction = 0;  // a polyhedral sphere must tip onto a face, under its centroid
  auto e = make(mat, true);
  e->set_container(box(10e-3));
  const auto s = ball();
  const Grain g0 = grain(0, s, at(5e-3, 1.05e-3), dim() == 3 ? Quat::from_axis_angle({1, 2, 0}, 0.3) : turn(0.3));
  e->add_grain(g0);
  run(*e, 0.15);  // fall 0.05 mm, settle
  const double mg = mass(s) * kG;
  const Mean m = average(*e, 0.01);
  EXPECT_NEAR(m.floor, mg, 0.01 * mg);
  EXPECT_NEAR(m.floor_contacts, m.floor, 1e-9 * mg) << "floor_force() is the sum of the floor contacts";
  EXPECT_NEAR(m.platen, 0.0, 1e-9 * mg);
  const auto cs = e->contacts();
  ASSERT_FALSE(cs.empty());
  const Grain g = state_of(*e, g0);
  for (const auto& c : cs) {
    // Conventions of contacts(): the grain is `a`, a wall has b = −1, the normal points
    // from b (the floor) towards a, the force is the one on a, the point under the grain.
    EXPECT_EQ(c.a, 0);
    EXPECT_EQ(c.b, -1);
    EXPECT_EQ(c.wall, kFloor);
    EXPECT_NEAR(up(c.normal), 1.0, 1e-6);
    EXPECT_GT(up(c.force), 0.0);
    EXPECT_NEAR(up(c.point), 0.0, 0.03e-3);
    EXPECT_NEAR(c.point.x, g.position.x, 0.05e-3);
  }
  EXPECT_LT(norm(g.velocity), 1e-3);
  EXPECT_NEAR(up(g.position), 1e-3, 0.1e-3);
}

TEST_P(EngineConformance, StackOfThreeCarriesTheWeightsDownwards) {
  auto e = make(Material{}, true);
  e->set_container(box(10e-3));
  const auto s = cube();
  const auto gs = add_stack(*e, s);
  run(*e, 0.2);
  const double mg = mass(s) * kG;
  const Mean m = average(*e, 0.01);
  EXPECT_NEAR(m.floor, 3 * mg, 0.01 * 3 * mg);
  EXPECT_NEAR(m.floor_contacts, m.floor, 1e-9 * mg);
  EXPECT_NEAR(pair_of(m, 2, 5), 2 * mg, 0.01 * 2 * mg) << "bottom holds up middle and top";
  EXPECT_NEAR(pair_of(m, 9, 2), mg, 0.01 * mg) << "middle holds up top";
  EXPECT_EQ(pair_of(m, 9, 5), 0.0) << "top and bottom do not touch";
  for (const auto& c : e->contacts())
    if (c.is_wall()) {
      EXPECT_EQ(c.wall, kFloor);
      EXPECT_EQ(c.a, 5) << "only the bottom cube touches the floor";
    } else {
      EXPECT_LT(c.a, c.b) << "a grain pair is reported once, a = the smaller id";
      EXPECT_TRUE(is_finite(c.force) && is_finite(c.point) && is_finite(c.normal));
    }
  const Grain top = state_of(*e, gs[2]);
  EXPECT_NEAR(up(top.position), 5e-3, 0.02e-3);
  EXPECT_LT(norm(top.velocity), 1e-3);
}

TEST_P(EngineConformance, PlatenForceIsFloorForceMinusWeight) {
  auto e = make(Material{}, true);
  const Container c = box(6.4e-3);
  e->set_container(c);
  const auto s = cube();
  add_stack(*e, s);
  const double W = 3 * mass(s) * kG;
  const double F = 10 * W;  // the weight is 9 % of the floor force
  run(*e, 0.1);
  // Bring the platen down until it touches, then ramp the force command and hold it.
  e->set_platen({PlatenCommand::Mode::Velocity, -0.02});
  const double dt = step_of(*e);
  for (double t = 0; t < 0.05 && !(e->platen_force() > 0); t += dt) e->step(dt);
  ASSERT_GT(e->platen_force(), 0.0) << "the platen never reached the stack";
  const long ramp = std::lround(0.02 / dt);
  for (long k = 1; k <= ramp; ++k) {
    e->set_platen({PlatenCommand::Mode::Force, F * k / ramp});
    e->step(dt);
  }
  run(*e, 0.1);
  const Mean m = average(*e, 0.01);
  EXPECT_NEAR(m.platen, F, 0.02 * F);
  EXPECT_NEAR(m.floor - W, m.platen, 0.02 * m.platen);
  EXPECT_NEAR(m.floor_contacts, m.floor, 1e-9 * F);
  EXPECT_NEAR(m.platen_contacts, m.platen, 1e-9 * F);
  for (const auto& k : e->contacts()) {
    EXPECT_TRUE(is_finite(k.force) && is_finite(k.point) && is_finite(k.normal));
    if (k.wall == kPlaten) EXPECT_LT(up(k.normal), -0.99);
  }
  EXPECT_LT(e->platen_position(), c.height);
  EXPECT_GT(e->platen_position(), 5.9e-3);  // on the stack, not through it
}

// Gravity turned towards one side wall at a time: a cube resting against that wall pushes
// it with its weight m·g (1 %), wall_force() of every other wall is zero, and wall_force()
// is the sum of the normal components of that wall's contacts (the per-wall force a K0
// measurement reads; floor and platen agree with floor_force() and platen_force()).
TEST_P(EngineConformance, SideWallCarriesASidewaysWeight) {
  std::vector<int> walls = {kWallXMin, kWallXMax};
  if (dim() == 3) walls.insert(walls.end(), {kWallYMin, kWallYMax});
  const auto s = cube();
  const double mg = mass(s) * kG;
  const Container c = box(10e-3);
  for (int w : walls) {
    SCOPED_TRACE("wall " + std::to_string(w));
    const Vec3 n = wall_inward_normal(w, dim());
    auto e = make_with_gravity(n * -kG, Material{}, true);
    e->set_container(c);
    // 0.05 mm off the wall, halfway up the box and across it.
    Vec3 p = dim() == 3 ? Vec3{5e-3, 5e-3, 5e-3} : Vec3{5e-3, 5e-3, 0};
    const double gap = 1.05e-3;
    if (w == kWallXMin) p.x = gap;
    if (w == kWallXMax) p.x = c.lx - gap;
    if (w == kWallYMin) p.y = gap;
    if (w == kWallYMax) p.y = c.ly - gap;
    e->add_grain(grain(0, s, p));
    run(*e, 0.15);
    const double dt = step_of(*e);
    const long n_avg = std::max(50L, std::lround(0.01 / dt));
    double mean = 0, from_contacts = 0, others = 0;
    for (long k = 0; k < n_avg; ++k) {
      e->step(dt);
      mean += e->wall_force(w) / n_avg;
      for (const auto& ct : e->contacts())
        if (ct.wall == w) from_contacts += dot(ct.force, n) / n_avg;
      for (int o : {kFloor, kPlaten, kWallXMin, kWallXMax, kWallYMin, kWallYMax})
        if (o != w) others = std::max(others, std::abs(e->wall_force(o)));
      EXPECT_EQ(e->wall_force(kFloor), e->floor_force());
      EXPECT_EQ(e->wall_force(kPlaten), e->platen_force());
    }
    EXPECT_NEAR(mean, mg, 0.01 * mg);
    EXPECT_NEAR(from_contacts, mean, 1e-9 * mg) << "wall_force() is the sum of the wall's contacts";
    EXPECT_LE(others, 1e-9 * mg) << "no other wall is touched";
  }
}

// Semi-implicit Euler gives v = −g·t and z = z0 − g·t²/2 − g·t·Δt/2; other integrators
// differ by at most one step's worth: |Δv| ≤ g·Δt, |Δz| ≤ g·t·Δt, and the kinetic energy
// equals the work of the weight within m·g·|v|·Δt.
TEST_P(EngineConformance, FreeFallMatchesTheClosedForm) {
  auto e = make();
  e->set_container(box(100e-3));
  const auto s = ball();
  const double z0 = 50e-3;
  const Grain g0 = grain(0, s, at(5e-3, z0));
  e->add_grain(g0);
  const double dt = step_of(*e);
  const long n = run(*e, 0.05);  // falls 12 mm
  const double t = n * dt;
  const Grain g = state_of(*e, g0);
  EXPECT_NEAR(up(g.velocity), -kG * t, 1.01 * kG * dt);
  EXPECT_NEAR(up(g.position), z0 - 0.5 * kG * t * t, 1.01 * kG * t * dt);
  EXPECT_NEAR(g.velocity.x, 0, 1e-12);
  EXPECT_NEAR(g.position.x, 5e-3, 1e-12);
  const double m = mass(s), v = norm(g.velocity);
  EXPECT_NEAR(0.5 * m * v * v, m * kG * (z0 - up(g.position)), 1.01 * m * kG * v * dt);
  EXPECT_TRUE(e->contacts().empty());
  EXPECT_EQ(e->floor_force(), 0.0);
}

TEST_P(EngineConformance, SameResultTwiceWithOneThread) {
  struct Out {
    std::vector<Grain> grains;
    std::vector<Contact> contacts;
    double platen = 0, floor = 0;
  };
  // A pile of spheres and cubes (disks and squares) that collapses in a 6 mm box, then a
  // force-controlled platen comes down on it.
  auto once = [&] {
    auto e = make();
    Container c = box(9e-3);
    c.lx = 6e-3;
    c.ly = dim() == 3 ? 6e-3 : 0;
    e->set_container(c);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    Out o;
    double weight = 0;
    for (int i = 0; i < 8; ++i) {
      const auto s = i % 3 ? ball() : cube();
      weight += mass(s) * kG;
      const double x = 1.5e-3 + 3e-3 * (i % 2) + 0.3e-3 * u(rng);
      Grain g = dim() == 3 ? grain(i, s, {x, 1.5e-3 + 3e-3 * ((i / 2) % 2) + 0.3e-3 * u(rng), 1.5e-3 + 2.6e-3 * (i / 4)},
                                   Quat::from_axis_angle({u(rng), u(rng), 1}, 2 * u(rng)))
                           : grain(i, s, {x, 1.5e-3 + 2.6e-3 * (i / 2), 0}, turn(2 * u(rng)));
      g.velocity = dim() == 3 ? Vec3{0.02 * u(rng), 0.02 * u(rng), 0} : Vec3{0.02 * u(rng), 0, 0};
      e->add_grain(g);
      o.grains.push_back(g);
    }
    run(*e, 0.03);
    e->set_platen({PlatenCommand::Mode::Force, 20 * weight});
    run(*e, 0.04);
    e->read_state(o.grains);
    o.contacts = e->contacts();
    o.platen = e->platen_force();
    o.floor = e->floor_force();
    return o;
  };
  const Out a = once(), b = once();
  ASSERT_GT(a.contacts.size(), 4u) << "the scene must exercise contacts";
  EXPECT_GT(a.platen, 0.0) << "the platen must be pressing on the grains";
  for (std::size_t i = 0; i < a.grains.size(); ++i) {
    EXPECT_EQ(std::memcmp(&a.grains[i].position, &b.grains[i].position, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.grains[i].orientation, &b.grains[i].orientation, sizeof(Quat)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.grains[i].velocity, &b.grains[i].velocity, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.grains[i].angular_velocity, &b.grains[i].angular_velocity, sizeof(Vec3)), 0) << i;
  }
  ASSERT_EQ(a.contacts.size(), b.contacts.size());
  for (std::size_t i = 0; i < a.contacts.size(); ++i) {
    EXPECT_EQ(a.contacts[i].a, b.contacts[i].a);
    EXPECT_EQ(a.contacts[i].b, b.contacts[i].b);
    EXPECT_EQ(a.contacts[i].wall, b.contacts[i].wall);
    EXPECT_EQ(std::memcmp(&a.contacts[i].force, &b.contacts[i].force, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.contacts[i].point, &b.contacts[i].point, sizeof(Vec3)), 0) << i;
  }
  EXPECT_EQ(std::memcmp(&a.platen, &b.platen, sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&a.floor, &b.floor, sizeof(double)), 0);
}

// A grain replaced mid-run by its two halves (what every breakage event does): no NaN, the
// halves settle where the parent was, and the floor carries the same weight (1 %).
TEST_P(EngineConformance, ReplacingAGrainByTwoHalvesMidRun) {
  auto e = make(Material{}, true);
  e->set_container(box(10e-3));
  // 4 × 2 (× 2) mm, cut into two 2 mm cubes (squares); a ball rests on it.
  const auto whole = dim() == 3 ? Shape::box({2e-3, 1e-3, 1e-3})
                                : Shape::polygon({{-2e-3, -1e-3, 0}, {2e-3, -1e-3, 0}, {2e-3, 1e-3, 0}, {-2e-3, 1e-3, 0}});
  const auto half = cube();
  const auto top = dim() == 3 ? Shape::sphere(0.9e-3) : Shape::disk(0.9e-3);
  Grain parent = grain(7, whole, at(5e-3, 1.01e-3), turn(dim() == 3 ? 0.3 : 0));
  e->add_grain(parent);
  e->add_grain(grain(8, top, at(5e-3, 3.2e-3)));
  run(*e, 0.05);
  parent = state_of(*e, parent);
  // Children in the parent frame at x = ±1 mm, velocities v + ω × r.
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
  const double dt = step_of(*e);
  for (long k = 0, n = std::lround(0.075 / dt); k < n; ++k) {
    e->step(dt);
    ASSERT_TRUE(std::isfinite(e->floor_force())) << "step " << k;
  }
  const double W = (mass(whole) + mass(top)) * kG;
  EXPECT_NEAR(average(*e, 0.01).floor, W, 0.01 * W);
  for (auto& c : kids) {
    c = state_of(*e, c);
    EXPECT_TRUE(is_finite(c.position) && is_finite(c.velocity));
    EXPECT_NEAR(up(c.position), 1e-3, 0.05e-3);
  }
  for (const auto& c : e->contacts()) EXPECT_TRUE(is_finite(c.force));
}

// Coulomb friction: a cube (square) launched at v0 along what it rests on stops after
// v0²/(2μg) (less half a step's travel for semi-implicit Euler), μ the wall friction on the floor (2 %) and the grain
// friction on another grain (3 %). With Engine::set_friction_scale(0.5) (frictionless-ish
// settling of a packing) both distances double; engines that cannot scale friction skip that part.
TEST_P(EngineConformance, SlidingFrictionStopsAtTheCoulombDistance) {
  Material mat;
  mat.friction = 0.5;
  mat.wall_friction = 0.3;
  mat.rolling_friction = 0;
  const double v0 = 0.05;
  Container c = box(10e-3);
  c.lx = 20e-3;
  if (dim() == 3) c.ly = 20e-3;
  const auto slide = [&](bool on_grain, double scale) {
    auto e = make(mat);
    e->set_container(c);
    ASSERT_TRUE(e->set_friction_scale(scale));
    double h = 1e-3;
    if (on_grain) {
      const auto slab = dim() == 3 ? Shape::box({4e-3, 4e-3, 1e-3})
                                   : Shape::polygon({{-4e-3, -1e-3, 0}, {4e-3, -1e-3, 0}, {4e-3, 1e-3, 0}, {-4e-3, 1e-3, 0}});
      Grain base = grain(0, slab, at(10e-3, 1e-3));
      if (dim() == 3) base.position.y = 10e-3;
      e->add_grain(base);
      h = 3e-3;
    }
    Grain s = grain(1, cube(), at(on_grain ? 8e-3 : 5e-3, h));  // touching what it slides on
    if (dim() == 3) s.position.y = 10e-3;
    s.velocity = {v0, 0, 0};
    e->add_grain(s);
    const double x0 = s.position.x;
    const double mu = (on_grain ? mat.friction : mat.wall_friction) * scale;
    run(*e, 1.5 * v0 / (mu * kG));  // it stops after v0/(μg)
    const Grain r = state_of(*e, s);
    const double expect = v0 * v0 / (2 * mu * kG) - 0.5 * v0 * step_of(*e);
    EXPECT_NEAR(r.position.x - x0, expect, (on_grain ? 0.03 : 0.02) * expect)
        << (on_grain ? "on a grain" : "on the floor") << ", friction scale " << scale;
    EXPECT_NEAR(r.velocity.x, 0.0, 0.005 * v0);  // an explicit engine's tangential spring still rings
  };
  slide(false, 1.0);
  slide(true, 1.0);
  if (!make(mat)->set_friction_scale(0.5)) GTEST_SKIP() << "the engine cannot scale friction (Engine::set_friction_scale)";
  slide(false, 0.5);
  slide(true, 0.5);
}

// Mass scaling (Zhu & Zhao 2019 §5: ×70) slows the dynamics but keeps the weights physical:
// the floor carries m·g, not 70·m·g. Engines without a `mass_scale` option skip.
TEST_P(EngineConformance, MassScalingKeepsWeightsPhysical) {
  bool has = false;
  for (const auto& o : engines().find(GetParam().name, "/engine/type").options) has = has || o.key == "mass_scale";
  if (!has) GTEST_SKIP() << GetParam().name << " declares no mass_scale option";
  auto e = make(Material{}, true, {{"mass_scale", 70}});
  e->set_container(box(10e-3));
  const auto s = cube();
  e->add_grain(grain(0, s, at(5e-3, 1.02e-3)));
  run(*e, 0.1);
  const double mg = mass(s) * kG;
  EXPECT_NEAR(average(*e, 0.01).floor, mg, 0.01 * mg);
}

INSTANTIATE_TEST_SUITE_P(Registry, EngineConformance, ::testing::ValuesIn(registered_engines()),
                         [](const auto& info) { return param_name(info.param); });

}  // namespace
