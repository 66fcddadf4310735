#include "tools/Sweep.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>

#include "core/Config.h"
#include "tools/Compare.h"
#include "scenarios/ScenarioFactory.h"
#include "tools/Metrics.h"
#include "run/RunPipeline.h"
#include "tools/TableCells.h"
#include "output/OutputReference.h"
#include "output/Writers.h"

namespace crumble {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::vector<bool> pareto_front(const std::vector<double>& cost, const std::vector<double>& error) {
  const std::size_t n = std::min(cost.size(), error.size());
  std::vector<bool> front(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isnan(cost[i]) || std::isnan(error[i]) || std::isinf(error[i])) continue;
    bool dominated = false;
    for (std::size_t j = 0; j < n && !dominated; ++j) {
      if (j == i || std::isnan(cost[j]) || std::isnan(error[j])) continue;
      dominated = cost[j] <= cost[i] && error[j] <= error[i] && (cost[j] < cost[i] || error[j] < error[i]);
    }
    front[i] = !dominated;
  }
  return front;
}

namespace {

std::string fmt(double v, int prec = 4) { return table_number(v, prec, "inf"); }

double num(const Json& j, const std::string& key) {
  if (j.is_object() && j.contains(key) && j[key].is_number()) return j[key].get<double>();
  return std::nan("");
}

double part(const Json& s, const std::string& k) {
  return s.is_object() && s.contains("time_breakdown_s") ? num(s["time_breakdown_s"], k) : std::nan("");
}

// The metric's column name in sweep.csv: name_unit (name alone for a pure number).
std::string column(const Metric& m) { return m.unit == "1" ? m.name : m.name + "_" + m.unit; }

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

std::string joined_values(const VaryAxis& a) {
  std::string s;
  for (const auto& v : a.values) s += (s.empty() ? "" : ", ") + v;
  return s;
}

// The --param/--values pairs as --vary arguments, and their axes.
std::vector<VaryAxis> sweep_axes(const SweepRequest& req, std::vector<std::string>& vary) {
  if (req.params.empty()) throw InputError("sweep: give at least one --param PATH --values a,b,c");
  if (req.values.size() != req.params.size())
    throw InputError("sweep: " + std::to_string(req.params.size()) + " --param but " +
                     std::to_string(req.values.size()) +
                     " --values; give one --values a,b,c after each --param PATH, in the same order");
  if (!req.reference.empty() && req.reference.size() != req.params.size())
    throw InputError("--reference: " + std::to_string(req.reference.size()) + " given for " +
                     std::to_string(req.params.size()) +
                     " --param; give one reference value per --param, in the same order, or none (the last value of "
                     "each)");
  std::vector<VaryAxis> axes;
  for (std::size_t i = 0; i < req.params.size(); ++i) {
    const std::string p = trim(req.params[i]);
    if (p.find('=') != std::string::npos)
      throw InputError("--param " + req.params[i] + ": expected a scenario path (e.g. breakage.spacing_fraction); "
                       "the values go in --values");
    if (trim(req.values[i]).empty())
      throw InputError("--param " + p + " --values '" + req.values[i] + "': empty value list; expected a,b,c");
    vary.push_back(p + "=" + req.values[i]);
    try {
      axes.push_back(parse_vary(vary.back()));
    } catch (const InputError& e) {
      throw InputError("--param " + p + " --values '" + req.values[i] + "': " + e.what());
    }
  }
  return axes;
}

// The reference setting: --reference, or the last value of each --param.
std::vector<std::string> reference_values(const SweepRequest& req, const std::vector<VaryAxis>& axes) {
  std::vector<std::string> ref_values;
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const std::string r = req.reference.empty() ? axes[i].values.back() : trim(req.reference[i]);
    if (std::find(axes[i].values.begin(), axes[i].values.end(), r) == axes[i].values.end())
      throw InputError("--reference " + r + ": not among the --values of --param " + axes[i].path + " (" +
                       joined_values(axes[i]) + ")");
    ref_values.push_back(r);
  }
  return ref_values;
}

// The --metric choices, each once.
std::vector<Metric> chosen_metrics(const SweepRequest& req) {
  std::vector<Metric> chosen;
  for (const auto& m : req.metrics) {
    Metric x = find_metric(trim(m), "--metric " + m);
    if (std::none_of(chosen.begin(), chosen.end(), [&](const Metric& c) { return c.name == x.name; }))
      chosen.push_back(x);
  }
  return chosen;
}

CompareRequest sweep_compare_request(const SweepRequest& req, const std::vector<std::string>& vary) {
  CompareRequest cr;
  cr.scenario = req.scenario;
  cr.source_name = req.source_name;
  cr.out = req.out;
  cr.vary = vary;
  cr.sets = req.sets;
  cr.seed = req.seed;
  cr.threads = req.threads;
  cr.jobs = req.jobs;
  cr.force = req.force;
  cr.quiet = req.quiet;
  cr.command = "sweep";
  return cr;
}

// Every setting's metrics against the reference: values, relative errors, the largest of
// them (error), the wall time (cost) and the error–cost front.
struct SweepTable {
  std::size_t ref = 0;  // the reference's row (rows.size(): none)
  bool ref_ok = false, default_metrics = false;
  std::vector<Metric> chosen;
  std::vector<std::vector<std::optional<double>>> value, rel;
  std::vector<double> error, cost;
  std::vector<bool> front;
  std::vector<std::string> notes;
};

// Notes on the metrics that do not count: the reference has no value, or 0.
void reference_notes(SweepTable& t, const RunOutputs& ref) {
  for (const auto& m : t.chosen) {
    const auto rv = m.value(ref, m.name);
    if (!rv) t.notes.push_back("`" + m.name + "`: the reference run has no value; it does not count.");
    else if (*rv == 0) t.notes.push_back("`" + m.name + "`: the reference value is 0, a relative error is undefined; it does not count.");
  }
}

// Row i's metric values, relative errors and error.
void row_errors(SweepTable& t, std::size_t i, const ComparisonRow& row, const std::vector<RunOutputs>& outputs) {
  const bool ok = row.status == "ok";
  if (ok) t.cost[i] = num(row.summary, "wall_seconds");
  double e = 0;
  bool any = false;
  for (std::size_t k = 0; k < t.chosen.size(); ++k) {
    t.value[i][k] = t.chosen[k].value(outputs[i], t.chosen[k].name);
    if (!t.ref_ok) continue;
    const auto rv = t.chosen[k].value(outputs[t.ref], t.chosen[k].name);
    if (!rv || *rv == 0) continue;  // does not count (noted above)
    t.rel[i][k] = relative_error(t.value[i][k], rv);
    any = true;
    // A figure the reference has and this setting never reached: no finite error.
    e = std::max(e, t.rel[i][k] ? *t.rel[i][k] : std::numeric_limits<double>::infinity());
  }
  if (ok && t.ref_ok && any) t.error[i] = e;
}

SweepTable sweep_table(const CompareOutcome& run, const fs::path& dir, const std::vector<std::string>& ref_values,
                       std::vector<Metric> chosen) {
  SweepTable t;
  const std::size_t n = run.rows.size();
  t.ref = n;
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<std::string> v;
    for (const auto& pv : run.rows[i].combination.values) v.push_back(pv.second);
    if (v == ref_values) t.ref = i;
  }
  std::vector<RunOutputs> outputs;
  for (const auto& r : run.rows) outputs.push_back(read_run_outputs((dir / r.combination.name).string()));
  t.ref_ok = t.ref < n && run.rows[t.ref].status == "ok";
  t.default_metrics = chosen.empty();
  if (t.default_metrics && t.ref_ok) chosen = available_metrics(outputs[t.ref]);
  t.chosen = std::move(chosen);
  const std::size_t nm = t.chosen.size();
  t.value.assign(n, std::vector<std::optional<double>>(nm));
  t.rel.assign(n, std::vector<std::optional<double>>(nm));
  t.error.assign(n, std::nan(""));
  t.cost.assign(n, std::nan(""));
  if (t.ref_ok) reference_notes(t, outputs[t.ref]);
  for (std::size_t i = 0; i < n; ++i) row_errors(t, i, run.rows[i], outputs);
  t.front = pareto_front(t.cost, t.error);
  return t;
}

// sweep.csv: full precision, SI units.
std::string sweep_csv(const std::vector<VaryAxis>& axes, const CompareOutcome& run, const SweepTable& t) {
  const auto& parts = time_breakdown_parts();
  std::ostringstream c;
  c << std::setprecision(10);
  // The declared columns (output/OutputReference.cpp), each family expanded.
  c << csv_header("sweep.csv", "", [&](const std::string& family) {
    std::vector<std::string> names;
    if (family == "<path>")
      for (const auto& a : axes) names.push_back(csv_field(a.path));
    if (family == "time_<part>_s")
      for (const auto& p : parts) names.push_back("time_" + p + "_s");
    if (family == "<metric>")
      for (const auto& m : t.chosen) names.insert(names.end(), {column(m), m.name + "_rel_error"});
    return names;
  }) << '\n';
  for (std::size_t i = 0; i < run.rows.size(); ++i) {
    const auto& r = run.rows[i];
    for (const auto& pv : r.combination.values) c << csv_field(pv.second) << ',';
    c << csv_field(r.combination.name) << ',' << r.status << ',' << r.exit_status << ',' << csv_field(r.reason) << ','
      << (i == t.ref ? 1 : 0) << ',' << fmt(num(r.summary, "wall_seconds"), 10);
    for (const auto& p : parts) c << ',' << fmt(part(r.summary, p), 10);
    c << ',' << (r.peak_rss_bytes > 0 ? fmt(r.peak_rss_bytes, 12) : "");
    for (std::size_t k = 0; k < t.chosen.size(); ++k)
      c << ',' << (t.value[i][k] ? fmt(*t.value[i][k], 10) : "") << ',' << (t.rel[i][k] ? fmt(*t.rel[i][k], 10) : "");
    c << ',' << fmt(t.error[i], 10) << ',' << (t.front[i] ? 1 : 0) << '\n';
  }
  return c.str();
}

// pareto.md's opening: what was swept, the reference, the metrics and how the error is read.
void pareto_intro(std::ostream& m, const SweepRequest& req, const std::vector<VaryAxis>& axes,
                  const std::vector<std::string>& ref_values, const CompareOutcome& run, const SweepTable& t) {
  const std::size_t n = run.rows.size(), nm = t.chosen.size();
  const std::string name = req.scenario.is_object() ? req.scenario.value("name", std::string("scenario")) : "scenario";
  m << "# crumble sweep: " << name << " (" << req.source_name << ")\n\n";
  std::string how;
  for (std::size_t i = 0; i < axes.size(); ++i) {
    how += (how.empty() ? "" : "; ") + std::string("`") + axes[i].path + "` = ";
    for (std::size_t j = 0; j < axes[i].values.size(); ++j) how += (j ? ", " : "") + axes[i].values[j];
  }
  m << "Swept: " << how << " (" << n << " settings, " << req.jobs << " at a time";
  if (req.threads) m << ", " << *req.threads << (*req.threads == 1 ? " thread" : " threads") << " each";
  m << ").";
  for (const auto& s : req.sets) m << " `--set " << s << "`.";
  m << "\n\nReference: ";
  for (std::size_t i = 0; i < axes.size(); ++i) m << (i ? ", " : "") << "`" << axes[i].path << "` = " << ref_values[i];
  m << (req.reference.empty() ? " (the last value given of each --param, taken as the finest)" : " (--reference)");
  if (!t.ref_ok)
    m << ". **The reference run did not finish (" << (t.ref < n ? run.rows[t.ref].status + ": " + run.rows[t.ref].reason : "")
      << "): no errors.**";
  m << "\n\nMetrics" << (t.default_metrics ? " (every one the reference run reports; choose with --metric)" : "")
    << ": ";
  for (std::size_t k = 0; k < nm; ++k) m << (k ? ", " : "") << "`" << t.chosen[k].name << "` (" << t.chosen[k].unit << ")";
  if (nm == 0) m << "none";
  m << ".\n\n";
  m << "Error = the largest relative error |x − x_ref| / |x_ref| over the metrics; cost = the run's wall time "
       "(summary.json `wall_seconds`). A setting is on the front (✓) when no other setting has both lower-or-equal "
       "cost and lower-or-equal error, one of them strictly lower.\n\n";
}

// The cells of row i of pareto.md; a row with a reason gets a numbered note.
std::vector<std::string> pareto_row(const ComparisonRow& r, std::size_t i, const SweepTable& t,
                                    std::vector<std::string>& notes) {
  std::vector<std::string> cell;
  for (const auto& pv : r.combination.values) cell.push_back(pv.second);
  std::string st = r.status + (i == t.ref ? " (reference)" : "");
  if (!r.reason.empty()) {
    notes.push_back(r.combination.label() + ": " + r.status + ": " + r.reason);
    st += " (" + std::to_string(notes.size()) + ")";
  }
  cell.push_back(st);
  cell.push_back(t.front[i] ? "✓" : "");
  cell.push_back(std::isnan(t.error[i]) ? "" : std::isinf(t.error[i]) ? "not reached" : fmt(100 * t.error[i], 3));
  cell.push_back(fmt(num(r.summary, "wall_seconds"), 4));
  for (std::size_t k = 0; k < t.chosen.size(); ++k) {
    cell.push_back(t.value[i][k] ? fmt(*t.value[i][k], 5) : "");
    cell.push_back(t.rel[i][k] ? fmt(100 * *t.rel[i][k], 3) : "");
  }
  for (const auto& p : time_breakdown_parts()) cell.push_back(fmt(part(r.summary, p), 3));
  cell.push_back(r.peak_rss_bytes > 0 ? fmt(r.peak_rss_bytes / (1024.0 * 1024.0), 4) : "");
  return cell;
}

// pareto.md's table, one row per setting, the front marked.
void pareto_table(std::ostream& m, const std::vector<VaryAxis>& axes, const CompareOutcome& run, const SweepTable& t,
                  std::vector<std::string>& notes) {
  std::vector<std::string> cols;
  for (const auto& a : axes) cols.push_back(a.path);
  cols.insert(cols.end(), {"status", "front", "error %", "wall s"});
  for (const auto& k : t.chosen) {
    cols.push_back(k.name + (k.unit == "1" ? "" : " " + k.unit));
    cols.push_back("err %");
  }
  for (const auto& p : time_breakdown_parts()) cols.push_back(p + " s");
  cols.push_back("peak MiB");
  m << "|";
  for (const auto& h : cols) m << ' ' << h << " |";
  m << "\n|";
  for (std::size_t i = 0; i < cols.size(); ++i) m << "---|";
  m << "\n";
  for (std::size_t i = 0; i < run.rows.size(); ++i) {
    m << "|";
    for (const auto& x : pareto_row(run.rows[i], i, t, notes)) m << ' ' << md_cell(x) << " |";
    m << "\n";
  }
}

// The front by cost: what a user picks from.
void pareto_front_line(std::ostream& m, const CompareOutcome& run, const SweepTable& t) {
  std::vector<std::size_t> on;
  for (std::size_t i = 0; i < run.rows.size(); ++i)
    if (t.front[i]) on.push_back(i);
  std::sort(on.begin(), on.end(), [&](std::size_t a, std::size_t b) { return t.cost[a] < t.cost[b]; });
  m << "\nFront, cheapest first:";
  if (on.empty()) m << " none (no setting and reference finished with a metric to compare).";
  for (std::size_t j = 0; j < on.size(); ++j)
    m << (j ? ";" : "") << " " << run.rows[on[j]].combination.label() << " (" << fmt(t.cost[on[j]], 3) << " s, error "
      << fmt(100 * t.error[on[j]], 3) << " %)";
  m << "\n";
}

}  // namespace

int run_sweep(const SweepRequest& req) {
  const auto t0 = std::chrono::steady_clock::now();
  // 1. Arguments, all checked before anything runs.
  std::vector<std::string> vary;
  const std::vector<VaryAxis> axes = sweep_axes(req, vary);
  const std::vector<std::string> ref_values = reference_values(req, axes);
  std::vector<Metric> chosen = chosen_metrics(req);

  // 2. Every setting, from one packing (compare_runs checks every combination first).
  CompareOutcome run = compare_runs(sweep_compare_request(req, vary));
  if (run.rows.empty()) return run.status;  // the packing stage failed: nothing to compare

  // 3. Metrics of every setting against the reference; 4. sweep.csv.
  const fs::path dir(req.out);
  SweepTable t = sweep_table(run, dir, ref_values, std::move(chosen));
  write_file_atomic((dir / "sweep.csv").string(), sweep_csv(axes, run, t));

  // 5. pareto.md: the same for a person, the front marked.
  std::ostringstream m;
  pareto_intro(m, req, axes, ref_values, run, t);
  pareto_table(m, axes, run, t, t.notes);
  pareto_front_line(m, run, t);
  if (!t.notes.empty()) {
    m << "\n";
    for (std::size_t i = 0; i < t.notes.size(); ++i) m << "(" << i + 1 << ") " << t.notes[i] << "\n";
  }
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  m << "\nEvery setting starts from the same packing (" << (run.packing_hash.empty() ? "built by the scenario's scene in each run; see packing_hash in comparison.csv" : "packing.json, SHA-256 " + run.packing_hash)
    << "). `peak MiB`: the run process's peak resident memory (getrusage ru_maxrss). sweep.csv holds every "
       "figure at full precision in SI units; comparison.csv/.md the runs' own figures. Wall time of the whole "
       "sweep: "
    << fmt(total, 4) << " s.\n";
  write_file_atomic((dir / "pareto.md").string(), m.str());
  if (!req.quiet) std::cerr << "crumble: sweep: " << run.rows.size() << " settings in " << fmt(total, 4) << " s; front in " << (dir / "pareto.md").string() << "\n";
  if (run.status != 0) return run.status;
  return t.ref_ok ? 0 : 1;
}

namespace {

// A study's value as `--values` and `--set` take it: a string as is, anything else as JSON.
std::string study_value(const Json& v, const Config& where, const std::string& key) {
  if (v.is_string()) {
    const auto& t = v.get_ref<const std::string&>();
    if (t.empty() || t.find(',') != std::string::npos)
      where.fail(key, "expected a non-empty value without commas (a string '" + t +
                          "' would be split at its commas; give a number, a boolean, an object or an array)");
    return t;
  }
  if (v.is_null()) where.fail(key, "expected a value (a number, string, boolean, object or array), not null");
  return v.dump();
}

}  // namespace

SweepRequest load_study(const std::string& study_file, const SweepRequest& cli, bool cli_has_scenario,
                        bool cli_sets_jobs) {
  if (cli_has_scenario)
    throw InputError("sweep --study " + study_file + ": give the scenario in the study file (\"scenario\"), not on "
                     "the command line");
  if (!cli.params.empty() || !cli.values.empty() || !cli.reference.empty() || !cli.metrics.empty())
    throw InputError("sweep --study " + study_file + ": --param, --values, --reference and --metric belong in the "
                     "study file (\"params\", \"metrics\"); the command line may add --set, --seed, --threads, "
                     "--jobs");
  Json doc = load_scenario_file(study_file);  // any JSON file: errors name the file, line and column
  SweepRequest req = cli;
  std::string scenario_path;  // read after the study is checked: its errors name its own file
  try {
    if (!doc.is_object()) throw ConfigError("/", "a study must be a JSON object (docs/speed-accuracy.md)");
    Config st(doc);
    st.string("study");
    st.string("description", "");
    // The scenario: a file next to the study, or the scenario itself.
    if (!st.has("scenario")) st.fail("scenario", "missing: a scenario file name (relative to the study) or an object");
    const Json& sc = st.raw("scenario");
    if (sc.is_string()) {
      const fs::path f = fs::path(sc.get<std::string>());
      const fs::path resolved = f.is_absolute() ? f : fs::path(study_file).parent_path() / f;
      std::error_code ec;
      if (!fs::is_regular_file(resolved, ec))
        st.fail("scenario", "no scenario file '" + resolved.string() + "' (a name is relative to the study's folder)");
      scenario_path = resolved.lexically_normal().string();
    } else if (sc.is_object()) {
      req.scenario = sc;
      req.source_name = study_file + "#/scenario";
    } else {
      st.fail("scenario", "expected a scenario file name or a scenario object");
    }
    if (st.has("set")) {
      const Json& sets = st.raw("set");
      if (!sets.is_array()) st.fail("set", "expected an array of \"path=value\" strings");
      std::vector<std::string> fixed;
      for (std::size_t i = 0; i < sets.size(); ++i) {
        if (!sets[i].is_string() || sets[i].get<std::string>().find('=') == std::string::npos)
          st.fail("set/" + std::to_string(i), "expected a string \"path=value\" (e.g. \"breakage.spacing_fraction=0.08\")");
        fixed.push_back(sets[i].get<std::string>());
      }
      req.sets.insert(req.sets.begin(), fixed.begin(), fixed.end());  // the command line's --set come after
    }
    auto params = st.children("params");
    if (params.empty()) st.fail("params", "expected at least one {\"path\": ..., \"values\": [...]}");
    bool any_reference = false;
    for (auto& p : params) any_reference = any_reference || p.has("reference");
    for (auto& p : params) {
      const std::string path = p.string("path");
      if (path.empty() || path.find('=') != std::string::npos)
        p.fail("path", "expected a scenario path such as breakage.spacing_fraction");
      const Json& vals = p.raw("values");
      if (!vals.is_array() || vals.empty()) p.fail("values", "expected a non-empty array of values, coarse to fine");
      std::string joined;
      for (std::size_t i = 0; i < vals.size(); ++i) {
        if (i) joined += ',';
        joined += study_value(vals[i], p, "values/" + std::to_string(i));
      }
      req.params.push_back(path);
      req.values.push_back(joined);
      if (any_reference) {
        // One reference per param (the last value where one is not given).
        req.reference.push_back(p.has("reference") ? study_value(p.raw("reference"), p, "reference")
                                                   : study_value(vals.back(), p, "values"));
      }
    }
    if (st.has("metrics")) {
      const Json& ms = st.raw("metrics");
      if (!ms.is_array()) st.fail("metrics", "expected an array of metric names (docs/sweep.md)");
      for (std::size_t i = 0; i < ms.size(); ++i) {
        if (!ms[i].is_string()) st.fail("metrics/" + std::to_string(i), "expected a metric name");
        find_metric(ms[i].get<std::string>(), study_file + ": /metrics/" + std::to_string(i));
        req.metrics.push_back(ms[i].get<std::string>());
      }
    }
    if (st.has("threads") && !cli.threads) req.threads = static_cast<int>(st.integer("threads", 1, 1, 1024));
    else if (st.has("threads")) st.accept("threads");
    if (st.has("seed") && !cli.seed) req.seed = st.unsigned_integer("seed", 1);
    else if (st.has("seed")) st.accept("seed");
    if (st.has("jobs") && !cli_sets_jobs) req.jobs = static_cast<int>(st.integer("jobs", 1, 1, 64));
    else if (st.has("jobs")) st.accept("jobs");
    st.check_unknown();
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    const std::string prefix = e.path() + ": ";
    throw ConfigError(study_file, e.path(), what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what);
  }
  if (!scenario_path.empty()) {
    req.scenario = load_scenario_file(scenario_path);
    req.source_name = scenario_path;
  }
  return req;
}

}  // namespace crumble
