#include "output/StagesWriter.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "output/OutputReference.h"

namespace crumble {
namespace fs = std::filesystem;

StageAxisNames stage_axis_names(StagesWriter::Axis a) {
  return a == StagesWriter::Axis::Strain ? StageAxisNames{"strain_from_percent", "strain_to_percent", "% strain", "percent"}
                                         : StageAxisNames{"stress_from_MPa", "stress_to_MPa", "MPa", "MPa"};
}

namespace {

// The declared columns (output/OutputReference.cpp), the axis's bounds first.
std::string header(StagesWriter::Axis a) {
  return csv_header("stages.csv", a == StagesWriter::Axis::Strain ? "strain" : "stress");
}

double seconds_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// The last kept row of a resumed run's table: where the next stage starts and the counters.
template <class R>
long read_resume(const std::string& path, StagesWriter::Axis axis, long resume_step, R* out) {
  if (resume_step < 0) return resume_step;
  const std::string file = fs::exists(path + ".part") ? path + ".part" : path;
  if (!fs::exists(file)) return resume_step;
  const auto rows = read_csv(file);
  if (rows.empty()) return resume_step;
  auto col = [&](const char* name) {
    for (std::size_t c = 0; c < rows[0].size(); ++c)
      if (rows[0][c] == name) return static_cast<int>(c);
    return -1;
  };
  const int c_step = col("step"), c_to = col(stage_axis_names(axis).to), c_wall = col("wall_total_s"), c_g = col("grains"),
            c_a = col("analyses_total"), c_e = col("breakage_events_total");
  const int last = std::max({c_step, c_to, c_wall, c_g, c_a, c_e});
  if (std::min({c_step, c_to, c_wall, c_g, c_a, c_e}) < 0) return resume_step;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& r = rows[i];
    if (static_cast<int>(r.size()) <= last || std::atol(r[c_step].c_str()) > resume_step) continue;
    out->found = true;
    out->from = std::atof(r[c_to].c_str());
    out->wall_total = std::atof(r[c_wall].c_str());
    out->step = std::atol(r[c_step].c_str());
    out->grains = static_cast<std::size_t>(std::atol(r[c_g].c_str()));
    out->analyses_total = std::atol(r[c_a].c_str());
    out->events_total = std::atol(r[c_e].c_str());
  }
  return resume_step;
}
}  // namespace

StagesWriter::StagesWriter(const std::string& dir, Axis axis, long resume_step)
    : axis_(axis),
      resumed_(resume_step >= 0),
      resume_step_(resume_step),
      csv_(dir + "/stages.csv", header(axis), read_resume(dir + "/stages.csv", axis, resume_step, &resume_)) {}

StagesWriter::Mark StagesWriter::mark(const Simulation& sim, const RunState& s) const {
  const Timings& t = sim.timings();
  return {std::chrono::steady_clock::now(), t.engine, t.analyses, t.fragments, s.step, s.analyses, s.breakage_events,
          s.grains};
}

void StagesWriter::on_start(const Simulation& sim, const RunState& s) {
  start_ = mark(sim, s);
  timed_from_step_ = s.step;
  from_ = 0;
  level_ = 0;
  if (resumed_) {
    // An interrupted run (SIGINT/SIGTERM) writes its last row and a checkpoint at the same
    // step: nothing is lost. A killed one resumes from an earlier checkpoint.
    stage_resumed_ = !(resume_.found && resume_.step == resume_step_);
    // The counters continue from the stage's start (the last kept row), so the stage in
    // progress at the interruption gets the same counts as in an uninterrupted run; its wall
    // time misses what was spent on it before the interruption (resumed = 1).
    if (resume_.found) {
      from_ = level_ = resume_.from;
      wall_total_ = resume_.wall_total;
      start_.step = resume_.step;
      start_.grains = resume_.grains;
      start_.analyses_total = resume_.analyses_total;
      start_.events_total = resume_.events_total;
    } else {
      // Interrupted in the first stage: it started at step 0 with the initial packing.
      start_.step = 0;
      start_.grains = sim.saved_state().grains_initial;
      start_.analyses_total = start_.events_total = 0;
    }
  }
  stage_ = static_cast<long>(std::floor(from_ + 1e-9));
}

void StagesWriter::on_analysis(const Simulation&, const AnalysisRecord& r) {
  analysis_ms_ += r.analysis.wall_ms;
  ++analyses_seen_;
}

void StagesWriter::on_breakage(const Simulation&, const BreakageEvent& e) { breaking_ms_ += e.analysis.wall_ms; }

void StagesWriter::write_row(const Simulation& sim, const RunState& s, double to, bool complete) {
  const Mark now = mark(sim, s);
  const double wall = seconds_between(start_.clock, now.clock);
  wall_total_ += wall;
  const long steps = now.step - start_.step, analyses = now.analyses_total - start_.analyses_total;
  const double engine = now.engine - start_.engine;
  // A resumed stage's engine time covers only the steps since the resume.
  const long timed_steps = now.step - timed_from_step_;
  auto& o = csv_.row();
  o << from_ << ',' << to << ',' << (complete ? 1 : 0) << ',' << (stage_resumed_ ? 1 : 0) << ',' << s.step
    << ',' << s.time << ',' << start_.grains << ',' << s.grains << ',' << wall << ',' << wall_total_ << ',' << steps << ','
    << engine << ',';
  if (timed_steps > 0) o << 1e3 * engine / timed_steps;
  o << ',' << analyses << ',' << now.events_total - start_.events_total << ',' << now.analyses - start_.analyses << ',';
  if (analyses_seen_ > 0) o << analysis_ms_ / analyses_seen_;
  o << ',';
  if (analysis_ms_ > 0) o << breaking_ms_ / analysis_ms_;
  o << ',' << now.fragments - start_.fragments << ',' << now.analyses_total << ',' << now.events_total << '\n';
  o.flush();
  start_ = now;
  timed_from_step_ = now.step;
  analysis_ms_ = breaking_ms_ = 0;
  analyses_seen_ = 0;
  stage_resumed_ = false;
}

void StagesWriter::on_sample(const Simulation& sim, const RunState& s) {
  // A stress ramp by the stress it commands (its measured stress rings), else the largest
  // measured stress so far; strain stages by the largest axial strain so far: a stage is
  // never entered twice.
  const double level = axis_ == Axis::Strain ? 100 * s.axial_strain
                                             : 1e-6 * (s.target_stress > 0 ? s.target_stress : s.platen_stress);
  if (std::isfinite(level)) level_ = std::max(level_, level);
  const long stage = static_cast<long>(std::floor(level_ + 1e-9));
  if (stage <= stage_) return;
  write_row(sim, s, static_cast<double>(stage), true);
  stage_ = stage;
  from_ = static_cast<double>(stage);
}

void StagesWriter::on_finish(const Simulation& sim, const RunState& s, RunSummary&) {
  if (s.step > start_.step) write_row(sim, s, std::max(level_, from_), false);
  csv_.finish();
}

}  // namespace crumble
