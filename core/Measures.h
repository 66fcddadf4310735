// Post-processing measures: the figures a run reports, as pure functions of
// sizes, masses, stresses and forces, so that the writers, `compare`, `sweep` and the tests
// all compute them the same way. SI units throughout (m, kg, Pa, N). A figure that is not
// defined for the input (no mass, fewer than two points) is NaN; callers leave it out of
// their files (crumble never writes a NaN).
//
// Shape descriptors of one grain live one layer down, in geometry/ShapeMetrics.h (included
// here): circularity and aspect ratio (2D), Wadell sphericity and Zingg EI/FI from the
// principal dimensions (3D), and the sieve size (Harmon et al. 2020, eq. 21).
#pragma once
#include <array>
#include <string>
#include <vector>

#include "geometry/ShapeMetrics.h"

namespace crumble {

// ---- Fits ----

// Least-squares slope of log10(y) against log10(x) over the pairs with x, y > 0.
// Returns NaN with fewer than two usable pairs.
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y);

// Least-squares slope of y against log10(x) over the pairs with x > 0 and finite y. NaN with
// fewer than two usable pairs.
double semilog_slope(const std::vector<double>& x, const std::vector<double>& y);

// y = coefficient · x^exponent by least squares of log y against log x over the pairs with
// x, y > 0 (both finite). NaN coefficient and exponent with fewer than two usable pairs or
// when every usable x is the same.
struct PowerLaw {
  double coefficient = 0, exponent = 0;
  int points = 0;
  double operator()(double x) const;
};
PowerLaw fit_power_law(const std::vector<double>& x, const std::vector<double>& y);

// y where x first reaches `level`, interpolated linearly between that sample and the one
// before it (a series sampled every 100 steps otherwise reports its value at a sample well
// past the level). A series whose largest x falls short of the level by at most
// `tolerance`·level (a ramp whose last sample reads 4.9999 MPa for 5 MPa) gives y at that
// largest x. NaN when the level is not reached.
double value_at_level(const std::vector<double>& x, const std::vector<double>& y, double level,
                      double tolerance = 1e-4);

// ---- Particle size distribution by mass ----

// Percent (0–100) of the total mass passing each sieve: grains with size <= sieve. Sizes in
// m (removed fines enter at size 0 and pass every sieve), masses in kg. 0 at every sieve
// when there is no mass.
std::vector<double> percent_passing(const std::vector<double>& sizes, const std::vector<double>& masses,
                                    const std::vector<double>& sieves);

// `count` sieves from `largest` down by the factor `ratio` each (largest, largest/ratio, …).
std::vector<double> geometric_sieves(double largest, int count, double ratio);

// Mass-weighted quantile of sizes (e.g. d50 = 0.5): the size below which `fraction` of the
// mass lies, interpolated linearly between the sorted sizes' cumulative mass fractions
// (mid-point rule). NaN when there is no mass.
double mass_quantile(std::vector<double> sizes, std::vector<double> masses, double fraction);

// Characteristic sizes of a PSD by mass (mass_quantile) and the two classic gradation
// coefficients: uniformity C_u = d60/d10 and curvature C_c = d30²/(d10·d60) (NaN when d10
// or d60 is 0, e.g. more than 10 % removed fines at size 0).
struct Gradation {
  double d10 = 0, d30 = 0, d50 = 0, d60 = 0;  // m
  double uniformity = 0, curvature = 0;
};
Gradation gradation(const std::vector<double>& sizes, const std::vector<double>& masses);

// ---- Fractal dimension ----

// Zhu & Zhao 2019, eq. 17: N(d > d0) ∝ d0^(−D), by number of grains (as the paper fits it,
// Fig. 16). D from the least-squares fit of log N(d > d0) against log d0 at `sieves`
// geometric sieve sizes between the smallest and largest diameter; sieves retaining fewer
// than max(10, n/1000) grains are left out. NaN when all grains have one size.
double fractal_dimension(const std::vector<double>& diameters, int sieves = 12);

// The same D read from a PSD by mass (Tyler & Wheatcraft 1992: M(d < d0)/M_T = (d0/d_max)^(E−D)
// for a fractal distribution of self-similar grains in E dimensions; 2D "mass" is area):
// E minus the log–log slope of the fraction passing against the sieve size, over the sieves
// with 0 < passing < 100 %. For the tables of psd.csv, where only masses are known. NaN with
// fewer than two such sieves.
double fractal_dimension_by_mass(const std::vector<double>& sieves, const std::vector<double>& percent_passing,
                                 int dimension = 3);

// ---- Relative breakage ----

// Hardin (1985) relative breakage B_r = B_t / B_p on the plot of fraction passing against
// log10 size: the breakage potential B_p is the area between the initial PSD and
// 100 % passing above the cut-off size, the total breakage B_t the area between the initial
// and the current PSD above it. Hardin's cut-off is the No. 200 sieve, 0.074 mm (silt does
// not break further); crumble uses that size unscaled by default (kHardinCutoff), so B_r is
// comparable with laboratory values for sand-sized grains. Sizes below the cut-off (and
// removed fines, at size 0) count as passing. Computed exactly for the step-function PSDs of
// discrete grains. NaN when the initial sample has no mass above the cut-off.
constexpr double kHardinCutoff = 0.074e-3;  // m
double relative_breakage(const std::vector<double>& initial_sizes, const std::vector<double>& initial_masses,
                         const std::vector<double>& sizes, const std::vector<double>& masses,
                         double cutoff = kHardinCutoff);

// The same B_r from two sieve curves (percent passing of the initial and the current sample
// at the same sieves, in any order), as Hardin read it off plotted curves: straight lines in
// log size between the sieves, 100 % passing above the largest sieve, the smallest sieve's
// value continued down to the cut-off. What psd.csv holds, so a resumed run gives the same
// figure. NaN when the initial curve passes 100 % above the cut-off or the inputs disagree
// in length.
double relative_breakage_sieved(const std::vector<double>& sieves, const std::vector<double>& initial_percent,
                                const std::vector<double>& percent, double cutoff = kHardinCutoff);

// ---- Compression ----

// Normal compression line over the samples with stress_min <= σ_v <= stress_max (σ_v > 0):
// loglog_slope — the slope of log10 e against log10 σ_v (Zhu & Zhao 2019 §5, Fig. 12, the
// log e – log σ line of McDowell 2005; the paper quotes its magnitude, ≈ 0.52; negative here);
// compression_index — C_c = −de/dlog10 σ_v (the e – log σ line). Least squares; NaN with
// fewer than two samples in the range.
struct NclFit {
  double loglog_slope = 0;
  double compression_index = 0;
  std::size_t points = 0;
};
NclFit fit_ncl(const std::vector<double>& stress, const std::vector<double>& void_ratio, double stress_min,
               double stress_max);

// The loading range crumble fits in summary.json: the upper part of the loading,
// σ_v >= 0.3·max σ_v (the curved yield region below it is left out, Zhu & Zhao 2019 §5).
NclFit fit_ncl_upper(const std::vector<double>& stress, const std::vector<double>& void_ratio);

// Breakage events per stress increment (Zhu & Zhao 2019, Fig. 12: crushing events per 1 MPa):
// counts[k] = events with k·increment <= σ < (k+1)·increment (negative stresses in bin 0), for
// k = 0 … max(floor(top/increment), the highest bin with an event).
std::vector<long> events_per_increment(const std::vector<double>& event_stresses, double increment, double top);

// ---- Lateral stress ratio ----

// Normal forces of the grains on the side walls of a rigid box (Engine::wall_force of
// kWallXMin, kWallXMax, kWallYMin, kWallYMax; N, 2D: N/m, the y walls absent).
struct SideWallForces {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
};

// Mean horizontal stress on the side walls of a box lx × ly (2D: lx) filled to `height`:
// each wall's force over its loaded area (ly·height for an x wall, lx·height for a y wall;
// 2D: the height, per metre of thickness), averaged over the walls (3D: four, 2D: two). NaN
// for a non-positive height or side.
double lateral_stress(const SideWallForces& f, double lx, double ly, double height, int dimension);

// Coefficient of lateral earth pressure at rest K0 = σ_h / σ_v (one-dimensional compression:
// no lateral strain). NaN when σ_v <= 0.
double lateral_stress_ratio(double horizontal_stress, double vertical_stress);

// ---- Load–displacement ----

// A platen test (single grain between plates, Zhu & Zhao 2019 §4.2; plate on spheres):
// displacement of the platen from its first sample (positive downwards, m) against the
// platen force (N), and the peak.
struct LoadDisplacement {
  std::vector<double> displacement, load;
  double peak_load = 0, displacement_at_peak = 0;
};
LoadDisplacement load_displacement(const std::vector<double>& platen_height, const std::vector<double>& platen_force);

}  // namespace crumble
