// Everything that records results attaches as an Observer; the Simulation never writes a
// file itself.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "core/BreakageModel.h"

namespace crumble {

class Simulation;

struct RunState {
  double time = 0;
  long step = 0;
  double dt = 0;
  double platen_stress = 0;   // Pa, measured on the platen
  double target_stress = 0;   // Pa, what the loading asks for
  double platen_force = 0;    // N
  double floor_force = 0;     // N
  double platen_height = 0;   // m
  double axial_strain = 0;
  double void_ratio = 0;
  std::size_t grains = 0;
  long breakage_events = 0;
  long analyses = 0;
};

struct AnalysisRecord {
  double time = 0;
  long step = 0;
  double platen_stress = 0;
  GrainId grain = -1;
  double diameter = 0;
  int generation = 0;
  BreakageAnalysis analysis;  // fracture dropped
};

struct BreakageEvent {
  double time = 0;
  long step = 0;
  double platen_stress = 0;
  GrainId parent = -1;
  double parent_diameter = 0;
  double parent_volume = 0;
  int generation = 0;
  std::vector<GrainId> children;
  std::vector<double> child_volumes;
  std::vector<double> child_diameters;
  double removed_volume = 0;  // fines taken out of the engine
  std::string fragment_method;
  BreakageAnalysis analysis;  // fracture dropped
};

struct Timings {
  // fragments: building the children (FragmentBuilder::build) and putting them into the engine.
  double engine = 0, contacts = 0, screening = 0, analyses = 0, fragments = 0, observers = 0, guards = 0;
  // loop: the rest of the loading loop's wall time (platen command, state read-out, scalar
  // checks, breakage schedule): what the simulation loop adds to the engine's own stepping.
  double loop = 0;
  // observers by Observer::name(): their seconds sum to `observers` (summary.json
  // time_breakdown_s.output_by_writer). Filled at the end of Simulation::run().
  std::map<std::string, double> output_by_writer;
};

struct RunSummary {
  long steps = 0;
  double time = 0;
  double wall_seconds = 0;
  std::size_t grains_initial = 0, grains_final = 0;
  long breakage_events = 0, analyses = 0, fragment_fallbacks = 0, dt_reductions = 0;
  long analyses_skipped = 0;  // screened in, but the skip rule (Screening.h) spared the analysis
  double mass_initial = 0, mass_final = 0, mass_removed = 0;
  double void_ratio_initial = 0, void_ratio_final = 0;
  double max_platen_stress = 0;
  bool interrupted = false;  // stopped early by a signal
  Timings timings;
  std::map<std::string, double> extra;  // method-specific figures
  std::map<std::string, std::vector<double>> extra_arrays;
};

class Observer {
 public:
  virtual ~Observer() = default;
  // The key of its seconds in summary.json time_breakdown_s.output_by_writer (observers of
  // one name are summed).
  virtual std::string name() const { return "other"; }
  virtual void on_start(const Simulation&, const RunState&) {}
  virtual void on_sample(const Simulation&, const RunState&) {}
  virtual void on_analysis(const Simulation&, const AnalysisRecord&) {}
  virtual void on_breakage(const Simulation&, const BreakageEvent&) {}
  // May add to summary.extra (method-specific figures) before it is written.
  virtual void on_finish(const Simulation&, const RunState&, RunSummary&) {}
};

}  // namespace crumble
