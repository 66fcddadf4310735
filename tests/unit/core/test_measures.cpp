#include <gtest/gtest.h>

#include <cmath>

#include "core/Measures.h"
#include "core/Rng.h"
#include "geometry/Shape.h"
#include "geometry/TriMesh.h"

using namespace crumble;

TEST(Analysis, LogLogSlopeOfAPowerLaw) {
  std::vector<double> x, y;
  for (int i = 1; i < 20; ++i) {
    x.push_back(i * 1e6);
    y.push_back(3.0 * std::pow(i * 1e6, -0.52));
  }
  EXPECT_NEAR(loglog_slope(x, y), -0.52, 1e-12);
  EXPECT_TRUE(std::isnan(loglog_slope({1.0}, {1.0})));
}

TEST(Analysis, ValueAtLevelInterpolatesAroundTheFirstCrossing) {
  // Samples at 0, 3.2 and 6.4 MPa: e at 5 MPa lies between the last two (not e at 6.4 MPa).
  const std::vector<double> s{0, 3.2e6, 6.4e6, 4e6}, e{0.9, 0.8, 0.7, 0.75};
  EXPECT_NEAR(value_at_level(s, e, 5e6), 0.8 - 0.1 * (1.8 / 3.2), 1e-12);
  EXPECT_DOUBLE_EQ(value_at_level(s, e, 0.0), 0.9);  // reached at the first sample
  EXPECT_TRUE(std::isnan(value_at_level(s, e, 7e6)));
  // A ramp whose last sample reads a hair below its end still reaches it (1e-4 relative).
  EXPECT_DOUBLE_EQ(value_at_level({1e6, 4.9999e6}, {0.9, 0.8}, 5e6), 0.8);
  EXPECT_TRUE(std::isnan(value_at_level({1e6, 4.99e6}, {0.9, 0.8}, 5e6)));
}

TEST(Analysis, PowerLawFitRecoversCoefficientAndExponent) {
  // y = 0.0123 · x^1.37 exactly; points with x <= 0 or y <= 0 are left out.
  std::vector<double> x{-1.0, 0.0, 720, 1500, 3000, 9000, 27400}, y;
  for (double v : x) y.push_back(v > 0 ? 0.0123 * std::pow(v, 1.37) : 5.0);
  const PowerLaw p = fit_power_law(x, y);
  EXPECT_EQ(p.points, 5);
  EXPECT_NEAR(p.exponent, 1.37, 1e-12);
  EXPECT_NEAR(p.coefficient, 0.0123, 1e-12 * 0.0123 * 1e3);
  EXPECT_NEAR(p(2000.0), 0.0123 * std::pow(2000.0, 1.37), 1e-9);
  // Fewer than two usable points, or one x only: no fit.
  EXPECT_TRUE(std::isnan(fit_power_law({1.0}, {2.0}).exponent));
  EXPECT_TRUE(std::isnan(fit_power_law({3.0, 3.0, 3.0}, {1.0, 2.0, 4.0}).exponent));
}

namespace {
std::vector<double> pareto(double D, int n) {
  // Sizes with N(d > s) ∝ s^-D above 0.1 mm (Pareto, truncation far away at 1 m).
  Rng rng(3);
  const double a = 0.1e-3, b = 1.0;
  std::vector<double> d;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform();
    d.push_back(a * std::pow(1 - u * (1 - std::pow(a / b, D)), -1.0 / D));
  }
  return d;
}
}  // namespace

TEST(Analysis, FractalDimensionOfAPowerLawSample) {
  EXPECT_NEAR(fractal_dimension(pareto(2.5, 200000), 12), 2.5, 0.05);
  EXPECT_NEAR(fractal_dimension(pareto(1.5, 200000), 12), 1.5, 0.05);
  EXPECT_TRUE(std::isnan(fractal_dimension({1e-3, 1e-3})));
}

// ---- PSD by mass ----

TEST(Analysis, PercentPassingByMassAtEachSieve) {
  // 1, 2, 3 mm grains of 1, 1, 2 kg: 25 % of the mass is 1 mm, 50 % at most 2 mm.
  const std::vector<double> p = percent_passing({1e-3, 2e-3, 3e-3}, {1, 1, 2}, {3e-3, 2e-3, 1e-3, 0.5e-3});
  ASSERT_EQ(p.size(), 4u);
  EXPECT_DOUBLE_EQ(p[0], 100.0);
  EXPECT_DOUBLE_EQ(p[1], 50.0);
  EXPECT_DOUBLE_EQ(p[2], 25.0);
  EXPECT_DOUBLE_EQ(p[3], 0.0);
  // Removed fines at size 0 pass every sieve.
  EXPECT_DOUBLE_EQ(percent_passing({0.0, 2e-3}, {1, 3}, {1e-3})[0], 25.0);
  EXPECT_DOUBLE_EQ(percent_passing({}, {}, {1e-3})[0], 0.0);
  const auto s = geometric_sieves(2e-3, 3, 2.0);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_DOUBLE_EQ(s[2], 0.5e-3);
}

TEST(Analysis, GradationOfTenEqualMasses) {
  // Sizes 1…10 mm, 1 kg each: the mid-point cumulative fraction of size i mm is (i − 0.5)/10,
  // so d10 = 1.5, d30 = 3.5, d50 = 5.5, d60 = 6.5 mm; C_u = 6.5/1.5, C_c = 3.5²/(1.5·6.5).
  std::vector<double> d, m;
  for (int i = 1; i <= 10; ++i) {
    d.push_back(i * 1e-3);
    m.push_back(1.0);
  }
  const Gradation g = gradation(d, m);
  EXPECT_NEAR(g.d10, 1.5e-3, 1e-15);
  EXPECT_NEAR(g.d30, 3.5e-3, 1e-15);
  EXPECT_NEAR(g.d50, 5.5e-3, 1e-15);
  EXPECT_NEAR(g.d60, 6.5e-3, 1e-15);
  EXPECT_NEAR(g.uniformity, 6.5 / 1.5, 1e-12);
  EXPECT_NEAR(g.curvature, 12.25 / 9.75, 1e-12);
  // More than 10 % removed fines (size 0): d10 = 0, no uniformity.
  const Gradation f = gradation({0.0, 1e-3}, {0.5, 0.5});
  EXPECT_EQ(f.d10, 0.0);
  EXPECT_TRUE(std::isnan(f.uniformity));
}

TEST(Analysis, FractalDimensionFromAPowerLawPsdByMass) {
  // Tyler & Wheatcraft: passing = 100 (d/d_max)^(3 − D); D = 2.3 (Zhu & Zhao 2019 Fig. 17).
  for (double D : {2.3, 2.7}) {
    std::vector<double> sv, p;
    for (int k = 1; k <= 12; ++k) {
      sv.push_back(2e-3 * std::pow(2.0, -k / 2.0));
      p.push_back(100 * std::pow(sv.back() / 2e-3, 3 - D));
    }
    sv.push_back(2e-3);  // 100 % passing: left out of the fit
    p.push_back(100);
    EXPECT_NEAR(fractal_dimension_by_mass(sv, p), D, 1e-12);
    // The same curve of areas in 2D: E = 2, so D is one less.
    EXPECT_NEAR(fractal_dimension_by_mass(sv, p, 2), D - 1, 1e-12);
  }
  EXPECT_TRUE(std::isnan(fractal_dimension_by_mass({1e-3, 2e-3}, {0, 100})));
}

// ---- Hardin (1985) relative breakage ----

TEST(Analysis, RelativeBreakageOfHandComputedCurves) {
  const double c = kHardinCutoff;
  // Initial: all mass at 1 mm. B_p = ∫ from 0.074 to 1 mm of (1 − 0) dlog10 d = log10(1/0.074).
  // Current: half at 1 mm, half at 0.1 mm: B_t = ∫ from 0.1 to 1 mm of 0.5 dlog10 d = 0.5.
  const double bp = std::log10(1e-3 / c);
  EXPECT_NEAR(relative_breakage({1e-3}, {1}, {1e-3, 0.1e-3}, {1, 1}), 0.5 / bp, 1e-12);
  // Unchanged: 0. Everything crushed below the cut-off, or removed as fines: 1.
  EXPECT_NEAR(relative_breakage({1e-3, 2e-3}, {1, 1}, {2e-3, 1e-3}, {1, 1}), 0.0, 1e-15);
  EXPECT_NEAR(relative_breakage({1e-3}, {1}, {0.05e-3, 0.0}, {1, 1}), 1.0, 1e-12);
  // Two initial sizes (1 and 2 mm, 1 kg each); the 2 mm grain breaks into two of 0.5 mm:
  // B_p = log10(1/0.074) + 0.5·log10(2), B_t = 0.5·log10(1/0.5) + 0.5·log10(2/1).
  const double bp2 = std::log10(1e-3 / c) + 0.5 * std::log10(2.0);
  const double bt2 = 0.5 * std::log10(2.0) + 0.5 * std::log10(2.0);
  EXPECT_NEAR(relative_breakage({1e-3, 2e-3}, {1, 1}, {1e-3, 0.5e-3, 0.5e-3}, {1, 0.5, 0.5}), bt2 / bp2, 1e-12);
  // A scaled cut-off: 0.5 mm (a tenth of… whatever a scene states) is honoured.
  EXPECT_NEAR(relative_breakage({1e-3}, {1}, {1e-3, 0.1e-3}, {1, 1}, 0.5e-3), 0.5, 1e-12);
  // Nothing above the cut-off at the start: undefined.
  EXPECT_TRUE(std::isnan(relative_breakage({0.05e-3}, {1}, {0.05e-3}, {1})));
}

TEST(Analysis, RelativeBreakageFromSieveCurves) {
  // Sieves 0.01, 0.1, 1 mm (one decade apart), cut-off 0.01 mm; initial 0, 0, 100 %, current
  // 0, 50, 100 %, straight in log size between sieves:
  // B_p = 1 (first decade, nothing passes) + (1 − 0.5) (second, the initial line 0 → 1) = 1.5;
  // B_t = 0.25 (current 0 → 0.5 over the first decade) + (0.75 − 0.5) = 0.5; B_r = 1/3.
  const std::vector<double> sv = {1e-3, 0.1e-3, 0.01e-3};
  EXPECT_NEAR(relative_breakage_sieved(sv, {100, 0, 0}, {100, 50, 0}, 0.01e-3), 1.0 / 3.0, 1e-12);
  // A cut-off halfway (in log) through the second decade: there the initial line is at 0.5
  // and the current at 0.75; B_p = 0.5·(1 − 0.75) = 0.125, B_t = 0.5·(0.25 + 0)/2 = 0.0625.
  EXPECT_NEAR(relative_breakage_sieved(sv, {100, 0, 0}, {100, 50, 0}, std::sqrt(0.1) * 1e-3), 0.5, 1e-12);
  EXPECT_NEAR(relative_breakage_sieved(sv, {100, 0, 0}, {100, 0, 0}), 0.0, 1e-15);
  EXPECT_TRUE(std::isnan(relative_breakage_sieved(sv, {100, 0}, {100, 0, 0})));
}

// ---- Compression ----

TEST(Analysis, NclSlopesOverAStressRange) {
  // e = 0.8 (σ/1 MPa)^(−0.52) between 5 and 30 MPa (Zhu & Zhao 2019 §5's slope); below 5 MPa a
  // flat part that the range leaves out.
  std::vector<double> s, e;
  for (int i = 1; i <= 30; ++i) {
    s.push_back(i * 1e6);
    e.push_back(i < 5 ? 0.8 : 0.8 * std::pow(i, -0.52));
  }
  const NclFit f = fit_ncl(s, e, 5e6, 30e6);
  EXPECT_EQ(f.points, 26u);
  EXPECT_NEAR(f.loglog_slope, -0.52, 1e-12);
  // The upper range σ >= 0.3·30 MPa = 9 MPa is inside the power law too.
  EXPECT_NEAR(fit_ncl_upper(s, e).loglog_slope, -0.52, 1e-12);
  EXPECT_EQ(fit_ncl_upper(s, e).points, 22u);
  // e = 1.1 − 0.3 log10(σ/1 MPa): compression index 0.3.
  std::vector<double> e2;
  for (double v : s) e2.push_back(1.1 - 0.3 * std::log10(v / 1e6));
  EXPECT_NEAR(fit_ncl(s, e2, 1e6, 30e6).compression_index, 0.3, 1e-12);
  EXPECT_TRUE(std::isnan(fit_ncl(s, e2, 40e6, 50e6).loglog_slope));
}

TEST(Analysis, EventsPerStressIncrement) {
  const auto c = events_per_increment({0.5e6, 1.2e6, 1.9e6, 3.5e6, -1.0}, 1e6, 2.2e6);
  EXPECT_EQ(c, (std::vector<long>{2, 2, 0, 1}));  // the negative stress counts in bin 0
  EXPECT_EQ(events_per_increment({}, 1e6, 2.5e6), (std::vector<long>{0, 0, 0}));
  EXPECT_EQ(events_per_increment({1e6}, 0.0, 1e6).size(), 0u);
}

// ---- K0 ----

TEST(Analysis, LateralStressRatioFromSideWallForces) {
  // 3D box 10 × 20 mm filled to 5 mm: an x wall has 20 × 5 mm² = 1e-4 m², a y wall 5e-5 m².
  // 10 N on each x wall and 5 N on each y wall are 1e5 Pa everywhere.
  const SideWallForces f{10, 10, 5, 5};
  const double sh = lateral_stress(f, 10e-3, 20e-3, 5e-3, 3);
  EXPECT_NEAR(sh, 1e5, 1e-9);
  EXPECT_NEAR(lateral_stress_ratio(sh, 2e5), 0.5, 1e-15);
  // Unequal walls are averaged: 20 N and 0 N on the x walls, nothing on the y walls.
  EXPECT_NEAR(lateral_stress({20, 0, 0, 0}, 10e-3, 20e-3, 5e-3, 3), 0.25 * 2e5, 1e-9);
  // 2D: 100 N/m on each side wall of a 10 mm high sample is 1e4 Pa; the y walls do not exist.
  EXPECT_NEAR(lateral_stress({100, 100, 999, 999}, 10e-3, 0, 10e-3, 2), 1e4, 1e-9);
  EXPECT_TRUE(std::isnan(lateral_stress(f, 10e-3, 20e-3, 0, 3)));
  EXPECT_TRUE(std::isnan(lateral_stress_ratio(1e5, 0)));
}

// ---- Load–displacement ----

TEST(Analysis, LoadDisplacementOfAPlatenTest) {
  const LoadDisplacement r = load_displacement({2e-3, 1.9e-3, 1.8e-3, 1.85e-3}, {0, 10, 30, 5});
  ASSERT_EQ(r.displacement.size(), 4u);
  EXPECT_NEAR(r.displacement[2], 0.2e-3, 1e-15);
  EXPECT_NEAR(r.displacement[3], 0.15e-3, 1e-15);
  EXPECT_EQ(r.peak_load, 30.0);
  EXPECT_NEAR(r.displacement_at_peak, 0.2e-3, 1e-15);
}

// ---- Shape: Zingg, sieve size ----

TEST(Analysis, ZinggIndicesOfABoxFromItsPrincipalExtents) {
  // Zhu & Zhao 2019 §5: a 6 × 4 × 1 mm box has L, I, S = 6, 4, 1 mm, EI = 2/3, FI = 1/4,
  // turned any way.
  const auto box = Shape::box({3e-3, 2e-3, 0.5e-3});
  TriMesh m = box->mesh();
  const Quat q = Quat::from_axis_angle({1, 2, 3}, 0.7);
  for (auto& v : m.vertices) v = q.rotate(v) + Vec3{1e-3, -2e-3, 5e-3};
  const auto s = shape_metrics_3d(m, polyhedron_mass_properties(m));
  EXPECT_NEAR(s.principal_dimensions[0], 6e-3, 1e-12);
  EXPECT_NEAR(s.principal_dimensions[1], 4e-3, 1e-12);
  EXPECT_NEAR(s.principal_dimensions[2], 1e-3, 1e-12);
  EXPECT_NEAR(s.elongation, 2.0 / 3.0, 1e-9);
  EXPECT_NEAR(s.flatness, 0.25, 1e-9);
  EXPECT_STREQ(zingg_class(s.elongation + 1e-6, s.flatness), "disc");
  EXPECT_STREQ(zingg_class(0.9, 0.9), "spheroid");
  EXPECT_STREQ(zingg_class(0.3, 0.3), "blade");
  EXPECT_STREQ(zingg_class(0.3, 0.9), "rod");
}

TEST(Analysis, SieveSizeIsTheMinorAxisChord) {
  // Harmon et al. 2020 eq. 21: a box's shortest side, a sphere's diameter (level-set chord,
  // within a few per mille of the grid), a rectangle's shorter side (exact outline chord).
  EXPECT_NEAR(sieve_size(*Shape::box({3e-3, 2e-3, 0.5e-3})), 1e-3, 0.01e-3);
  EXPECT_NEAR(sieve_size(*Shape::sphere(1e-3)), 2e-3, 0.01e-3);
  EXPECT_NEAR(sieve_size(*Shape::polygon({{-3e-3, -1e-3, 0}, {3e-3, -1e-3, 0}, {3e-3, 1e-3, 0}, {-3e-3, 1e-3, 0}})),
              2e-3, 1e-15);
}
