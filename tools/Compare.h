// `crumble compare`: one scenario run under every combination of a few varied values
// (engines, breakage models, criteria, ...) from one identical packing, and a table of the
// results. Built on the run pipeline (run/RunPipeline.h); docs/compare.md.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace crumble {

// One --vary argument: path=value1,value2,...
struct VaryAxis {
  std::string arg;                  // as given
  std::string path;                 // dotted, as --set takes it
  std::vector<std::string> values;  // in the order given
};

// Parses "path=v1,v2,..." (values split at commas outside brackets, braces and quotes, so a
// JSON array may be a value). Throws InputError naming the argument: no '=', an empty path
// or path component, an empty value list or value, a value given twice.
VaryAxis parse_vary(const std::string& arg);

struct Combination {
  std::vector<std::pair<std::string, std::string>> values;  // (path, value), one per axis
  std::string name;                                          // its folder: path=value__path=value (sanitised)
  std::vector<std::string> sets() const;                     // path=value, as --set takes them
  std::string label() const;                                 // "path=value, path=value"
};

// Every combination, the first axis varying slowest. Throws InputError when a path is
// repeated or two combinations would share a folder name.
std::vector<Combination> combinations(const std::vector<VaryAxis>& axes);

// A folder name from "path=value" parts: characters other than letters, digits and ._=+-
// become '_'; parts are joined by "__".
std::string sanitise_folder_name(const std::string& s);

struct CompareRequest {
  nlohmann::json scenario;  // the scenario document as read
  std::string source_name;  // its file name
  std::string out;
  std::vector<std::string> vary, sets;
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  int jobs = 1;
  bool force = false, quiet = false;
  // Continue the comparison in `out` (docs/compare.md): runs that finished are kept, the
  // others continue from their checkpoints (or start again), the packing is reused.
  bool resume = false;
  std::string command = "compare";  // the subcommand, in progress lines and the table's title
};

// One row of the comparison: a combination, how its run ended and its summary.json.
struct ComparisonRow {
  Combination combination;
  std::string status = "not run";  // ok | failed | interrupted | bad input | crashed | not run
  int exit_status = -1;
  std::string reason;
  nlohmann::json summary;  // DIR/<combination>/summary.json (null when there is none)
  // Peak resident memory of the run's process (getrusage ru_maxrss via wait4, bytes); 0 when
  // it did not run. The run is a fork of crumble, so it includes the parent's pages it kept.
  double peak_rss_bytes = 0;
};

// The parts of summary.json `time_breakdown_s`, in table order.
const std::vector<std::string>& time_breakdown_parts();

// comparison.csv and comparison.md in `dir`, from the rows' summaries only. `levels`: the
// void-ratio keys the scenario reports (a column each even when no run reached the level;
// keys found in the summaries are added). `header` lines go above the Markdown table.
void write_comparison(const std::string& dir, const std::vector<VaryAxis>& axes, const std::vector<ComparisonRow>& rows,
                      const std::vector<std::string>& levels, const std::vector<std::string>& header);

// Runs a comparison. Returns the exit status: 0 every combination ran, 1 one failed (its row
// says why; the others still run), 130/143 interrupted. Bad input (any combination's
// scenario, a malformed --vary, an --out folder holding other files) throws ConfigError or
// InputError before anything runs.
int run_compare(const CompareRequest& req);

// What a comparison ran: its axes, one row per combination (in order) and the exit status
// run_compare returns. `crumble sweep` builds on it (tools/Sweep.h).
struct CompareOutcome {
  int status = 0;
  std::vector<VaryAxis> axes;
  std::vector<ComparisonRow> rows;
  std::string packing_hash;  // empty when the scene builds its packing in each combination
};
// The request with --threads filled in for --jobs N > 1 when not given: cores / N each (at least 1).
CompareRequest with_threads_per_job(CompareRequest req);

CompareOutcome compare_runs(const CompareRequest& req);

}  // namespace crumble
