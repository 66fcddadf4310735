// `crumble sweep`: one scenario run at several settings of one or more knobs (from one
// identical packing, as `crumble compare` runs them), every setting's metrics compared with a
// reference setting, and the error–cost front (docs/sweep.md). Built on compare_runs
// (tools/Compare.h) and the metrics table (tools/Metrics.h).
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace crumble {

struct SweepRequest {
  nlohmann::json scenario;  // the scenario document as read
  std::string source_name;
  std::string out;
  std::vector<std::string> params;     // --param PATH, in order
  std::vector<std::string> values;     // --values a,b,c, one per --param, in the same order
  std::vector<std::string> reference;  // --reference VALUE, one per --param; empty: the last value of each
  std::vector<std::string> metrics;    // --metric NAME; empty: every metric the reference run reports
  std::vector<std::string> sets;
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  int jobs = 1;
  bool force = false, quiet = false;
};

// Settings on the error–cost front: a setting is on it when no other setting is at least as
// good in both (cost ≤, error ≤) and strictly better in one. NaN costs or errors (a failed
// run) are never on the front and dominate nothing; an infinite error (the run never reached
// a metric the reference has) dominates nothing finite.
std::vector<bool> pareto_front(const std::vector<double>& cost, const std::vector<double>& error);

// Runs the sweep: checks the arguments (exit 2 via InputError / ConfigError before anything
// runs: a --values count that differs from --param, an empty value list, a --reference not
// among the values, an unknown --metric, a path the scenario refuses), runs every setting
// through compare_runs, writes DIR/sweep.csv and DIR/pareto.md (besides comparison.csv/.md).
// Returns compare's status (0 all ran, 1 one failed, 130/143 interrupted), or 1 when the
// reference setting failed (no errors can be computed; the tables still say so).
int run_sweep(const SweepRequest& req);

// A study file (studies/*.json, docs/speed-accuracy.md): one sweep written down, so it can be
// run again as it was measured. An object with
//   "study": name, "description": text (optional),
//   "scenario": a scenario file name (relative to the study file's folder) or an inline scenario,
//   "set": ["path=value", ...] (optional, fixed for every setting),
//   "params": [{"path": "breakage.spacing_fraction", "values": [0.1, 0.062], "reference": 0.062}, ...]
//             (values: numbers, strings without commas, booleans, objects or arrays; reference
//             optional, default the last value),
//   "metrics": ["crushing_force", ...] (optional), "threads", "seed", "jobs" (optional).
// Returns the request `crumble sweep --study FILE` runs: the study's fields, then those of
// `cli` (its sets appended; its threads, seed and jobs when given). Throws ConfigError naming
// the file and the JSON path on a malformed study, and InputError when `cli` also gives a
// scenario, --param, --values, --reference or --metric (they belong in the study).
SweepRequest load_study(const std::string& study_file, const SweepRequest& cli, bool cli_has_scenario,
                        bool cli_sets_jobs);

}  // namespace crumble
