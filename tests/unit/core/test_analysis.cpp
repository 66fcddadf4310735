#include <gtest/gtest.h>

#include <cmath>

#include "core/Analysis.h"
#include "core/Rng.h"

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
