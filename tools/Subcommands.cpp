#include "tools/Subcommand.h"

#include "base/Errors.h"

namespace crumble {

const char* const kExitStatus =
    "Exit status: 0 success; 2 bad input (the message names the file, the JSON path and what was expected; "
    "also an --out folder that holds another run); 1 a failure while running; 130 (SIGINT, Ctrl-C) or 143 "
    "(SIGTERM): the run was interrupted, every output was written (\"interrupted\": true in summary.json).";

std::vector<std::unique_ptr<Subcommand>> make_subcommands() {
  std::vector<std::unique_ptr<Subcommand>> all;
  all.push_back(make_run_command());
  all.push_back(make_compare_command());
  all.push_back(make_sweep_command());
  all.push_back(make_validate_command());
  all.push_back(make_list_command());
  all.push_back(make_shape_command());
  all.push_back(make_plot_command());
  all.push_back(make_stages_command());
  all.push_back(make_bench_command());
  return all;
}

bool plots_wanted(const nlohmann::json& scenario, const std::vector<std::string>& sets) {
  RunRequest r;
  r.scenario = scenario;
  r.sets = sets;
  const nlohmann::json doc = request_document(r);
  return !(doc.is_object() && doc.contains("output") && doc["output"].is_object() &&
           doc["output"].contains("plots") && doc["output"]["plots"].is_boolean() && !doc["output"]["plots"].get<bool>());
}

void refuse_under_mpi(const CommandContext& ctx, const std::string& command) {
  if (ctx.mpi_ranks > 1)
    throw InputError(command +
                     " does not run under mpirun (only `crumble run` spreads its breakage analyses over MPI "
                     "ranks); run it without mpirun, with --jobs N");
}

}  // namespace crumble
