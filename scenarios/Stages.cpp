#include "scenarios/Stages.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "core/Analysis.h"
#include "scenarios/RunPipeline.h"

namespace crumble {
namespace fs = std::filesystem;

namespace {
const char* kColumns =
    ",complete,resumed,step,time_s,grains_start,grains,wall_s,wall_total_s,steps,engine_s,"
    "engine_ms_per_step,analyses,breaking_analyses,analysis_s,mean_analysis_ms,breaking_share_of_analysis_time,"
    "fragments_s,analyses_total,breakage_events_total";

// The first two columns: the stage's bounds in the table's unit.
struct AxisNames {
  const char *from, *to, *unit, *key;  // column names, unit in text, JSON key suffix
};
AxisNames axis_names(StagesWriter::Axis a) {
  return a == StagesWriter::Axis::Strain ? AxisNames{"strain_from_percent", "strain_to_percent", "% strain", "percent"}
                                         : AxisNames{"stress_from_MPa", "stress_to_MPa", "MPa", "MPa"};
}
std::string header(StagesWriter::Axis a) {
  const AxisNames n = axis_names(a);
  return std::string(n.from) + "," + n.to + kColumns;
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
  const int c_step = col("step"), c_to = col(axis_names(axis).to), c_wall = col("wall_total_s"), c_g = col("grains"),
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

// ---- The report ----

namespace {
struct StageRow {
  double from = 0, to = 0, wall = 0, wall_total = 0, engine_ms = NAN, mean_ms = NAN, share = NAN;
  bool complete = false, resumed = false;
  long grains_start = 0, grains = 0, analyses = 0, breaking = 0, steps = 0;
};

// Weighted mean of two values that may be missing (NaN: nothing to average).
double weighted(double a, double wa, double b, double wb) {
  if (!std::isfinite(a) || !(wa > 0)) return std::isfinite(b) && wb > 0 ? b : a;
  if (!std::isfinite(b) || !(wb > 0)) return a;
  return (a * wa + b * wb) / (wa + wb);
}

// A run stopped cleanly (SIGTERM, or a time budget) inside a stage writes it as a partial row;
// resumed, it writes the rest of that stage from where the partial row ended. Joined, the two
// are the row an uninterrupted run writes (counts and times summed, means weighted).
void join_into(StageRow& a, const StageRow& b) {
  const double ta = std::isfinite(a.mean_ms) ? a.mean_ms * static_cast<double>(a.analyses) : 0;
  const double tb = std::isfinite(b.mean_ms) ? b.mean_ms * static_cast<double>(b.analyses) : 0;
  a.share = weighted(a.share, ta, b.share, tb);
  a.mean_ms = weighted(a.mean_ms, static_cast<double>(a.analyses), b.mean_ms, static_cast<double>(b.analyses));
  a.engine_ms = weighted(a.engine_ms, static_cast<double>(a.steps), b.engine_ms, static_cast<double>(b.steps));
  a.to = b.to;
  a.complete = b.complete;
  a.resumed = a.resumed || b.resumed;
  a.grains = b.grains;
  a.wall += b.wall;
  a.wall_total = b.wall_total;
  a.analyses += b.analyses;
  a.breaking += b.breaking;
  a.steps += b.steps;
}

std::string fmt(double v, int prec = 3) {
  if (!std::isfinite(v)) return "—";
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}
}  // namespace

nlohmann::json stage_report(const std::string& dir, double target, std::string* markdown) {
  std::string path = dir + "/stages.csv";
  bool unfinished = false;
  if (!fs::exists(path)) {
    // A run still going (or killed) has its rows so far in stages.csv.part.
    if (!fs::exists(path + ".part"))
      throw InputError("cannot read " + path + ": no such file (a run of crumble writes it in its output folder)");
    path += ".part";
    unfinished = true;
  }
  const auto rows = read_csv(path);
  if (rows.empty()) throw InputError(path + ": empty file");
  auto col = [&](const char* name) {
    for (std::size_t c = 0; c < rows[0].size(); ++c)
      if (rows[0][c] == name) return c;
    throw InputError(path + ", line 1: no column '" + std::string(name) + "'");
  };
  const bool strain = !rows[0].empty() && rows[0][0] == axis_names(StagesWriter::Axis::Strain).from;
  const AxisNames ax = axis_names(strain ? StagesWriter::Axis::Strain : StagesWriter::Axis::Stress);
  const std::string unit = ax.unit, key = ax.key;
  if (!std::isfinite(target)) target = strain ? 15 : 30;
  const std::size_t c_from = col(ax.from), c_to = col(ax.to), c_complete = col("complete"),
                    c_resumed = col("resumed"), c_g0 = col("grains_start"), c_g = col("grains"), c_wall = col("wall_s"),
                    c_total = col("wall_total_s"), c_eng = col("engine_ms_per_step"), c_an = col("analyses"),
                    c_br = col("breaking_analyses"), c_mean = col("mean_analysis_ms"), c_steps = col("steps"),
                    c_share = col("breaking_share_of_analysis_time");
  std::vector<StageRow> st;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& r = rows[i];
    if (r.size() < rows[0].size())
      throw InputError(path + ", line " + std::to_string(i + 1) + ": " + std::to_string(r.size()) + " cells, expected " +
                       std::to_string(rows[0].size()));
    auto num = [&](std::size_t c, bool optional = false) {
      if (optional && r[c].empty()) return std::nan("");
      char* end = nullptr;
      const double v = std::strtod(r[c].c_str(), &end);
      if (r[c].empty() || *end != '\0' || !std::isfinite(v))
        throw InputError(path + ", line " + std::to_string(i + 1) + ", column " + rows[0][c] + ": not a number: '" + r[c] +
                         "'");
      return v;
    };
    StageRow s;
    s.from = num(c_from), s.to = num(c_to), s.complete = num(c_complete) != 0, s.resumed = num(c_resumed) != 0;
    s.grains_start = static_cast<long>(num(c_g0)), s.grains = static_cast<long>(num(c_g));
    s.wall = num(c_wall), s.wall_total = num(c_total), s.engine_ms = num(c_eng, true);
    s.analyses = static_cast<long>(num(c_an)), s.breaking = static_cast<long>(num(c_br));
    s.mean_ms = num(c_mean, true), s.share = num(c_share, true);
    s.steps = static_cast<long>(num(c_steps));
    if (!st.empty() && !st.back().complete && std::abs(s.from - st.back().to) < 1e-9 &&
        std::floor(s.from + 1e-9) == std::floor(st.back().from + 1e-9)) {
      join_into(st.back(), s);  // the rest of a stage interrupted and resumed
      continue;
    }
    st.push_back(s);
  }
  if (st.empty()) throw InputError(path + ": no stage yet");

  nlohmann::json j;
  j["stages"] = nlohmann::json::array();
  for (const auto& s : st)
    j["stages"].push_back({{"from_" + key, s.from}, {"to_" + key, s.to}, {"complete", s.complete}, {"resumed", s.resumed},
                           {"grains", s.grains}, {"wall_s", s.wall}, {"analyses", s.analyses},
                           {"breaking_analyses", s.breaking}});
  const double measured_to = st.back().to, measured_wall = st.back().wall_total;
  j["axis"] = strain ? "axial strain" : "vertical stress";
  j["measured_to_" + key] = measured_to;
  j["unfinished"] = unfinished;
  j["measured_wall_s"] = measured_wall;

  // The fits use the stages from the first one with a breakage on (before it the
  // cost is the engine's alone and the grain count does not move).
  std::vector<const StageRow*> fit;
  bool breaking = false;
  for (const auto& s : st) {
    breaking = breaking || s.breaking > 0;
    // Partial stages count (an interrupted run's last one), but not those shorter than a
    // quarter of a stage (noise) nor those that lost wall time to a kill.
    if (breaking && !s.resumed && s.to - s.from >= 0.25) fit.push_back(&s);
  }
  // Cost per stage unit (MPa or %) against the mean grain count of the stage.
  std::vector<double> n, cost;
  for (const auto* s : fit) {
    n.push_back(0.5 * static_cast<double>(s->grains_start + s->grains));
    cost.push_back(s->wall / (s->to - s->from));
  }
  const PowerLaw cf = fit_power_law(n, cost);
  // Grain count against the level, over the later half of those stages (at least three).
  std::vector<double> sig, ng;
  const std::size_t first = fit.size() > 6 ? fit.size() / 2 : 0;
  for (std::size_t k = first; k < fit.size(); ++k) {
    sig.push_back(fit[k]->to);
    ng.push_back(static_cast<double>(fit[k]->grains));
  }
  const PowerLaw gf = fit_power_law(sig, ng);
  const bool can = std::isfinite(cf.exponent) && std::isfinite(gf.exponent) && cf.points >= 3 && gf.points >= 3;
  if (can) {
    j["cost_fit"] = {{"law", strain ? "wall s per % strain = a · N^b" : "wall s per MPa = a · N^b"},
                     {"a", cf.coefficient},
                     {"b", cf.exponent},
                     {"stages", cf.points}};
    j["grains_fit"] = {{"law", strain ? "N = c · (ε/%)^k" : "N = c · (σ/MPa)^k"},
                       {"c", gf.coefficient},
                       {"k", gf.exponent},
                       {"stages", gf.points}};
  }
  j["target_" + key] = target;
  double predicted = measured_wall, n_end = static_cast<double>(st.back().grains);
  if (can && target > measured_to) {
    // Continue the grain count from the last measured one with the fitted growth.
    const double scale = n_end / gf(measured_to);
    double s0 = measured_to;
    while (s0 < target - 1e-9) {
      const double s1 = std::min(target, std::floor(s0 + 1 + 1e-9));
      const double n1 = scale * gf(s1);
      predicted += cf(0.5 * (n_end + n1)) * (s1 - s0);
      n_end = n1;
      s0 = s1;
    }
    j["predicted_grains_at_target"] = n_end;
    j["predicted_wall_s"] = predicted;
    j["predicted_hours"] = predicted / 3600;
  } else if (!can) {
    j["note"] = "too few complete stages with breakage to fit (need 3): run further";
  }

  if (markdown) {
    std::ostringstream md;
    md << "| " << unit << " | grains | wall s | analyses | breaking | mean analysis ms | breaking share of analysis time | engine ms/step |\n"
          "|---|---|---|---|---|---|---|---|\n";
    for (const auto& s : st)
      md << "| " << fmt(s.from) << "–" << fmt(s.to) << (s.complete ? "" : " (partial)") << (s.resumed ? " (resumed)" : "")
         << " | " << s.grains << " | " << fmt(s.wall) << " | " << s.analyses << " | " << s.breaking << " | "
         << fmt(s.mean_ms) << " | " << (std::isfinite(s.share) ? fmt(100 * s.share, 2) + " %" : "—") << " | "
         << fmt(s.engine_ms) << " |\n";
    md << "\nMeasured: " << fmt(measured_to) << " " << unit << " in " << fmt(measured_wall, 4) << " s of wall"
       << (unfinished ? " (from stages.csv.part: the run is still going, or was killed)" : "") << ".\n";
    if (can) {
      md << "Cost per " << (strain ? "% strain" : "MPa") << " = " << fmt(cf.coefficient) << " s · N^"
         << fmt(cf.exponent) << " (" << cf.points << " stages); grains N = " << fmt(gf.coefficient)
         << (strain ? " · (ε/%)^" : " · (σ/MPa)^") << fmt(gf.exponent) << " (" << gf.points << " stages).\n";
      if (target > measured_to)
        md << "Extrapolated to " << fmt(target) << " " << unit << ": " << fmt(n_end, 4) << " grains, " << fmt(predicted, 4)
           << " s = " << fmt(predicted / 3600, 3) << " h of wall in all.\n";
    } else {
      md << "Too few complete stages with breakage to fit (need 3): run further.\n";
    }
    *markdown = md.str();
  }
  return j;
}

}  // namespace crumble
