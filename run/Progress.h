// Progress lines of a run on stderr, with an ETA that follows the cost of the loading as it
// grows. The loop reports the fraction of the loading done (Loading::progress: the control
// variable — simulated time of a stress ramp, stress or strain towards its stop value — as a
// fraction of its end value); the wall time per unit of it grows as grains break (more
// grains, more contacts, more breakage analyses), so an ETA from the average rate since the
// start, or from steps, comes out too short. EtaEstimator measures the wall-time cost per
// unit of fraction over two recent windows and extrapolates its trend linearly to the end.
#pragma once
#include <deque>
#include <string>

#include "core/Observer.h"

namespace crumble {

class EtaEstimator {
 public:
  // A sample: wall seconds since the loading started (non-decreasing) and the fraction done
  // in [0, 1]. Non-finite values and samples that go back in time are ignored.
  void add(double wall_s, double fraction);
  // Estimated wall seconds to the end of the loading; negative while unknown (fewer than two
  // samples, or no progress yet). Everything in the wall time counts: engine steps, breakage
  // analyses, fragment building, output.
  double eta_s() const;
  // Wall seconds per unit fraction over the recent window (0 while unknown).
  double recent_cost() const;

 private:
  std::deque<std::pair<double, double>> s_;  // (wall, fraction), thinned to a bounded size
};

// "[ 45.0%] t=0.009 s step 1200 | stress 0.45 MPa, strain 0.012 | 85 grains, 10 breakages
// (3 analyses) | elapsed 1 m 20 s, ETA 2 m 10 s".
std::string format_progress(const RunState& s, double fraction, double elapsed_s, double eta_s);
// "45 s", "3 m 05 s", "2 h 07 m".
std::string format_duration(double seconds);

// The end of a run: "done in 4 m 00 s: 250 steps, 200 grains, 0 breakage events; results in DIR".
std::string format_done(double wall_s, long steps, std::size_t grains, long breakage_events, const std::string& dir);
// What to look at first in a run folder: its main figure (the first of ncl.png,
// load_displacement.png, stress_strain.png, product_psd.png, psd.png that exists) and
// scene.pvd in ParaView; empty when the folder holds neither.
std::string what_to_open(const std::string& dir);

}  // namespace crumble
