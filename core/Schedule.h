// When the Simulation checks breakage. The breakage model proposes the defaults
// (BreakageModel::default_schedule); a scenario's "schedule" object overrides them.
#pragma once

namespace crumble {

// Breakage checks every `every_stress` Pa of platen stress (Zhu & Zhao 2019: 0.08 MPa)
// and/or every `every_steps` steps; 0 disables a rule. The stress is the commanded one
// under a stress ramp, the measured one under a strain rate (a peak there advances the
// schedule past it: pair every_stress with every_steps on an explicit engine).
struct ScheduleSettings {
  double every_stress = 0;
  long every_steps = 0;
};

class Schedule {
 public:
  explicit Schedule(ScheduleSettings s) : s_(s) {}
  bool due(long step, double stress);
  const ScheduleSettings& settings() const { return s_; }
  double last_stress() const { return last_stress_; }
  void set_last_stress(double s) { last_stress_ = s; }

 private:
  ScheduleSettings s_;
  double last_stress_ = 0;
};

}  // namespace crumble
