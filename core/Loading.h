// Platen loading: a stress ramp (force-controlled platen with a mass, as in Zhu & Zhao 2019 §5)
// or a constant strain rate (kinematic platen), stopped at a stress or force limit.
#pragma once
#include <string>

namespace crumble {

struct PlatenCommand {
  enum class Mode { Velocity, Force } mode = Mode::Velocity;
  double value = 0;  // m/s (negative = down) or N (pushing down)
};

struct LoadingSettings {
  std::string mode = "stress_ramp";  // "stress_ramp" | "strain_rate" | "none" (platen held still)
  double max_stress = 1e6;           // Pa, ramp end value
  double ramp_time = 0.1;            // s
  double hold_time = 0.0;            // s at max_stress after the ramp
  double initial_stress = 0;         // Pa at t = 0
  double strain_rate = 0.1;          // 1/s (strain_rate mode)
  double stop_stress = 0;            // Pa; 0 = none (strain_rate mode: required or stop_strain)
  double stop_force = 0;             // N; 0 = none
  double stop_strain = 0;            // 0 = none
  double duration = 0;               // s; "none" mode: simulated time (0 = until max_steps)
};

class Loading {
 public:
  explicit Loading(LoadingSettings s) : s_(s) {}
  const LoadingSettings& settings() const { return s_; }
  // Stress the ramp asks for at t (Pa); the strain-rate mode returns 0.
  double target_stress(double t) const;
  PlatenCommand command(double t, double area, double initial_height) const;
  bool finished(double t, double stress, double force, double strain) const;
  // Rough fraction done, for progress/ETA.
  double progress(double t, double stress, double strain) const;

 private:
  LoadingSettings s_;
};

// The stress at which a reported level (output.psd_at_stress) counts as reached: under a
// stress ramp the smaller of the measured and the commanded stress (an explicit engine's
// measured stress rings around the ramp, and a peak above a level the ramp has not yet
// commanded is not that level reached), otherwise the measured stress.
double level_stress(const std::string& mode, double measured, double commanded);

}  // namespace crumble
