// Where the breakage analyses of one check run. The Simulation hands the analyses of a
// check (one job per candidate grain) to an executor when one is attached
// (Simulation::set_analysis_executor); without one it runs them on its own threads. An
// executor elsewhere (parallel/: MPI ranks) must give results identical to
// BreakageModel::analyse called in this process: the model is pure, so it only has to ship
// every input the model reads (the grain with its shape and strength values, the material,
// the contacts) and the whole BreakageAnalysis back.
#pragma once
#include <span>
#include <string>
#include <vector>

#include "core/BreakageModel.h"

namespace crumble {

struct AnalysisJob {
  const Grain* grain = nullptr;
  int material = 0;                   // index into EngineContext::materials
  std::span<const Contact> contacts;  // forces on the grain, world frame
};

class AnalysisExecutor {
 public:
  virtual ~AnalysisExecutor() = default;
  // Runs model.analyse for every job (materials[job.material] being its material):
  // results[k] and errors[k] belong to jobs[k] (both sized like jobs by the caller). A job
  // whose analysis throws leaves the message in errors[k]; every job is run or reported
  // before this returns.
  virtual void analyse(const BreakageModel& model, const std::vector<Material>& materials,
                       std::span<const AnalysisJob> jobs, std::vector<BreakageAnalysis>& results,
                       std::vector<std::string>& errors) = 0;
  // How many processes run analyses (summary.json "analysis_ranks").
  virtual int ranks() const = 0;
  // Per rank so far: analyses run and the sum of their wall times (s), to see how the work
  // was shared (summary.json "analyses_per_rank", "analysis_seconds_per_rank").
  struct RankLoad {
    long analyses = 0;
    double seconds = 0;
  };
  virtual std::vector<RankLoad> load() const = 0;
};

}  // namespace crumble
