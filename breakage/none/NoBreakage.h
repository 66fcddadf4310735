#pragma once
#include <algorithm>
#include <memory>

#include "core/BreakageModel.h"
#include "core/Config.h"

namespace crumble {

// Breakage model `none`: grains never break, so rigid runs are scenarios too.
class NoBreakage : public BreakageModel {
 public:
  std::string name() const override { return "none"; }
  bool active() const override { return false; }
  ScheduleSettings default_schedule() const override { return {0.0, 0}; }  // never checked
  void assign_strength(Grain&, const Material&, Rng&) const override {}
  void inherit_strength(const Grain&, Grain&, const Material&, Rng&) const override {}
  BreakageAnalysis analyse(const Grain&, const Material&, std::span<const Contact>) const override {
    BreakageAnalysis a;
    a.outcome = "intact";
    return a;
  }
  // Nothing breaks, but how hard each grain is pressed still shows the force chains of a
  // rigid run: the largest contact force on the grain.
  std::string load_measure_name() const override { return "max_contact_force_N"; }
  double load_measure(const Grain&, const Material&, std::span<const Contact> contacts) const override {
    double f = 0;
    for (const auto& c : contacts)
      if (is_finite(c.force)) f = std::max(f, norm(c.force));
    return f;
  }
};

inline std::unique_ptr<BreakageModel> make_no_breakage(const Config&) { return std::make_unique<NoBreakage>(); }

}  // namespace crumble
