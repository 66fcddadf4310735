#include "core/Analysis.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace crumble {

double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0)) continue;
    const double a = std::log10(x[i]), b = std::log10(y[i]);
    sx += a;
    sy += b;
    sxx += a * a;
    sxy += a * b;
    ++n;
  }
  const double den = n * sxx - sx * sx;
  if (n < 2 || std::abs(den) < 1e-300) return std::numeric_limits<double>::quiet_NaN();
  return (n * sxy - sx * sy) / den;
}

double fractal_dimension(const std::vector<double>& d, int sieves) {
  if (d.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  if (!(*hi > *lo)) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> x, y;
  for (int k = 0; k < sieves; ++k) {
    // Sieves strictly inside (lo, hi) so every count is > 0.
    const double s = *lo * std::pow(*hi / *lo, (k + 0.5) / sieves);
    const auto n = std::count_if(d.begin(), d.end(), [&](double v) { return v > s; });
    // Too few grains above this sieve to count on (Poisson noise of the tail).
    if (n < std::max<long>(10, static_cast<long>(d.size() / 1000))) continue;
    x.push_back(s);
    y.push_back(static_cast<double>(n));
  }
  return -loglog_slope(x, y);
}

}  // namespace crumble
