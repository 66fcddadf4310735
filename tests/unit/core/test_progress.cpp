// The ETA of the progress lines (run/Progress.h) on synthetic runs whose remaining wall
// time is known in closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "run/Progress.h"

using crumble::EtaEstimator;

namespace {
// A run whose wall-time cost per unit of loading is c(f) = a (1 + g f): W(f) = a (f + g f²/2).
double wall(double f, double a, double g) { return a * (f + 0.5 * g * f * f); }
// Samples at every 0.5 % of the loading up to f_now (as the progress callback sees them).
EtaEstimator sampled(double f_now, double a, double g) {
  EtaEstimator e;
  for (double f = 0; f <= f_now + 1e-12; f += 0.005) e.add(wall(f, a, g), f);
  return e;
}
}  // namespace

TEST(EtaEstimator, ConstantCostGivesTheLinearRemainder) {
  // 100 s for the whole loading, half done: 50 s left (1e-9: exact arithmetic up to rounding).
  const EtaEstimator e = sampled(0.5, 100, 0);
  EXPECT_NEAR(e.eta_s(), 50.0, 1e-6);
  EXPECT_NEAR(e.recent_cost(), 100.0, 1e-6);
}

TEST(EtaEstimator, GrowingBreakageCostIsExtrapolated) {
  // Cost 4x higher at the end than at the start (grains break, analyses pile up): at half
  // way W(1) − W(0.5) = a (1 + 1.5·1 − 0.5 − 1.5·0.25) = 1.625 a. The average since the start
  // says W(0.5)·1 = 0.875 a (46 % short); the estimator must be within 5 %.
  const double a = 100, g = 3;
  const EtaEstimator e = sampled(0.5, a, g);
  const double truth = wall(1, a, g) - wall(0.5, a, g);
  EXPECT_NEAR(e.eta_s(), truth, 0.05 * truth);
  const double naive = wall(0.5, a, g) * (1 - 0.5) / 0.5;
  EXPECT_LT(std::abs(e.eta_s() - truth), 0.2 * std::abs(naive - truth));
  // Early (10 %) and late (90 %) in the same run.
  for (double f : {0.1, 0.9}) {
    const double t = wall(1, a, g) - wall(f, a, g);
    EXPECT_NEAR(sampled(f, a, g).eta_s(), t, 0.05 * t) << "at " << f;
  }
}

TEST(EtaEstimator, UnknownWithoutProgressAndZeroAtTheEnd) {
  EtaEstimator e;
  EXPECT_LT(e.eta_s(), 0);  // no sample
  e.add(0, 0);
  e.add(10, 0);
  EXPECT_LT(e.eta_s(), 0);  // time passes, the loading does not move: unknown, not infinite
  e.add(20, 1);
  EXPECT_EQ(e.eta_s(), 0);
  // Non-finite samples and samples going back in time are ignored.
  EtaEstimator f;
  f.add(0, 0);
  f.add(NAN, 0.5);
  f.add(10, 0.1);
  f.add(5, 0.9);
  EXPECT_NEAR(f.eta_s(), 90, 1e-9);
}

TEST(EtaEstimator, FormatsDurations) {
  EXPECT_EQ(crumble::format_duration(45.2), "45 s");
  EXPECT_EQ(crumble::format_duration(185), "3 m 05 s");
  EXPECT_EQ(crumble::format_duration(7620), "2 h 07 m");
  EXPECT_EQ(crumble::format_duration(-1), "?");
}
