// crumble: the command line.
//   crumble run SCENARIO --out DIR [--set path=value]... [--seed N] [--threads N]
//   crumble compare SCENARIO --out DIR --vary path=v1,v2... [--set path=value]... [--jobs N]
//   crumble sweep SCENARIO --out DIR --param PATH --values a,b,c [...] [--reference V] [--metric NAME]...
//   crumble validate SCENARIO [--set path=value]... [--print]
//   crumble list [--options NAME [--markdown]]
//   crumble plot DIR          (PNG figures of a run, compare or sweep folder)
//   crumble shape --json SPEC --representation level_set|mesh|hull [--spacing h] [--nodes n]
//   crumble bench engine|pd-kernel|pd-analysis|lsdem ...
//   crumble --plugin lib.so <subcommand> ...   (out-of-tree engines, models, builders)
// Exit status: 0 success, 2 bad input (scenario, option, mesh, output folder), 1 failure while
// running, 130 / 143 a run ended early by SIGINT / SIGTERM (every output written).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

#include "crumble_config.h"
#include "geometry/LevelSetGrid.h"
#include "scenarios/Checkpoint.h"
#include "scenarios/Compare.h"
#include "scenarios/Fidelity.h"
#include "scenarios/Sweep.h"
#include "scenarios/OptionDocs.h"
#include "scenarios/Plots.h"
#include "scenarios/Plugins.h"
#include "scenarios/Registry.h"
#include "scenarios/RunPipeline.h"
#include "scenarios/ScenarioFactory.h"
#include "scenarios/ShapeSpec.h"
#include "scenarios/Stages.h"
#include "scenarios/Tools.h"
#include "scenarios/Writers.h"
#if CRUMBLE_MPI
#include "parallel/MpiAnalyses.h"
#endif

namespace fs = std::filesystem;
using namespace crumble;
using Json = nlohmann::json;

namespace {

const char* kExitStatus =
    "Exit status: 0 success; 2 bad input (the message names the file, the JSON path and what was expected; "
    "also an --out folder that holds another run); 1 a failure while running; 130 (SIGINT, Ctrl-C) or 143 "
    "(SIGTERM): the run was interrupted, every output was written (\"interrupted\": true in summary.json).";

// Under mpirun (a build with CRUMBLE_MPI): the breakage analyses of `crumble run` over the
// ranks (parallel/MpiAnalyses.h); unset otherwise.
decltype(RunRequest::analysis_executor) g_analysis_executor;

// `crumble run`: the shared run pipeline (scenarios/RunPipeline.h).
int cmd_run(const std::string& file, const std::string& out, const std::vector<std::string>& sets,
            std::optional<std::uint64_t> seed, std::optional<int> threads, bool quiet, bool resume, bool force) {
  RunRequest req;
  req.scenario = load_scenario_file(file);
  req.source_name = file;
  req.out = out;
  req.sets = sets;
  req.seed = seed;
  req.threads = threads;
  req.quiet = quiet;
  req.resume = resume;
  req.force = force;
  req.plots = true;
  req.analysis_executor = g_analysis_executor;
  const RunResult r = run_pipeline(req);
  if (r.status == 1) std::cerr << "crumble: failed: " << r.reason << "\n";
  return r.status;
}

// The figures of a compare or sweep folder follow the scenario's output.plots (with --set applied).
bool plots_wanted(const Json& scenario, const std::vector<std::string>& sets) {
  RunRequest r;
  r.scenario = scenario;
  r.sets = sets;
  const Json doc = request_document(r);
  return !(doc.is_object() && doc.contains("output") && doc["output"].is_object() &&
           doc["output"].contains("plots") && doc["output"]["plots"].is_boolean() && !doc["output"]["plots"].get<bool>());
}

// `crumble compare`: every combination of the --vary values from one packing (scenarios/Compare.h).
int cmd_compare(const std::string& file, const std::string& out, const std::vector<std::string>& vary,
                const std::vector<std::string>& sets, std::optional<std::uint64_t> seed, std::optional<int> threads,
                int jobs, bool quiet, bool force) {
  CompareRequest req;
  req.scenario = load_scenario_file(file);
  req.source_name = file;
  req.out = out;
  req.vary = vary;
  req.sets = sets;
  req.seed = seed;
  req.threads = threads;
  req.jobs = jobs;
  req.quiet = quiet;
  req.force = force;
  const int status = run_compare(req);
  if ((status == 0 || status == 1) && plots_wanted(req.scenario, req.sets)) plots_after(out, quiet);
  return status;
}

// `crumble sweep`: settings of a few knobs against a reference, error and cost (scenarios/Sweep.h).
// With --study FILE the scenario, params and metrics come from the study (studies/*.json).
int cmd_sweep(const std::string& file, const std::string& out, SweepRequest req, const std::string& study,
              bool jobs_given) {
  if (!study.empty()) {
    req = load_study(study, req, !file.empty(), jobs_given);
  } else {
    if (file.empty()) throw InputError("sweep: give a SCENARIO file, or --study FILE");
    if (req.params.empty()) throw InputError("sweep: give --param PATH --values a,b,c (or --study FILE)");
    req.scenario = load_scenario_file(file);
    req.source_name = file;
  }
  req.out = out;
  const int status = run_sweep(req);
  if ((status == 0 || status == 1) && plots_wanted(req.scenario, req.sets)) plots_after(out, req.quiet);
  return status;
}

// `crumble plot DIR`: the figures of an output folder, again or for the first time.
int cmd_plot(const std::string& dir) {
  const PlotOutcome o = make_plots(dir);
  if (o.status == PlotOutcome::Status::Written) {
    for (const auto& f : o.files) std::cout << f << "\n";
    return 0;
  }
  std::cerr << "crumble: plot: " << (o.status == PlotOutcome::Status::Skipped ? "cannot plot: " : "") << o.message
            << "\n";
  return o.status == PlotOutcome::Status::BadInput ? 2 : 1;
}

int cmd_validate(const std::string& file, const std::vector<std::string>& sets, bool print) {
  RunRequest req;
  req.scenario = load_scenario_file(file);
  req.source_name = file;
  req.sets = sets;
  Scenario sc = build_request(req);
  for (const auto& n : sc.notes) std::cerr << "crumble: note: " << n << "\n";
  if (print) std::cout << sc.effective.dump(2) << "\n";
  std::cerr << file << ": ok (" << sc.packing.grains.size() << " grains, engine " << sc.engine_name << ", breakage "
            << sc.breakage_name << ", fragments " << sc.fragments_name << ")\n";
  return 0;
}

template <class T>
void list_table(const char* title, const T& t) {
  std::cout << title << ":\n";
  for (const auto& e : t.entries()) {
    std::cout << "  " << e.name << " — " << e.description << " [";
    for (std::size_t i = 0; i < e.dimensions.size(); ++i) std::cout << (i ? "," : "") << e.dimensions[i] << "D";
    std::cout << "]";
    if (!e.variants.empty()) {
      std::cout << " criteria:";
      for (const auto& v : e.variants) std::cout << " " << v;
    }
    std::cout << "\n";
    if (!e.options.empty()) {
      std::cout << "      options (" << e.options.size() << "):";
      for (std::size_t i = 0; i < e.options.size(); ++i) std::cout << (i ? ", " : " ") << e.options[i].key;
      std::cout << "\n";
    }
  }
}

// `crumble list --options NAME [--markdown]`: the option table NAME declares (the Markdown
// form is the one docs/scenarios.md holds between its markers).
int cmd_list_options(const std::string& name, bool markdown) {
  for (const auto& n : find_options(name, "--options " + name)) {
    if (markdown) {
      std::cout << option_table_markdown(*n.options);
    } else {
      std::cout << n.name << " (" << n.seam << "): " << n.description << "\n" << option_table_text(*n.options);
    }
  }
  return 0;
}

int cmd_list() {
  list_table("engines", engines());
  list_table("breakage models", breakage_models());
  list_table("fragment builders", fragment_builders());
  for (const char* n : {"bullet", "ode"}) {
    const auto why = not_compiled_reason("engine", n);
    if (!why.empty()) std::cout << "  (engine " << n << " not available: " << why << ")\n";
  }
  const auto why = not_compiled_reason("fragment builder", "alpha_shape");
  if (!why.empty()) std::cout << "  (fragment builder alpha_shape not available: " << why << ")\n";
  std::cout << fidelity_text();
  std::cout << "crumble list --options NAME: each option's type, default, range and meaning\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string version = std::string("crumble ") + CRUMBLE_VERSION;
#if CRUMBLE_MPI
  // Ranks >= 1 only serve breakage analyses to rank 0, which parses the command line.
  mpi::Session mpi(&argc, &argv);
  if (mpi.worker()) return mpi.serve();
  version += " (built with MPI" + (mpi.active() ? ": " + mpi.describe() + ", analyses of `run` on every rank" : std::string()) + ")";
#endif
  CLI::App app{"crumble — particle breakage in granular materials (Zhu & Zhao 2019, Harmon et al. 2020)"};
  app.set_version_flag("--version", version);
  app.footer(kExitStatus);
  app.require_subcommand(1);
  std::vector<std::string> plugins;
  app.add_option("--plugin", plugins, "load a plugin shared library (repeatable; before the subcommand)");

  std::string file, out, shape_spec, repr = "level_set", bench_what, bench_scenario;
  std::vector<std::string> sets;
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  bool quiet = false, print = false, resume = false, force = false;
  double spacing = 0;
  long nodes = 0, bench_steps = 0, bench_settle = -1;  // bench_steps 0: the benchmark's default
  std::string bench_engine;
  int bench_threads = 1;

  auto* run = app.add_subcommand("run", "run a scenario");
  run->add_option("scenario", file, "scenario JSON file")->required();
  run->add_option("--out", out, "output directory")->required();
  run->add_option("--set", sets, "override a scenario value: path=value (e.g. engine.type=lsdem)");
  run->add_option("--seed", seed, "random seed (overrides the scenario's)");
  run->add_option("--threads", threads,
                  "threads (overrides the scenario's); a warning when more than the idle CPUs "
                  "(docs/performance.md, \"Threads on a busy machine\")")
      ->check(CLI::Range(1, 1024));
  run->add_flag("--quiet", quiet,
                "no progress on stderr (otherwise a line with an ETA every 2 s on a terminal, every 60 s in a log)");
  run->add_flag("--resume", resume,
                "continue from DIR/checkpoint.json (written every output.checkpoint_every_s seconds, default 300, "
                "and every output.checkpoint_every steps), also after SIGKILL; the effective scenario must equal "
                "DIR/effective_scenario.json but for threads, simulation.max_steps and output.checkpoint_every_s");
  run->add_flag("--force", force,
                "use a non-empty --out folder: first remove the earlier run's files there (only crumble's own)");
  run->footer(kExitStatus);

  std::vector<std::string> vary;
  int jobs = 1;
  auto* cmp = app.add_subcommand("compare", "run a scenario under every combination of --vary values, from one packing");
  cmp->add_option("scenario", file, "scenario JSON file")->required();
  cmp->add_option("--out", out, "output directory (one folder per combination, comparison.csv, comparison.md)")
      ->required();
  cmp->add_option("--vary", vary, "path=value1,value2,... (repeatable; e.g. engine.type=bullet,lsdem,ode)")
      ->required();
  cmp->add_option("--set", sets, "fix a scenario value for every combination: path=value");
  cmp->add_option("--seed", seed, "random seed (overrides the scenario's)");
  cmp->add_option("--threads", threads, "threads of each run (overrides the scenario's)")->check(CLI::Range(1, 1024));
  cmp->add_option("--jobs", jobs, "combinations run at the same time (each a process; default 1)")
      ->check(CLI::Range(1, 64));
  cmp->add_flag("--quiet", quiet, "only errors on stderr");
  cmp->add_flag("--force", force,
                "use a non-empty --out folder: first remove the files an earlier compare wrote (only crumble's own)");
  cmp->footer("Exit status: 0 every combination ran; 1 one or more failed while running (their rows say why, the "
              "others still ran); 2 bad input in any combination (checked before anything runs); 130/143 "
              "interrupted.");

  SweepRequest sweep_req;
  auto* swp = app.add_subcommand("sweep", "run a scenario at several settings of a knob, from one packing; error "
                                          "against a reference setting, cost, the error–cost front");
  std::string study;
  swp->add_option("scenario", file, "scenario JSON file (not with --study)");
  swp->add_option("--study", study,
                  "a study file (studies/*.json): the scenario, params, values, references and metrics of a sweep "
                  "(docs/speed-accuracy.md)");
  swp->add_option("--out", out, "output directory (one folder per setting, sweep.csv, pareto.md, comparison.*)")
      ->required();
  swp->add_option("--param", sweep_req.params, "scenario path to sweep (repeatable; each followed by --values)");
  swp->add_option("--values", sweep_req.values, "a,b,c: the values of the --param before it");
  swp->add_option("--reference", sweep_req.reference,
                  "the reference value of each --param, in order (default: the last value given, taken as the finest)");
  swp->add_option("--metric", sweep_req.metrics,
                  "metric to compare (repeatable; default: every one the reference run reports), e.g. crushing_force");
  swp->add_option("--set", sweep_req.sets, "fix a scenario value for every setting: path=value");
  swp->add_option("--seed", sweep_req.seed, "random seed (overrides the scenario's)");
  swp->add_option("--threads", sweep_req.threads, "threads of each run (overrides the scenario's)")
      ->check(CLI::Range(1, 1024));
  auto* swp_jobs = swp->add_option("--jobs", sweep_req.jobs, "settings run at the same time (each a process; default 1)")
      ->check(CLI::Range(1, 64));
  swp->add_flag("--quiet", sweep_req.quiet, "only errors on stderr");
  swp->add_flag("--force", sweep_req.force,
                "use a non-empty --out folder: first remove the files an earlier sweep wrote (only crumble's own)");
  swp->footer("Exit status: 0 every setting ran; 1 one or more failed while running (their rows say why), or the "
              "reference failed; 2 bad input (unknown --metric, a path the scenario refuses, empty --values, ...), "
              "checked before anything runs; 130/143 interrupted. docs/sweep.md");

  auto* val = app.add_subcommand("validate", "check a scenario without running it");
  val->add_option("scenario", file, "scenario JSON file")->required();
  val->add_option("--set", sets, "override a scenario value: path=value");
  val->add_flag("--print", print, "print the effective scenario (all defaults filled in)");

  auto* lst = app.add_subcommand("list", "registered engines, breakage models and criteria, fragment builders");
  std::string list_options;
  bool list_markdown = false;
  lst->add_option("--options", list_options,
                  "print the options one implementation declares (key, type, default, range, meaning), e.g. lsdem");
  lst->add_flag("--markdown", list_markdown, "with --options: as the Markdown table of docs/scenarios.md");

  auto* shp = app.add_subcommand("shape", "report how well a shape is resolved by a representation");
  shp->add_option("--json", shape_spec, "shape JSON (inline text, or a file name)")->required();
  shp->add_option("--representation", repr, "level_set | mesh | hull")
      ->check(CLI::IsMember({"level_set", "mesh", "hull"}));
  shp->add_option("--spacing", spacing, "level-set grid spacing (m)");
  shp->add_option("--nodes", nodes, "level-set surface nodes");

  std::string plot_dir;
  auto* plt = app.add_subcommand("plot", "PNG figures of a run, compare or sweep output folder (python3-matplotlib)");
  plt->add_option("dir", plot_dir, "output folder of crumble run, compare or sweep")->required();
  plt->footer("Writes ncl.png, psd.png, breakage.png, ... into DIR, chosen by what DIR holds (README, \"Plots\"). "
              "Exit status: 0 written; 2 DIR or one of its files cannot be read (the message names it); 1 no python3 "
              "with matplotlib, or the plotting script failed.");

  std::string stages_dir;
  double stages_to = std::nan("");  // the table's default: 30 MPa or 15 % strain
  bool stages_json = false;
  auto* stg = app.add_subcommand("stages", "where a run's wall time went per MPa (or % strain), and its extrapolation further");
  stg->add_option("dir", stages_dir, "output folder of crumble run (it holds stages.csv)")->required();
  stg->add_option("--to", stages_to,
                  "extrapolate the wall time to this level, in the table's unit: vertical stress in MPa (default 30: "
                  "Zhu & Zhao 2019 §5) or, for a strain-controlled run, axial strain in % (default 15: Harmon et al. 2020 §5)")
      ->check(CLI::Range(0.0, 1e6));
  stg->add_flag("--json", stages_json, "print JSON instead of Markdown");
  stg->footer("Reads DIR/stages.csv (one row per MPa of vertical stress, or per % of axial strain for loading.mode "
              "strain_rate: wall time, grains, analyses, breaking analyses, "
              "mean analysis time, engine time per step), fits the wall time per MPa against the grain count and the "
              "grain count against the stress (power laws over the stages with breakage), and extrapolates. "
              "docs/performance.md shows it on the Zhu & Zhao run.");

  auto* bench = app.add_subcommand("bench", "benchmarks (one JSON line on stdout)");
  bench->add_option("what", bench_what, "engine | pd-kernel | pd-analysis | lsdem")->required();
  bench->add_option("--steps", bench_steps, "steps (default 1000); pd-analysis: repeats (default 3)")->check(CLI::Range(1L, 100000000L));
  bench->add_option("--threads", bench_threads, "threads")->check(CLI::Range(1, 1024));
  bench->add_option("--scenario", bench_scenario,
                    "scenario file (lsdem; engine: default scenarios/oedometer_rigid_quick.json)");
  bench->add_option("--engine", bench_engine, "engine for `bench engine` (bullet, ode, lsdem, ...)");
  bench->add_option("--settle-steps", bench_settle, "engine: steps the placed grains fall before timing (default: settle them as the scenario's packing does)")
      ->check(CLI::Range(-1L, 100000000L));

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }

  try {
    for (const auto& p : plugins) load_plugin(p);
#if CRUMBLE_MPI
    // Only `run` spreads its analyses; compare and sweep fork runs of their own.
    if (mpi.size() > 1 && (*cmp || *swp))
      throw InputError(std::string(*cmp ? "compare" : "sweep") +
                       " does not run under mpirun (only `crumble run` spreads its breakage analyses over MPI "
                       "ranks); run it without mpirun, with --jobs N");
    if (mpi.size() > 1)
      g_analysis_executor = [&](const Json& doc, const Scenario& sc) { return mpi.executor(doc, sc, plugins); };
#endif
    if (*run) return cmd_run(file, out, sets, seed, threads, quiet, resume, force);
    if (*cmp) return cmd_compare(file, out, vary, sets, seed, threads, jobs, quiet, force);
    if (*swp) return cmd_sweep(file, out, sweep_req, study, swp_jobs->count() > 0);
    if (*val) return cmd_validate(file, sets, print);
    if (*plt) return cmd_plot(plot_dir);
    if (*stg) {
      std::string md;
      const auto j = stage_report(stages_dir, stages_to, &md);
      std::cout << (stages_json ? j.dump(2) + "\n" : md);
      return 0;
    }
    if (*lst) {
      if (list_markdown && list_options.empty()) throw InputError("list --markdown needs --options NAME");
      return list_options.empty() ? cmd_list() : cmd_list_options(list_options, list_markdown);
    }
    if (*shp) {
      std::cout << shape_report(shape_spec, repr, spacing, nodes).dump() << "\n";
      return 0;
    }
    if (*bench) {
      std::cout << run_benchmark(bench_what, bench_steps, bench_threads, bench_scenario, bench_engine, bench_settle).dump() << "\n";
      return 0;
    }
  } catch (const ConfigError& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    return 2;
  } catch (const InputError& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "crumble: failed: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
