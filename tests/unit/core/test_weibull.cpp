// Weibull strength sampling against the closed-form distributions (KS test).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/Rng.h"
#include "core/Weibull.h"

using namespace crumble;

namespace {
// Kolmogorov–Smirnov statistic of samples against a CDF.
template <class Cdf>
double ks(std::vector<double> x, Cdf cdf) {
  std::sort(x.begin(), x.end());
  double d = 0;
  const double n = static_cast<double>(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double f = cdf(x[i]);
    d = std::max({d, std::abs(f - i / n), std::abs((i + 1) / n - f)});
  }
  return d;
}

std::vector<double> draw(const WeibullParams& p, double d, int n, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(weibull_sample(p, d, rng.uniform()));
  return v;
}

// Critical KS value at 1 % significance: 1.63 / sqrt(n).
double critical(int n) { return 1.63 / std::sqrt(static_cast<double>(n)); }
}  // namespace

TEST(Weibull, InverseTransformMatchesClosedFormSeeds004) {
  WeibullParams p;
  p.variant = "weibull";
  p.sigma0 = 30e6;
  p.d0 = 2e-3;
  p.modulus = 3.0;
  const int n = 20000;
  for (double d : {1e-3, 2e-3, 3.5e-3}) {
    auto x = draw(p, d, n, 7);
    EXPECT_LT(ks(x, [&](double s) { return weibull_cdf(p, d, s); }), critical(n)) << "d=" << d;
  }
}

TEST(Weibull, KsDetectsAWrongModulus) {
  // The test above must be able to fail: samples with m = 3 against an m = 4 CDF.
  WeibullParams p;
  p.sigma0 = 30e6;
  p.modulus = 3.0;
  auto x = draw(p, 2e-3, 20000, 7);
  WeibullParams q = p;
  q.modulus = 4.0;
  EXPECT_GT(ks(x, [&](double s) { return weibull_cdf(q, 2e-3, s); }), critical(20000));
}

TEST(Weibull, LinearFitMatchesClosedFormSeeds000) {
  // Zhu & Zhao 2019 eq. 12: sigma/sigma0 = (U - b)/a * (d/d0)^(-3/psi), uniform between
  // (1 - b)/a and -b/a at d = d0 (a = -0.76, b = 1.13: 0.171 .. 1.487).
  WeibullParams p;
  p.variant = "linear";
  p.sigma0 = 45e6;
  p.modulus = 3.1;
  const int n = 20000;
  auto x = draw(p, 2e-3, n, 11);
  EXPECT_LT(ks(x, [&](double s) { return weibull_cdf(p, 2e-3, s); }), critical(n));
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  EXPECT_NEAR(*lo / 45e6, (1 - 1.13) / -0.76, 2e-3);
  EXPECT_NEAR(*hi / 45e6, -1.13 / -0.76, 2e-3);
  // Size effect: a 1 mm grain is stronger by 2^(3/3.1).
  auto y = draw(p, 1e-3, n, 11);
  EXPECT_NEAR(y[0] / x[0], std::pow(2.0, 3.0 / 3.1), 1e-12);
}

TEST(Weibull, SizeEffectOfChildren) {
  // Zhu & Zhao 2019 eq. 14 / Harmon et al. 2020 eq. 13
  EXPECT_NEAR(weibull_size_effect(10.0, 1.0, 2.0, 3.0), 20.0, 1e-12);
  EXPECT_NEAR(weibull_size_effect(10.0, 2.0, 2.0, 3.1), 10.0, 1e-12);
}

TEST(Weibull, RngStreamsAreStableAndDistinct) {
  Rng a(42), b(42);
  EXPECT_EQ(a.derive(5).uniform(), b.derive(5).uniform());
  EXPECT_NE(a.derive(5).uniform(), a.derive(6).uniform());
}
