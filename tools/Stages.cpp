#include "tools/Stages.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "base/Errors.h"
#include "core/Measures.h"
#include "output/StagesWriter.h"

namespace crumble {
namespace fs = std::filesystem;

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
// The stages of a run's stages.csv (or stages.csv.part while it runs), resumed stages joined.
struct StageTable {
  std::string path;
  bool unfinished = false;
  bool strain = false;  // the stages are steps of axial strain (%), not of stress (MPa)
  std::vector<StageRow> st;
};

// The columns of stages.csv that the report reads.
struct StageColumns {
  std::size_t from, to, complete, resumed, g0, g, wall, total, eng, an, br, mean, steps, share;
};

StageColumns stage_columns(const std::vector<std::string>& head, const std::string& path, const StageAxisNames& ax) {
  auto col = [&](const char* name) {
    for (std::size_t c = 0; c < head.size(); ++c)
      if (head[c] == name) return c;
    throw InputError(path + ", line 1: no column '" + std::string(name) + "'");
  };
  return {col(ax.from),    col(ax.to),       col("complete"),          col("resumed"),
          col("grains_start"), col("grains"),   col("wall_s"),            col("wall_total_s"),
          col("engine_ms_per_step"), col("analyses"), col("breaking_analyses"), col("mean_analysis_ms"),
          col("steps"),    col("breaking_share_of_analysis_time")};
}

// One row of the file; `line` counts from 1 at the header.
StageRow parse_stage(const std::vector<std::string>& head, const std::vector<std::string>& r, std::size_t line,
                     const std::string& path, const StageColumns& c) {
  auto num = [&](std::size_t k, bool optional = false) {
    if (optional && r[k].empty()) return std::nan("");
    char* end = nullptr;
    const double v = std::strtod(r[k].c_str(), &end);
    if (r[k].empty() || *end != '\0' || !std::isfinite(v))
      throw InputError(path + ", line " + std::to_string(line) + ", column " + head[k] + ": not a number: '" + r[k] +
                       "'");
    return v;
  };
  StageRow s;
  s.from = num(c.from), s.to = num(c.to), s.complete = num(c.complete) != 0, s.resumed = num(c.resumed) != 0;
  s.grains_start = static_cast<long>(num(c.g0)), s.grains = static_cast<long>(num(c.g));
  s.wall = num(c.wall), s.wall_total = num(c.total), s.engine_ms = num(c.eng, true);
  s.analyses = static_cast<long>(num(c.an)), s.breaking = static_cast<long>(num(c.br));
  s.mean_ms = num(c.mean, true), s.share = num(c.share, true);
  s.steps = static_cast<long>(num(c.steps));
  return s;
}

StageTable read_stages(const std::string& dir) {
  StageTable t;
  t.path = dir + "/stages.csv";
  if (!fs::exists(t.path)) {
    // A run still going (or killed) has its rows so far in stages.csv.part.
    if (!fs::exists(t.path + ".part"))
      throw InputError("cannot read " + t.path + ": no such file (a run of crumble writes it in its output folder)");
    t.path += ".part";
    t.unfinished = true;
  }
  const auto rows = read_csv(t.path);
  if (rows.empty()) throw InputError(t.path + ": empty file");
  t.strain = !rows[0].empty() && rows[0][0] == stage_axis_names(StagesWriter::Axis::Strain).from;
  const StageAxisNames ax = stage_axis_names(t.strain ? StagesWriter::Axis::Strain : StagesWriter::Axis::Stress);
  const StageColumns cols = stage_columns(rows[0], t.path, ax);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& r = rows[i];
    if (r.size() < rows[0].size())
      throw InputError(t.path + ", line " + std::to_string(i + 1) + ": " + std::to_string(r.size()) + " cells, expected " +
                       std::to_string(rows[0].size()));
    const StageRow s = parse_stage(rows[0], r, i + 1, t.path, cols);
    if (!t.st.empty() && !t.st.back().complete && std::abs(s.from - t.st.back().to) < 1e-9 &&
        std::floor(s.from + 1e-9) == std::floor(t.st.back().from + 1e-9)) {
      join_into(t.st.back(), s);  // the rest of a stage interrupted and resumed
      continue;
    }
    t.st.push_back(s);
  }
  if (t.st.empty()) throw InputError(t.path + ": no stage yet");
  return t;
}

// The two power laws the extrapolation uses; `can`: both fitted on at least three stages.
struct StageFits {
  PowerLaw cost, grains;
  bool can = false;
};

StageFits fit_stages(const std::vector<StageRow>& st) {
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
  StageFits f;
  f.cost = fit_power_law(n, cost);
  // Grain count against the level, over the later half of those stages (at least three).
  std::vector<double> sig, ng;
  const std::size_t first = fit.size() > 6 ? fit.size() / 2 : 0;
  for (std::size_t k = first; k < fit.size(); ++k) {
    sig.push_back(fit[k]->to);
    ng.push_back(static_cast<double>(fit[k]->grains));
  }
  f.grains = fit_power_law(sig, ng);
  f.can = std::isfinite(f.cost.exponent) && std::isfinite(f.grains.exponent) && f.cost.points >= 3 &&
          f.grains.points >= 3;
  return f;
}

// Continues the grain count from the last measured one (n_end at measured_to) with the
// fitted growth, stage by stage to `target`, adding each stage's fitted cost to `predicted`.
void extrapolate(const StageFits& f, double measured_to, double target, double& predicted, double& n_end) {
  const double scale = n_end / f.grains(measured_to);
  double s0 = measured_to;
  while (s0 < target - 1e-9) {
    const double s1 = std::min(target, std::floor(s0 + 1 + 1e-9));
    const double n1 = scale * f.grains(s1);
    predicted += f.cost(0.5 * (n_end + n1)) * (s1 - s0);
    n_end = n1;
    s0 = s1;
  }
}

std::string stages_markdown(const StageTable& t, const StageFits& f, double target, double predicted, double n_end) {
  const std::string unit = stage_axis_names(t.strain ? StagesWriter::Axis::Strain : StagesWriter::Axis::Stress).unit;
  const double measured_to = t.st.back().to, measured_wall = t.st.back().wall_total;
  std::ostringstream md;
  md << "| " << unit << " | grains | wall s | analyses | breaking | mean analysis ms | breaking share of analysis time | engine ms/step |\n"
        "|---|---|---|---|---|---|---|---|\n";
  for (const auto& s : t.st)
    md << "| " << fmt(s.from) << "–" << fmt(s.to) << (s.complete ? "" : " (partial)") << (s.resumed ? " (resumed)" : "")
       << " | " << s.grains << " | " << fmt(s.wall) << " | " << s.analyses << " | " << s.breaking << " | "
       << fmt(s.mean_ms) << " | " << (std::isfinite(s.share) ? fmt(100 * s.share, 2) + " %" : "—") << " | "
       << fmt(s.engine_ms) << " |\n";
  md << "\nMeasured: " << fmt(measured_to) << " " << unit << " in " << fmt(measured_wall, 4) << " s of wall"
     << (t.unfinished ? " (from stages.csv.part: the run is still going, or was killed)" : "") << ".\n";
  if (f.can) {
    md << "Cost per " << (t.strain ? "% strain" : "MPa") << " = " << fmt(f.cost.coefficient) << " s · N^"
       << fmt(f.cost.exponent) << " (" << f.cost.points << " stages); grains N = " << fmt(f.grains.coefficient)
       << (t.strain ? " · (ε/%)^" : " · (σ/MPa)^") << fmt(f.grains.exponent) << " (" << f.grains.points << " stages).\n";
    if (target > measured_to)
      md << "Extrapolated to " << fmt(target) << " " << unit << ": " << fmt(n_end, 4) << " grains, " << fmt(predicted, 4)
         << " s = " << fmt(predicted / 3600, 3) << " h of wall in all.\n";
  } else {
    md << "Too few complete stages with breakage to fit (need 3): run further.\n";
  }
  return md.str();
}
}  // namespace

nlohmann::json stage_report(const std::string& dir, double target, std::string* markdown) {
  const StageTable t = read_stages(dir);
  const std::vector<StageRow>& st = t.st;
  const bool strain = t.strain;
  const std::string key = stage_axis_names(strain ? StagesWriter::Axis::Strain : StagesWriter::Axis::Stress).key;
  if (!std::isfinite(target)) target = strain ? 15 : 30;
  nlohmann::json j;
  j["stages"] = nlohmann::json::array();
  for (const auto& s : st)
    j["stages"].push_back({{"from_" + key, s.from}, {"to_" + key, s.to}, {"complete", s.complete}, {"resumed", s.resumed},
                           {"grains", s.grains}, {"wall_s", s.wall}, {"analyses", s.analyses},
                           {"breaking_analyses", s.breaking}});
  const double measured_to = st.back().to, measured_wall = st.back().wall_total;
  j["axis"] = strain ? "axial strain" : "vertical stress";
  j["measured_to_" + key] = measured_to;
  j["unfinished"] = t.unfinished;
  j["measured_wall_s"] = measured_wall;
  const StageFits f = fit_stages(st);
  if (f.can) {
    j["cost_fit"] = {{"law", strain ? "wall s per % strain = a · N^b" : "wall s per MPa = a · N^b"},
                     {"a", f.cost.coefficient},
                     {"b", f.cost.exponent},
                     {"stages", f.cost.points}};
    j["grains_fit"] = {{"law", strain ? "N = c · (ε/%)^k" : "N = c · (σ/MPa)^k"},
                       {"c", f.grains.coefficient},
                       {"k", f.grains.exponent},
                       {"stages", f.grains.points}};
  }
  j["target_" + key] = target;
  double predicted = measured_wall, n_end = static_cast<double>(st.back().grains);
  if (f.can && target > measured_to) {
    extrapolate(f, measured_to, target, predicted, n_end);
    j["predicted_grains_at_target"] = n_end;
    j["predicted_wall_s"] = predicted;
    j["predicted_hours"] = predicted / 3600;
  } else if (!f.can) {
    j["note"] = "too few complete stages with breakage to fit (need 3): run further";
  }
  if (markdown) *markdown = stages_markdown(t, f, target, predicted, n_end);
  return j;
}

}  // namespace crumble

#include <iostream>

#include "tools/Subcommand.h"

namespace crumble {
namespace {

class StagesCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c = app.add_subcommand("stages",
                                 "where a run's wall time went per MPa (or % strain), and its extrapolation further");
    c->add_option("dir", dir_, "output folder of crumble run (it holds stages.csv)")->required();
    c->add_option("--to", to_,
                  "extrapolate the wall time to this level, in the table's unit: vertical stress in MPa (default 30: "
                  "Zhu & Zhao 2019 §5) or, for a strain-controlled run, axial strain in % (default 15: Harmon et al. "
                  "2020 §5)")
        ->check(CLI::Range(0.0, 1e6));
    c->add_flag("--json", json_, "print JSON instead of Markdown");
    c->footer("Reads DIR/stages.csv (one row per MPa of vertical stress, or per % of axial strain for loading.mode "
              "strain_rate: wall time, grains, analyses, breaking analyses, "
              "mean analysis time, engine time per step), fits the wall time per MPa against the grain count and the "
              "grain count against the stress (power laws over the stages with breakage), and extrapolates. "
              "docs/performance.md shows it on the Zhu & Zhao run.");
    return c;
  }

  int run(const CommandContext&) override {
    std::string md;
    const auto j = stage_report(dir_, to_, &md);
    std::cout << (json_ ? j.dump(2) + "\n" : md);
    return 0;
  }

 private:
  std::string dir_;
  double to_ = std::nan("");  // the table's default: 30 MPa or 15 % strain
  bool json_ = false;
};

}  // namespace

std::unique_ptr<Subcommand> make_stages_command() { return std::make_unique<StagesCommand>(); }

}  // namespace crumble
