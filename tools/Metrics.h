// Named figures of merit over one run's outputs (summary.json, events.csv), each with a unit:
// what `crumble sweep` compares between settings (docs/sweep.md). One table, so a new metric
// is one entry; every function reads only the files a run folder holds, so a metric can be
// computed again from any finished (or resumed) run.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace crumble {

// What a metric reads: a run folder's summary.json and the breakage rows of its events.csv
// (header first; empty when the file is missing; read_breakage_rows: the intact analyses are
// skipped).
struct RunOutputs {
  nlohmann::json summary;
  std::vector<std::vector<std::string>> events;
};

// Reads DIR/summary.json (null when missing or unreadable) and DIR/events.csv.
RunOutputs read_run_outputs(const std::string& dir);

struct Metric {
  std::string name;         // as --metric takes it
  std::string unit;         // SI: N, Pa, m, 1
  std::string description;  // one line, for `--metric` errors and docs
  // The value, or nothing when the run does not have it (no breakage yet, a level not reached).
  std::optional<double> (*value)(const RunOutputs&, const std::string& name);
};

// The fixed metrics, in the order sweep.csv lists them. The void ratio at a reported level is a
// family on top: void_ratio_at_stress_<Pa> (e.g. void_ratio_at_stress_1e6) and
// void_ratio_at_strain_<value> (e.g. void_ratio_at_strain_0.05), read from summary.json.
const std::vector<Metric>& metrics();

// The metric NAME (a fixed one or one of the void-ratio family). Throws InputError naming
// `where` and listing the known names when there is none.
Metric find_metric(const std::string& name, const std::string& where);

// The metrics a run reports (every fixed metric with a value, then the void ratio at each
// reported level in summary.json): what sweep compares when no --metric is given.
std::vector<Metric> available_metrics(const RunOutputs& run);

// |value − reference| / |reference|; nothing when either is missing or the reference is 0
// (a relative error is undefined there).
std::optional<double> relative_error(std::optional<double> value, std::optional<double> reference);

}  // namespace crumble
