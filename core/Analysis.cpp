#include "core/Analysis.h"

#include "geometry/LevelSetGrid.h"

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

namespace crumble {

namespace {
// Distance from the centroid (inside) to the surface along the unit direction u: the first
// sign change of the signed distance, marched at `step` and refined by bisection.
double exit_distance(const Shape& s, const Vec3& u, double step, double reach) {
  double a = 0, b = step;
  while (b < reach && s.signed_distance(u * b) < 0) {
    a = b;
    b += step;
  }
  b = std::min(b, reach);
  for (int i = 0; i < 60; ++i) {
    const double m = 0.5 * (a + b);
    (s.signed_distance(u * m) < 0 ? a : b) = m;
  }
  return 0.5 * (a + b);
}
}  // namespace

double sieve_size(const Shape& s) {
  if (!(s.signed_distance({}) < 0)) return s.equivalent_diameter();
  const auto& nodes = s.level_set().nodes();
  Vec3 pmin;
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : nodes)
    if (norm(p) < best) {
      best = norm(p);
      pmin = p;
    }
  if (!(best > 0) || !std::isfinite(best)) return s.equivalent_diameter();
  const Vec3 u = pmin * (1.0 / best);
  const double reach = 2.0 * s.bounding_radius() + 1e-12;
  // March finely enough not to step over a thin part: a fraction of the distance to p_min.
  const double step = std::max(0.25 * best, 1e-3 * reach);
  return exit_distance(s, u, step, reach) + exit_distance(s, u * -1.0, step, reach);
}

double mass_quantile(std::vector<double> sizes, std::vector<double> masses, double fraction) {
  const std::size_t n = std::min(sizes.size(), masses.size());
  std::vector<std::size_t> idx(n);
  for (std::size_t i = 0; i < n; ++i) idx[i] = i;
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return sizes[a] < sizes[b]; });
  double total = 0;
  for (std::size_t i = 0; i < n; ++i) total += masses[i];
  if (!(total > 0)) return std::numeric_limits<double>::quiet_NaN();
  // Cumulative fraction at each grain's mid-point; linear between neighbours.
  double cum = 0, prev_x = sizes[idx[0]], prev_f = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = idx[k];
    const double f = (cum + 0.5 * masses[i]) / total;
    if (f >= fraction) {
      if (k == 0 || f == prev_f) return sizes[i];
      return prev_x + (sizes[i] - prev_x) * (fraction - prev_f) / (f - prev_f);
    }
    cum += masses[i];
    prev_x = sizes[i];
    prev_f = f;
  }
  return sizes[idx[n - 1]];
}

}  // namespace crumble
