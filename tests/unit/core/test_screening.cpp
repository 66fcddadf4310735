#include <gtest/gtest.h>

#include <cmath>

#include "core/Screening.h"

using namespace crumble;

namespace {
// The grain and its screening force (what BreakageModel::threshold_force gives).
struct Loaded {
  Grain g;
  double threshold;
};
Loaded grain(double d, double threshold) {
  Grain g;
  g.id = 1;
  g.shape = Shape::sphere(d / 2);
  return {g, threshold};
}
ScreeningResult screen(const Loaded& l, std::span<const Contact> cs, const ScreeningSettings& s) {
  return crumble::screen(l.g, cs, s, l.threshold);
}
const ScreeningSettings kZhuZhao = zhu_zhao_screening();
Contact contact(Vec3 p, Vec3 f) {
  Contact c;
  c.a = 1;
  c.b = 2;
  c.point = p;
  c.normal = normalized(f);
  c.force = f;
  return c;
}
}  // namespace

TEST(Screening, DiametricalPairIsSelected) {
  const Loaded g = grain(2e-3, 80);
  std::vector<Contact> cs{contact({0, 0, 1e-3}, {0, 0, -100}), contact({0, 0, -1e-3}, {0, 0, 100})};
  auto r = screen(g, cs, kZhuZhao);
  EXPECT_TRUE(r.selected) << r.reason;
  EXPECT_NEAR(r.max_force, 100, 1e-12);
  EXPECT_NEAR(r.unbalanced_force_ratio, 0, 1e-12);
  EXPECT_NEAR(r.unbalanced_moment_ratio, 0, 1e-12);
}

TEST(Screening, SizeLimit) {
  const Loaded g = grain(0.29e-3, 0);
  std::vector<Contact> cs{contact({0, 0, 1e-4}, {0, 0, -100}), contact({0, 0, -1e-4}, {0, 0, 100})};
  EXPECT_STREQ(screen(g, cs, kZhuZhao).reason, "too_small");
  ScreeningSettings s = kZhuZhao;
  s.min_diameter = 0.2e-3;
  EXPECT_TRUE(screen(g, cs, s).selected);
}

// A grain of exactly the crushing limit passes (Zhu & Zhao 2019 §5: d_e >= 0.3 mm): cbrt(6V/π)
// of a 0.3 mm sphere is 8e-20 m short of 0.3 mm and was screened out as too small.
TEST(Screening, GrainAtTheCrushingLimitIsSelected) {
  const Loaded g = grain(0.3e-3, 0);
  std::vector<Contact> cs{contact({0, 0, 1.5e-4}, {0, 0, -100}), contact({0, 0, -1.5e-4}, {0, 0, 100})};
  EXPECT_TRUE(screen(g, cs, kZhuZhao).selected) << screen(g, cs, kZhuZhao).reason;
  EXPECT_STREQ(screen(grain(0.2999e-3, 0), cs, kZhuZhao).reason, "too_small");
}

TEST(Screening, ForceThreshold) {
  const Loaded g = grain(2e-3, 80);
  std::vector<Contact> cs{contact({0, 0, 1e-3}, {0, 0, -79}), contact({0, 0, -1e-3}, {0, 0, 79})};
  EXPECT_STREQ(screen(g, cs, kZhuZhao).reason, "below_threshold");
  ScreeningSettings s = kZhuZhao;
  s.force_threshold = false;
  EXPECT_TRUE(screen(g, cs, s).selected);
}

TEST(Screening, UnbalancedForce) {
  const Loaded g = grain(2e-3, 80);
  // |ΣF| = 3, mean |F| = 98.5 → ratio 0.0305 > 0.02.
  std::vector<Contact> cs{contact({0, 0, 1e-3}, {0, 0, -100}), contact({0, 0, -1e-3}, {0, 0, 97})};
  auto r = screen(g, cs, kZhuZhao);
  EXPECT_STREQ(r.reason, "unbalanced_force");
  EXPECT_NEAR(r.unbalanced_force_ratio, 3 / 98.5, 1e-12);
}

TEST(Screening, UnbalancedMoment) {
  const Loaded g = grain(2e-3, 80);
  // Balanced forces but a couple: two opposite forces offset sideways.
  std::vector<Contact> cs{contact({0, 0, 1e-3}, {0, 0, -100}), contact({0.5e-3, 0, -1e-3}, {0, 0, 100})};
  auto r = screen(g, cs, kZhuZhao);
  EXPECT_STREQ(r.reason, "unbalanced_moment");
  // |M| = 0.5 mm · 100 N; scale = |(0.5, 0, -2) mm| · 100 N.
  EXPECT_NEAR(r.unbalanced_moment_ratio, 0.5 / std::sqrt(0.25 + 4.0), 1e-12);
}

TEST(Screening, NearlyCollinearPairIsBalanced) {
  // A grain between two plates: round-off offsets must not read as an unbalanced moment.
  const Loaded g = grain(2e-3, 80);
  std::vector<Contact> cs{contact({1e-12, 0, 1e-3}, {0, 0, -100}), contact({0, 1e-12, -1e-3}, {0, 0, 100})};
  auto r = screen(g, cs, kZhuZhao);
  EXPECT_TRUE(r.selected) << r.reason << " " << r.unbalanced_moment_ratio;
  EXPECT_LT(r.unbalanced_moment_ratio, 1e-8);
}
