// `crumble run`, `crumble validate` and `crumble plot`: the run pipeline (run/RunPipeline.h)
// and the figures of an output folder (output/Plots.h).
#include <iostream>
#include <optional>

#include "output/Plots.h"
#include "scenarios/Sections.h"
#include "tools/Subcommand.h"

namespace crumble {
namespace {

class RunCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c = app.add_subcommand("run", "run a scenario");
    c->add_option("scenario", file_, "scenario JSON file")->required();
    c->add_option("--out", out_, "output directory")->required();
    c->add_option("--set", sets_, "override a scenario value: path=value (e.g. engine.type=lsdem)");
    c->add_option("--seed", seed_, "random seed (overrides the scenario's)")->check(seed_validator());
    c->add_option("--threads", threads_,
                  "threads (overrides the scenario's); a warning when more than the idle CPUs "
                  "(docs/performance.md, \"Threads on a busy machine\")")
        ->check(CLI::Range(1, 1024));
    c->add_flag("--quiet", quiet_,
                "no progress on stderr (otherwise a line with an ETA every 2 s on a terminal, every 60 s in a log)");
    c->add_flag("--resume", resume_,
                "continue from DIR/checkpoint.json (written while the packing settles and while it is loaded, every output.checkpoint_every_s, default " +
                    option_default_text(find_option(output_options(), "checkpoint_every_s")) +
                    ", and every output.checkpoint_every steps of either), also after SIGKILL; the effective scenario must "
                    "equal DIR/effective_scenario.json but for threads, simulation.max_steps and "
                    "output.checkpoint_every_s");
    c->add_flag("--force", force_,
                "use a non-empty --out folder: first remove the earlier run's files there (only crumble's own)");
    c->footer(kExitStatus);
    return c;
  }

  int run(const CommandContext& ctx) override {
    RunRequest req;
    req.scenario = load_scenario_file(file_);
    req.source_name = file_;
    req.out = out_;
    req.sets = sets_;
    req.seed = seed_;
    req.threads = threads_;
    req.quiet = quiet_;
    req.resume = resume_;
    req.force = force_;
    req.plots = true;
    req.analysis_executor = ctx.analysis_executor;
    const RunResult r = run_pipeline(req);
    if (r.status == 1) std::cerr << "crumble: failed: " << r.reason << "\n";
    return r.status;
  }

 private:
  std::string file_, out_;
  std::vector<std::string> sets_;
  std::optional<std::uint64_t> seed_;
  std::optional<int> threads_;
  bool quiet_ = false, resume_ = false, force_ = false;
};

class ValidateCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c = app.add_subcommand("validate", "check a scenario without running it");
    c->add_option("scenario", file_, "scenario JSON file")->required();
    c->add_option("--set", sets_, "override a scenario value: path=value");
    c->add_flag("--print", print_, "print the effective scenario (all defaults filled in)");
    return c;
  }

  int run(const CommandContext&) override {
    RunRequest req;
    req.scenario = load_scenario_file(file_);
    req.source_name = file_;
    req.sets = sets_;
    Scenario sc = build_request(req);
    for (const auto& n : sc.notes) std::cerr << "crumble: note: " << n << "\n";
    if (print_) std::cout << sc.effective.dump(2) << "\n";
    std::cerr << file_ << ": ok (" << sc.packing.grains.size() << " grains, engine " << sc.engine_name << ", breakage "
              << sc.breakage_name << ", fragments " << sc.fragments_name << ")\n";
    return 0;
  }

 private:
  std::string file_;
  std::vector<std::string> sets_;
  bool print_ = false;
};

class PlotCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c = app.add_subcommand("plot", "PNG figures of a run, compare or sweep output folder (python3-matplotlib)");
    c->add_option("dir", dir_, "output folder of crumble run, compare or sweep")->required();
    c->footer("Writes ncl.png, psd.png, breakage.png, ... into DIR, chosen by what DIR holds (README, \"Plots\"). "
              "Exit status: 0 written; 2 DIR or one of its files cannot be read (the message names it); 1 no python3 "
              "with matplotlib, or the plotting script failed.");
    return c;
  }

  int run(const CommandContext&) override {
    const PlotOutcome o = make_plots(dir_);
    if (o.status == PlotOutcome::Status::Written) {
      for (const auto& f : o.files) std::cout << f << "\n";
      return 0;
    }
    std::cerr << "crumble: plot: " << (o.status == PlotOutcome::Status::Skipped ? "cannot plot: " : "") << o.message
              << "\n";
    return o.status == PlotOutcome::Status::BadInput ? 2 : 1;
  }

 private:
  std::string dir_;
};

}  // namespace

std::unique_ptr<Subcommand> make_run_command() { return std::make_unique<RunCommand>(); }
std::unique_ptr<Subcommand> make_validate_command() { return std::make_unique<ValidateCommand>(); }
std::unique_ptr<Subcommand> make_plot_command() { return std::make_unique<PlotCommand>(); }

}  // namespace crumble
