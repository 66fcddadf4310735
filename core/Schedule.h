// When the Simulation checks breakage. The breakage model proposes the defaults
// (BreakageModel::default_schedule); a scenario's "schedule" object overrides them.
#pragma once

namespace crumble {

// Breakage checks every `every_stress` Pa of platen stress (Zhu & Zhao 2019: 0.08 MPa)
// and/or every `every_steps` steps; 0 disables a rule.
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
