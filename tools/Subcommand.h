// A subcommand of the `crumble` command line. Each one declares its options on the CLI11
// app and runs when selected; apps/main.cpp only parses and dispatches. The table of
// subcommands is explicit (tools/Subcommands.cpp): static libraries drop self-registering
// objects at link time.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "run/RunPipeline.h"

namespace crumble {

// What main knows before a subcommand runs.
struct CommandContext {
  std::vector<std::string> plugins;  // --plugin libraries, loaded before the subcommand runs
  int mpi_ranks = 1;                 // > 1 under mpirun (a build with CRUMBLE_MPI)
  // Under mpirun: spreads the breakage analyses of `crumble run` over the ranks; unset otherwise.
  decltype(RunRequest::analysis_executor) analysis_executor;
};

class Subcommand {
 public:
  virtual ~Subcommand() = default;
  // Adds the subcommand and its options to `app`; the subcommand it returns is selected when
  // the command line names it.
  virtual CLI::App* add_to(CLI::App& app) = 0;
  // Runs it after parsing: the exit status (0 success, 1 failure while running, 2 bad input).
  // Throws ConfigError / InputError / std::invalid_argument for bad input.
  virtual int run(const CommandContext& ctx) = 0;
};

// --seed: a number in [0, 2^64 - 1]. CLI11 reads "-1" into an unsigned integer as 2^64 - 1;
// this check refuses a sign (and anything but digits) before it does.
inline CLI::Validator seed_validator() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos)
          return s + ": expected a whole number from 0 to 18446744073709551615";
        return "";
      },
      "UINT", "seed");
}

// Exit statuses, shared by the footers of the subcommands.
extern const char* const kExitStatus;

// One factory per file of tools/; the table, in the order `crumble --help` lists them.
std::unique_ptr<Subcommand> make_run_command();
std::unique_ptr<Subcommand> make_compare_command();
std::unique_ptr<Subcommand> make_sweep_command();
std::unique_ptr<Subcommand> make_validate_command();
std::unique_ptr<Subcommand> make_list_command();
std::unique_ptr<Subcommand> make_shape_command();
std::unique_ptr<Subcommand> make_plot_command();
std::unique_ptr<Subcommand> make_stages_command();
std::unique_ptr<Subcommand> make_bench_command();
std::vector<std::unique_ptr<Subcommand>> make_subcommands();

// Whether a compare or sweep folder gets figures: the scenario's output.plots with `sets` applied.
bool plots_wanted(const nlohmann::json& scenario, const std::vector<std::string>& sets);

// Refuses compare and sweep under mpirun: only `crumble run` spreads its analyses over ranks.
void refuse_under_mpi(const CommandContext& ctx, const std::string& command);

}  // namespace crumble
