#include "core/Loading.h"

#include <algorithm>

namespace crumble {

double Loading::target_stress(double t) const {
  if (s_.mode != "stress_ramp") return 0;
  const double f = s_.ramp_time > 0 ? std::min(1.0, t / s_.ramp_time) : 1.0;
  return s_.initial_stress + (s_.max_stress - s_.initial_stress) * f;
}

PlatenCommand Loading::command(double t, double area, double initial_height) const {
  if (s_.mode == "stress_ramp") return {PlatenCommand::Mode::Force, target_stress(t) * area};
  if (s_.mode == "none") return {PlatenCommand::Mode::Velocity, 0.0};
  return {PlatenCommand::Mode::Velocity, -s_.strain_rate * initial_height};
}

bool Loading::finished(double t, double stress, double force, double strain) const {
  if (s_.stop_force > 0 && force >= s_.stop_force) return true;
  if (s_.stop_stress > 0 && stress >= s_.stop_stress) return true;
  if (s_.stop_strain > 0 && strain >= s_.stop_strain) return true;
  if (s_.mode == "stress_ramp") return t >= s_.ramp_time + s_.hold_time;
  if (s_.mode == "none" && s_.duration > 0) return t >= s_.duration;
  return false;
}

double Loading::progress(double t, double stress, double strain) const {
  double p = 0;
  if (s_.mode == "stress_ramp") p = t / std::max(1e-300, s_.ramp_time + s_.hold_time);
  if (s_.mode == "none" && s_.duration > 0) p = t / s_.duration;
  if (s_.stop_stress > 0) p = std::max(p, stress / s_.stop_stress);
  if (s_.stop_strain > 0) p = std::max(p, strain / s_.stop_strain);
  return std::clamp(p, 0.0, 1.0);
}

double level_stress(const std::string& mode, double measured, double commanded) {
  return mode == "stress_ramp" ? std::min(measured, commanded) : measured;
}

}  // namespace crumble
