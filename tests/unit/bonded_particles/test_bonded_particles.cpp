// Breakage model "bonded_particles" (the densely arrayed bonded-particle model, DA-BPM):
// the element array against the densest-packing closed forms, the bond stiffness against the
// material's Young's modulus, breakage below/above the strength, determinism, options.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "breakage/bonded_particles/BondedParticles.h"
#include "breakage/bonded_particles/BpmSystem.h"
#include "core/Config.h"
#include "core/Rng.h"
#include "scenarios/Registry.h"
#include "tests/support/Contacts.h"

namespace crumble {
namespace {

Material silica() {
  Material m;
  m.density = 2650;
  m.young = 70e9;
  m.poisson = 0.15;
  m.friction = 0.8;  // the DA-BPM paper's single-particle test
  return m;
}

Shape::Ptr grain_shape(int dim) { return dim == 2 ? Shape::disk(1e-3) : Shape::sphere(1e-3); }

// ------------------------------------------------------------------ the element array

// Densest packing (DA-BPM, "Densely arrayed BPM"): a disc of diameter D filled with
// elements of diameter d holds ≈ A / ((√3/2) d²) of them, packing fraction π/(2√3) =
// 0.9069; a sphere ≈ V / (d³/√2), π/(3√2) = 0.7405. The clipped boundary costs O(d/D):
// measured −0.6 % (2D, D/d = 40) and −1.6 % (3D, D/d = 24); tolerances 1.5 % and 3 %.
TEST(BpmArray, CountAndPackingFractionMatchTheDensestPacking) {
  for (int dim : {2, 3}) {
    const auto s = grain_shape(dim);
    const double across = dim == 2 ? 40 : 24, tol = dim == 2 ? 0.015 : 0.03;
    const double d = 2e-3 / across;
    const auto a = bpm::dense_array(*s, d);
    const double expected = s->volume() / bpm::cell_volume(dim, d);
    const double eta = static_cast<double>(a.size()) * bpm::element_volume(dim, d) / s->volume();
    std::printf("dim %d: %zu elements (closed form %.1f), packing fraction %.4f (closed form %.4f)\n", dim, a.size(),
                expected, eta, bpm::packing_fraction(dim));
    EXPECT_NEAR(static_cast<double>(a.size()), expected, tol * expected) << dim;
    EXPECT_NEAR(eta, bpm::packing_fraction(dim), tol * bpm::packing_fraction(dim)) << dim;
    EXPECT_NEAR(bpm::packing_fraction(dim), dim == 2 ? 0.906900 : 0.740480, 1e-6);
    // Every element well inside the grain has the full coordination (6 or 12 bonds).
    for (std::size_t i = 0; i < a.size(); ++i)
      if (norm(a.points[i]) < 1e-3 - 2 * d)
        ASSERT_EQ(a.coordination[i], a.full_coordination()) << dim << " at " << a.points[i].x << " " << a.points[i].y << " " << a.points[i].z;
    // Bonds join centres exactly one element diameter apart.
    for (const auto& b : a.bonds) ASSERT_NEAR(norm(a.points[b.j] - a.points[b.i]), d, 1e-9 * d);
  }
}

// ------------------------------------------------------------------ stiffness

// A bar of elements pulled along its axis by F on its top layer, bottom layer fixed; the
// strain between the layers at 1/4 and 3/4 of its length gives E = σ/ε, σ = F/A (A = the
// elements' cells per length). The bond stiffness comes from the material (kn from E by the
// array's Cauchy–Born modulus, ks/kn from ν). The free sides soften a bar in proportion to
// 1/width (measured, 2D: −8.8, −3.7, −1.5 % at 8, 16, 32 elements wide; 3D: −13.3, −6.5 % at
// 8, 16), so the test extrapolates two widths w, 2w to the bulk, E∞ = 2E(2w) − E(w)
// (measured +0.8 % in 2D, +0.3 % in 3D), tolerance 2 %, and checks that the error halves
// with the width (ratio 0.35–0.65).
double bar_young(int dim, const Material& m, int width, int layers, int steps) {
  const double d = 1e-4;
  std::vector<Vec3> pts;
  double length = 0;
  if (dim == 2) {
    const double h = 0.5 * std::sqrt(3.0) * d;
    for (int j = 0; j < layers; ++j)
      for (int i = 0; i < width; ++i) pts.push_back({(i + 0.5 * (j % 2)) * d, j * h, 0});
    length = layers * h;
  } else {
    const double s = d / std::sqrt(2.0);
    for (int k = 0; k < layers; ++k)
      for (int j = 0; j < width; ++j)
        for (int i = 0; i < width; ++i)
          if ((i + j + k) % 2 == 0) pts.push_back({i * s, j * s, k * s});
    length = layers * s;
  }
  const auto a = bpm::array_from_points(dim, d, pts);
  BpmOptions o;
  bpm::BondLaw law;
  law.radius = 0.5 * d;
  law.kn = 1;
  law.ks = bpm::shear_ratio_for_poisson(dim, m.poisson);
  const double e1 = bpm::array_young(dim, d, law, dim == 2 ? 1 : 2);
  law.kn = m.young / e1;
  law.ks *= law.kn;
  law.normal_strength = law.shear_strength = 1e30;
  bpm::System sys(a, law, m.density);
  const int ax = dim == 2 ? 1 : 2;
  const double top = a.points.back()[ax];
  std::vector<std::int32_t> bottom, loaded;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a.points[i][ax] < 1e-3 * d) bottom.push_back(static_cast<std::int32_t>(i));
    if (a.points[i][ax] > top - 1e-3 * d) loaded.push_back(static_cast<std::int32_t>(i));
  }
  const double F = 1.0;
  Vec3 f;
  f[ax] = F;
  sys.fix(bottom);
  sys.add_load(loaded, f);
  const double dt = sys.stable_dt();
  for (int n = 1; n <= steps; ++n) sys.step(dt, std::min(1.0, n / (0.1 * steps)), 0.7);
  EXPECT_LT(sys.kinetic_energy(), 1e-6 * sys.load_work(1.0)) << "the bar is at rest";
  // Mean displacement of the layers nearest 1/4 and 3/4 of the length.
  auto mean_u = [&](double at) {  // the layer nearest `at`: its position and mean displacement
    double z = a.points[0][ax];
    for (const auto& p : a.points)
      if (std::abs(p[ax] - at) < std::abs(z - at)) z = p[ax];
    double n = 0, s = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (std::abs(a.points[i][ax] - z) < 1e-3 * d) {
        s += sys.displacement(i)[ax];
        ++n;
      }
    return std::pair<double, double>{z, s / n};
  };
  const auto [z1, u1] = mean_u(0.25 * top);
  const auto [z2, u2] = mean_u(0.75 * top);
  const double strain = (u2 - u1) / (z2 - z1);
  const double area = static_cast<double>(a.size()) * bpm::cell_volume(dim, d) / length;
  return F / area / strain;
}

TEST(BpmStiffness, BarOfElementsHasTheMaterialsYoungsModulus) {
  const Material m = silica();
  for (int dim : {2, 3}) {
    const int w = dim == 2 ? 16 : 8;
    const double E1 = bar_young(dim, m, w, 31, 12000), E2 = bar_young(dim, m, 2 * w, 31, 12000);
    const double bulk = 2 * E2 - E1;
    std::printf("dim %d: E of the bar %.4g Pa (%d wide), %.4g Pa (%d wide), extrapolated %.4g Pa, material %.4g Pa\n",
                dim, E1, w, E2, 2 * w, bulk, m.young);
    EXPECT_NEAR(bulk, m.young, 0.02 * m.young) << dim;
    const double ratio = (E2 - m.young) / (E1 - m.young);
    EXPECT_GT(ratio, 0.35) << dim;
    EXPECT_LT(ratio, 0.65) << dim;
  }
}

// The Cauchy–Born modulus of the hexagonal array against the closed form of a triangular
// lattice of normal and shear springs Kn, Ks (per metre of thickness): E = 2√3·Kn(Kn + Ks)/
// (3Kn + Ks), ν = (Kn − Ks)/(3Kn + Ks) (Ks = 0: the central-force lattice, E = 2Kn/√3, ν = 1/3),
// isotropic; so ks/kn = (1 − 3ν)/(1 + ν) gives ν. Tolerance: rounding (1e-9).
TEST(BpmStiffness, HexagonalArrayModulusMatchesTheClosedForm) {
  const double d = 1e-4;
  for (double r : {0.0, 0.3, 1.0}) {
    bpm::BondLaw law;
    law.radius = 0.5 * d;
    law.kn = 1e15;
    law.ks = r * law.kn;
    const double Kn = law.kn * 2 * law.radius, Ks = law.ks * 2 * law.radius;
    const double closed = 2 * std::sqrt(3.0) * Kn * (Kn + Ks) / (3 * Kn + Ks);
    for (int axis : {0, 1}) {
      const double E = bpm::array_young(2, d, law, axis);
      EXPECT_NEAR(E, closed, 1e-9 * closed) << "ks/kn " << r << " axis " << axis;
    }
  }
}

// ------------------------------------------------------------------ breakage

BpmOptions test_options() {
  BpmOptions o;
  o.elements_across = 12;
  return o;
}


// A pair of opposite forces P at the poles, in the world frame of a rotated grain.
std::vector<Contact> diametral(const Grain& g, int dim, double P) {
  const Vec3 up = dim == 2 ? Vec3{0.6, 0.8, 0} : Vec3{0, 0.6, 0.8};
  using testing_support::wall_contact;
  return {wall_contact(g, kPlaten, up * 1e-3, up * -P), wall_contact(g, kFloor, up * -1e-3, up * P)};
}

Grain test_grain(int dim, const BreakageModel& m) {
  Grain g;
  g.id = 7;
  g.shape = grain_shape(dim);
  g.position = {0.01, 0.02, dim == 3 ? 0.03 : 0.0};
  g.orientation = dim == 3 ? Quat::from_axis_angle({1, 2, 3}, 0.4) : Quat::from_axis_angle({0, 0, 1}, 0.4);
  Rng rng(1);
  m.assign_strength(g, silica(), rng);
  return g;
}

// The single-particle crushing force against the Brazilian-test estimate (π/2)σd (2D, per
// metre) and σd²/0.9 (3D), for 8 and 16 elements across, and its dependence on the ramp.
// Measured (σ = 30 MPa, elastic preload, force/estimate for ramps of 3000, 6000, 12000
// (default), 24000 steps): 2D, 8 across 1.26, 1.12, 1.05, 1.03; 16 across 1.05, 0.96, 0.85,
// 0.83; 3D, 8 across 0.98, 0.90, 0.85, 0.82; 16 across 1.12, 0.98, 0.85. So the default ramp is
// within ≈ 4 % of its slow limit, and a faster ramp overestimates the strength.
// Tolerances: within 20 % of the estimate; a ramp twice as slow changes it by less than 6 %.
TEST(BpmBreakage, CrushingForceIsNearTheBrazilianEstimate) {
  for (int dim : {2, 3}) {
    const auto s = grain_shape(dim);
    const double est = bpm_crush_estimate(dim, 30e6, 2e-3);
    for (double across : {8.0, 16.0}) {
      BpmOptions o;
      o.elements_across = across;
      const auto r = bpm_crush_single_grain(*s, silica(), o);
      ASSERT_TRUE(r.split) << r.outcome;
      EXPECT_NEAR(r.force / est, 1.0, 0.20) << dim << "D, " << across << " across";
      EXPECT_GE(r.pieces, 2);
      if (across == 8.0) {
        o.ramp_steps *= 2;
        const auto slow = bpm_crush_single_grain(*s, silica(), o);
        ASSERT_TRUE(slow.split);
        EXPECT_NEAR(slow.force / r.force, 1.0, 0.06) << dim << "D: " << slow.force << " vs " << r.force;
      }
    }
  }
}

// The elastic preload changes neither verdict nor much the force: the crushing force with it
// and without it (ramp from zero) agree within 10 % (2D and 3D, 8 across).
TEST(BpmBreakage, ElasticPreloadKeepsTheCrushingForce) {
  for (int dim : {2, 3}) {
    BpmOptions o;
    o.elements_across = 8;
    const auto with = bpm_crush_single_grain(*grain_shape(dim), silica(), o);
    o.elastic_preload = false;
    const auto without = bpm_crush_single_grain(*grain_shape(dim), silica(), o);
    ASSERT_TRUE(with.split && without.split);
    std::printf("dim %d: crushing force %.4g with preload (%ld steps), %.4g without (%ld steps)\n", dim, with.force,
                with.steps, without.force, without.steps);
    EXPECT_NEAR(with.force / without.force, 1.0, 0.10) << dim;
    EXPECT_LT(with.steps, without.steps) << dim;
  }
}

TEST(BpmBreakage, OppositeForcesBelowStrengthKeepTheGrainAboveSplitIt) {
  for (int dim : {2, 3}) {
    const BondedParticlesModel model(test_options());
    const Grain g = test_grain(dim, model);
    const auto crush = bpm_crush_single_grain(*g.shape, silica(), test_options());
    ASSERT_TRUE(crush.split);
    // The screening threshold sits below the crushing force.
    EXPECT_LT(model.threshold_force(g), 0.5 * crush.force) << dim;
    const auto below = model.analyse(g, silica(), diametral(g, dim, 0.5 * crush.force));
    EXPECT_FALSE(below.broken) << below.outcome;
    EXPECT_EQ(below.outcome, "intact");
    // 2D: no bond breaks at half the crushing force; 3D: the zone under the contact crushes
    // locally (≈ 300 of 6700 bonds) while the grain holds.
    if (dim == 2) EXPECT_EQ(below.figure("broken_bonds", -1), 0.0);
    const auto above = model.analyse(g, silica(), diametral(g, dim, 2.0 * crush.force));
    ASSERT_TRUE(above.broken) << above.outcome;
    const auto& pc = std::get<PointClusters>(*above.fracture);
    EXPECT_GE(pc.clusters, 2);
    EXPECT_EQ(above.figure("pieces"), pc.clusters);
    EXPECT_GT(above.figure("force_at_split_N"), 0.0);
    EXPECT_LE(above.figure("force_at_split_N"), 2.0 * crush.force * (1 + 1e-12));
    EXPECT_EQ(above.figure("elements"), static_cast<double>(pc.points.size()));
    EXPECT_NEAR(pc.spacing, 2e-3 / 12, 1e-15);
    for (int c = 0; c < pc.clusters; ++c) EXPECT_FALSE(pc.fracture_points[c].empty()) << c;
    // The DECA correction: the largest piece's diameter from its elements' cells is at most
    // the grain's, and the inner pores are (1 − η) of the elements' cells.
    EXPECT_LE(above.figure("largest_piece_deca_m"), 2e-3 * 1.01);
    const double cells = pc.points.size() * bpm::cell_volume(dim, pc.spacing);
    EXPECT_NEAR(above.figure("inner_pore_volume_m3"), (1 - bpm::packing_fraction(dim)) * cells, 1e-9 * cells);
    std::printf("dim %d: crush %.4g, split at %.4g, %g elements, %g steps, %g broken bonds, %d pieces, %.2f ms\n", dim,
                crush.force, above.figure("force_at_split_N"), above.figure("elements"), above.figure("steps"),
                above.figure("broken_bonds"), pc.clusters, above.wall_ms);
  }
}

TEST(BpmBreakage, AnalysisIsDeterministic) {
  for (int dim : {2, 3}) {
    const BondedParticlesModel model(test_options());
    const Grain g = test_grain(dim, model);
    const auto cs = diametral(g, dim, 2.5 * bpm_crush_estimate(dim, 30e6, 2e-3));
    const auto a = model.analyse(g, silica(), cs), b = model.analyse(g, silica(), cs);
    ASSERT_TRUE(a.broken && b.broken);
    EXPECT_EQ(a.figures, b.figures);
    const auto& pa = std::get<PointClusters>(*a.fracture);
    const auto& pb = std::get<PointClusters>(*b.fracture);
    EXPECT_EQ(pa.cluster, pb.cluster);
    EXPECT_EQ(pa.fracture_points.size(), pb.fracture_points.size());
  }
}

// ------------------------------------------------------------------ strength and options

TEST(BpmStrength, WeibullFactorHasMeanOneAndChildrenInheritIt) {
  BpmOptions o = test_options();
  o.weibull_modulus = 3;
  const BondedParticlesModel model(o);
  Rng rng(5);
  double sum = 0;
  const int n = 4000;
  Grain g;
  g.shape = Shape::disk(1e-3);
  for (int k = 0; k < n; ++k) {
    model.assign_strength(g, silica(), rng);
    sum += g.strength.get(BondedParticlesModel::kFactor);
  }
  EXPECT_NEAR(sum / n, 1.0, 0.03);  // standard error of the mean ≈ 0.006 for m = 3
  Grain child;
  child.shape = Shape::disk(0.5e-3);
  model.inherit_strength(g, child, silica(), rng);
  EXPECT_EQ(child.strength.get(BondedParticlesModel::kFactor), g.strength.get(BondedParticlesModel::kFactor));
  // Threshold ∝ d in 2D: half the size, half the screening force.
  EXPECT_NEAR(child.strength.get(BondedParticlesModel::kThreshold), 0.5 * g.strength.get(BondedParticlesModel::kThreshold),
              1e-9 * g.strength.get(BondedParticlesModel::kThreshold));
}

TEST(BpmOptions, BadOptionsAreConfigErrorsNamingThePath) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, nlohmann::json>>{
           {"normal_strength", -1}, {"damping", 1.5}, {"elements_across", "many"}, {"ramp_steps", 0}}) {
    nlohmann::json doc = {{"type", "bonded_particles"}, {key, value}};
    Config cfg(doc);
    EngineContext ctx;
    ctx.dimension = 2;
    try {
      breakage_models().find("bonded_particles", "/breakage/type").make(cfg, ctx);
      ADD_FAILURE() << key << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

TEST(BpmOptions, TooFewElementsAndNoLoadAreCountedOutcomes) {
  BpmOptions o;
  o.element_diameter = 1e-3;  // a 2 mm disc holds a handful of elements
  o.min_elements = 50;
  const BondedParticlesModel model(o);
  const Grain g = test_grain(2, model);
  EXPECT_EQ(model.analyse(g, silica(), diametral(g, 2, 1e6)).outcome, "too_few_elements");
  EXPECT_EQ(model.analyse(g, silica(), {}).outcome, "no_load");
}

}  // namespace
}  // namespace crumble
