// Analysis of results (DESIGN.md core/): fits used by the summary and the tests.
#pragma once
#include <vector>

#include "geometry/Shape.h"

namespace crumble {

// Least-squares slope of log10(y) against log10(x) over the pairs with x, y > 0.
// Returns NaN with fewer than two usable pairs.
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y);

// Zhu & Zhao 2019 eq. 17: N(d > d0) ∝ d0^(−D). D from the least-squares fit of log N(d > d0)
// against log d0 at `sieves` geometric sieve sizes between the smallest and largest
// diameter; sieves retaining fewer than max(10, n/1000) grains are left out. NaN when all grains have
// one size.
double fractal_dimension(const std::vector<double>& diameters, int sieves = 12);

// Harmon et al. 2020 §4.2: the sieve size of a grain approximates its minor axis as the
// chord through the centroid along the line to the closest surface point p_min (eq. 21):
// |p_min| plus the distance from the centroid to the surface in the opposite direction.
// A disk gives its diameter, a rectangle its shorter side. Surface points are the shape's
// level-set surface nodes. A shape whose centroid lies outside it (a crescent) has no such
// chord: its equivalent diameter is used.
double sieve_size(const Shape& s);

// Mass-weighted quantile of sizes (e.g. d50 = 0.5): the size below which `fraction` of the
// mass lies, interpolated linearly between the sorted sizes' cumulative mass fractions
// (mid-point rule). NaN when there is no mass.
double mass_quantile(std::vector<double> sizes, std::vector<double> masses, double fraction);

}  // namespace crumble
