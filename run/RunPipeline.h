// The run pipeline that `crumble run` and `crumble compare` share (and `sweep` will): prepare
// the output folder, build the scenario, build (settle) or load the packing, attach the
// writers, run, write summary.json; continue a run from its checkpoint; end cleanly on
// SIGINT/SIGTERM. The command line only parses options into a RunRequest.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/Errors.h"
#include "core/AnalysisExecutor.h"
#include "core/Observer.h"
#include "scenarios/ScenarioFactory.h"

namespace crumble {

struct RunRequest {
  nlohmann::json scenario;                 // the scenario document as read (before `sets`)
  std::string source_name = "scenario";    // its file name, for messages
  std::string out;                         // output folder
  std::vector<std::string> sets;           // --set path=value, applied in order
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  bool force = false;   // a non-empty `out`: remove the earlier run's files (only crumble's own) first
  bool resume = false;  // continue from out/checkpoint.json
  bool quiet = false;   // no progress lines on stderr
  // Seconds of wall time between progress lines; 0: every 2 s when stderr is a terminal,
  // every 60 s otherwise (a log).
  double progress_every_s = 0;
  // Start from this packing.json instead of the scenario's packing: the "packing" section is
  // replaced by {"type": "file", "path": packing_file} after `sets` (scenarios with a "scene"
  // build their own packing and keep it).
  std::optional<std::string> packing_file;
  // Stop once the packing is built (settled) and out/packing.json written; summary.json then
  // holds only the packing stage's figures (`stage`: "packing").
  bool packing_only = false;
  // PNG figures at the end (when the scenario's output.plots is true): `crumble run` sets it;
  // the runs of `compare` and `sweep` leave it off, their folder gets the overlaid figures.
  bool plots = false;
  // Where the breakage analyses run: given the scenario document the run builds (`sets`
  // applied) and the scenario built from it, an executor (core/AnalysisExecutor.h; `crumble
  // run` under mpirun: the MPI ranks, parallel/), or null for this process's threads.
  // summary.json then says how many ranks ran analyses ("analysis_ranks").
  std::function<std::shared_ptr<AnalysisExecutor>(const nlohmann::json& document, const Scenario& sc)>
      analysis_executor;
  // Called with each progress line's figures (about once a second of wall time during the
  // loading, --quiet or not): the state, the loading's fraction done [0, 1], the seconds since
  // the loading started and the estimated seconds left (< 0: unknown). The Python module's
  // `progress=` (python/). An exception it throws ends the run as a failure (status 1).
  std::function<void(const RunState& state, double fraction, double elapsed_s, double eta_s)> on_progress;
};

struct RunResult {
  int status = 0;             // 0 done, 1 a failure while running (e.g. a physics guard), 130/143 interrupted
  nlohmann::json summary;     // summary.json as written; null when none was
  std::string out;            // the output folder
  std::string reason;         // why status != 0
};

// The scenario document a request runs: `sets` applied, the packing replaced by
// `packing_file`. Throws ConfigError.
nlohmann::json request_document(const RunRequest& req);

// Builds the scenario of a request without running it or touching `out` (what `validate`
// and `compare`'s up-front check do). Throws ConfigError for any input problem.
Scenario build_request(const RunRequest& req);

// Refuses (InputError naming the first differing JSON path) when the run in req.out was run
// with another effective scenario than req builds, but for the settings a --resume may change
// (threads, max_steps, ...). What `compare --resume` checks of a run it keeps or continues.
void check_same_run(const RunRequest& req);

// Runs a request. Bad input (ConfigError, InputError, std::invalid_argument) is thrown, before
// anything is written wherever it can be known then; a failure while running is returned
// (status 1 and its reason, nothing thrown); an interrupted run returns 130 / 143 with every
// output written.
RunResult run_pipeline(const RunRequest& req);

// SIGINT / SIGTERM set a flag: a running pipeline finishes its step, writes its outputs and
// returns 130 / 143.
void install_stop_signals();
bool stop_requested();
int received_signal();      // 0 when none
int interrupted_status();   // 130 after SIGINT, 143 after SIGTERM
// Forgets a received signal, so that the next run of this process runs (the Python module,
// whose process outlives an interrupted run).
void clear_stop_request();

// SHA-256 (FIPS 180-4) of a file's bytes as 64 lower-case hex digits, what `sha256sum` prints.
// Throws InputError when the file cannot be read.
std::string file_sha256(const std::string& path);
std::string sha256_hex(const std::string& bytes);

}  // namespace crumble
