// Where the time of a long run goes, stage by stage. `stages.csv` gets one row per MPa of vertical stress (the commanded stress of a
// stress ramp, else the largest measured platen stress so far) or, for a strain-controlled
// run (loading.mode strain_rate: Harmon et al. 2020 §5, whose stress is a sawtooth), one row
// per percent of axial strain: the wall time of the stage, the grains at its end, the
// analyses and the breaking analyses in it, the mean analysis time and the engine time per
// step. `crumble stages DIR` reads it back, fits the cost per stage against the grain count
// and the grain count against the level (power laws, core/Measures.h fit_power_law) and
// extrapolates the wall time to a target level.
#pragma once
#include <chrono>
#include <string>

#include <nlohmann/json.hpp>

#include "output/Writers.h"

namespace crumble {

class StagesWriter : public Observer {
 public:
  std::string name() const override { return "stages"; }
  // What a stage is one unit of: MPa of vertical stress, or percent of axial strain.
  enum class Axis { Stress, Strain };
  // resume_step >= 0: continue the table of a run resumed at that step (the rows up to it
  // are kept; a stage in progress at a kill loses the wall time spent on it since the last
  // checkpoint and says so: resumed = 1).
  StagesWriter(const std::string& dir, Axis axis = Axis::Stress, long resume_step = -1);
  void on_start(const Simulation&, const RunState& s) override;
  void on_analysis(const Simulation&, const AnalysisRecord& r) override;
  void on_breakage(const Simulation&, const BreakageEvent& e) override;
  void on_sample(const Simulation& sim, const RunState& s) override;
  void on_finish(const Simulation& sim, const RunState& s, RunSummary&) override;

 private:
  // The state at a stage boundary: counters from RunState (restored on resume, so a resumed
  // run writes the same counts as an uninterrupted one) and wall times of this process.
  struct Mark {
    std::chrono::steady_clock::time_point clock;
    double engine = 0, analyses = 0, fragments = 0;  // s, Simulation::timings()
    long step = 0, analyses_total = 0, events_total = 0;
    std::size_t grains = 0;
  };
  Mark mark(const Simulation& sim, const RunState& s) const;
  void write_row(const Simulation& sim, const RunState& s, double to, bool complete);

  Axis axis_;
  // From the last kept row of a resumed run.
  struct Resume {
    bool found = false;
    double from = 0, wall_total = 0;
    long step = 0, analyses_total = 0, events_total = 0;
    std::size_t grains = 0;
  } resume_;
  bool resumed_ = false;
  long resume_step_ = -1;
  CsvStream csv_;
  long stage_ = -1;     // index of the stage in progress (its level_from = stage_)
  double from_ = 0;     // MPa or %: where the stage in progress began
  double level_ = 0;    // MPa or %: the loading level so far
  double wall_total_ = 0;
  bool stage_resumed_ = false;
  Mark start_;
  double analysis_ms_ = 0, breaking_ms_ = 0;  // per-analysis wall times summed (all threads)
  long analyses_seen_ = 0;                    // analyses this process saw in the stage
  long timed_from_step_ = 0;                  // first step of the stage this process timed
};

// The first two columns of stages.csv: the stage's bounds in the table's unit.
struct StageAxisNames {
  const char *from, *to, *unit, *key;  // column names, unit in text, JSON key suffix
};
StageAxisNames stage_axis_names(StagesWriter::Axis a);

}  // namespace crumble
