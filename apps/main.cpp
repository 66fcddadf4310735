// crumble: the command line.
//   crumble run SCENARIO --out DIR [--set path=value]... [--seed N] [--threads N]
//   crumble validate SCENARIO [--set path=value]... [--print]
//   crumble list
//   crumble shape --json SPEC --representation level_set|mesh|hull [--spacing h] [--nodes n]
//   crumble bench pd-kernel|lsdem ...
//   crumble --plugin lib.so <subcommand> ...   (out-of-tree engines, models, builders)
// Exit status: 0 success, 2 bad input (scenario, option, mesh), 1 failure while running.
#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "crumble_config.h"
#include "geometry/LevelSetGrid.h"
#include "scenarios/Checkpoint.h"
#include "scenarios/Plugins.h"
#include "scenarios/Registry.h"
#include "scenarios/ScenarioFactory.h"
#include "scenarios/ShapeSpec.h"
#include "scenarios/Tools.h"
#include "scenarios/Writers.h"

namespace fs = std::filesystem;
using namespace crumble;
using Json = nlohmann::json;

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }
// Exit status of a run ended early by SIGINT/SIGTERM before it had anything to resume.
constexpr int kExitInterrupted = 130;

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

Scenario load(const std::string& file, const std::vector<std::string>& sets, std::optional<std::uint64_t> seed,
              std::optional<int> threads) {
  BuildOptions opt;
  opt.overrides = sets;
  opt.seed = seed;
  opt.threads = threads;
  opt.source_name = file;
  Json doc = load_scenario_file(file);
  Scenario sc = build_scenario(std::move(doc), opt);
  for (const auto& n : sc.notes) std::cerr << "crumble: note: " << n << "\n";
  return sc;
}

int cmd_run(const std::string& file, const std::string& out, const std::vector<std::string>& sets,
            std::optional<std::uint64_t> seed, std::optional<int> threads, bool quiet, bool resume) {
  Scenario sc = load(file, sets, seed, threads);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw InputError("--out " + out + ": cannot create directory: " + ec.message());

  Simulation& sim = *sc.sim;
  // Ctrl-C / SIGTERM: finish the current step, then write every output and the checkpoint.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const auto t0 = std::chrono::steady_clock::now();
  long settle_steps = 0, resumed_step = -1;
  bool packing_settled = true;
  if (resume) {
    // Continue from DIR/checkpoint.json: the same scenario, its grains and loop state.
    Checkpoint cp = read_checkpoint(out + "/checkpoint.json", sc.name, sim.context().dimension);
    Container c = sc.packing.container;
    c.height = cp.state.platen_position;
    sim.set_container(c);
    resumed_step = cp.state.step;
    sim.resume(cp.state, std::move(cp.grains));
    if (!quiet)
      std::cerr << "crumble: resuming at step " << cp.state.step << " (t = " << cp.state.time << " s, "
                << sim.grains().size() << " grains)\n";
  } else {
    write_file_atomic(out + "/effective_scenario.json", sc.effective.dump(2) + "\n");
    if (!quiet) std::cerr << "crumble: building packing (" << sc.packing.grains.size() << " grains)\n";
    const SettleResult settled = build_packing(sim, sc.packing, &g_stop);
    settle_steps = settled.steps;
    if (settled.interrupted) {
      // An unsettled packing is not the start of this run: nothing is written that a
      // later --resume or another scenario could take for it.
      std::cerr << "crumble: interrupted while the packing settled (after " << settled.steps
                << " steps); no packing.json or checkpoint was written: run the scenario again (without --resume)\n";
      return kExitInterrupted;
    }
    if (!settled.converged)
      std::cerr << "crumble: warning: the packing did not come to rest within packing.settle.max_time ("
                << settled.steps << " steps); the run starts from it anyway (summary.json: packing_settled false)\n";
    packing_settled = settled.converged;
    write_file_atomic(out + "/packing.json", packing_to_json(sim, sc.packing).dump(1) + "\n");
    if (!quiet && settle_steps > 0) std::cerr << "crumble: packing settled in " << settle_steps << " steps\n";
  }

  attach_standard_observers(sc, out);
  sim.set_stop_flag(&g_stop);
  const auto t_loading = std::chrono::steady_clock::now();
  auto progress = [&](const RunState& s, double f) {
    if (quiet) return;
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_loading).count();
    std::cerr << format_progress(s, f, el) << "\n";
  };
  RunSummary sum = sim.run(progress);
  sum.extra["packing_settle_steps"] = static_cast<double>(settle_steps);
  if (!resume) sum.extra["packing_settled"] = packing_settled ? 1.0 : 0.0;
  if (resume) sum.extra["resumed_from_step"] = static_cast<double>(resumed_step);
  sum.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Json j = summary_json(sum, sc.name, sc.engine_name, sc.breakage_name, sc.fragments_name, sc.seed, sc.threads);
  write_file_atomic(out + "/summary.json", j.dump(2) + "\n");
  if (sum.interrupted)
    std::cerr << "crumble: interrupted at step " << sum.steps << "; outputs written"
              << (sc.output.checkpoint_every > 0 ? ", resume with --resume\n" : "\n");
  if (!quiet)
    std::cerr << "crumble: done in " << sum.wall_seconds << " s, " << sum.steps << " steps, " << sum.grains_final
              << " grains, " << sum.breakage_events << " breakage events; results in " << out << "\n";
  return 0;
}

int cmd_validate(const std::string& file, const std::vector<std::string>& sets, bool print) {
  Scenario sc = load(file, sets, std::nullopt, std::nullopt);
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
  }
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
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"crumble — particle breakage in granular materials (Zhu & Zhao 2019, Harmon et al. 2020)"};
  app.set_version_flag("--version", std::string("crumble ") + CRUMBLE_VERSION);
  app.require_subcommand(1);
  std::vector<std::string> plugins;
  app.add_option("--plugin", plugins, "load a plugin shared library (repeatable; before the subcommand)");

  std::string file, out, shape_spec, repr = "level_set", bench_what, bench_scenario;
  std::vector<std::string> sets;
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  bool quiet = false, print = false, resume = false;
  double spacing = 0;
  long nodes = 0, bench_steps = 1000;
  int bench_threads = 1;

  auto* run = app.add_subcommand("run", "run a scenario");
  run->add_option("scenario", file, "scenario JSON file")->required();
  run->add_option("--out", out, "output directory")->required();
  run->add_option("--set", sets, "override a scenario value: path=value (e.g. engine.type=lsdem)");
  run->add_option("--seed", seed, "random seed (overrides the scenario's)");
  run->add_option("--threads", threads, "threads (overrides the scenario's)")->check(CLI::Range(1, 1024));
  run->add_flag("--quiet", quiet, "no progress on stderr");
  run->add_flag("--resume", resume, "continue from DIR/checkpoint.json (written when output.checkpoint_every > 0)");

  auto* val = app.add_subcommand("validate", "check a scenario without running it");
  val->add_option("scenario", file, "scenario JSON file")->required();
  val->add_option("--set", sets, "override a scenario value: path=value");
  val->add_flag("--print", print, "print the effective scenario (all defaults filled in)");

  auto* lst = app.add_subcommand("list", "registered engines, breakage models and criteria, fragment builders");

  auto* shp = app.add_subcommand("shape", "report how well a shape is resolved by a representation");
  shp->add_option("--json", shape_spec, "shape JSON (inline text, or a file name)")->required();
  shp->add_option("--representation", repr, "level_set | mesh | hull")
      ->check(CLI::IsMember({"level_set", "mesh", "hull"}));
  shp->add_option("--spacing", spacing, "level-set grid spacing (m)");
  shp->add_option("--nodes", nodes, "level-set surface nodes");

  auto* bench = app.add_subcommand("bench", "benchmarks (one JSON line on stdout)");
  bench->add_option("what", bench_what, "pd-kernel | lsdem")->required();
  bench->add_option("--steps", bench_steps, "steps")->check(CLI::Range(1L, 100000000L));
  bench->add_option("--threads", bench_threads, "threads")->check(CLI::Range(1, 1024));
  bench->add_option("--scenario", bench_scenario, "scenario file (lsdem)");

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
    if (*run) return cmd_run(file, out, sets, seed, threads, quiet, resume);
    if (*val) return cmd_validate(file, sets, print);
    if (*lst) return cmd_list();
    if (*shp) {
      std::cout << shape_report(shape_spec, repr, spacing, nodes).dump() << "\n";
      return 0;
    }
    if (*bench) {
      std::cout << run_benchmark(bench_what, bench_steps, bench_threads, bench_scenario).dump() << "\n";
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
