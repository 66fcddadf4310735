#include "core/Measures.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace crumble {

namespace {
// Least-squares slope of v(y) against log10(x) over the pairs with x > 0 that `v` accepts
// (it returns NaN for the others). NaN with fewer than two usable pairs.
template <class V>
double slope_against_log10(const std::vector<double>& x, const std::vector<double>& y, V v) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    const double b = v(y[i]);
    if (!(x[i] > 0) || !std::isfinite(b)) continue;
    const double a = std::log10(x[i]);
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
}  // namespace

double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  return slope_against_log10(x, y, [](double v) { return v > 0 ? std::log10(v) : std::numeric_limits<double>::quiet_NaN(); });
}

double semilog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  return slope_against_log10(x, y, [](double v) { return v; });
}

double value_at_level(const std::vector<double>& x, const std::vector<double>& y, double level, double tolerance) {
  const std::size_t n = std::min(x.size(), y.size());
  std::size_t best = n;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    if (x[i] >= level) {
      if (i == 0 || !std::isfinite(x[i - 1]) || !std::isfinite(y[i - 1]) || !(x[i - 1] < level)) return y[i];
      const double t = (level - x[i - 1]) / (x[i] - x[i - 1]);
      return y[i - 1] + t * (y[i] - y[i - 1]);
    }
    if (best == n || x[i] > x[best]) best = i;
  }
  if (best < n && x[best] >= level * (1 - tolerance)) return y[best];
  return std::numeric_limits<double>::quiet_NaN();
}

double PowerLaw::operator()(double x) const { return coefficient * std::pow(x, exponent); }

PowerLaw fit_power_law(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0) || !std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
    ++n;
  }
  PowerLaw p;
  p.points = n;
  const double den = n * sxx - sx * sx;
  if (n < 2 || !(std::abs(den) > 1e-12 * std::max(1.0, n * sxx))) {
    p.coefficient = p.exponent = std::numeric_limits<double>::quiet_NaN();
    return p;
  }
  p.exponent = (n * sxy - sx * sy) / den;
  p.coefficient = std::exp((sy - p.exponent * sx) / n);
  return p;
}

// Zhu & Zhao 2019, eq. 17 (counted as in their Fig. 16).
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


std::vector<double> percent_passing(const std::vector<double>& sizes, const std::vector<double>& masses,
                                    const std::vector<double>& sieves) {
  const std::size_t n = std::min(sizes.size(), masses.size());
  double total = 0;
  for (std::size_t i = 0; i < n; ++i) total += masses[i];
  std::vector<double> out;
  out.reserve(sieves.size());
  for (double sv : sieves) {
    double pass = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (sizes[i] <= sv) pass += masses[i];
    out.push_back(total > 0 ? 100.0 * pass / total : 0.0);
  }
  return out;
}

std::vector<double> geometric_sieves(double largest, int count, double ratio) {
  std::vector<double> s;
  for (int k = 0; k < count; ++k) s.push_back(largest * std::pow(ratio, -k));
  return s;
}

Gradation gradation(const std::vector<double>& sizes, const std::vector<double>& masses) {
  Gradation g;
  g.d10 = mass_quantile(sizes, masses, 0.1);
  g.d30 = mass_quantile(sizes, masses, 0.3);
  g.d50 = mass_quantile(sizes, masses, 0.5);
  g.d60 = mass_quantile(sizes, masses, 0.6);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  g.uniformity = g.d10 > 0 ? g.d60 / g.d10 : nan;
  g.curvature = g.d10 > 0 && g.d60 > 0 ? g.d30 * g.d30 / (g.d10 * g.d60) : nan;
  return g;
}

double fractal_dimension_by_mass(const std::vector<double>& sieves, const std::vector<double>& passing, int dimension) {
  std::vector<double> x, y;
  for (std::size_t i = 0; i < std::min(sieves.size(), passing.size()); ++i)
    if (sieves[i] > 0 && passing[i] > 0 && passing[i] < 100) {
      x.push_back(sieves[i]);
      y.push_back(passing[i]);
    }
  // Tyler & Wheatcraft 1992: M(d < d0)/M_T = (d0/d_max)^(E − D).
  return dimension - loglog_slope(x, y);
}

namespace {
// Mass passing (fraction) as a step function of size: sorted sizes with cumulative fractions.
struct Cumulative {
  std::vector<double> size, passing;  // passing[i]: fraction with size <= size[i]
  Cumulative(const std::vector<double>& sizes, const std::vector<double>& masses) {
    const std::size_t n = std::min(sizes.size(), masses.size());
    std::vector<std::size_t> idx(n);
    std::iota(idx.begin(), idx.end(), 0);
    std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return sizes[a] < sizes[b]; });
    double total = 0;
    for (std::size_t i = 0; i < n; ++i) total += masses[i];
    if (!(total > 0)) return;
    double cum = 0;
    for (std::size_t i : idx) {
      cum += masses[i];
      if (!size.empty() && size.back() == sizes[i]) passing.back() = cum / total;
      else {
        size.push_back(sizes[i]);
        passing.push_back(cum / total);
      }
    }
  }
  bool empty() const { return size.empty(); }
  double at(double d) const {  // fraction with size <= d
    const auto it = std::upper_bound(size.begin(), size.end(), d);
    return it == size.begin() ? 0.0 : passing[static_cast<std::size_t>(it - size.begin()) - 1];
  }
};
}  // namespace

double relative_breakage(const std::vector<double>& initial_sizes, const std::vector<double>& initial_masses,
                         const std::vector<double>& sizes, const std::vector<double>& masses, double cutoff) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Cumulative f0(initial_sizes, initial_masses), f1(sizes, masses);
  if (f0.empty() || f1.empty() || !(cutoff > 0)) return nan;
  // Both curves are steps between the grain sizes: integrate exactly over log10 d from the
  // cut-off to the largest size of either curve (both pass 100 % above it).
  std::vector<double> knots = {cutoff};
  for (double d : f0.size)
    if (d > cutoff) knots.push_back(d);
  for (double d : f1.size)
    if (d > cutoff) knots.push_back(d);
  std::sort(knots.begin(), knots.end());
  knots.erase(std::unique(knots.begin(), knots.end()), knots.end());
  double bp = 0, bt = 0;
  for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
    const double w = std::log10(knots[k + 1] / knots[k]);
    // The steps change at the knots: on [knot_k, knot_k+1) the passing is its value at knot_k.
    const double p0 = f0.at(knots[k]), p1 = f1.at(knots[k]);
    bp += (1.0 - p0) * w;  // Hardin 1985: potential, initial curve to 100 % passing
    bt += (p1 - p0) * w;   // total breakage, initial to current curve
  }
  return bp > 0 ? bt / bp : nan;
}

double relative_breakage_sieved(const std::vector<double>& sieves, const std::vector<double>& p0_in,
                                const std::vector<double>& p1_in, double cutoff) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::size_t n = sieves.size();
  if (n == 0 || p0_in.size() != n || p1_in.size() != n || !(cutoff > 0)) return nan;
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0);
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return sieves[a] < sieves[b]; });
  // Knots in log10 size with the fractions passing; the smallest sieve's value reaches down
  // to the cut-off.
  std::vector<double> x, f0, f1;
  for (std::size_t i : idx) {
    if (!(sieves[i] > 0)) continue;
    if (x.empty() && sieves[i] > cutoff) {
      x.push_back(std::log10(cutoff));
      f0.push_back(p0_in[i] / 100);
      f1.push_back(p1_in[i] / 100);
    }
    x.push_back(std::log10(sieves[i]));
    f0.push_back(p0_in[i] / 100);
    f1.push_back(p1_in[i] / 100);
  }
  const double xc = std::log10(cutoff);
  double bp = 0, bt = 0;
  for (std::size_t k = 0; k + 1 < x.size(); ++k) {
    double a = x[k], b = x[k + 1];
    if (b <= xc) continue;
    // Clip the segment at the cut-off, interpolating the straight lines there.
    auto lerp = [&](const std::vector<double>& f, double t) { return f[k] + (f[k + 1] - f[k]) * (t - x[k]) / (x[k + 1] - x[k]); };
    const double a0 = a < xc ? lerp(f0, xc) : f0[k], a1 = a < xc ? lerp(f1, xc) : f1[k];
    a = std::max(a, xc);
    // Trapezoids are exact for straight lines.
    bp += (b - a) * (1 - 0.5 * (a0 + f0[k + 1]));
    bt += (b - a) * 0.5 * ((a1 - a0) + (f1[k + 1] - f0[k + 1]));
  }
  return bp > 0 ? bt / bp : nan;
}

NclFit fit_ncl(const std::vector<double>& stress, const std::vector<double>& e, double lo, double hi) {
  std::vector<double> x, y;
  for (std::size_t i = 0; i < std::min(stress.size(), e.size()); ++i)
    if (stress[i] > 0 && stress[i] >= lo && stress[i] <= hi && std::isfinite(e[i])) {
      x.push_back(stress[i]);
      y.push_back(e[i]);
    }
  NclFit f;
  f.points = x.size();
  f.loglog_slope = loglog_slope(x, y);
  f.compression_index = -semilog_slope(x, y);
  return f;
}

NclFit fit_ncl_upper(const std::vector<double>& stress, const std::vector<double>& e) {
  double smax = 0;
  for (double s : stress)
    if (std::isfinite(s)) smax = std::max(smax, s);
  return fit_ncl(stress, e, 0.3 * smax, smax);
}

std::vector<long> events_per_increment(const std::vector<double>& event_stresses, double increment, double top) {
  if (!(increment > 0)) return {};
  auto bin = [&](double s) { return static_cast<long>(std::floor(std::max(0.0, s) / increment)); };
  long last = std::isfinite(top) ? bin(top) : 0;
  for (double s : event_stresses)
    if (std::isfinite(s)) last = std::max(last, bin(s));
  std::vector<long> counts(static_cast<std::size_t>(last + 1), 0);
  for (double s : event_stresses)
    if (std::isfinite(s)) ++counts[static_cast<std::size_t>(bin(s))];
  return counts;
}

double lateral_stress(const SideWallForces& f, double lx, double ly, double height, int dimension) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!(height > 0) || !(lx > 0)) return nan;
  if (dimension == 2) return 0.5 * (f.x_min + f.x_max) / height;  // N/m over the height: Pa
  if (!(ly > 0)) return nan;
  return 0.25 * ((f.x_min + f.x_max) / (ly * height) + (f.y_min + f.y_max) / (lx * height));
}

double lateral_stress_ratio(double horizontal, double vertical) {
  if (!(vertical > 0) || !std::isfinite(horizontal)) return std::numeric_limits<double>::quiet_NaN();
  return horizontal / vertical + 0.0;  // + 0.0: no "-0" in a file when no wall is touched
}

LoadDisplacement load_displacement(const std::vector<double>& h, const std::vector<double>& f) {
  LoadDisplacement r;
  const std::size_t n = std::min(h.size(), f.size());
  for (std::size_t i = 0; i < n; ++i) {
    r.displacement.push_back(h[0] - h[i]);
    r.load.push_back(f[i]);
    if (i == 0 || f[i] > r.peak_load) {
      r.peak_load = f[i];
      r.displacement_at_peak = h[0] - h[i];
    }
  }
  return r;
}

}  // namespace crumble
