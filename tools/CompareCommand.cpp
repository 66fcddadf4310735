// `crumble compare` and `crumble sweep` on the command line (tools/Compare.h, tools/Sweep.h).
#include <optional>

#include "base/Errors.h"
#include "output/Plots.h"
#include "tools/Compare.h"
#include "tools/Subcommand.h"
#include "tools/Sweep.h"

namespace crumble {
namespace {

class CompareCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c =
        app.add_subcommand("compare", "run a scenario under every combination of --vary values, from one packing");
    c->add_option("scenario", req_.source_name, "scenario JSON file")->required();
    c->add_option("--out", req_.out, "output directory (one folder per combination, comparison.csv, comparison.md)")
        ->required();
    c->add_option("--vary", req_.vary, "path=value1,value2,... (repeatable; e.g. engine.type=bullet,lsdem,ode)")
        ->required();
    c->add_option("--set", req_.sets, "fix a scenario value for every combination: path=value");
    c->add_option("--seed", req_.seed, "random seed (overrides the scenario's)")->check(seed_validator());
    c->add_option("--threads", req_.threads, "threads of each run (overrides the scenario's)")
        ->check(CLI::Range(1, 1024));
    c->add_option("--jobs", req_.jobs, "combinations run at the same time (each a process; default 1); without --threads each gets cores / jobs threads")
        ->check(CLI::Range(1, 64));
    c->add_flag("--quiet", req_.quiet, "only errors on stderr");
    c->add_flag("--force", req_.force,
                "use a non-empty --out folder: first remove the files an earlier compare wrote (only crumble's own)");
    c->add_flag("--resume", req_.resume,
                "continue the comparison in --out (same scenario, --vary and --set): runs that finished are kept, "
                "stopped ones continue from their checkpoints, the rest start; the packing is reused");
    c->footer("Exit status: 0 every combination ran; 1 one or more failed while running (their rows say why, the "
              "others still ran); 2 bad input in any combination (checked before anything runs); 130/143 "
              "interrupted.");
    return c;
  }

  int run(const CommandContext& ctx) override {
    refuse_under_mpi(ctx, "compare");
    req_.scenario = load_scenario_file(req_.source_name);
    const int status = run_compare(req_);
    if ((status == 0 || status == 1) && plots_wanted(req_.scenario, req_.sets)) plots_after(req_.out, req_.quiet);
    return status;
  }

 private:
  CompareRequest req_;
};

class SweepCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c = app.add_subcommand("sweep", "run a scenario at several settings of a knob, from one packing; error "
                                          "against a reference setting, cost, the error–cost front");
    c->add_option("scenario", file_, "scenario JSON file (not with --study)");
    c->add_option("--study", study_,
                  "a study file (studies/*.json): the scenario, params, values, references and metrics of a sweep "
                  "(docs/speed-accuracy.md)");
    c->add_option("--out", out_, "output directory (one folder per setting, sweep.csv, pareto.md, comparison.*)")
        ->required();
    c->add_option("--param", req_.params, "scenario path to sweep (repeatable; each followed by --values)");
    c->add_option("--values", req_.values, "a,b,c: the values of the --param before it");
    c->add_option("--reference", req_.reference,
                  "the reference value of each --param, in order (default: the last value given, taken as the finest)");
    c->add_option("--metric", req_.metrics,
                  "metric to compare (repeatable; default: every one the reference run reports), e.g. crushing_force");
    c->add_option("--set", req_.sets, "fix a scenario value for every setting: path=value");
    c->add_option("--seed", req_.seed, "random seed (overrides the scenario's)")->check(seed_validator());
    c->add_option("--threads", req_.threads, "threads of each run (overrides the scenario's)")
        ->check(CLI::Range(1, 1024));
    jobs_ = c->add_option("--jobs", req_.jobs, "settings run at the same time (each a process; default 1); without --threads each gets cores / jobs threads")
                ->check(CLI::Range(1, 64));
    c->add_flag("--quiet", req_.quiet, "only errors on stderr");
    c->add_flag("--force", req_.force,
                "use a non-empty --out folder: first remove the files an earlier sweep wrote (only crumble's own)");
    c->footer("Exit status: 0 every setting ran; 1 one or more failed while running (their rows say why), or the "
              "reference failed; 2 bad input (unknown --metric, a path the scenario refuses, empty --values, ...), "
              "checked before anything runs; 130/143 interrupted. docs/sweep.md");
    return c;
  }

  int run(const CommandContext& ctx) override {
    refuse_under_mpi(ctx, "sweep");
    SweepRequest req = req_;
    if (!study_.empty()) {
      req = load_study(study_, req_, !file_.empty(), jobs_->count() > 0);
    } else {
      if (file_.empty()) throw InputError("sweep: give a SCENARIO file, or --study FILE");
      if (req.params.empty()) throw InputError("sweep: give --param PATH --values a,b,c (or --study FILE)");
      req.scenario = load_scenario_file(file_);
      req.source_name = file_;
    }
    req.out = out_;
    const int status = run_sweep(req);
    if ((status == 0 || status == 1) && plots_wanted(req.scenario, req.sets)) plots_after(out_, req.quiet);
    return status;
  }

 private:
  SweepRequest req_;
  std::string file_, out_, study_;
  CLI::Option* jobs_ = nullptr;
};

}  // namespace

std::unique_ptr<Subcommand> make_compare_command() { return std::make_unique<CompareCommand>(); }
std::unique_ptr<Subcommand> make_sweep_command() { return std::make_unique<SweepCommand>(); }

}  // namespace crumble
