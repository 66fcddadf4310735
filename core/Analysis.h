// Analysis of results (DESIGN.md core/): fits used by the summary and the tests.
#pragma once
#include <vector>

namespace crumble {

// Least-squares slope of log10(y) against log10(x) over the pairs with x, y > 0.
// Returns NaN with fewer than two usable pairs.
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y);

// seeds/000 eq. 17: N(d > d0) ∝ d0^(−D). D from the least-squares fit of log N(d > d0)
// against log d0 at `sieves` geometric sieve sizes between the smallest and largest
// diameter; sieves retaining fewer than max(10, n/1000) grains are left out. NaN when all grains have
// one size.
double fractal_dimension(const std::vector<double>& diameters, int sieves = 12);

}  // namespace crumble
