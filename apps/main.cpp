// crumble: the command line.
//   crumble run SCENARIO --out DIR [--set path=value]... [--seed N] [--threads N]
//   crumble validate SCENARIO [--set path=value]... [--print]
//   crumble list [--options NAME [--markdown]]
//   crumble shape --json SPEC --representation level_set|mesh|hull [--spacing h] [--nodes n]
//   crumble bench engine|pd-kernel|lsdem ...
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
#include "scenarios/OptionDocs.h"
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
std::atomic<int> g_signal{0};
extern "C" void on_signal(int sig) {
  g_signal.store(sig);
  g_stop.store(true);
}
// An interrupted run is not a finished one: 128 + the signal, as a shell reports it.
int interrupted_status() { return g_signal.load() == SIGINT ? 130 : 143; }

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const char* kExitStatus =
    "Exit status: 0 success; 2 bad input (the message names the file, the JSON path and what was expected; "
    "also an --out folder that holds another run); 1 a failure while running; 130 (SIGINT, Ctrl-C) or 143 "
    "(SIGTERM): the run was interrupted, every output was written (\"interrupted\": true in summary.json).";

// Files a run writes into --out (and their temporary names): the only files --force removes.
bool is_run_output(const std::string& name) {
  static const std::set<std::string> files = {"summary.json", "series.csv", "events.csv", "breakage_per_mpa.csv",
                                              "ncl.csv", "psd.csv", "shape.csv", "product_psd.csv", "product.csv",
                                              "grains.pvd", "effective_scenario.json",
                                              "packing.json", "checkpoint.json"};
  for (const char* suffix : {"", ".part", ".tmp", ".part.tmp"}) {
    const std::string sfx = suffix;
    if (name.size() > sfx.size() && name.compare(name.size() - sfx.size(), sfx.size(), sfx) == 0 &&
        files.count(name.substr(0, name.size() - sfx.size())))
      return true;
  }
  return false;
}
bool is_vtk_output(const std::string& name) {
  // vtk/grains_NNNNNNNN.vtp (and its temporary name)
  return name.rfind("grains_", 0) == 0 &&
         (name.size() > 4 && (name.compare(name.size() - 4, 4, ".vtp") == 0 ||
                              (name.size() > 8 && name.compare(name.size() - 8, 8, ".vtp.tmp") == 0)));
}

// Entries of DIR that crumble wrote (vtk/ counted as one when it holds only snapshots).
std::vector<std::string> run_outputs(const fs::path& dir, std::vector<std::string>* others) {
  std::vector<std::string> mine;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    bool ours = e.is_regular_file() && is_run_output(n);
    if (e.is_directory() && n == "vtk") {
      ours = true;
      for (const auto& v : fs::directory_iterator(e.path()))
        if (!(v.is_regular_file() && is_vtk_output(v.path().filename().string()))) ours = false;
    }
    (ours ? mine : *others).push_back(n);
  }
  std::sort(mine.begin(), mine.end());
  std::sort(others->begin(), others->end());
  return mine;
}

std::string list_names(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size() && i < 6; ++i) s += (i ? ", " : "") + v[i];
  if (v.size() > 6) s += ", …";
  return s;
}

// A fresh run never mixes its files with another run's: an --out folder that is not empty is
// refused unless --force, which removes crumble's own files of the earlier run (never other
// files) first.
void prepare_fresh_out(const std::string& out, bool force) {
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  if (!fs::is_directory(out, ec)) throw InputError("--out " + out + ": exists and is not a directory");
  std::vector<std::string> others;
  const auto mine = run_outputs(out, &others);
  if (mine.empty() && others.empty()) return;
  if (!force) {
    const bool resumable = fs::exists(fs::path(out) / "checkpoint.json");
    throw InputError("--out " + out + ": the folder is not empty (" + list_names(mine.empty() ? others : mine) +
                     "); a new run would mix its files with " + (mine.empty() ? "these" : "an earlier run's") +
                     ". Choose an empty folder, pass --force to remove the earlier run's files first" +
                     (resumable ? ", or --resume to continue the run it holds" : "") + ".");
  }
  for (const auto& n : mine) {
    const fs::path p = fs::path(out) / n;
    if (n == "vtk") {
      for (const auto& v : fs::directory_iterator(p)) fs::remove(v.path());
      fs::remove(p);
    } else {
      fs::remove(p);
    }
  }
}

// The first JSON path where two documents differ ("" when equal), skipping `ignore`.
std::string first_difference(const Json& a, const Json& b, const std::string& path,
                             const std::set<std::string>& ignore) {
  if (ignore.count(path)) return "";
  if (a.is_object() && b.is_object()) {
    std::set<std::string> keys;
    for (auto it = a.begin(); it != a.end(); ++it) keys.insert(it.key());
    for (auto it = b.begin(); it != b.end(); ++it) keys.insert(it.key());
    for (const auto& k : keys) {
      const std::string p = path + "/" + k;
      if (ignore.count(p)) continue;
      if (!a.contains(k) || !b.contains(k)) return p;
      const std::string d = first_difference(a[k], b[k], p, ignore);
      if (!d.empty()) return d;
    }
    return "";
  }
  if (a.is_array() && b.is_array()) {
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
      const std::string d = first_difference(a[i], b[i], path + "/" + std::to_string(i), ignore);
      if (!d.empty()) return d;
    }
    return a.size() == b.size() ? "" : path + "/" + std::to_string(std::min(a.size(), b.size()));
  }
  return a == b ? "" : (path.empty() ? "/" : path);
}

// Keys that may differ between a run and its resumption: the thread count (results do not
// depend on it) and simulation.max_steps (raising it is how a run stopped by it continues).
const std::set<std::string> kResumeMayDiffer = {"/threads", "/simulation/max_steps"};

void check_resumable(const std::string& out, const Json& effective) {
  const fs::path dir(out);
  if (!fs::exists(dir / "checkpoint.json"))
    throw InputError("--out " + out + " --resume: no checkpoint.json to resume from (a run writes one when "
                     "output.checkpoint_every > 0)");
  std::ifstream in(dir / "effective_scenario.json");
  if (!in) throw InputError("--out " + out + " --resume: no effective_scenario.json beside the checkpoint");
  std::stringstream ss;
  ss << in.rdbuf();
  const Json before = parse_json_text(ss.str(), (dir / "effective_scenario.json").string());
  const std::string d = first_difference(before, effective, "", kResumeMayDiffer);
  if (d.empty()) return;
  auto show = [&](const Json& j) {
    try {
      const Json::json_pointer ptr(d == "/" ? "" : d);
      return j.contains(ptr) ? j.at(ptr).dump() : std::string("(absent)");
    } catch (const std::exception&) {
      return std::string("?");
    }
  };
  throw InputError("--resume: the scenario differs from the run in " + out + " at " + d + " (was " + show(before) +
                   ", now " + show(effective) +
                   "); a resumed run must use the same effective scenario (only /threads and "
                   "/simulation/max_steps may change). Use the same file and --set options, or start a new run "
                   "in another folder");
}

// packing_settle_steps of the run being resumed (its last summary.json), -1 when unknown.
double previous_settle_steps(const std::string& out) {
  std::ifstream in(fs::path(out) / "summary.json");
  if (!in) return -1;
  try {
    const Json j = Json::parse(in);
    if (j.contains("packing_settle_steps") && j["packing_settle_steps"].is_number())
      return j["packing_settle_steps"].get<double>();
  } catch (const std::exception&) {
  }
  return -1;
}


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
            std::optional<std::uint64_t> seed, std::optional<int> threads, bool quiet, bool resume, bool force) {
  Scenario sc = load(file, sets, seed, threads);
  if (resume && force) throw InputError("--resume and --force exclude each other");
  double settle_before = -1;
  if (resume) {
    check_resumable(out, sc.effective);
    settle_before = previous_settle_steps(out);
  } else {
    prepare_fresh_out(out, force);
  }
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
                << " steps); no packing.json or checkpoint was written: start the run again (with --force to reuse this folder)\n";
      return interrupted_status();
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
  // A resumed run settled nothing: report the settling of the run it continues.
  if (!resume) {
    sum.extra["packing_settle_steps"] = static_cast<double>(settle_steps);
    sum.extra["packing_settled"] = packing_settled ? 1.0 : 0.0;
  } else if (settle_before >= 0) {
    sum.extra["packing_settle_steps"] = settle_before;
  }
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
  // An interrupted run is not a finished one: 128 + the signal, as a shell reports it.
  if (sum.interrupted) return interrupted_status();
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
  std::cout << "crumble list --options NAME: each option's type, default, range and meaning\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"crumble — particle breakage in granular materials (Zhu & Zhao 2019, Harmon et al. 2020)"};
  app.set_version_flag("--version", std::string("crumble ") + CRUMBLE_VERSION);
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
  long nodes = 0, bench_steps = 1000, bench_settle = -1;
  std::string bench_engine;
  int bench_threads = 1;

  auto* run = app.add_subcommand("run", "run a scenario");
  run->add_option("scenario", file, "scenario JSON file")->required();
  run->add_option("--out", out, "output directory")->required();
  run->add_option("--set", sets, "override a scenario value: path=value (e.g. engine.type=lsdem)");
  run->add_option("--seed", seed, "random seed (overrides the scenario's)");
  run->add_option("--threads", threads, "threads (overrides the scenario's)")->check(CLI::Range(1, 1024));
  run->add_flag("--quiet", quiet, "no progress on stderr");
  run->add_flag("--resume", resume,
                "continue from DIR/checkpoint.json (written when output.checkpoint_every > 0); the effective scenario "
                "must equal DIR/effective_scenario.json but for threads and simulation.max_steps");
  run->add_flag("--force", force,
                "use a non-empty --out folder: first remove the earlier run's files there (only crumble's own)");
  run->footer(kExitStatus);

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

  auto* bench = app.add_subcommand("bench", "benchmarks (one JSON line on stdout)");
  bench->add_option("what", bench_what, "engine | pd-kernel | lsdem")->required();
  bench->add_option("--steps", bench_steps, "steps")->check(CLI::Range(1L, 100000000L));
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
    if (*run) return cmd_run(file, out, sets, seed, threads, quiet, resume, force);
    if (*val) return cmd_validate(file, sets, print);
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
