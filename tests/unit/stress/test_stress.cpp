// Breakage model "stress" (Harmon et al. 2020, §3.1, §3.3): criteria on known stress
// states, the average stress against closed forms, the fracture plane and its fallbacks,
// Weibull strengths and their size effect, and the option errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "breakage/stress/StressModel.h"
#include "core/Config.h"
#include "geometry/level_set/LevelSetBuilder.h"

using namespace crumble;
using Json = nlohmann::json;

namespace {


double equivalent(const std::string& criterion, const stress::Principal& p) {
  return stress::find_criterion(criterion)->make()->equivalent_stress(p);
}

StrengthState strengths(double s, double t = 0) {
  StrengthState st;
  st.set(stress::kStrength, s);
  if (t > 0) st.set(stress::kTensileStrength, t);
  return st;
}

Contact wall_contact(int wall, Vec3 p, Vec3 f) {
  Contact c;
  c.a = 0;
  c.wall = wall;
  c.point = p;
  c.force = f;
  c.normal = normalized(f);
  return c;
}

std::unique_ptr<StressModel> model(const Json& breakage, int dim) {
  Json doc = breakage;
  Config cfg(doc);
  EngineContext ctx;
  ctx.dimension = dim;
  auto m = make_stress(cfg, ctx);
  return std::unique_ptr<StressModel>(static_cast<StressModel*>(m.release()));
}

}  // namespace

// ---------------------------------------------------------------- criteria (eqs. 7–10)

TEST(StressCriteria, UniaxialHydrostaticAndPureShear) {
  const double S = 10e6;
  // Uniaxial compression S (tension positive: principal values 0, 0, −S).
  const stress::Principal uni{0, 0, -S};
  EXPECT_NEAR(equivalent("von_mises", uni), S, 1e-6);
  EXPECT_NEAR(equivalent("tresca", uni), S, 1e-6);
  EXPECT_NEAR(equivalent("max_principal", uni), S, 1e-6);
  // Hydrostatic compression p: no deviatoric stress.
  const stress::Principal hyd{-S, -S, -S};
  EXPECT_NEAR(equivalent("von_mises", hyd), 0, 1e-6);
  EXPECT_NEAR(equivalent("tresca", hyd), 0, 1e-6);
  EXPECT_NEAR(equivalent("max_principal", hyd), S, 1e-6);
  // Pure shear τ: principal values τ, 0, −τ; σ_V = √3 τ, Tresca 2τ.
  const double tau = 4e6;
  const stress::Principal shear{tau, 0, -tau};
  EXPECT_NEAR(equivalent("von_mises", shear), std::sqrt(3.0) * tau, 1e-6);
  EXPECT_NEAR(equivalent("tresca", shear), 2 * tau, 1e-6);
  EXPECT_NEAR(equivalent("max_principal", shear), tau, 1e-6);
  // Uniaxial tension: the compressive measure is 0.
  EXPECT_EQ(equivalent("max_principal", {S, 0, 0}), 0.0);
}

TEST(StressCriteria, FailureAgainstTheStrengths) {
  auto vm = stress::find_criterion("von_mises")->make();
  EXPECT_TRUE(vm->fails({0, 0, -35e6}, strengths(35e6)));
  EXPECT_FALSE(vm->fails({0, 0, -34.9e6}, strengths(35e6)));
  auto tr = stress::find_criterion("tresca")->make();
  // eq. 10: τ ≥ ½σ^max, i.e. a pure shear of 20 MPa breaks a 40 MPa grain.
  EXPECT_TRUE(tr->fails({20e6, 0, -20e6}, strengths(40e6)));
  EXPECT_FALSE(tr->fails({19.9e6, 0, -19.9e6}, strengths(40e6)));
  auto mp = stress::find_criterion("max_principal")->make();
  // eqs. 7–8: 40 MPa in compression, 0.4 MPa in tension.
  EXPECT_TRUE(mp->fails({0, 0, -40e6}, strengths(40e6, 0.4e6)));
  EXPECT_FALSE(mp->fails({0, 0, -39e6}, strengths(40e6, 0.4e6)));
  EXPECT_TRUE(mp->fails({0.4e6, 0, -1e6}, strengths(40e6, 0.4e6)));
  EXPECT_FALSE(mp->fails({0.39e6, 0, -1e6}, strengths(40e6, 0.4e6)));
}

TEST(StressCriteria, TableHasThePapersCriteriaAndStrengths) {
  EXPECT_EQ(stress::criterion_names(), (std::vector<std::string>{"max_principal", "von_mises", "tresca"}));
  // Harmon et al. 2020, Table 2.
  EXPECT_EQ(stress::find_criterion("max_principal")->default_strength, 40e6);
  EXPECT_EQ(stress::find_criterion("max_principal")->default_tensile_strength, 0.4e6);
  EXPECT_EQ(stress::find_criterion("von_mises")->default_strength, 35e6);
  EXPECT_EQ(stress::find_criterion("tresca")->default_strength, 40e6);
  EXPECT_EQ(stress::find_criterion("nope"), nullptr);
}

// ---------------------------------------------------------------- average stress (eq. 5)

TEST(AverageStress, SphereBetweenTwoEqualAndOppositeForces) {
  // Closed form: σ = (1/V) Σ x ⊗ F = −2PR/V along the load axis, 0 elsewhere;
  // V = 4/3 πR³ → σ_axis = −3P/(2πR²).
  const double R = 1e-3, P = 100, V = 4.0 / 3.0 * kPi * R * R * R;
  const Vec3 c{0.01, 0.02, 0.03};
  for (const Vec3 axis : {Vec3{0, 0, 1}, normalized(Vec3{1, 1, 1}), normalized(Vec3{0.3, -2, 0.7})}) {
    std::vector<Contact> cs{wall_contact(1, c + axis * R, axis * -P), wall_contact(0, c - axis * R, axis * P)};
    const Mat3 s = average_stress(c, V, cs);
    const auto p = principal_stresses(s, 3);
    const double expect = -3 * P / (2 * kPi * R * R);
    EXPECT_NEAR(p[2], expect, 1e-9 * std::abs(expect));
    EXPECT_NEAR(p[0], 0, 1e-9 * std::abs(expect));
    EXPECT_NEAR(p[1], 0, 1e-9 * std::abs(expect));
    // von Mises of that uniaxial state is its magnitude.
    EXPECT_NEAR(equivalent("von_mises", p), -expect, 1e-9 * std::abs(expect));
  }
}

TEST(AverageStress, DiskBetweenTwoEqualAndOppositeForces) {
  // 2D: V = πR² (forces per unit thickness), σ_axis = −2PR/(πR²) = −2P/(πR); plane stress.
  const double R = 1e-3, P = 50;
  const Vec3 axis = normalized(Vec3{1, 2, 0});
  std::vector<Contact> cs{wall_contact(1, axis * R, axis * -P), wall_contact(0, axis * -R, axis * P)};
  const auto p = principal_stresses(average_stress({}, kPi * R * R, cs), 2);
  const double expect = -2 * P / (kPi * R);
  EXPECT_NEAR(p[2], expect, 1e-9 * std::abs(expect));
  EXPECT_NEAR(p[0], 0, 1e-9 * std::abs(expect));
  EXPECT_NEAR(p[1], 0, 1e-9 * std::abs(expect));
}

TEST(AverageStress, IsSymmetrised) {
  // A single tangential force: x ⊗ F is not symmetric; σ̄ is its symmetric part.
  std::vector<Contact> cs{wall_contact(0, {1, 0, 0}, {0, 2, 0})};
  const Mat3 s = average_stress({}, 1.0, cs);
  EXPECT_DOUBLE_EQ(s(0, 1), 1.0);
  EXPECT_DOUBLE_EQ(s(1, 0), 1.0);
}

// ---------------------------------------------------------------- fracture plane (§3.3)

TEST(FracturePlane, ThroughThreePoints) {
  const double R = 1e-3;
  const auto pl = fracture_plane({{R, 0, 0}, {0, R, 0}, {0, 0, R}}, {-1, 0, 0}, 3, 2 * R);
  ASSERT_TRUE(pl);
  const Vec3 n = pl->normal * (pl->normal.x > 0 ? 1.0 : -1.0);
  EXPECT_NEAR(n.x, 1 / std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(n.y, 1 / std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(n.z, 1 / std::sqrt(3.0), 1e-12);
  for (const Vec3 p : {Vec3{R, 0, 0}, Vec3{0, R, 0}, Vec3{0, 0, R}}) EXPECT_NEAR(pl->signed_distance(p), 0, 1e-15);
}

TEST(FracturePlane, TwoPointsAndTheCentroid) {
  const double R = 1e-3;
  const auto pl = fracture_plane({{R, 0, 0}, {0, R, 0}}, {-1, 0, 0}, 3, 2 * R);
  ASSERT_TRUE(pl);
  EXPECT_NEAR(std::abs(pl->normal.z), 1, 1e-12);
  EXPECT_NEAR(pl->offset, 0, 1e-15);
  // 2D: one contact and the centroid make the line.
  const auto line = fracture_plane({{R, R, 0}}, {-1, 0, 0}, 2, 2 * R);
  ASSERT_TRUE(line);
  EXPECT_NEAR(line->signed_distance({0, 0, 0}), 0, 1e-15);
  EXPECT_NEAR(line->signed_distance({R, R, 0}), 0, 1e-15);
  EXPECT_NEAR(line->normal.z, 0, 1e-15);
}

TEST(FracturePlane, CollinearAndCoincidentFallbacks) {
  const double R = 1e-3;
  // Diametral load: top, bottom and centroid collinear, force along the line → a meridian
  // plane containing the load axis.
  auto pl = fracture_plane({{0, 0, R}, {0, 0, -R}}, {0, 0, -100}, 3, 2 * R);
  ASSERT_TRUE(pl);
  EXPECT_NEAR(pl->normal.z, 0, 1e-15);
  EXPECT_NEAR(norm(pl->normal), 1, 1e-15);
  EXPECT_NEAR(pl->signed_distance({0, 0, 0.5 * R}), 0, 1e-15);
  // Collinear points, oblique force: the plane holds the line and the force direction.
  pl = fracture_plane({{0, 0, R}, {0, 0, -R}}, {1, 0, -1}, 3, 2 * R);
  ASSERT_TRUE(pl);
  EXPECT_NEAR(std::abs(pl->normal.y), 1, 1e-12);
  // Coincident points: the line along the force through the point.
  pl = fracture_plane({{R, 0, 0}, {R, 0, 0}, {R, 0, 0}}, {-1, 0, 0}, 3, 2 * R);
  ASSERT_TRUE(pl);
  EXPECT_NEAR(pl->normal.x, 0, 1e-15);
  EXPECT_NEAR(pl->signed_distance({R, 0, 0}), 0, 1e-15);
  // 2D coincident: the line through the point along the force.
  pl = fracture_plane({{R, 0, 0}, {R, 0, 0}}, {-3, 1, 0}, 2, 2 * R);
  ASSERT_TRUE(pl);
  EXPECT_NEAR(dot(pl->normal, normalized(Vec3{-3, 1, 0})), 0, 1e-12);
  // Nothing fixes a direction: no plane.
  EXPECT_FALSE(fracture_plane({{0, 0, 0}, {0, 0, 0}}, {0, 0, 0}, 3, 2 * R));
  EXPECT_FALSE(fracture_plane({{0, 0, 0}}, {0, 0, 0}, 2, 2 * R));
}

TEST(FracturePlane, NeverNaN) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::uniform_int_distribution<int> pick(0, 3);
  for (int t = 0; t < 2000; ++t) {
    std::vector<Vec3> pts;
    const int n = 1 + pick(rng) % 3;
    const Vec3 base{u(rng), u(rng), u(rng)};
    for (int i = 0; i < n; ++i) {
      // Mix of general, tiny-offset (nearly coincident) and collinear points.
      const int kind = pick(rng);
      Vec3 p = kind == 0 ? base : kind == 1 ? base + Vec3{1e-15, 0, 0} : kind == 2 ? base * -2.0 : Vec3{u(rng), u(rng), u(rng)};
      pts.push_back(p);
    }
    const Vec3 f = pick(rng) == 0 ? Vec3{} : Vec3{u(rng), u(rng), u(rng)};
    for (int dim : {2, 3}) {
      std::vector<Vec3> q = pts;
      if (dim == 2)
        for (auto& p : q) p.z = 0;
      if (dim == 3 && q.size() < 2) q.push_back(base * 0.5);
      const auto pl = fracture_plane(q, dim == 2 ? Vec3{f.x, f.y, 0} : f, dim, 2e-3);
      if (!pl) continue;
      EXPECT_TRUE(is_finite(pl->normal) && std::isfinite(pl->offset));
      EXPECT_NEAR(norm(pl->normal), 1, 1e-12);
      EXPECT_NEAR(pl->signed_distance(q.front()), 0, 1e-12);
    }
  }
}

// ---------------------------------------------------------------- strengths (eqs. 12–13)

TEST(StressStrength, WeibullSamplesFollowEq11) {
  // The median of eq. 11 at d0: σ0 (ln 2)^(1/m).
  auto m = model({{"criterion", "von_mises"}}, 3);
  Rng rng(11);
  std::vector<double> s;
  for (int i = 0; i < 4000; ++i) {
    Grain g;
    g.shape = Shape::sphere(1e-3);
    Rng r = rng.derive(static_cast<std::uint64_t>(i));
    m->assign_strength(g, Material{}, r);
    s.push_back(g.strength.get(stress::kStrength));
  }
  std::nth_element(s.begin(), s.begin() + 2000, s.end());
  EXPECT_NEAR(s[2000], 35e6 * std::cbrt(std::log(2.0)), 0.03 * 35e6);
}

TEST(StressStrength, ChildrenStrongerByEq13) {
  auto m = model({{"criterion", "max_principal"}, {"weibull", false}}, 3);
  Grain parent, child;
  parent.shape = Shape::sphere(1e-3);  // d = d0: σ0 exactly
  child.shape = Shape::sphere(0.5e-3);
  Rng rng(1);
  m->assign_strength(parent, Material{}, rng);
  EXPECT_DOUBLE_EQ(parent.strength.get(stress::kStrength), 40e6);
  EXPECT_DOUBLE_EQ(parent.strength.get(stress::kTensileStrength), 0.4e6);
  m->inherit_strength(parent, child, Material{}, rng);
  // (d_a/d_b)^(−3/m) with d_a/d_b = 1/2, m = 3: twice as strong.
  EXPECT_NEAR(child.strength.get(stress::kStrength), 80e6, 1e-6);
  EXPECT_NEAR(child.strength.get(stress::kTensileStrength), 0.8e6, 1e-9);
}

// ---------------------------------------------------------------- the model

TEST(StressModel, SplitsASphereThroughItsLoadAxis) {
  auto m = model({{"criterion", "von_mises"}, {"weibull", false}}, 3);
  Grain g;
  g.id = 7;
  g.shape = Shape::sphere(1e-3);
  g.position = {0.01, 0.01, 0.01};
  g.orientation = Quat::from_axis_angle({1, 0, 0}, 0.3);
  Rng rng(1);
  m->assign_strength(g, Material{}, rng);
  const double R = 1e-3;
  const double P_fail = 35e6 * 2 * kPi * R * R / 3;  // σ_V = 3P/(2πR²) = 35 MPa
  auto load = [&](double P) {
    return std::vector<Contact>{wall_contact(1, g.position + Vec3{0, 0, R}, {0, 0, -P}),
                                wall_contact(0, g.position - Vec3{0, 0, R}, {0, 0, P})};
  };
  const auto low = m->analyse(g, Material{}, load(0.99 * P_fail));
  EXPECT_FALSE(low.broken);
  EXPECT_EQ(low.outcome, "intact");
  EXPECT_NEAR(low.figure("equivalent_stress_Pa"), 0.99 * 35e6, 1e-6 * 35e6);
  const auto hit = m->analyse(g, Material{}, load(1.01 * P_fail));
  ASSERT_TRUE(hit.broken);
  EXPECT_EQ(hit.outcome, "split");
  EXPECT_NEAR(hit.load, 1.01 * P_fail, 1e-9);
  EXPECT_NEAR(hit.figure("sigma_3_Pa"), -1.01 * 35e6, 1e-6 * 35e6);
  EXPECT_NEAR(hit.figure("strength_Pa"), 35e6, 1e-6 * 35e6);
  ASSERT_TRUE(hit.fracture && std::holds_alternative<CuttingSurfaces>(*hit.fracture));
  const auto& planes = std::get<CuttingSurfaces>(*hit.fracture).planes;
  ASSERT_EQ(planes.size(), 1u);
  // The plane holds the load axis (world z) through the centroid: in the body frame.
  const Vec3 axis_body = g.orientation.conjugate().rotate({0, 0, 1});
  EXPECT_NEAR(dot(planes[0].normal, axis_body), 0, 1e-9);
  EXPECT_NEAR(planes[0].offset, 0, 1e-12);
  EXPECT_EQ(m->figure_names(), (std::vector<std::string>{"sigma_1_Pa", "sigma_2_Pa", "sigma_3_Pa",
                                                          "equivalent_stress_Pa", "strength_Pa", "plane_through_centroid"}));
}

// The plane through three strongest contacts close together near the top of a sphere
// (eqs. 19–20) would shave a cap of ~0.1 % of the grain; min_piece_fraction = 0.1 moves it
// along its normal until the cap holds 10 % of the volume. Closed form: a cap of height
// h·R holds h²(3 − h)/4 of the sphere, 0.1 at h = 0.3925, i.e. offset 0.6075 R.
TEST(StressModel, ContactsNearOneSideStillSplitTheGrainInTwoMeaningfulPieces) {
  const double R = 1e-3, f = 0.1;
  double lo = 0, hi = 1;  // solve h²(3 − h)/4 = f by bisection
  for (int i = 0; i < 60; ++i) ((0.5 * (lo + hi)) * (0.5 * (lo + hi)) * (3 - 0.5 * (lo + hi)) / 4 < f ? lo : hi) = 0.5 * (lo + hi);
  const double offset_exact = R * (1 - lo);
  ASSERT_NEAR(offset_exact / R, 0.6075, 1e-3);

  // plane_fallback "shift": the orientation of the contacts' plane is kept and only shifted.
  auto m = model({{"criterion", "von_mises"}, {"weibull", false}, {"strength", 1e6}, {"plane_fallback", "shift"}}, 3);
  EXPECT_DOUBLE_EQ(m->options().min_piece_fraction, f);  // the default
  Grain g;
  g.id = 3;
  g.shape = Shape::sphere(R);
  Rng rng(1);
  m->assign_strength(g, Material{}, rng);
  // Three partners pressing at points 0.1 R apart around the pole; the counter-force below
  // is shared by four weaker supports, so the three strongest contacts are the top ones.
  const double zc = std::sqrt(R * R - 0.01 * R * R);
  const double zb = -std::sqrt(R * R - 0.18 * R * R);
  std::vector<Contact> cs{wall_contact(1, {0.1 * R, 0, zc}, {0, 0, -300}), wall_contact(2, {-0.05 * R, 0.0866 * R, zc}, {0, 0, -300}),
                          wall_contact(3, {-0.05 * R, -0.0866 * R, zc}, {0, 0, -300}),
                          wall_contact(4, {0.3 * R, 0.3 * R, zb}, {0, 0, 225}), wall_contact(5, {-0.3 * R, 0.3 * R, zb}, {0, 0, 225}),
                          wall_contact(6, {-0.3 * R, -0.3 * R, zb}, {0, 0, 225}), wall_contact(7, {0.3 * R, -0.3 * R, zb}, {0, 0, 225})};
  const auto a = m->analyse(g, Material{}, cs);
  ASSERT_TRUE(a.broken);
  EXPECT_EQ(a.figure("plane_through_centroid"), 0.0);
  const CutPlane p = std::get<CuttingSurfaces>(*a.fracture).planes.at(0);
  EXPECT_NEAR(std::abs(p.normal.z), 1.0, 1e-9);  // orientation from the contacts (eq. 20)
  // The lattice estimate (24³ cells over the bounds) is within 2 % of R of the closed form.
  EXPECT_NEAR(std::abs(p.offset), offset_exact, 0.02 * R);
  // Without the clamp: the paper's plane through the points, a sliver of 0.07 % of the grain.
  auto raw = model({{"criterion", "von_mises"}, {"weibull", false}, {"strength", 1e6}, {"min_piece_fraction", 0.0}}, 3);
  raw->assign_strength(g, Material{}, rng);
  EXPECT_NEAR(std::abs(std::get<CuttingSurfaces>(*raw->analyse(g, Material{}, cs).fracture).planes.at(0).offset), zc, 1e-12);

  // The level-set builder then makes two children, the smaller one >= the stated fraction
  // (grid tolerance: 0.08 against 0.1).
  const FragmentResult r = LevelSetBuilder().build(*g.shape, *a.fracture);
  ASSERT_EQ(r.children.size(), 2u);
  const double v0 = r.children[0].shape->volume(), v1 = r.children[1].shape->volume();
  EXPECT_GE(std::min(v0, v1), 0.08 * g.shape->volume());
  EXPECT_LE(std::min(v0, v1), 0.12 * g.shape->volume());

  // The default plane_fallback "centroid": the centroid replaces the weakest of the three
  // points (Harmon et al. 2020 §3.3 let it fill in), so the plane holds the two strongest
  // contacts and the centroid: a meridian plane, two halves (lattice estimate within 3 %).
  auto mc = model({{"criterion", "von_mises"}, {"weibull", false}, {"strength", 1e6}}, 3);
  EXPECT_EQ(mc->options().plane_fallback, "centroid");
  mc->assign_strength(g, Material{}, rng);
  const auto ac = mc->analyse(g, Material{}, cs);
  ASSERT_TRUE(ac.broken);
  EXPECT_EQ(ac.figure("plane_through_centroid"), 1.0);
  const CutPlane pc = std::get<CuttingSurfaces>(*ac.fracture).planes.at(0);
  EXPECT_NEAR(pc.offset, 0.0, 1e-12 * R);                                     // through the centroid
  int in_plane = 0;  // and two of the three equally strong top contacts
  for (const Vec3& q : {Vec3{0.1 * R, 0, zc}, Vec3{-0.05 * R, 0.0866 * R, zc}, Vec3{-0.05 * R, -0.0866 * R, zc}})
    in_plane += std::abs(dot(pc.normal, q)) < 1e-12 * R;
  EXPECT_EQ(in_plane, 2);
  EXPECT_NEAR(smaller_side_fraction(*g.shape, pc), 0.5, 0.03);

  // 2D: a disk under two contacts close together on its rim (±0.05 rad from the top) and one
  // opposite. 2D forces are per metre of thickness, so eq. 5 gives a uniaxial σ_yy =
  // −(2·P·R·cos 0.05 + 2P·R)/(π R²) (the x–y terms of the two top contacts cancel); plane
  // stress: σ_VM = |σ_yy|. With P = 400 N/m on a 1 mm disk that is 0.51 MPa, below the 1 MPa
  // strength: the disk stays intact, as it should (the case removed in 85ad7c2). Ten times
  // the load breaks it; the line through the strongest contact (below) and the strongest
  // top one is nearly a diameter.
  auto m2 = model({{"criterion", "von_mises"}, {"weibull", false}, {"strength", 1e6}}, 2);
  Grain d;
  d.shape = Shape::disk(R);
  m2->assign_strength(d, Material{}, rng);
  const double s = std::sin(0.05), c = std::cos(0.05);
  for (double P : {400.0, 4000.0}) {
    std::vector<Contact> c2{wall_contact(1, {R * s, R * c, 0}, {0, -P, 0}), wall_contact(2, {-R * s, R * c, 0}, {0, -P, 0}),
                            wall_contact(0, {0, -R, 0}, {0, 2 * P, 0})};
    const double syy = (2 * P * R * c + 2 * P * R) / (kPi * R * R);
    const auto a2 = m2->analyse(d, Material{}, c2);
    EXPECT_NEAR(a2.figure("equivalent_stress_Pa"), syy, 1e-9 * syy) << P;
    EXPECT_EQ(a2.broken, syy >= 1e6) << P;
    if (!a2.broken) {
      EXPECT_EQ(a2.outcome, "intact");
      EXPECT_LT(syy, 1e6);
      continue;
    }
    const FragmentResult r2 = LevelSetBuilder().build(*d.shape, *a2.fracture);
    ASSERT_EQ(r2.children.size(), 2u);
    EXPECT_GE(std::min(r2.children[0].shape->volume(), r2.children[1].shape->volume()), 0.4 * d.shape->volume());
  }

  // Option range: a fraction of 0.5 or more is refused with its path.
  nlohmann::json bad = {{"criterion", "von_mises"}, {"min_piece_fraction", 0.5}};
  Config cb(bad);
  EXPECT_THROW(make_stress(cb, EngineContext{}), ConfigError);
}

// Harmon et al. 2020 §3.4, first method (min_piece_diameter): each side of the plane holds at
// least a sphere of that diameter. The sliver plane of the test above (three contacts close
// around the pole, plane_fallback "shift") is moved until the cap holds a quarter of the grain
// (d_min = 2R·0.25^(1/3)): closed form h²(3 − h)/4 = 0.25, offset 0.347 R. A grain of less than twice that
// sphere does not break (outcome too_small); below the strength it stays intact as before.
TEST(StressModel, MinPieceDiameterMovesThePlaneAndHaltsBreakageOfSmallGrains) {
  const double R = 1e-3;
  double lo = 0, hi = 1;  // h²(3 − h)/4 = 0.25 by bisection
  for (int i = 0; i < 60; ++i) ((0.5 * (lo + hi)) * (0.5 * (lo + hi)) * (3 - 0.5 * (lo + hi)) / 4 < 0.25 ? lo : hi) = 0.5 * (lo + hi);
  const double offset_exact = R * (1 - lo);
  const double d_quarter = 2 * R * std::cbrt(0.25);
  auto m = model({{"criterion", "von_mises"}, {"weibull", false}, {"strength", 1e6}, {"plane_fallback", "shift"},
                  {"min_piece_diameter", d_quarter}},
                 3);
  EXPECT_DOUBLE_EQ(model({{"criterion", "von_mises"}}, 3)->options().min_piece_diameter, 0.0);  // off by default
  Grain g;
  g.shape = Shape::sphere(R);
  Rng rng(1);
  m->assign_strength(g, Material{}, rng);
  const double zc = std::sqrt(R * R - 0.01 * R * R);
  const double zb = -std::sqrt(R * R - 0.18 * R * R);
  auto load = [&](double P) {
    return std::vector<Contact>{wall_contact(1, {0.1 * R, 0, zc}, {0, 0, -P}), wall_contact(2, {-0.05 * R, 0.0866 * R, zc}, {0, 0, -P}),
                                wall_contact(3, {-0.05 * R, -0.0866 * R, zc}, {0, 0, -P}),
                                wall_contact(4, {0.3 * R, 0.3 * R, zb}, {0, 0, 0.75 * P}), wall_contact(5, {-0.3 * R, 0.3 * R, zb}, {0, 0, 0.75 * P}),
                                wall_contact(6, {-0.3 * R, -0.3 * R, zb}, {0, 0, 0.75 * P}), wall_contact(7, {0.3 * R, -0.3 * R, zb}, {0, 0, 0.75 * P})};
  };
  const auto a = m->analyse(g, Material{}, load(300));
  ASSERT_TRUE(a.broken);
  const CutPlane p = std::get<CuttingSurfaces>(*a.fracture).planes.at(0);
  EXPECT_NEAR(std::abs(p.normal.z), 1.0, 1e-9);
  // The 24³ lattice estimate: within one lattice layer (R/12) of the closed form; without
  // the option the plane would shave the 0.07 % sliver (previous test).
  EXPECT_NEAR(std::abs(p.offset), offset_exact, R / 12);
  EXPECT_GT(smaller_side_fraction(*g.shape, p), 0.18);

  // Twice the sphere of d_min is more than the grain: it cannot give two such pieces.
  auto halt = model({{"criterion", "von_mises"}, {"weibull", false}, {"strength", 1e6}, {"min_piece_diameter", 1.01 * 2 * R * std::cbrt(0.5)}}, 3);
  halt->assign_strength(g, Material{}, rng);
  const auto h = halt->analyse(g, Material{}, load(300));
  EXPECT_FALSE(h.broken);
  EXPECT_EQ(h.outcome, "too_small");
  EXPECT_FALSE(h.fracture);
  EXPECT_EQ(halt->analyse(g, Material{}, load(0.1)).outcome, "intact");  // σ_VM ≈ 0.14 MPa < 1 MPa
  // Just below the limit it still splits, through the middle.
  auto just = model({{"criterion", "von_mises"}, {"weibull", false}, {"strength", 1e6}, {"min_piece_diameter", 0.99 * 2 * R * std::cbrt(0.5)}}, 3);
  just->assign_strength(g, Material{}, rng);
  const auto j = just->analyse(g, Material{}, load(300));
  ASSERT_TRUE(j.broken);
  EXPECT_NEAR(smaller_side_fraction(*g.shape, std::get<CuttingSurfaces>(*j.fracture).planes.at(0)), 0.5, 0.03);
}

// min_piece_thickness: a 2D slab 100 × 6 mm pressed on its top face by two equal contacts
// (the line through them runs along the face, plane_fallback "shift" keeps it so) and held
// by two weaker ones below. min_piece_fraction alone moves the plane to the 10 % band, a strip
// 0.6 mm thick; with a thickness of 2 mm each side reaches at least 2 mm from the plane
// (offset at most 1 mm below the top face's 3 mm, within a lattice cell of 6/64 mm); with
// 3.1 mm the slab (6 mm) cannot give two such pieces along its length and is cut across,
// through its centroid; with 51 mm not that way either (too_small). A plane across the slab
// (extent 100 mm along its normal) is left where it is.
TEST(StressModel, MinPieceThicknessKeepsALongSlabFromBeingCutIntoAStrip) {
  const double a = 0.05, b = 0.003, P = 1e5;
  Grain g;
  g.shape = Shape::polygon({{-a, -b, 0}, {a, -b, 0}, {a, b, 0}, {-a, b, 0}});
  const std::vector<Contact> cs{wall_contact(1, {-0.6 * a, b, 0}, {0, -P, 0}), wall_contact(2, {0.6 * a, b, 0}, {0, -P, 0}),
                                wall_contact(3, {-0.6 * a, -b, 0}, {0, 0.9 * P, 0}),
                                wall_contact(4, {0.6 * a, -b, 0}, {0, 0.9 * P, 0})};
  auto cut_with = [&](double thickness) {
    auto m = model({{"criterion", "von_mises"}, {"weibull", false}, {"strength", 1e6}, {"plane_fallback", "shift"},
                    {"min_piece_thickness", thickness}},
                   2);
    Rng rng(1);
    m->assign_strength(g, Material{}, rng);
    return m->analyse(g, Material{}, cs);
  };
  EXPECT_DOUBLE_EQ(model({{"criterion", "von_mises"}}, 2)->options().min_piece_thickness, 0.0);  // off by default
  const auto strip = cut_with(0);
  ASSERT_TRUE(strip.broken) << strip.outcome;
  const CutPlane p0 = std::get<CuttingSurfaces>(*strip.fracture).planes.at(0);
  ASSERT_NEAR(std::abs(p0.normal.y), 1.0, 1e-9);
  EXPECT_NEAR(b - std::abs(p0.offset), 0.1 * 2 * b, 2 * b / 64 + 1e-12);  // the 10 % strip
  const auto kept = cut_with(0.002);
  ASSERT_TRUE(kept.broken) << kept.outcome;
  const CutPlane p1 = std::get<CuttingSurfaces>(*kept.fracture).planes.at(0);
  EXPECT_NEAR(std::abs(p1.normal.y), 1.0, 1e-9);
  EXPECT_LE(std::abs(p1.offset), b - 0.002 + 1e-12);
  EXPECT_GE(std::abs(p1.offset), b - 0.002 - 2 * b / 64);
  const auto across_cut = cut_with(0.0031);
  ASSERT_TRUE(across_cut.broken) << across_cut.outcome;
  const CutPlane p2 = std::get<CuttingSurfaces>(*across_cut.fracture).planes.at(0);
  EXPECT_NEAR(std::abs(p2.normal.x), 1.0, 1e-9);
  EXPECT_NEAR(p2.offset, 0.0, 1e-12);
  EXPECT_NEAR(smaller_side_fraction(*g.shape, p2), 0.5, 0.02);
  const auto none = cut_with(0.051);
  EXPECT_FALSE(none.broken);
  EXPECT_EQ(none.outcome, "too_small");
  EXPECT_FALSE(none.fracture);
  const CutPlane across{{1, 0, 0}, 0.02};
  const auto same = keep_piece_thickness(*g.shape, across, 0.002);
  ASSERT_TRUE(same);
  EXPECT_EQ(same->offset, 0.02);
  EXPECT_NEAR(keep_piece_thickness(*g.shape, across, 0.04)->offset, a - 0.04, a / 64);
  EXPECT_FALSE(keep_piece_thickness(*g.shape, across, 0.051));
}

TEST(StressModel, SingleContactIn3DIsHeldOff) {
  auto m = model({{"criterion", "von_mises"}, {"weibull", false}}, 3);
  Grain g;
  g.shape = Shape::sphere(1e-3);
  Rng rng(1);
  m->assign_strength(g, Material{}, rng);
  // Two contacts with the same partner (wall 1): one point, breakage held off.
  std::vector<Contact> cs{wall_contact(1, {0, 0, 1e-3}, {0, 0, -1e4}), wall_contact(1, {1e-4, 0, 1e-3}, {0, 0, -1e3})};
  const auto a = m->analyse(g, Material{}, cs);
  EXPECT_FALSE(a.broken);
  EXPECT_EQ(a.outcome, "single_contact");
  EXPECT_EQ(m->analyse(g, Material{}, {}).outcome, "no_load");
}

TEST(StressModel, DefaultsOfScreeningAndSchedule) {
  auto m3 = model(Json::object(), 3);
  auto m2 = model(Json::object(), 2);
  EXPECT_EQ(m3->options().criterion, "von_mises");
  EXPECT_EQ(m3->default_screening().min_contacts, 2);
  EXPECT_EQ(m2->default_screening().min_contacts, 1);
  EXPECT_EQ(m3->default_screening().min_diameter, 0);
  EXPECT_FALSE(m3->default_screening().force_threshold);
  EXPECT_EQ(m3->default_screening().max_unbalanced_force_ratio, 0);
  EXPECT_EQ(m3->default_schedule().every_steps, 100);
  EXPECT_EQ(m3->default_schedule().every_stress, 0);
  EXPECT_EQ(m2->figure_names().size(), 5u);  // σ1, σ2, equivalent, strength, plane_through_centroid
}

TEST(StressModel, UnknownCriterionAndMisplacedTensileStrength) {
  try {
    model({{"criterion", "mohr_coulomb"}}, 3);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("criterion"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_principal, von_mises, tresca"), std::string::npos) << e.what();
  }
  EXPECT_THROW(model({{"criterion", "tresca"}, {"tensile_strength", 1e6}}, 3), ConfigError);
  EXPECT_THROW(model({{"criterion", "von_mises"}, {"strength", -1}}, 3), ConfigError);
  EXPECT_NO_THROW(model({{"criterion", "max_principal"}, {"tensile_strength", 1e6}}, 3));
}
