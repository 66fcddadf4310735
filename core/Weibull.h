// Weibull strength sampling, both variants used by the reference papers.
#pragma once
#include <string>

namespace crumble {

struct WeibullParams {
  // "linear": Zhu & Zhao 2019 eq. 12 — a linear fit to the normalised survival curve,
  //           sigma = sigma0 * (U - b) / a * (d/d0)^(-3/psi), i.e. uniform between
  //           sigma0*(1-b)/a and sigma0*(-b)/a at d = d0.
  // "weibull": Harmon et al. 2020 eq. 12 — inverse transform of eq. 11,
  //           sigma = sigma0 * (-(d0/d)^3 ln(1 - P))^(1/m).
  std::string variant = "weibull";
  double sigma0 = 1;      // characteristic value at d0 (any unit: Pa, or G_c via sqrt)
  double d0 = 2e-3;       // m
  double modulus = 3.0;   // psi (Zhu & Zhao 2019) or m (Harmon et al. 2020)
  double a = -0.76;       // linear variant: slope (Zhu & Zhao 2019 §4.2)
  double b = 1.13;        // linear variant: intercept
};

// Strength for a grain of size d from a uniform variate u in [0, 1).
double weibull_sample(const WeibullParams& p, double d, double u);
// Probability that the sampled strength is <= s for size d (closed form).
double weibull_cdf(const WeibullParams& p, double d, double s);
// Zhu & Zhao 2019 eq. 14, Harmon et al. 2020 eq. 13: sigma_a / sigma_b = (d_a / d_b)^(-3/m).
double weibull_size_effect(double strength_parent, double d_child, double d_parent, double modulus);

}  // namespace crumble
