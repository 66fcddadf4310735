// Conformance of the breakage-model seam (core/BreakageModel.h): every registered model, in
// every dimension it declares, on a single 2 mm grain (sphere; 2D: disk) squeezed by two
// prescribed opposite contacts (the diametral test the model unit tests use):
//   - no break below its strength, a break above it (an inactive model never breaks);
//   - degenerate input (no contact, one contact, two contacts at one point) gives a counted
//     outcome: no exception, a non-empty outcome word, finite figures, a fracture only
//     with a break.
// The models come from the registration table (tests/support/Registered.h): a new model,
// or a plugin's (CRUMBLE_TEST_PLUGINS), is tested by registering it.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/Config.h"
#include "scenarios/Registry.h"
#include "tests/support/Contacts.h"
#include "tests/support/Registered.h"

using namespace crumble;
using namespace crumble::testing_support;
using nlohmann::json;

namespace {

constexpr double kR = 1e-3;  // grain radius, m

// Test profile: the options that make a model's strength known, and the diametral load
// (N; 2D: N/m) below and above which it must hold and break.
struct Profile {
  json options = json::object();
  double below = 0, above = 0;
};

Profile profile(const std::string& model, int dim) {
  if (model == "stress") {
    // Harmon et al. 2020 eq. 5: two opposite forces P at ±R give σ = −2RP/V along the axis,
    // so σ_eq = 3P/(2πR²) (3D) and 2P/(πR) (2D); von Mises strength 35 MPa (Table 2) at
    // d = d0 without Weibull scatter.
    const double fail = dim == 3 ? 35e6 * 2 * kPi * kR * kR / 3 : 35e6 * kPi * kR / 2;
    return {{{"weibull", false}, {"criterion", "von_mises"}, {"strength", 35e6}}, 0.9 * fail, 1.1 * fail};
  }
  if (model == "peridynamics") {
    // Zhu & Zhao 2019 §4.2, Fig. 9: a 2 mm grain with G_c = 30 J/m² crushes at ≈ 180 N; a
    // coarse lattice (≈ 500 points) keeps the analysis short.
    return {{{"weibull", false}, {"gc0", 30}, {"spacing_fraction", 0.1}}, 60, 300};
  }
  if (model == "bonded_particles") {
    // The diametral crushing estimate of the DA-BPM grain with 30 MPa bonds, (π/2)σd (2D,
    // N/m) or σd²/0.9 (3D, N); tests/unit/bonded_particles measures 0.85–1.16 of it. A coarse
    // array (8 elements across) keeps the analysis short.
    const double est = dim == 3 ? 30e6 * 4 * kR * kR / 0.9 : 0.5 * kPi * 30e6 * 2 * kR;
    return {{{"normal_strength", 30e6}, {"shear_strength", 30e6}, {"elements_across", 8}}, 0.4 * est, 2.5 * est};
  }
  if (model == "block_beam") {
    // Liu et al. 2019 blocks and beams, 3 MPa tensile strength (the default): a 4 cm
    // concrete sphere holds 1.5 kN and splits at 2 kN (tests/unit/block_beam); forces scale
    // with d², so a 2 mm grain holds ≈ 3.7 N and splits at ≈ 5 N.
    return {{{"tensile_strength", 3e6}}, 1.5, 20};
  }
  // Unknown models: a load that cannot break a 2 mm grain (1 µN) and one that must (1 MN,
  // 3e11 Pa).
  return {json::object(), 1e-6, 1e6};
}

class ModelConformance : public ::testing::TestWithParam<Registered> {
 protected:
  int dim() const { return GetParam().dimension; }
  Vec3 up() const { return dim() == 3 ? Vec3{0, 0, 1} : Vec3{0, 1, 0}; }

  std::unique_ptr<BreakageModel> make() const {
    json opts = profile(GetParam().name, dim()).options;
    opts["type"] = GetParam().name;
    Config cfg(opts);
    EngineContext ctx;
    ctx.dimension = dim();
    ctx.gravity = dim() == 3 ? Vec3{0, 0, -9.81} : Vec3{0, -9.81, 0};
    auto m = breakage_models().find(GetParam().name, "/breakage/type").make(cfg, ctx);
    cfg.accept("type");  // read by the scenario factory, not the model
    cfg.check_unknown();
    return m;
  }

  Grain grain(const BreakageModel& m) const {
    Grain g;
    g.id = 4;
    g.shape = dim() == 3 ? Shape::sphere(kR) : Shape::disk(kR);
    g.position = dim() == 3 ? Vec3{0.01, 0.01, 0.01} : Vec3{0.01, 0.01, 0};
    g.orientation = dim() == 3 ? Quat::from_axis_angle({1, 2, 3}, 0.7) : Quat::from_axis_angle({0, 0, 1}, 0.7);
    Rng rng(1);
    m.assign_strength(g, Material{}, rng);
    return g;
  }

  // Platen pressing down on the top, floor pushing up on the bottom.
  std::vector<Contact> diametral(const Grain& g, double P) const {
    return {wall_contact(g, kPlaten, up() * kR, up() * -P), wall_contact(g, kFloor, up() * -kR, up() * P)};
  }

  // What every analysis must give, broken or not.
  static void expect_counted(const BreakageAnalysis& a, const std::string& what) {
    EXPECT_FALSE(a.outcome.empty()) << what;
    EXPECT_TRUE(std::isfinite(a.load)) << what;
    for (const auto& [name, v] : a.figures) EXPECT_TRUE(std::isfinite(v)) << what << ": " << name;
    EXPECT_EQ(a.broken, a.fracture.has_value()) << what << ": a fracture exactly when broken";
  }
};

TEST_P(ModelConformance, NoBreakBelowStrength) {
  const auto m = make();
  const Grain g = grain(*m);
  const auto a = m->analyse(g, Material{}, diametral(g, profile(GetParam().name, dim()).below));
  expect_counted(a, "below strength");
  EXPECT_FALSE(a.broken) << a.outcome;
}

TEST_P(ModelConformance, BreaksAboveStrength) {
  const auto m = make();
  const Grain g = grain(*m);
  const double P = profile(GetParam().name, dim()).above;
  const auto a = m->analyse(g, Material{}, diametral(g, P));
  expect_counted(a, "above strength");
  if (!m->active()) {
    EXPECT_FALSE(a.broken) << "an inactive model never breaks";
    return;
  }
  ASSERT_TRUE(a.broken) << a.outcome;
  ASSERT_TRUE(a.fracture.has_value());
  EXPECT_NEAR(a.load, P, 1e-9 * P) << "the largest contact force considered";
  // Children inherit a strength (Weibull size effect) without error.
  Grain child = g;
  child.shape = g.shape->scaled(0.5);
  Rng rng(2);
  EXPECT_NO_THROW(m->inherit_strength(g, child, Material{}, rng));
}

TEST_P(ModelConformance, DegenerateInputGivesACountedOutcome) {
  const auto m = make();
  const Grain g = grain(*m);
  const double P = profile(GetParam().name, dim()).above;
  const Vec3 top = up() * kR;
  const std::vector<std::pair<std::string, std::vector<Contact>>> cases = {
      {"no contact", {}},
      {"one contact", {wall_contact(g, kPlaten, top, up() * -P)}},
      {"two contacts at one point, opposite forces",
       {wall_contact(g, kPlaten, top, up() * -P), wall_contact(g, kFloor, top, up() * P)}},
      {"two contacts at one point, the same force",
       {wall_contact(g, kPlaten, top, up() * -P), wall_contact(g, kFloor, top, up() * -P)}},
  };
  for (const auto& [what, cs] : cases) {
    BreakageAnalysis a;
    ASSERT_NO_THROW(a = m->analyse(g, Material{}, cs)) << what;
    expect_counted(a, what);
    if (cs.empty()) EXPECT_FALSE(a.broken) << "nothing loads the grain";
  }
}

// BreakageModel::load_measure (a VTK cell field, docs/output.md): finite, 0 without a
// contact, growing with the load; a name ending in its unit. The built-in models against
// their closed forms: stress, the von Mises equivalent stress of eq. 5 under the diametral
// pair, 3P/(2πR²) (3D) or 2P/(πR) (2D); peridynamics, the largest contact force P.
TEST_P(ModelConformance, LoadMeasureIsFiniteAndFollowsTheLoad) {
  const auto m = make();
  const std::string name = m->load_measure_name();
  if (name.empty()) GTEST_SKIP() << GetParam().name << " declares no load measure";
  EXPECT_NE(name.rfind('_'), std::string::npos) << name << ": the name ends in its unit (e.g. _Pa, _N)";
  const Grain g = grain(*m);
  const Profile pr = profile(GetParam().name, dim());
  const double none = m->load_measure(g, Material{}, {});
  const double lo = m->load_measure(g, Material{}, diametral(g, pr.below));
  const double hi = m->load_measure(g, Material{}, diametral(g, pr.above));
  EXPECT_EQ(none, 0.0);
  EXPECT_TRUE(std::isfinite(lo) && std::isfinite(hi));
  EXPECT_GT(lo, 0.0);
  EXPECT_GT(hi, lo);
  if (GetParam().name == "stress") {
    const double P = pr.above;
    const double expect = dim() == 3 ? 3 * P / (2 * kPi * kR * kR) : 2 * P / (kPi * kR);
    EXPECT_NEAR(hi, expect, 1e-9 * expect);
  } else if (GetParam().name == "peridynamics") {
    EXPECT_NEAR(hi, pr.above, 1e-12 * pr.above);
  }
}

// BreakageAnalysis::points (output.vtk_analyses): when a model returns per-point data, every
// field has one entry per point and every value is finite; peridynamics' split returns its
// lattice with damage in [0, 1], some of it broken.
TEST_P(ModelConformance, AnalysisPointsAreConsistent) {
  const auto m = make();
  if (!m->active()) GTEST_SKIP() << "an inactive model never analyses";
  const Grain g = grain(*m);
  const auto a = m->analyse(g, Material{}, diametral(g, profile(GetParam().name, dim()).above));
  if (GetParam().name == "peridynamics") ASSERT_TRUE(a.points) << "a peridynamic split returns its lattice";
  if (!a.points) GTEST_SKIP() << GetParam().name << " returns no per-point data";
  const auto& c = *a.points;
  ASSERT_GT(c.points.size(), 0u);
  for (const auto& p : c.points) {
    EXPECT_TRUE(is_finite(p));
    EXPECT_LT(norm(p), 2 * kR) << "body frame: inside the grain's reach";
  }
  for (const auto& [name, v] : c.scalars) {
    EXPECT_EQ(v.size(), c.points.size()) << name;
    for (double x : v) EXPECT_TRUE(std::isfinite(x)) << name;
  }
  for (const auto& [name, v] : c.vectors) {
    EXPECT_EQ(v.size(), c.points.size()) << name;
    for (const auto& x : v) EXPECT_TRUE(is_finite(x)) << name;
  }
  if (GetParam().name == "peridynamics") {
    double max_damage = 0;
    for (const auto& [name, v] : c.scalars)
      if (name == "damage")
        for (double x : v) {
          EXPECT_GE(x, 0.0);
          EXPECT_LE(x, 1.0);
          max_damage = std::max(max_damage, x);
        }
    EXPECT_GT(max_damage, 0.0) << "a split grain has broken bonds";
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, ModelConformance, ::testing::ValuesIn(registered_models()),
                         [](const auto& info) { return param_name(info.param); });

}  // namespace
