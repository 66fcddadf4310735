// Breakage analyses over MPI ranks (Open MPI; built with -DCRUMBLE_MPI=ON). Analyses of
// different grains are independent (core/AnalysisExecutor.h): under `mpirun -np N crumble
// run ...` rank 0 runs everything else (the engine, screening, fragment building, outputs)
// and hands the analyses of each breakage check out one job at a time (master/worker,
// dynamic) to ranks 1..N-1, running jobs itself too; ranks >= 1 build the scenario's
// breakage model from the document rank 0 sends and serve jobs until rank 0 says stop.
// A job carries every input the model reads (the grain with its shape, pose and strength
// values, its material index, the contacts on it) in a binary form that keeps every double
// bit for bit; the reply is the whole BreakageAnalysis. So a run on N ranks gives the same
// results as the 1-thread run (tests/integration/mpi).
//
// MPI is initialised only when an MPI launcher started the process (mpirun, srun): the same
// binary run directly is the threaded crumble.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/AnalysisExecutor.h"
#include "scenarios/ScenarioFactory.h"

namespace crumble::mpi {

class Session {
 public:
  Session(int* argc, char*** argv);
  // Rank 0 tells every worker to stop (also after an error); then MPI_Finalize.
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  bool active() const { return active_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  bool worker() const { return rank_ > 0; }
  // Ranks >= 1: serve analyses until rank 0 says stop; returns the process's exit status.
  int serve();
  // Rank 0: an executor over every rank for the run of `document` (the scenario with --set
  // applied), whose breakage model the workers build; `plugins` are loaded there first.
  // Null when this process is alone (no mpirun, or -np 1).
  std::shared_ptr<AnalysisExecutor> executor(const nlohmann::json& document, const Scenario& sc,
                                             const std::vector<std::string>& plugins);
  // "Open MPI v4.1.4, N ranks" (empty when not active).
  std::string describe() const;

 private:
  bool active_ = false;
  int rank_ = 0, size_ = 1;
};

}  // namespace crumble::mpi
