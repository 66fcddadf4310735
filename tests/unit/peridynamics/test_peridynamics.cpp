// Breakage model "peridynamics" (Zhu & Zhao 2019 §2.1, §3, §4): physics against the paper and
// closed forms, conservation, strength sampling, bad inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include <nlohmann/json.hpp>

#include "breakage/peridynamics/PdClusters.h"
#include "breakage/peridynamics/PdKernel.h"
#include "breakage/peridynamics/PdLattice.h"
#include "breakage/peridynamics/PdSystem.h"
#include "breakage/peridynamics/Peridynamics.h"
#include "core/Config.h"
#include "core/Rng.h"
#include "scenarios/Registry.h"

namespace crumble {
namespace {

using pd::Lattice;
using pd::LpsMaterial;
using pd::PdSystem;

Material table1() {  // Zhu & Zhao 2019 Table 1
  Material m;
  m.density = 2650;
  m.young = 100e9;
  m.poisson = 0.15;
  return m;
}

// Lattice points of a cube of (2·half + 1)³ points centred at the origin.
Lattice cube_lattice(int half, double h, bool partial_volumes) {
  std::vector<Vec3> pts;
  for (int k = -half; k <= half; ++k)
    for (int j = -half; j <= half; ++j)
      for (int i = -half; i <= half; ++i) pts.push_back(Vec3(i, j, k) * h);
  return pd::build_lattice(pts, h, 3.0002, partial_volumes);
}

double volume_sum(const CrushResult& r) { return std::accumulate(r.fragment_volumes.begin(), r.fragment_volumes.end(), 0.0); }

// ------------------------------------------------------------------ crushing (§4.2, Fig. 9)

// The reference grain: 2 mm sphere, G_c = 30 J/m², Table 1 material, default options
// (density ×4, elastic preload, spectral step). Paper: ≈ 180 N, 45 MPa. Tolerance ±10 %.
TEST(PeridynamicsCrush, ReferenceGrainCrushesNear180N) {
  const auto s = Shape::sphere(1e-3);
  const CrushResult r = crush_single_grain(*s, table1(), 30.0, PdOptions{});
  ASSERT_TRUE(r.split) << r.outcome;
  EXPECT_NEAR(r.force, 180.0, 18.0);
  EXPECT_NEAR(r.strength, 45e6, 4.5e6);
  EXPECT_NEAR(r.strength, r.force / (2e-3 * 2e-3), 1e-6 * r.strength);
  // meridian cracks: four wedges and the crushed column between the contacts
  EXPECT_GE(r.fragments, 4);
  EXPECT_LT(*std::max_element(r.fragment_volumes.begin(), r.fragment_volumes.end()), 0.4 * s->volume());
  EXPECT_GT(r.points, 2000);  // ≈ 2000–2500 points (Zhu & Zhao 2019 §3.1)
  EXPECT_LT(r.points, 2600);
  EXPECT_NEAR(volume_sum(r), s->volume(), 1e-12 * s->volume());
}

// Fig. 9: σ ∝ √G_c. Coarser lattice (spacing 0.1 d_e, ≈ 500 points) to stay fast; the
// slope at the paper's spacing is measured in the DISABLED_ test below.
double crush_slope(double spacing_fraction) {
  PdOptions o;
  o.spacing_fraction = spacing_fraction;
  const auto s = Shape::sphere(1e-3);
  std::vector<double> x, y;
  for (double gc : {5.0, 10.0, 20.0, 30.0, 50.0}) {
    const CrushResult r = crush_single_grain(*s, table1(), gc, o);
    EXPECT_TRUE(r.split) << "G_c = " << gc;
    x.push_back(std::log(gc));
    y.push_back(std::log(r.force));
  }
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / x.size();
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / y.size();
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
  }
  return sxy / sxx;
}

TEST(PeridynamicsCrush, ForceScalesWithSqrtGc) { EXPECT_NEAR(crush_slope(0.1), 0.5, 0.05); }

TEST(PeridynamicsCrush, DISABLED_ForceScalesWithSqrtGcAtPaperSpacing) {
  const double slope = crush_slope(0.062);
  std::printf("log-log slope F(G_c), spacing 0.062 d: %.4f\n", slope);
  EXPECT_NEAR(slope, 0.5, 0.05);
}

// The accelerations (density ×4, elastic preload, spectral step) against a run without any:
// physical density, ramp from zero, Silling–Askari step. Force within 5 %.
TEST(PeridynamicsCrush, DISABLED_AccelerationKeepsForceWithin5Percent) {
  const auto s = Shape::sphere(1e-3);
  PdOptions plain;
  plain.density_scale = 1;
  plain.elastic_preload = false;
  plain.dt_rule = "silling_askari";
  const CrushResult ref = crush_single_grain(*s, table1(), 30.0, plain);
  const CrushResult fast = crush_single_grain(*s, table1(), 30.0, PdOptions{});
  std::printf("unaccelerated: F = %.2f N, %ld steps, %.3f s; default: F = %.2f N, %ld steps, %.3f s\n", ref.force,
              ref.steps, ref.wall_seconds, fast.force, fast.steps, fast.wall_seconds);
  ASSERT_TRUE(ref.split && fast.split);
  EXPECT_NEAR(fast.force / ref.force, 1.0, 0.05);
  EXPECT_NEAR(ref.force, 180.0, 18.0);
}

// The lattice is fixed to the body axes, so the crushing force depends on the load
// direction relative to it (measured: 179 N along an axis, 191 N along [110], 151 N along
// [111], 144 N along (0.26, 0.43, 0.86)). Reported, with a ±25 % band around the axis value.
TEST(PeridynamicsCrush, DISABLED_CrushingForceVersusLatticeOrientation) {
  const PeridynamicsModel model{PdOptions{}};
  Grain g;
  g.id = 1;
  g.shape = Shape::sphere(1e-3);
  g.strength.set(PeridynamicsModel::kGc, 30);
  double axis = 0;
  for (Vec3 d : {Vec3{0, 0, 1}, Vec3{1, 1, 0}, Vec3{1, 1, 1}, Vec3{0.3, 0.5, 1}}) {
    const Vec3 n = normalized(d);
    std::vector<Contact> c(2);
    c[0].a = c[1].a = 1;
    c[0].point = n * 1e-3, c[0].force = n * -400.0;
    c[1].point = n * -1e-3, c[1].force = n * 400.0;
    const BreakageAnalysis a = model.analyse(g, table1(), c);
    ASSERT_TRUE(a.broken);
    if (axis == 0) axis = a.figure("force_at_split_N");
    std::printf("load along (%.2f, %.2f, %.2f): %.2f N, %.0f steps, %.0f ms\n", n.x, n.y, n.z, a.figure("force_at_split_N"), a.figure("steps"),
                a.wall_ms);
    EXPECT_NEAR(a.figure("force_at_split_N") / axis, 1.0, 0.25);
  }
}

// Size correction (eq. 16): with δ ∝ d the critical stretch, hence the characteristic
// strength F/d², does not depend on the size. 1 mm vs 2 mm at the same rate. ±10 %.
TEST(PeridynamicsCrush, StrengthDependsOnGcOnly) {
  PdOptions o;
  o.spacing_fraction = 0.1;
  o.rate_medium = o.rate_large;  // same loading rate for both sizes
  const CrushResult big = crush_single_grain(*Shape::sphere(1e-3), table1(), 30.0, o);
  const CrushResult small = crush_single_grain(*Shape::sphere(0.5e-3), table1(), 30.0, o);
  ASSERT_TRUE(big.split && small.split);
  EXPECT_NEAR(small.strength / big.strength, 1.0, 0.10);
}

// ------------------------------------------------------------------ elasticity

// Elastic constants from the partial stress at the centre of a block under homogeneous
// strain (uniaxial strain along z, then simple shear).
struct Cubic {
  double c11, c12, c44;
  double e100() const { return (c11 - c12) * (c11 + 2 * c12) / (c11 + c12); }
  double e111() const { return 1.0 / (1.0 / (3.0 * (c11 + 2 * c12)) + 1.0 / (3.0 * c44)); }
};

Cubic bulk_constants(bool partial_volumes, const LpsMaterial& mat) {
  const Lattice L = cube_lattice(6, 1e-4, partial_volumes);
  PdSystem sys(L, mat, 1.0);
  std::int32_t c = 0;
  for (std::size_t i = 0; i < L.size(); ++i)
    if (norm(L.points[i]) == 0) c = static_cast<std::int32_t>(i);
  const double eps = 1e-6;
  sys.set_displacement([&](const Vec3& p) { return Vec3{0, 0, eps * p.z}; });
  const Mat3 s1 = sys.partial_stress(c);
  sys.set_displacement([&](const Vec3& p) { return Vec3{eps * p.y, eps * p.x, 0}; });  // ε_xy = ε
  const Mat3 s2 = sys.partial_stress(c);
  return {s1(2, 2) / eps, s1(0, 0) / eps, s2(0, 1) / (2 * eps)};
}

// With partial volumes the lattice LPS is isotropic: E along [001] and [111] within 2 %,
// Poisson's ratio within 0.01.
TEST(PeridynamicsElastic, PartialVolumesRecoverYoungsModulus) {
  const Material m = table1();
  const auto mat = LpsMaterial::from_young(m.young, m.poisson, m.density);
  const Cubic c = bulk_constants(true, mat);
  EXPECT_NEAR(c.e100() / m.young, 1.0, 0.02);
  EXPECT_NEAR(c.e111() / m.young, 1.0, 0.02);
  EXPECT_NEAR(c.c12 / (c.c11 + c.c12), m.poisson, 0.01);
}

// The plain neighbour rule (the default, as in the paper's discretisation): bulk modulus
// exact, orientation-averaged shear modulus exact, but cubic anisotropy. The kernel must
// reproduce the closed-form lattice sums: μ1 = (15μ/2m)(S4 − S22), μ2 = 15μ S22/m with
// m = Σ r², S4 = Σ r² n_x⁴, S22 = Σ r² n_x² n_y² over the 122 offsets. Tolerance 1e-6.
TEST(PeridynamicsElastic, PlainRuleMatchesLatticeSums) {
  const Material m = table1();
  const auto mat = LpsMaterial::from_young(m.young, m.poisson, m.density);
  double M = 0, S4 = 0, S22 = 0;
  for (const auto& e : pd::horizon_stencil(3.0002, false)) {
    const double r2 = e.length * e.length;
    M += r2;
    S4 += std::pow(e.dx, 4) / r2;
    S22 += double(e.dx * e.dx) * (e.dy * e.dy) / r2;
  }
  EXPECT_EQ(pd::horizon_stencil(3.0002, false).size(), 122u);
  const double mu1 = mat.shear * 15.0 / (2 * M) * (S4 - S22), mu2 = mat.shear * 15.0 * S22 / M;
  const Cubic c = bulk_constants(false, mat);
  EXPECT_NEAR(c.c11, mat.bulk + 4 * mu1 / 3, 1e-6 * c.c11);
  EXPECT_NEAR(c.c12, mat.bulk - 2 * mu1 / 3, 1e-6 * c.c11);
  EXPECT_NEAR(c.c44, mu2, 1e-6 * c.c11);
  EXPECT_NEAR((c.c11 + 2 * c.c12) / 3, mat.bulk, 1e-6 * mat.bulk);  // K exact
  EXPECT_NEAR((2 * mu1 + 3 * mu2) / 5, mat.shear, 1e-9 * mat.shear);  // Voigt average exact
  EXPECT_NEAR(c.e100() / m.young, 0.868, 0.005);  // documented: −13 % along the lattice axes
}

// A free bar pulled by end loads: static solve, strain from the middle third. The free
// lateral surfaces stiffen the PD bar (surface effect ∝ δ/W); refining the lattice at fixed
// size halves the error (first order), and the Richardson-extrapolated modulus is within
// 2 % of E.
double bar_modulus(int w, const Material& m) {
  const double width = 1.2e-3, h = width / w;
  std::vector<Vec3> pts;
  for (int k = 0; k < 2 * w; ++k)
    for (int j = 0; j < w; ++j)
      for (int i = 0; i < w; ++i) pts.push_back(Vec3(i, j, k) * h);
  const Lattice L = pd::build_lattice(pts, h, 3.0002, true);
  PdSystem sys(L, LpsMaterial::from_young(m.young, m.poisson, m.density), 1.0);
  std::vector<std::int32_t> top, bottom;
  for (std::size_t i = 0; i < L.size(); ++i) {
    if (L.cell[i][2] == 2 * w - 1) top.push_back(static_cast<std::int32_t>(i));
    if (L.cell[i][2] == 0) bottom.push_back(static_cast<std::int32_t>(i));
  }
  const double F = 1.0;
  sys.add_load(top, {0, 0, F});
  sys.add_load(bottom, {0, 0, -F});
  int it = 0;
  const auto u = sys.static_unit_solution(1e-10, 5000, &it, 1);
  const int k1 = w / 2, k2 = 2 * w - 1 - w / 2;
  double u1 = 0, u2 = 0;
  int n1 = 0, n2 = 0;
  for (std::size_t i = 0; i < L.size(); ++i) {
    if (L.cell[i][2] == k1) u1 += u[3 * i + 2], ++n1;
    if (L.cell[i][2] == k2) u2 += u[3 * i + 2], ++n2;
  }
  const double strain = (u2 / n2 - u1 / n1) / ((k2 - k1) * h);
  return F / (width * width) / strain;
}

TEST(PeridynamicsElastic, BarModulusConvergesAtFirstOrder) {
  const Material m = table1();
  const double e8 = bar_modulus(8, m) / m.young, e16 = bar_modulus(16, m) / m.young;
  const double err8 = e8 - 1, err16 = e16 - 1;
  std::printf("bar E/E0: W = 8: %.4f, W = 16: %.4f, error ratio %.3f, extrapolated %.4f\n", e8, e16, err8 / err16,
              2 * e16 - e8);
  EXPECT_GT(err16, 0);
  EXPECT_NEAR(err8 / err16, 2.0, 0.4);
  EXPECT_NEAR(2 * e16 - e8, 1.0, 0.02);
}

// Homogeneous deformation: interior points carry no net force (internal consistency of
// the two passes); the dilatation equals tr ε.
TEST(PeridynamicsElastic, AffineFieldIsInEquilibriumInTheBulk) {
  for (bool pv : {false, true}) {
    const double h = 1e-4;
    const Lattice L = cube_lattice(5, h, pv);
    PdSystem sys(L, LpsMaterial::from_young(100e9, 0.15, 2650), 1.0);
    const double eps = 1e-5;
    sys.set_displacement([&](const Vec3& p) { return Vec3{eps * p.x + 0.3 * eps * p.y, -0.2 * eps * p.y, 0.5 * eps * p.z}; });
    sys.compute_forces();
    for (std::size_t i = 0; i < L.size(); ++i) {
      if (norm(L.points[i]) > 1e-12) continue;
      EXPECT_NEAR(sys.dilatation(static_cast<std::int32_t>(i)), 1.3 * eps, 1e-4 * eps);
      EXPECT_LT(norm(sys.force_density(static_cast<std::int32_t>(i))), 1e-6 * 100e9 * eps / h);
    }
  }
}

// ------------------------------------------------------------------ kernel properties

// The box kernel (half bond list, PdKernel.h) against the plain formulation of Zhu & Zhao
// 2019 eqs. 1–4 summed over each point's full CSR family, written out here: the same broken
// bonds and the same forces up to round-off (the sums run in another order).
TEST(PeridynamicsKernel, HalfBondBoxMatchesFullFamilySums) {
  const auto s = Shape::sphere(1e-3);
  const double h = 0.1 * s->equivalent_diameter();
  const Lattice L = pd::build_lattice(pd::lattice_points(*s, h), h, 3.0002, true);
  const auto mat = LpsMaterial::from_young(100e9, 0.15, 2650);
  const double sc = 5e-4;
  PdSystem sys(L, mat, sc);
  auto field = [](const Vec3& p) {
    return Vec3{std::sin(1.7e7 * p.y + 3e6 * p.z), std::cos(1.3e7 * p.z + 2e6 * p.x), std::sin(1.1e7 * p.x)} * 2e-6;
  };
  sys.set_displacement(field);
  sys.compute_forces(1);
  const std::size_t n = L.size();
  const double V = L.point_volume;
  std::vector<Vec3> x(n);
  std::vector<double> g(n), a(n), b(n), at(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = L.points[i] + field(L.points[i]);
    double m = 0;
    for (std::int32_t q = L.offsets[i]; q < L.offsets[i + 1]; ++q) m += L.weight[q] * L.length[q] * L.length[q];
    m *= V;
    g[i] = 3 * V / m;
    a[i] = V * (3 * mat.bulk - 5 * mat.shear) / m;
    b[i] = 15 * mat.shear * V / m;
  }
  std::vector<double> alive = L.weight;
  long broken = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double acc = 0;
    for (std::int32_t q = L.offsets[i]; q < L.offsets[i + 1]; ++q) {
      const double l = norm(x[L.neighbours[q]] - x[i]), r = L.length[q];
      if (l - r > sc * r) alive[q] = 0, ++broken;
      acc += alive[q] * r * (l - r);
    }
    at[i] = a[i] * g[i] * acc;
  }
  EXPECT_GT(broken, 0);
  EXPECT_EQ(sys.alive(), alive);
  EXPECT_EQ(sys.broken_bonds(), broken);  // counted from the box's lanes, without a sync
  long face_broken = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (auto q : L.face_bond[i]) face_broken += q >= 0 && alive[static_cast<std::size_t>(q)] == 0.0;
  EXPECT_EQ(sys.broken_face_bonds(), face_broken);
  double fmax = 0, dmax = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 f{0, 0, 0};
    for (std::int32_t q = L.offsets[i]; q < L.offsets[i + 1]; ++q) {
      const auto j = static_cast<std::size_t>(L.neighbours[q]);
      const Vec3 Y = x[j] - x[i];
      const double l = norm(Y), r = L.length[q];
      f += Y * (alive[q] * ((at[i] + at[j]) * r + (b[i] + b[j]) * (l - r)) / l);
    }
    fmax = std::max(fmax, norm(f));
    dmax = std::max(dmax, norm(f - sys.force_density(static_cast<std::int32_t>(i))));
  }
  EXPECT_GT(fmax, 0);
  EXPECT_LT(dmax, 1e-11 * fmax);
}

// Every version of the box kernel this CPU can run gives bitwise the same breaks and forces,
// and so does any thread count (slabs of one colour never touch the same cell; PdSystem.h).
TEST(PeridynamicsKernel, VariantsAndThreadsAgree) {
  const auto s = Shape::sphere(1e-3);
  const double h = 0.1 * s->equivalent_diameter();
  const Lattice L = pd::build_lattice(pd::lattice_points(*s, h), h, 3.0002, true);
  const std::size_t n = L.size();
  const auto mat = LpsMaterial::from_young(100e9, 0.15, 2650);
  auto field = [&](const Vec3& p) { return Vec3{std::sin(4e3 * p.y), std::cos(3e3 * p.z), std::sin(5e3 * p.x)} * 2e-7; };
  struct State {
    std::vector<double> alive, f;
  };
  auto run = [&](const std::string& isa, int threads) {
    pd::kernel::select_isa(isa);
    PdSystem sys(L, mat, 5e-4);
    sys.set_displacement(field);
    for (int k = 0; k < 3; ++k) sys.step(1e-9, 0.0, 0.0, threads);
    pd::kernel::select_isa("");
    State st{sys.alive(), {}};
    for (std::int32_t i = 0; i < static_cast<std::int32_t>(n); ++i) {
      const Vec3 f = sys.force_density(i);
      st.f.insert(st.f.end(), {f.x, f.y, f.z, sys.displacement(i, 0)});
    }
    return st;
  };
  const State ref = run("generic", 1);
  long broken = 0;
  for (double w : ref.alive) broken += w == 0;
  EXPECT_GT(broken, 0);
  for (const auto& isa : pd::kernel::available_isas())
    for (int threads : {1, 2, 3}) {
      const State st = run(isa, threads);
      EXPECT_EQ(st.alive, ref.alive) << isa << " threads " << threads;  // same bonds broken
      EXPECT_EQ(st.f, ref.f) << isa << " threads " << threads;
    }
  EXPECT_THROW(pd::kernel::select_isa("sse9"), std::invalid_argument);
  const auto av = pd::kernel::available_isas();
  if (std::find(av.begin(), av.end(), "avx512") == av.end()) {  // a version this CPU cannot run
    EXPECT_THROW(pd::kernel::select_isa("avx512"), std::invalid_argument);
  }
  std::printf("kernel isa: %s\n", pd::kernel::isa());
}

// Each bond is stored at both ends; both copies must break at the same step (the force
// pair stays equal and opposite). A sphere loaded far past its strength, every step.
TEST(PeridynamicsKernel, BondsBreakAtBothEndsTogether) {
  const auto s = Shape::sphere(1e-3);
  const double h = 0.1 * s->equivalent_diameter();
  const Lattice L = pd::build_lattice(pd::lattice_points(*s, h), h, 3.0002, true);
  const auto mat = LpsMaterial::from_young(100e9, 0.15, 2650);
  PdSystem sys(L, mat, pd::critical_stretch(30.0, mat.bulk, mat.shear, L.horizon));
  std::vector<std::int32_t> top, bottom;
  for (std::size_t i = 0; i < L.size(); ++i) {
    if (L.points[i].z > 0.6e-3) top.push_back(static_cast<std::int32_t>(i));
    if (L.points[i].z < -0.6e-3) bottom.push_back(static_cast<std::int32_t>(i));
  }
  sys.fix(bottom);
  sys.add_load(top, {0, 0, -1.0});
  const double dt = 0.8 * sys.spectral_dt();
  std::vector<std::int32_t> rev(L.neighbours.size());
  for (std::int32_t i = 0; i < static_cast<std::int32_t>(L.size()); ++i)
    for (std::int32_t q = L.offsets[i]; q < L.offsets[i + 1]; ++q) {
      const std::int32_t j = L.neighbours[q];
      const auto* b = L.neighbours.data() + L.offsets[j];
      const auto* e = L.neighbours.data() + L.offsets[j + 1];
      rev[q] = static_cast<std::int32_t>(std::lower_bound(b, e, i) - L.neighbours.data());
      ASSERT_EQ(L.neighbours[rev[q]], i);
    }
  long checked = 0, face_checked = 0;
  for (int n = 0; n < 400; ++n) {
    sys.step(dt, 4e7 * n * dt, 0.0);  // 4e7 N/s: far past the strength within the run
    if (n % 5) continue;
    long broken = 0, face_broken = 0;
    for (std::size_t q = 0; q < rev.size(); ++q) {
      ASSERT_EQ(sys.alive()[q], sys.alive()[rev[q]]) << "bond " << q << " step " << n;
      broken += sys.alive()[q] == 0.0;
    }
    for (const auto& fb : L.face_bond)
      for (auto q : fb) face_broken += q >= 0 && sys.alive()[static_cast<std::size_t>(q)] == 0.0;
    // The counts a check reads come from the box's lanes: they follow the breaks.
    ASSERT_EQ(sys.broken_bonds(), broken) << "step " << n;
    ASSERT_EQ(sys.broken_face_bonds(), face_broken) << "step " << n;
    checked += broken;
    face_checked += face_broken;
  }
  EXPECT_GT(checked, 0);
  EXPECT_GT(face_checked, 0);
}

// The spectral step estimate sits just below the real stability limit: undamped motion
// stays bounded at the estimate and blows up 20 % above it. The Silling–Askari bound is
// safe and about 2.2× smaller.
TEST(PeridynamicsKernel, StableStepEstimate) {
  const auto s = Shape::sphere(1e-3);
  const double h = 0.1 * s->equivalent_diameter();
  const Lattice L = pd::build_lattice(pd::lattice_points(*s, h), h, 3.0002, false);
  const auto mat = LpsMaterial::from_young(100e9, 0.15, 2650);
  auto growth = [&](double dt) {
    PdSystem sys(L, mat, 1.0);  // s_c = 1: nothing breaks
    std::uint32_t z = 1;
    sys.set_displacement([&](const Vec3&) {
      auto r = [&] { return ((z = z * 1103515245u + 12345u) >> 8 & 0xffff) / 65536.0 - 0.5; };
      return Vec3{r(), r(), r()} * 1e-9;
    });
    sys.step(dt, 0, 0);
    const double ke0 = sys.kinetic_energy();
    for (int n = 0; n < 3000; ++n) sys.step(dt, 0, 0);
    return sys.kinetic_energy() / ke0;
  };
  PdSystem probe(L, mat, 1.0);
  const double dt = probe.spectral_dt(40), sa = probe.stable_dt();
  EXPECT_GT(dt / sa, 1.8);
  EXPECT_LT(dt / sa, 2.6);
  EXPECT_LT(growth(dt), 10.0);
  EXPECT_LT(growth(sa), 10.0);
  EXPECT_GT(growth(1.2 * dt), 1e6);
}

// ------------------------------------------------------------------ outcome and conservation

// A 20×10×10 box lattice cut by a plane at x = 0 with one isolated point and a 2-point fine
// chip: two major clusters, fines joined to the nearest piece, every point counted once,
// fracture points on the cut.
TEST(PeridynamicsClusters, FinesJoinNearestPieceAndVolumeIsConserved) {
  const double h = 1e-4;
  std::vector<Vec3> pts;
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = -10; i < 10; ++i) pts.push_back(Vec3(i, j, k) * h);
  const Lattice L = pd::build_lattice(pts, h, 3.0002, false);
  std::vector<double> alive = L.weight;
  auto index = [&](int i, int j, int k) {
    for (std::size_t p = 0; p < L.size(); ++p)
      if (L.cell[p] == std::array<int, 3>{i, j, k}) return static_cast<int>(p);
    return -1;
  };
  auto cut_point = [&](int p) {  // break every face bond of p, both directions
    for (int d = 0; d < 6; ++d) {
      const auto q = L.face_bond[p][d];
      if (q < 0) continue;
      alive[q] = 0;
      const int j = L.neighbours[q];
      for (int e = 0; e < 6; ++e)
        if (L.face_bond[j][e] >= 0 && L.neighbours[L.face_bond[j][e]] == p) alive[L.face_bond[j][e]] = 0;
    }
  };
  // the plane between x = -1 and x = 0
  for (std::size_t p = 0; p < L.size(); ++p)
    if (L.cell[p][0] == -1) alive[L.face_bond[p][0]] = 0, alive[L.face_bond[index(0, L.cell[p][1], L.cell[p][2])][1]] = 0;
  const int lone = index(8, 5, 5);  // well inside the right half
  cut_point(lone);
  const pd::Components comp = pd::face_components(L, alive);
  EXPECT_EQ(comp.count, 3);
  EXPECT_EQ(pd::major_count(comp, 0.03), 2);
  const PointClusters pc = pd::point_clusters(L, alive, 0.03);
  ASSERT_EQ(pc.clusters, 2);
  ASSERT_EQ(pc.cluster.size(), L.size());
  std::vector<long> count(2, 0);
  for (int c : pc.cluster) {
    ASSERT_GE(c, 0);
    ASSERT_LT(c, 2);
    ++count[c];
  }
  EXPECT_EQ(count[0] + count[1], static_cast<long>(L.size()));
  EXPECT_EQ(std::abs(count[0] - count[1]), 0);  // lone point rejoined its half: 1000 each
  const int right = pc.cluster[index(9, 9, 9)];
  EXPECT_EQ(pc.cluster[lone], right);
  // fracture points: the 100 cut bonds, at x = -h/2, given to both pieces
  EXPECT_EQ(pc.fracture_points[0].size(), 100u);
  EXPECT_EQ(pc.fracture_points[1].size(), 100u);
  for (const auto& f : pc.fracture_points[0]) EXPECT_NEAR(f.x, -0.5 * h, 1e-15);
  // on_surface: the box's faces
  EXPECT_TRUE(pc.on_surface[index(-10, 5, 5)]);
  EXPECT_FALSE(pc.on_surface[index(-5, 5, 5)]);
}

// ------------------------------------------------------------------ the BreakageModel

Grain sphere_grain(double radius, double gc) {
  Grain g;
  g.id = 7;
  g.shape = Shape::sphere(radius);
  g.position = {1e-3, 2e-3, 3e-3};
  g.strength.set(PeridynamicsModel::kGc, gc);
  return g;
}

// Two opposite contacts on a 2 mm grain, world frame, grain rotated 90° about x (the
// forces act along the body y axis): a force above the crushing force splits it, with the
// criterion near the crushing force; a force well below it leaves the grain intact.
TEST(PeridynamicsModel, AnalyseSplitsOrKeepsAGrain) {
  const PeridynamicsModel model{PdOptions{}};
  Grain g = sphere_grain(1e-3, 30.0);
  g.orientation = Quat::from_axis_angle({1, 0, 0}, kPi / 2);
  auto contacts = [&](double F) {
    std::vector<Contact> c(2);
    c[0].a = g.id, c[0].wall = kPlaten, c[0].point = g.position + Vec3{0, 0, 1e-3}, c[0].force = {0, 0, -F};
    c[1].a = g.id, c[1].wall = kFloor, c[1].point = g.position - Vec3{0, 0, 1e-3}, c[1].force = {0, 0, F};
    return c;
  };
  const BreakageAnalysis hit = model.analyse(g, table1(), contacts(300.0));
  EXPECT_TRUE(hit.broken);
  EXPECT_EQ(hit.outcome, "split");
  EXPECT_NEAR(hit.load, 300.0, 1e-9);
  EXPECT_NEAR(hit.figure("force_at_split_N"), 180.0, 18.0);
  EXPECT_GT(hit.figure("points"), 2000);
  EXPECT_GT(hit.figure("steps"), 0);
  EXPECT_GT(hit.wall_ms, 0);
  ASSERT_TRUE(hit.fracture.has_value());
  const auto& pc = std::get<PointClusters>(*hit.fracture);
  EXPECT_GE(pc.clusters, 2);
  for (int c = 0; c < pc.clusters; ++c) EXPECT_FALSE(pc.fracture_points[c].empty());
  // the crack runs through the loading axis: body y; every cluster's fracture points lie
  // inside the grain
  for (const auto& fp : pc.fracture_points)
    for (const auto& p : fp) EXPECT_LT(norm(p), 1e-3);

  const BreakageAnalysis low = model.analyse(g, table1(), contacts(60.0));
  EXPECT_FALSE(low.broken);
  EXPECT_EQ(low.outcome, "intact");
  EXPECT_EQ(low.figure("force_at_split_N"), 0.0);
  EXPECT_FALSE(low.fracture.has_value());

  // The static first-break force is a property of the grain and the load pattern, not of the
  // final load (linear elasticity until the first bond breaks): the same at 60 N and 300 N up
  // to the round-off of the conjugate-gradient solve, and well below the crushing force (the
  // diametral grain splits at about 3.6 times it: 172.4 N against 48.0 N in single_grain_pd).
  const double first = hit.figure("first_break_force_N");
  EXPECT_NEAR(low.figure("first_break_force_N"), first, 1e-6 * first);
  EXPECT_GT(first, 20.0);
  EXPECT_LT(first, 0.5 * hit.figure("force_at_split_N"));
}

// The hold figures: an intact analysis whose bonds break during the ramp holds its load beyond
// the least hold (4 transits) while its motion decays; the longest quiet stretch at full load
// is at most the hold; an analysis that splits during the ramp has no hold.
TEST(PeridynamicsModel, HoldFiguresDescribeTheHold) {
  Grain g = sphere_grain(1e-3, 30.0);
  auto with = [&](double F) {
    std::vector<Contact> c(3);
    const double R = 1e-3, s = std::sqrt(0.5);
    for (auto& x : c) x.a = g.id;
    c[0].point = g.position + Vec3{0, 0, R}, c[0].force = {0, 0, -F};
    c[1].point = g.position + Vec3{R * s, 0, -R * s}, c[1].force = Vec3{-s, 0, s} * (F / (2 * s));
    c[2].point = g.position + Vec3{-R * s, 0, -R * s}, c[2].force = Vec3{s, 0, s} * (F / (2 * s));
    PdOptions o;
    o.spacing_fraction = 0.1;
    return PeridynamicsModel{o}.analyse(g, table1(), c);
  };
  // 180 N on three contacts at lattice 0.1: measured 985 steps, 148 of them at full load, with
  // a longest quiet stretch of 4.8 transits (≈ 12 steps each).
  const BreakageAnalysis held = with(180.0);
  ASSERT_EQ(held.outcome, "intact");
  EXPECT_GT(held.figure("hold_steps"), 100.0);
  EXPECT_LT(held.figure("hold_steps"), held.figure("steps"));
  EXPECT_GT(held.figure("quiet_transits_max"), 1.0);
  EXPECT_LE(held.figure("quiet_transits_max"), held.figure("hold_steps") / 5.0);  // ≥ 5 steps per transit here
  const BreakageAnalysis split = with(400.0);
  ASSERT_TRUE(split.broken);
  EXPECT_EQ(split.figure("hold_steps"), 0.0);
  EXPECT_EQ(split.figure("quiet_transits_max"), 0.0);
}

// A grain on two lower contacts pressed from above (three balanced contacts, rotated
// grain): it splits; all forces grow in proportion with the largest at the loading rate,
// so the force at the split does not depend on how far above it the final load lies.
TEST(PeridynamicsModel, ThreeContactsSplitIndependentlyOfTheFinalLoad) {
  PdOptions o;
  o.spacing_fraction = 0.1;
  const PeridynamicsModel model{o};
  Grain g = sphere_grain(1e-3, 30.0);
  g.orientation = Quat::from_axis_angle({0.3, 1, 0.2}, 0.7);
  auto analyse = [&](double F) {
    const double R = 1e-3, c = std::sqrt(0.5);
    std::vector<Contact> cs(3);
    for (auto& x : cs) x.a = g.id;
    cs[0].point = g.position + Vec3{0, 0, R}, cs[0].force = {0, 0, -F};
    cs[1].point = g.position + Vec3{R * c, 0, -R * c}, cs[1].force = Vec3{-c, 0, c} * (F / (2 * c));
    cs[2].point = g.position + Vec3{-R * c, 0, -R * c}, cs[2].force = Vec3{c, 0, c} * (F / (2 * c));
    return model.analyse(g, table1(), cs);
  };
  const BreakageAnalysis a = analyse(300.0), b = analyse(500.0);
  ASSERT_TRUE(a.broken && b.broken);
  EXPECT_NEAR(a.figure("force_at_split_N"), b.figure("force_at_split_N"), 0.02 * a.figure("force_at_split_N"));  // equal up to rounding of the load scale
  EXPECT_GT(a.figure("force_at_split_N"), 50.0);
  EXPECT_LT(a.figure("force_at_split_N"), 300.0);
  const auto& pc = std::get<PointClusters>(*a.fracture);
  EXPECT_GE(pc.clusters, 2);
  EXPECT_EQ(pc.cluster.size(), pc.points.size());
}

// analyse() is const and runs for several grains at once (one grain per OpenMP thread, as
// in Simulation::check_breakage): the same results as one after the other.
TEST(PeridynamicsModel, ConcurrentAnalysesMatchSerial) {
  PdOptions o;
  o.spacing_fraction = 0.1;
  const PeridynamicsModel model{o};
  const int n = 4;
  std::vector<Grain> grains;
  std::vector<std::vector<Contact>> contacts(n);
  for (int k = 0; k < n; ++k) {
    Grain g = sphere_grain(1e-3 * (1.0 - 0.1 * k), 30.0);
    g.id = k;
    g.orientation = Quat::from_axis_angle({1, 2, 3}, 0.4 * k);
    const double F = 60.0 + 60.0 * k;  // the first stays intact
    Contact a, b;
    a.a = b.a = g.id;
    a.point = g.position + Vec3{0, 0, g.shape->bounds().hi.z};
    b.point = g.position - Vec3{0, 0, g.shape->bounds().hi.z};
    a.force = {0, 0, -F};
    b.force = {0, 0, F};
    contacts[k] = {a, b};
    grains.push_back(g);
  }
  std::vector<BreakageAnalysis> serial(n), parallel(n);
  for (int k = 0; k < n; ++k) serial[k] = model.analyse(grains[k], table1(), contacts[k]);
#pragma omp parallel for num_threads(2) schedule(dynamic, 1)
  for (int k = 0; k < n; ++k) parallel[k] = model.analyse(grains[k], table1(), contacts[k]);
  int broken = 0;
  for (int k = 0; k < n; ++k) {
    EXPECT_EQ(serial[k].outcome, parallel[k].outcome);
    EXPECT_EQ(serial[k].figure("force_at_split_N"), parallel[k].figure("force_at_split_N"));
    EXPECT_EQ(serial[k].figure("steps"), parallel[k].figure("steps"));
    ASSERT_EQ(serial[k].fracture.has_value(), parallel[k].fracture.has_value());
    if (serial[k].fracture) {
      EXPECT_EQ(std::get<PointClusters>(*serial[k].fracture).cluster,
                std::get<PointClusters>(*parallel[k].fracture).cluster);
    }
    broken += serial[k].broken;
  }
  EXPECT_FALSE(serial[0].broken);
  EXPECT_GE(broken, 2);
}

TEST(PeridynamicsModel, BadInputsGiveOutcomesOrErrors) {
  const PeridynamicsModel model{PdOptions{}};
  Grain g = sphere_grain(1e-3, 30.0);
  std::vector<Contact> none;
  EXPECT_EQ(model.analyse(g, table1(), none).outcome, "no_load");

  Contact c;
  c.a = g.id;
  c.point = g.position + Vec3{0, 0, 1e-3};
  c.force = {0, 0, -100};
  std::vector<Contact> one{c};
  EXPECT_EQ(model.analyse(g, table1(), one).outcome, "no_load");

  Contact far = c;
  far.point = g.position + Vec3{0, 0, -2e-3};  // 1 mm below the grain
  far.force = {0, 0, 100};
  std::vector<Contact> off{c, far};
  const BreakageAnalysis a = model.analyse(g, table1(), off);
  EXPECT_EQ(a.outcome, "contact_off_grain");
  EXPECT_FALSE(a.broken);

  Contact nan = far;
  nan.point = g.position - Vec3{0, 0, 1e-3};
  nan.force = {0, 0, std::nan("")};
  std::vector<Contact> bad{c, nan};
  EXPECT_THROW(model.analyse(g, table1(), bad), std::invalid_argument);

  // too coarse a lattice: the outcome says so, the grain is kept
  PdOptions coarse;
  coarse.spacing_fraction = 0.4;
  const PeridynamicsModel cm{coarse};
  nan.force = {0, 0, 100};
  std::vector<Contact> two{c, nan};
  const BreakageAnalysis t = cm.analyse(g, table1(), two);
  EXPECT_EQ(t.outcome, "too_few_points");
  EXPECT_LT(t.figure("points"), 100);
  EXPECT_FALSE(t.broken);

  Grain no_gc = g;
  no_gc.strength.set(PeridynamicsModel::kGc, 0);
  EXPECT_THROW(model.analyse(no_gc, table1(), two), std::invalid_argument);
  Grain flat = g;
  flat.shape = Shape::disk(1e-3);
  EXPECT_THROW(model.analyse(flat, table1(), two), std::invalid_argument);
  Material wrong = table1();
  wrong.poisson = 0.5;
  EXPECT_THROW(model.analyse(g, wrong, two), std::invalid_argument);
  EXPECT_THROW(crush_single_grain(*Shape::sphere(1e-3), table1(), -1.0, PdOptions{}), std::invalid_argument);
}

// Any 3D shape: an ellipsoid and a box discretise (lattice through the centroid, every
// point inside) and crush. The cells of a lattice through the centroid cover a box only
// up to half a cell per face (here 85 %); the point volume is corrected to the grain's.
TEST(PeridynamicsModel, OtherShapesDiscretiseAndCrush) {
  for (const auto& s : {Shape::ellipsoid({1.2e-3, 0.9e-3, 0.8e-3}), Shape::box({0.8e-3, 0.8e-3, 0.7e-3})}) {
    const double h = 0.062 * s->equivalent_diameter();
    const auto pts = pd::lattice_points(*s, h);
    EXPECT_NEAR(pts.size() * h * h * h / s->volume(), 1.0, 0.2) << s->describe();
    for (const auto& p : pts) EXPECT_TRUE(s->contains(p));
    PdOptions o;
    o.spacing_fraction = 0.1;
    const CrushResult r = crush_single_grain(*s, table1(), 30.0, o);
    EXPECT_TRUE(r.split) << s->describe();
    EXPECT_NEAR(volume_sum(r), s->volume(), 1e-12 * s->volume());
  }
}

// The grains of Zhu & Zhao 2019 §5 are 42-vertex polyhedra; their lattice uses MeshDistance.
TEST(PeridynamicsModel, PolyhedralGrainCrushes) {
  TriMesh m = icosphere(1);
  m.scale(1e-3);
  const auto s = Shape::polyhedron(m);
  PdOptions o;
  o.spacing_fraction = 0.1;
  const CrushResult r = crush_single_grain(*s, table1(), 30.0, o);
  EXPECT_TRUE(r.split);
  EXPECT_NEAR(volume_sum(r), s->volume(), 1e-12 * s->volume());
}

// ------------------------------------------------------------------ strength (§4)

// eq. 13 at d0: G_c = G_c0 ((U − b)/a)², U uniform: bounds G_c0((1−b)/a)², G_c0(b/a)²;
// mean G_c0 (b³ − (b−1)³) / (3a²). Eq. 15 size effect on the mean. Threshold 80 N at the
// reference. 20 000 grains: mean within 1 %.
TEST(PeridynamicsStrength, WeibullSamplingFollowsEq13) {
  const PdOptions o;
  const PeridynamicsModel model{o};
  const double a = o.weibull_a, b = o.weibull_b;
  const double lo = o.gc0 * std::pow((1 - b) / a, 2), hi = o.gc0 * std::pow(b / a, 2);
  const double mean_ref = o.gc0 * (b * b * b - std::pow(b - 1, 3)) / (3 * a * a);
  for (double d : {2e-3, 1e-3}) {
    const double size = std::pow(d / o.d0, -6.0 / o.weibull_modulus);
    Rng rng(42);
    double sum = 0, mn = 1e300, mx = 0;
    const int n = 20000;
    const auto shape = Shape::sphere(d / 2);
    for (int k = 0; k < n; ++k) {
      Grain g;
      g.shape = shape;
      Rng r = rng.derive(k);
      model.assign_strength(g, table1(), r);
      sum += g.strength.get(PeridynamicsModel::kGc);
      mn = std::min(mn, g.strength.get(PeridynamicsModel::kGc));
      mx = std::max(mx, g.strength.get(PeridynamicsModel::kGc));
      EXPECT_NEAR(g.strength.get(PeridynamicsModel::kThreshold), pd_threshold_force(o, g.strength.get(PeridynamicsModel::kGc), d), 1e-12);
    }
    EXPECT_NEAR(sum / n / (mean_ref * size), 1.0, 0.01) << "d = " << d;
    EXPECT_GE(mn, lo * size * (1 - 1e-12));
    EXPECT_LE(mx, hi * size * (1 + 1e-12));
    EXPECT_LT(mn, lo * size * 1.05);  // the whole range is sampled
    EXPECT_GT(mx, hi * size * 0.95);
  }
  EXPECT_DOUBLE_EQ(pd_threshold_force(o, o.gc0, o.d0), 80.0);
  // threshold ∝ σ d² with σ ∝ √G_c (eqs. 12, 14)
  EXPECT_NEAR(pd_threshold_force(o, 4 * o.gc0, 0.5 * o.d0), 80.0 * 2 * 0.25, 1e-12);
}

TEST(PeridynamicsStrength, ChildrenAndDeterministicMode) {
  PdOptions o;
  o.weibull = false;
  const PeridynamicsModel model{o};
  Rng rng(1);
  Grain ref;
  ref.shape = Shape::sphere(1e-3);  // d = d0
  model.assign_strength(ref, table1(), rng);
  EXPECT_DOUBLE_EQ(ref.strength.get(PeridynamicsModel::kGc), 30.0);
  EXPECT_DOUBLE_EQ(ref.strength.get(PeridynamicsModel::kThreshold), 80.0);
  Grain small;
  small.shape = Shape::sphere(0.5e-3);
  model.assign_strength(small, table1(), rng);
  EXPECT_NEAR(small.strength.get(PeridynamicsModel::kGc), 30.0 * std::pow(0.5, -6.0 / 3.1), 1e-9);
  // eq. 15: the child of the reference grain
  Grain child;
  child.shape = Shape::sphere(0.5e-3);
  model.inherit_strength(ref, child, table1(), rng);
  EXPECT_NEAR(child.strength.get(PeridynamicsModel::kGc), 30.0 * std::pow(0.5, -6.0 / 3.1), 1e-9);
  EXPECT_NEAR(child.strength.get(PeridynamicsModel::kThreshold), 80.0 * std::pow(0.5, -3.0 / 3.1) * 0.25, 1e-9);
}

// ------------------------------------------------------------------ configuration

TEST(PeridynamicsConfig, RegistryBuildsWithDefaultsAndRejectsTypos) {
  nlohmann::json doc = {{"breakage", {{"type", "peridynamics"}, {"gc0", 25.0}, {"weibull", false}}}};
  Config root(doc);
  Config cfg = root.child("breakage");
  const auto& entry = breakage_models().find("peridynamics", "/breakage/type");
  auto model = entry.make(cfg, EngineContext{});
  ASSERT_TRUE(model);
  EXPECT_EQ(model->name(), "peridynamics");
  EXPECT_NO_THROW(root.check_unknown());
  // every default was written back
  for (const char* key : {"spacing_fraction", "horizon_factor", "partial_volumes", "d_ref", "zone_radius_factor",
                          "loading_rate_large", "dt_safety", "dt_rule", "density_scale", "elastic_preload",
                          "min_child_fraction", "weibull_modulus", "threshold_force_ref", "min_points",
                          "post_split_transits"})
    EXPECT_TRUE(doc["breakage"].contains(key)) << key;
  EXPECT_EQ(doc["breakage"]["spacing_fraction"], 0.062);
  auto* pdm = dynamic_cast<PeridynamicsModel*>(model.get());
  ASSERT_NE(pdm, nullptr);
  EXPECT_EQ(pdm->options().gc0, 25.0);

  nlohmann::json typo = {{"breakage", {{"type", "peridynamics"}, {"spacing_fractoin", 0.05}}}};
  Config r2(typo);
  entry.make(r2.child("breakage"), EngineContext{});
  EXPECT_THROW(r2.check_unknown(), ConfigError);

  nlohmann::json range = {{"breakage", {{"type", "peridynamics"}, {"dt_safety", 1.5}}}};
  Config r3(range);
  EXPECT_THROW(entry.make(r3.child("breakage"), EngineContext{}), ConfigError);
  nlohmann::json rule = {{"breakage", {{"type", "peridynamics"}, {"dt_rule", "courant"}}}};
  Config r4(rule);
  EXPECT_THROW(entry.make(r4.child("breakage"), EngineContext{}), ConfigError);
  EngineContext flat;
  flat.dimension = 2;
  nlohmann::json ok = {{"breakage", {{"type", "peridynamics"}}}};
  Config r5(ok);
  EXPECT_THROW(entry.make(r5.child("breakage"), flat), ConfigError);
}

TEST(PeridynamicsBench, KernelBenchReportsTheLammpsCylinder) {
  const std::string s = pd_kernel_bench(2, 1);
  const auto j = nlohmann::json::parse(s);
  EXPECT_EQ(j["points"], 3487);  // LAMMPS examples/peri: 3487 atoms
  EXPECT_GT(j["bonds"].get<long>(), 300000);
  EXPECT_EQ(j["steps"], 2);
  EXPECT_GT(j["bond_visits_per_second"].get<double>(), 0);
  EXPECT_THROW(pd_kernel_bench(0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace crumble

namespace crumble {
namespace {
// With the lattice aligned to the largest force (default), a diametral load breaks the
// reference grain at the same force whatever the grain's orientation; with the lattice
// fixed to the body axes the LPS lattice's anisotropy shows (179 N along an axis,
// ~144–151 N along generic directions).
TEST(PeridynamicsModel, LoadAlignedLatticeMakesStrengthOrientationFree) {
  auto crush = [](const Quat& q, bool align) {
    PdOptions o;
    o.align_lattice_to_load = align;
    const PeridynamicsModel model{o};
    Grain g = sphere_grain(1e-3, 30.0);
    g.orientation = q;
    std::vector<Contact> cs(2);
    for (auto& x : cs) x.a = g.id;
    cs[0].point = g.position + Vec3{0, 0, 1e-3}, cs[0].force = {0, 0, -300};
    cs[1].point = g.position - Vec3{0, 0, 1e-3}, cs[1].force = {0, 0, 300};
    const BreakageAnalysis a = model.analyse(g, table1(), cs);
    EXPECT_TRUE(a.broken);
    return a.figure("force_at_split_N");
  };
  const Quat generic = Quat::from_axis_angle({0.37, -0.81, 0.45}, 1.234);
  const double axis = crush(Quat{}, true), gen = crush(generic, true);
  EXPECT_NEAR(axis, 180.0, 18.0);
  EXPECT_NEAR(gen, axis, 0.02 * axis);
  const double body_gen = crush(generic, false);
  EXPECT_GT(std::abs(body_gen - axis), 0.05 * axis) << "the body-frame lattice is anisotropic";
}
}  // namespace
}  // namespace crumble
