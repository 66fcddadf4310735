#include "core/Weibull.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace crumble {

double weibull_sample(const WeibullParams& p, double d, double u) {
  if (!(d > 0)) throw std::invalid_argument("weibull_sample: size must be > 0");
  const double size = std::pow(d / p.d0, -3.0 / p.modulus);
  if (p.variant == "linear") {
    // Zhu & Zhao 2019 eq. 12
    return p.sigma0 * (u - p.b) / p.a * size;
  }
  // Harmon et al. 2020 eq. 12 (P_f = u; u < 1 so the log is finite)
  u = std::clamp(u, 0.0, 1.0 - 1e-16);
  return p.sigma0 * std::pow(-std::pow(p.d0 / d, 3.0) * std::log1p(-u), 1.0 / p.modulus);
}

double weibull_cdf(const WeibullParams& p, double d, double s) {
  const double size = std::pow(d / p.d0, -3.0 / p.modulus);
  if (p.variant == "linear") {
    // s = sigma0 * (u - b)/a * size  =>  u = b + a * s / (sigma0 * size); a < 0 so the
    // strength decreases with u: P(S <= s) = P(u >= u(s)) = 1 - u(s).
    const double u = p.b + p.a * s / (p.sigma0 * size);
    return std::clamp(1.0 - u, 0.0, 1.0);
  }
  // Harmon et al. 2020 eq. 11
  if (s <= 0) return 0;
  return 1.0 - std::exp(-std::pow(d / p.d0, 3.0) * std::pow(s / p.sigma0, p.modulus));
}

double weibull_size_effect(double strength_parent, double d_child, double d_parent, double modulus) {
  return strength_parent * std::pow(d_child / d_parent, -3.0 / modulus);
}

}  // namespace crumble
