#include "run/RunPipeline.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>

#include <unistd.h>

#include "base/BuildCounters.h"
#include "base/Format.h"
#include "output/Checkpoint.h"
#include "output/Plots.h"
#include "run/Progress.h"
#include "run/ThreadCheck.h"
#include "run/StandardObservers.h"
#include "scenarios/Sections.h"
#include "output/VtkWriter.h"
#include "output/Writers.h"

namespace crumble {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
extern "C" void on_stop_signal(int sig) {
  g_signal.store(sig);
  g_stop.store(true);
}

// Files a run writes into --out (and their temporary names): the only files --force removes.
bool is_run_output(const std::string& name) {
  static const std::set<std::string> files = {"summary.json", "series.csv", "events.csv", "breakage_per_mpa.csv", "stages.csv",
                                              "ncl.csv", "psd.csv", "shape.csv", "product_psd.csv", "product.csv",
                                              "grains.pvd", "scene.pvd", "analyses.pvd", "effective_scenario.json",
                                              "packing.json", "checkpoint.json"};
  for (const char* suffix : {"", ".part", ".tmp", ".part.tmp"}) {
    const std::string sfx = suffix;
    if (name.size() > sfx.size() && name.compare(name.size() - sfx.size(), sfx.size(), sfx) == 0 &&
        files.count(name.substr(0, name.size() - sfx.size())))
      return true;
  }
  for (const auto& png : plot_file_names())
    if (name == png || name == png + ".tmp") return true;
  return false;
}
bool is_vtk_output(const std::string& name) { return is_vtk_file_name(name); }  // output/VtkWriter.h

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
// depend on it), simulation.max_steps (raising it is how a run stopped by it continues),
// the wall-time checkpoint interval, and what a physical guard's message advises after a
// stop: the time step schedule, the contact solver's settings (iterations, Bullet's tolerance,
// residual and deep-penetration correction) and the guards themselves
// (they only check the state; a smaller step or a better converged contact solution from the
// last checkpoint on is how a stopped run goes on); and how Bullet collides concave grains
// (so a run from before their convex pieces can go on with them, or be compared both ways).
const std::set<std::string> kResumeMayDiffer = {
    "/threads",         "/simulation/max_steps",   "/output/checkpoint_every_s", "/time_step",
    "/engine/solver_iterations", "/engine/solver_tolerance", "/engine/solver_residual", "/engine/deep_penetration",
    "/engine/deep_erp",         "/simulation/guards", "/engine/concave_shapes", "/engine/concavity_tolerance",
    "/engine/max_convex_pieces", "/screening/moment_couples"};

// Compared by none of the above: the scenario's description (text; a file whose description
// was edited since the run still continues it, and the change is not reported).
std::set<std::string> resume_ignores() {
  std::set<std::string> s = kResumeMayDiffer;
  s.insert("/description");
  return s;
}

// Appends {"path", "was", "now"} for every leaf (or whole value, where the types differ) in
// which `was` and `now` differ below `path`.
void leaf_changes(const Json& was, const Json& now, const std::string& path, Json& out) {
  if (was.is_object() && now.is_object()) {
    std::set<std::string> keys;
    for (const auto& [k, v] : was.items()) keys.insert(k);
    for (const auto& [k, v] : now.items()) keys.insert(k);
    for (const std::string& k : keys)
      leaf_changes(was.contains(k) ? was.at(k) : Json(), now.contains(k) ? now.at(k) : Json(), path + "/" + k, out);
    return;
  }
  if (was != now) out.push_back(Json{{"path", path}, {"was", was}, {"now", now}});
}

// Where the keys of kResumeMayDiffer differ between the run's effective scenario and the
// resuming one, leaf by leaf, as [{"path", "was", "now"}] (absent values are null).
Json resume_changes(const Json& before, const Json& effective) {
  Json changes = Json::array();
  for (const std::string& key : kResumeMayDiffer) {
    const Json::json_pointer ptr(key);
    leaf_changes(before.contains(ptr) ? before.at(ptr) : Json(), effective.contains(ptr) ? effective.at(ptr) : Json(),
                 key, changes);
  }
  return changes;
}

// How often the scenario checkpoints, as "every N steps and every S s of wall time".
std::string checkpoint_schedule(const OutputSettings& o) {
  std::string s;
  if (o.checkpoint_every > 0) s = std::to_string(o.checkpoint_every) + " steps";
  if (o.checkpoint_every_s > 0) s += (s.empty() ? "" : " and every ") + fmt_num(o.checkpoint_every_s) + " s of wall time";
  return "every " + s;
}

// Why --resume finds no checkpoint.json in `out`, and what to do: no run there, a scenario
// that writes none, or a run stopped (killed) before its first one, while its packing settled
// or while it was loaded.
std::string no_checkpoint_message(const std::string& out, const Scenario& sc) {
  const fs::path dir(out);
  const std::string head = "--out " + out + " --resume: no checkpoint.json to resume from: ";
  const std::string again = "; start the run again (with --force to reuse this folder)";
  if (!fs::exists(dir / "effective_scenario.json"))
    return head + "the folder holds no run (no effective_scenario.json either)";
  const OutputSettings& o = sc.output;
  if (o.checkpoint_every <= 0 && o.checkpoint_every_s <= 0)
    return head + "the run writes none (output.checkpoint_every and output.checkpoint_every_s are 0)" + again +
           " with output.checkpoint_every or output.checkpoint_every_s > 0 to make it resumable";
  const std::string sooner = ", or with a smaller output.checkpoint_every or output.checkpoint_every_s to checkpoint sooner";
  if (!fs::exists(dir / "packing.json") && sc.packing.settle)
    return head + "the run in this folder stopped while its packing settled, before the settling's first checkpoint (" +
           checkpoint_schedule(o) + " of settling); nothing of it was saved" + again + sooner;
  return head + "the run in this folder stopped before its first checkpoint (" + checkpoint_schedule(o) +
         " of loading); nothing after its packing was saved" + again + sooner;
}

// Refuses a run in `out` whose effective scenario (effective_scenario.json) differs from
// `effective` but for kResumeMayDiffer; returns the allowed changes (resume_changes).
Json check_same_scenario(const std::string& out, const Json& effective) {
  const fs::path dir(out);
  std::ifstream in(dir / "effective_scenario.json");
  if (!in) throw InputError("--out " + out + " --resume: no effective_scenario.json in the folder");
  std::stringstream ss;
  ss << in.rdbuf();
  Json before = parse_json_text(ss.str(), (dir / "effective_scenario.json").string());
  // Options added to crumble since that run are absent from its file: fill them with this
  // build's defaults, as a new run would, so only a real change refuses the resume. (A file
  // this build no longer accepts is compared as it is, and the difference is named.)
  try {
    BuildOptions opt;
    opt.source_name = (dir / "effective_scenario.json").string();
    before = build_scenario(before, opt).effective;
  } catch (const std::exception&) {
  }
  const std::string d = first_difference(before, effective, "", resume_ignores());
  if (d.empty()) return resume_changes(before, effective);
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
                   "); a resumed run must use the same effective scenario (only /threads, "
                   "/simulation/max_steps, /output/checkpoint_every_s, /time_step, /engine/solver_iterations, "
                   "/engine/solver_tolerance, /engine/solver_residual, /engine/deep_penetration, /engine/deep_erp, "
                   "/engine/concave_shapes, /engine/concavity_tolerance, /engine/max_convex_pieces, "
                   "/screening/moment_couples and /simulation/guards may change). Use the same file and --set options, or start a new run "
                   "in another folder");
}

// Refuses a resume without a checkpoint, or whose effective scenario differs from the run's
// but for kResumeMayDiffer; returns the allowed changes (resume_changes).
Json check_resumable(const std::string& out, const Scenario& sc) {
  if (!fs::exists(fs::path(out) / "checkpoint.json")) throw InputError(no_checkpoint_message(out, sc));
  return check_same_scenario(out, sc.effective);
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

// The packing file a run started from: the scenario's file packing, or the packing.json the
// run wrote after building (settling) its packing.
std::string packing_source(const Scenario& sc, const std::string& out) {
  const Json& e = sc.effective;
  if (e.contains("packing") && e["packing"].is_object() && e["packing"].value("type", "") == "file" &&
      e["packing"].contains("path") && e["packing"]["path"].is_string())
    return e["packing"]["path"].get<std::string>();
  return (fs::path(out) / "packing.json").string();
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// summary.json `representations_built`: what this run built, by kind (base/BuildCounters.h).
Json representations_json(const RepresentationCounts& built) {
  Json j = Json::object();
  for (std::size_t i = 0; i < kRepresentationKinds; ++i) j[to_string(static_cast<Representation>(i))] = built.n[i];
  return j;
}

// Where the run starts: the settling of its packing (this run's, or on --resume the run it
// continues), the step it resumes at, and the changes of settings on --resume.
struct RunStart {
  Json changed_on_resume = Json::array();
  double settle_before = -1;
  long settle_steps = 0, resumed_step = -1;
  bool packing_settled = true;
  bool loading_resumed = false;  // --resume from a checkpoint of the loading (not of the settling)
  long resumed_settle_step = -1;  // --resume from a checkpoint of the settling: its step
  Json run_info = Json::object();
  Json relaxation;  // a file packing relaxed by this process (relaxation_report), else null
};

// The scenario's notes, and a warning when its threads oversubscribe the machine.
void print_scenario_notes(const Scenario& sc) {
  for (const auto& n : sc.notes) std::cerr << "crumble: note: " << n << "\n";
  if (sc.threads > 1)  // one thread never waits at a barrier: no need to read the machine's load
    if (const std::string w = thread_oversubscription_warning(sc.threads, current_cpu_load()); !w.empty())
      std::cerr << "crumble: warning: " << w << "\n";
}

// --out checked for --resume (the settings that changed noted and written), or prepared
// for a fresh run; then created.
void prepare_out(const RunRequest& req, const Scenario& sc, RunStart& st) {
  const std::string& out = req.out;
  if (req.resume && req.force) throw InputError("--resume and --force exclude each other");
  if (req.resume && req.packing_only) throw InputError("--resume: a packing stage has nothing to resume");
  if (req.resume) {
    st.changed_on_resume = check_resumable(out, sc);
    st.settle_before = previous_settle_steps(out);
    // From here on the run goes on with these settings: effective_scenario.json says so, and
    // summary.json's resume_changes keeps what they were before.
    for (const Json& c : st.changed_on_resume)
      std::cerr << "crumble: note: resuming with " << c["path"].get<std::string>() << " " << c["now"].dump()
                << " (was " << c["was"].dump() << ")\n";
    if (!st.changed_on_resume.empty())
      write_file_atomic(out + "/effective_scenario.json", sc.effective.dump(2) + "\n");
  } else {
    prepare_fresh_out(out, req.force);
  }
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw InputError("--out " + out + ": cannot create directory: " + ec.message());
}

// Checkpoints while the packing settles, by the loading's measures: every
// output.checkpoint_every settling steps and every output.checkpoint_every_s seconds of wall
// time, and once more when a signal stops the settling. None for --packing-only (a packing
// stage is not resumed).
SettleControl settle_control(const RunRequest& req, Scenario& sc) {
  SettleControl ctl;
  ctl.stop = &g_stop;
  const OutputSettings& o = sc.output;
  if (req.packing_only || (o.checkpoint_every <= 0 && o.checkpoint_every_s <= 0)) return ctl;
  auto last = std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
  ctl.after_step = [&sc, out = req.out, last](const SettleProgress& p, bool stopping) {
    const OutputSettings& o = sc.output;
    const bool by_steps = o.checkpoint_every > 0 && p.steps % o.checkpoint_every == 0;
    const bool by_time = o.checkpoint_every_s > 0 && seconds_since(*last) >= o.checkpoint_every_s;
    if (!stopping && !by_steps && !by_time) return;
    write_file_atomic(out + "/checkpoint.json", checkpoint_json(*sc.sim, sc.name, Json::object(), &p).dump() + "\n");
    *last = std::chrono::steady_clock::now();
  };
  return ctl;
}

// One line on what relaxing a file packing did (relaxation_report).
void print_relaxation(const Json& r, const std::string& engine) {
  const std::string by = r["built_by"].get<std::string>();
  std::cerr << "crumble: packing relaxed on '" << engine << "'" << (by.empty() ? "" : " (built by '" + by + "')")
            << " in " << r["steps"].get<long>() << " steps: platen stress " << fmt_num(r["platen_stress_first_Pa"].get<double>() / 1e6)
            << " MPa after the first step, at most " << fmt_num(r["platen_stress_max_Pa"].get<double>() / 1e6) << ", "
            << fmt_num(r["platen_stress_final_Pa"].get<double>() / 1e6) << " MPa at the end; grains moved "
            << fmt_num(r["grain_displacement_max_m"].get<double>() * 1e3) << " mm at most ("
            << fmt_num(r["grain_displacement_mean_m"].get<double>() * 1e3) << " mm on average); void ratio "
            << fmt_num(r["void_ratio_before"].get<double>()) << " -> " << fmt_num(r["void_ratio_after"].get<double>()) << "\n";
}

// The packing settled (from `from`, a checkpoint's progress, when given) and written. False
// when a signal interrupted the settling.
bool settle_and_write(const RunRequest& req, Scenario& sc, RunStart& st, const std::optional<SettleProgress>& from) {
  const std::string& out = req.out;
  Simulation& sim = *sc.sim;
  SettleControl ctl = settle_control(req, sc);
  ctl.from = from;
  const SettleResult settled = settle_packing(sim, sc.packing, ctl);
  st.settle_steps = settled.steps;
  if (settled.interrupted) {
    // An unsettled packing is not the start of this run: no packing.json that another
    // scenario could take for it; a checkpoint of the settling when the scenario writes them.
    if (ctl.after_step)
      std::cerr << "crumble: interrupted while the packing settled (after " << settled.steps
                << " steps); checkpoint written: continue the settling with --resume\n";
    else
      std::cerr << "crumble: interrupted while the packing settled (after " << settled.steps
                << " steps); no packing.json or checkpoint was written"
                << (req.packing_only ? "" : " (output.checkpoint_every and output.checkpoint_every_s are 0)")
                << ": start the run again (with --force to reuse this folder)\n";
    return false;
  }
  if (!settled.converged)
    std::cerr << "crumble: warning: the packing did not come to rest within packing.settle.max_time ("
              << settled.steps << " steps); the run starts from it anyway (summary.json: packing_settled false)\n";
  st.packing_settled = settled.converged;
  write_file_atomic(out + "/packing.json", packing_to_json(sim, sc.packing).dump(1) + "\n");
  if (sc.packing.type == "file" && sc.packing.settle) {
    st.relaxation = relaxation_report(sim, sc.packing, settled);
    if (!req.quiet) print_relaxation(st.relaxation, sc.engine_name);
  } else if (!req.quiet && st.settle_steps > 0) {
    std::cerr << "crumble: packing settled in " << st.settle_steps << " steps\n";
  }
  return true;
}

// The grains of a checkpoint of the settling are the packing's own (grain i has id i): they
// take the packing's shapes back, so that packing.json gives their specs as a fresh run's
// does. A grain whose saved shape is not its packing grain's is refused.
void take_packing_shapes(std::vector<Grain>& grains, const PackingSpec& spec, const std::string& path) {
  for (std::size_t k = 0; k < grains.size(); ++k) {
    Grain& g = grains[k];
    const auto i = static_cast<std::size_t>(g.id);
    const Shape::Ptr& own = i < spec.grains.size() ? spec.grains[i].shape : nullptr;
    if (!own || own->kind() != g.shape->kind() || own->volume() != g.shape->volume())
      throw ConfigError(path, "/grains/" + std::to_string(k),
                        "grain " + std::to_string(g.id) + " is not a grain of the scenario's packing (a checkpoint of "
                        "the settling holds the packing's grains)");
    g.shape = own;
  }
}

// Continue from DIR/checkpoint.json: the same scenario, its grains and loop state; a
// checkpoint of the settling goes on settling (false when a signal interrupts it again).
bool resume_run(const RunRequest& req, Scenario& sc, RunStart& st) {
  const std::string& out = req.out;
  Simulation& sim = *sc.sim;
  Checkpoint cp = read_checkpoint(out + "/checkpoint.json", sc.name, sim.context().dimension);
  // An engine that saves its state gets the container as it was and its platen from the
  // state; the others are rebuilt with the platen at rest where it was.
  // The moving walls and the feed of an open scene are the scenario's; their state at the
  // checkpoint follows from its time, its feed count and (lsdem) the engine state.
  PackingSpec spec = sc.packing;
  if (!cp.settling || cp.engine_state.is_null()) spec.container.height = cp.state.platen_position;
  place_packing(sim, spec, false);
  if (cp.settling) {
    take_packing_shapes(cp.grains, sc.packing, out + "/checkpoint.json");
    sim.restore_packing(cp.state, std::move(cp.grains));
    restore_engine_state(sim.engine(), cp, out + "/checkpoint.json");
    st.resumed_settle_step = cp.settling->steps;
    if (!req.quiet)
      std::cerr << "crumble: resuming the packing's settling at step " << cp.settling->steps << " ("
                << sim.grains().size() << " grains)\n";
    return settle_and_write(req, sc, st, cp.settling);
  }
  st.resumed_step = cp.state.step;
  st.loading_resumed = true;
  try {
    sim.resume(cp.state, std::move(cp.grains));
  } catch (const std::invalid_argument& e) {
    throw ConfigError(out + "/checkpoint.json", e.what());
  }
  restore_engine_state(sim.engine(), cp, out + "/checkpoint.json");
  // The settling of the run it continues (a run killed with SIGKILL left no summary.json).
  st.run_info = cp.run_info;
  if (st.run_info.contains("packing_settle_steps") && st.run_info["packing_settle_steps"].is_number())
    st.settle_before = st.run_info["packing_settle_steps"].get<double>();
  if (!req.quiet)
    std::cerr << "crumble: resuming at step " << cp.state.step << " (t = " << cp.state.time << " s, "
              << sim.grains().size() << " grains)\n";
  return true;
}

// A fresh run: effective_scenario.json, the packing placed, settled and written. False when
// a signal interrupted the settling.
bool build_and_settle(const RunRequest& req, Scenario& sc, RunStart& st) {
  write_file_atomic(req.out + "/effective_scenario.json", sc.effective.dump(2) + "\n");
  if (!req.quiet) std::cerr << "crumble: building packing (" << sc.packing.grains.size() << " grains)\n";
  place_packing(*sc.sim, sc.packing);
  return settle_and_write(req, sc, st, std::nullopt);
}

// --packing-only: summary.json of the packing stage.
Json packing_stage_summary(const Scenario& sc, const RunStart& st, const std::string& packing_hash,
                           const RepresentationCounts& built) {
  Json j;
  j["stage"] = "packing";
  j["scenario"] = sc.name;
  j["engine"] = sc.engine_name;
  j["seed"] = sc.seed;
  j["threads"] = sc.threads;
  j["grains"] = sc.sim->grains().size();
  j["packing_settle_steps"] = static_cast<double>(st.settle_steps);
  j["packing_settled"] = st.packing_settled ? 1.0 : 0.0;
  j["packing_hash"] = packing_hash;
  if (!st.changed_on_resume.empty()) j["resume_changes"] = st.changed_on_resume;
  j["representations_built"] = representations_json(built);
  return j;
}

// A file packing's summary.json figures: packing_relaxed (0 when it was loaded as it was) and the
// relax_* figures of relaxation_report.
void add_relaxation(RunSummary& sum, const Scenario& sc, const Json& r) {
  if (sc.packing.type != "file") return;
  sum.extra["packing_relaxed"] = r.is_object() ? 1.0 : 0.0;
  if (!r.is_object()) return;
  for (const auto& [k, v] : r.items()) {
    if (v.is_number()) sum.extra["relax_" + k] = v.get<double>();
    if (v.is_boolean()) sum.extra["relax_" + k] = v.get<bool>() ? 1.0 : 0.0;
  }
}

// The loading: observers attached, the simulation run with a progress line every few
// seconds on a terminal; in a log (stderr not a terminal: a batch job, a test) one a
// minute, so long runs still show where they are without flooding the log. --quiet: none.
RunSummary run_loading(const RunRequest& req, Scenario& sc, const RunStart& st) {
  Simulation& sim = *sc.sim;
  attach_standard_observers(sc, req.out, st.run_info);
  sim.set_stop_flag(&g_stop);
  if (req.analysis_executor) sim.set_analysis_executor(req.analysis_executor(request_document(req), sc));
  const auto t_loading = std::chrono::steady_clock::now();
  const double every = req.progress_every_s > 0 ? req.progress_every_s : (isatty(STDERR_FILENO) ? 2.0 : 60.0);
  EtaEstimator eta;
  double last_line = 0;
  auto progress = [&](const RunState& s, double f) {
    const double el = seconds_since(t_loading);
    eta.add(el, f);
    if (req.on_progress) req.on_progress(s, f, el, eta.eta_s());
    if (req.quiet || el - last_line < every) return;
    last_line = el;
    std::cerr << "crumble: " << format_progress(s, f, el, eta.eta_s()) << "\n";
  };
  RunSummary sum = sim.run(progress);
  // A run resumed in its loading settled nothing: report the settling of the run it continues.
  if (!st.loading_resumed) {
    sum.extra["packing_settle_steps"] = static_cast<double>(st.settle_steps);
    sum.extra["packing_settled"] = st.packing_settled ? 1.0 : 0.0;
  } else if (st.settle_before >= 0) {
    sum.extra["packing_settle_steps"] = st.settle_before;
    if (st.run_info.contains("packing_settled") && st.run_info["packing_settled"].is_boolean())
      sum.extra["packing_settled"] = st.run_info["packing_settled"].get<bool>() ? 1.0 : 0.0;
  }
  add_relaxation(sum, sc, st.run_info.value("relaxation", Json()));
  if (st.loading_resumed) sum.extra["resumed_from_step"] = static_cast<double>(st.resumed_step);
  if (st.resumed_settle_step >= 0) sum.extra["resumed_from_settle_step"] = static_cast<double>(st.resumed_settle_step);
  return sum;
}

// summary.json's notes: the scenario's (printed, or declared deliberate) and the run's.
Json notes_of(const Scenario& sc) {
  std::vector<Note> all = sc.setting_notes;
  for (const auto& text : sc.notes)  // the others (a fidelity preset's values)
    if (std::none_of(all.begin(), all.end(), [&](const Note& n) { return n.text == text; })) all.push_back({"", text, ""});
  all.insert(all.end(), sc.sim->notes().begin(), sc.sim->notes().end());
  return notes_json(all);
}

// summary.json of a run: the summary's figures, the packing's hash, the notes, the changes
// on --resume, the analyses per MPI rank and the representations built.
Json run_summary(const RunSummary& sum, const Scenario& sc, const RunStart& st, const std::string& packing_hash,
                 const RepresentationCounts& built) {
  Json j = summary_json(sum, sc.name, sc.engine_name, sc.breakage_name, sc.fragments_name, sc.seed, sc.threads);
  j["packing_hash"] = packing_hash;
  j["notes"] = notes_of(sc);
  for (auto it = sc.presets.begin(); it != sc.presets.end(); ++it) j[it.key()] = it.value();
  if (!st.changed_on_resume.empty()) j["resume_changes"] = st.changed_on_resume;
  if (const AnalysisExecutor* ex = sc.sim->analysis_executor()) {
    j["analysis_ranks"] = ex->ranks();
    Json n = Json::array(), t = Json::array();
    for (const auto& r : ex->load()) {
      n.push_back(r.analyses);
      t.push_back(r.seconds);
    }
    j["analyses_per_rank"] = n;
    j["analysis_seconds_per_rank"] = t;
  }
  j["representations_built"] = representations_json(built);
  return j;
}

void report_done(const RunRequest& req, const Scenario& sc, const RunSummary& sum) {
  if (sum.interrupted)
    std::cerr << "crumble: interrupted at step " << sum.steps << "; outputs written"
              << (sc.output.checkpoint_every > 0 || sc.output.checkpoint_every_s > 0 ? ", resume with --resume\n" : "\n");
  // The representations built are in summary.json (representations_built), not on stderr.
  if (!req.quiet)
    std::cerr << "crumble: " << format_done(sum.wall_seconds, sum.steps, sum.grains_final, sum.breakage_events, req.out)
              << "\n";
}

RunResult execute(const RunRequest& req) {
  const std::string& out = req.out;
  // Everything this run builds counts, the scenario's shapes and packing included.
  const RepresentationCounts built_before = representations_built();
  Scenario sc = build_request(req);
  print_scenario_notes(sc);
  RunStart st;
  prepare_out(req, sc, st);
  RunResult res;
  res.out = out;
  // Ctrl-C / SIGTERM: finish the current step, then write every output and the checkpoint.
  install_stop_signals();
  const auto t0 = std::chrono::steady_clock::now();
  if (!(req.resume ? resume_run(req, sc, st) : build_and_settle(req, sc, st))) {
    res.status = interrupted_status();
    res.reason = "interrupted while the packing settled";
    return res;
  }
  const std::string packing_hash = file_sha256(packing_source(sc, out));
  if (req.packing_only) {
    Json j = packing_stage_summary(sc, st, packing_hash, representations_built() - built_before);
    j["wall_seconds"] = seconds_since(t0);
    write_file_atomic(out + "/summary.json", j.dump(2) + "\n");
    res.summary = j;
    if (!req.quiet)
      std::cerr << "crumble: packing of " << sc.sim->grains().size() << " grains in " << out << "/packing.json\n";
    return res;
  }
  if (!st.loading_resumed) {
    st.run_info = {{"packing_settle_steps", st.settle_steps}, {"packing_settled", st.packing_settled}};
    if (!st.relaxation.is_null()) st.run_info["relaxation"] = st.relaxation;
  }
  RunSummary sum = run_loading(req, sc, st);
  sum.wall_seconds = seconds_since(t0);
  const RepresentationCounts built = representations_built() - built_before;
  const Json j = run_summary(sum, sc, st, packing_hash, built);
  write_file_atomic(out + "/summary.json", j.dump(2) + "\n");
  res.summary = j;
  report_done(req, sc, sum);
  // An interrupted run is not a finished one: 128 + the signal, as a shell reports it.
  if (req.plots && sc.output.plots) plots_after(out, req.quiet);
  if (!req.quiet && !sum.interrupted)
    if (const std::string open = what_to_open(out); !open.empty()) std::cerr << "crumble: " << open << "\n";
  if (sum.interrupted) {
    res.status = interrupted_status();
    res.reason = "interrupted at step " + std::to_string(sum.steps);
  }
  return res;
}

}  // namespace

Json request_document(const RunRequest& req) {
  Json doc = req.scenario;
  for (const auto& o : req.sets) apply_override_lapsing(doc, o);
  if (req.packing_file && doc.is_object() && !doc.contains("scene")) {
    // The scenario's settling stress and convergence test serve a relaxation (Packing.h); the
    // settle options a relaxation does not read (relax_options) go: a packing relaxes with
    // the friction and damping it is loaded with. Keys of no option stay, to be refused.
    Json file{{"type", "file"}, {"path", *req.packing_file}};
    const Json* settle = doc.contains("packing") && doc["packing"].is_object() && doc["packing"].contains("settle")
                             ? &doc["packing"]["settle"] : nullptr;
    if (settle && settle->is_object()) {
      Json s = *settle;
      for (const auto& o : settle_options())
        if (std::none_of(relax_options().begin(), relax_options().end(),
                         [&](const auto& r) { return r.key == o.key; }))
          s.erase(o.key);
      if (!s.empty()) file["settle"] = std::move(s);
    }
    doc["packing"] = std::move(file);
  }
  return doc;
}

Scenario build_request(const RunRequest& req) {
  BuildOptions opt;
  opt.seed = req.seed;
  opt.threads = req.threads;
  opt.source_name = req.source_name;
  return build_scenario(request_document(req), opt);
}

void check_same_run(const RunRequest& req) { check_same_scenario(req.out, build_request(req).effective); }

RunResult run_pipeline(const RunRequest& req) {
  try {
    return execute(req);
  } catch (const ConfigError&) {
    throw;
  } catch (const InputError&) {
    throw;
  } catch (const std::invalid_argument&) {
    throw;
  } catch (const std::exception& e) {
    // A failure while running (a physics guard, a backend error): no summary.json.
    RunResult r;
    r.status = 1;
    r.out = req.out;
    r.reason = e.what();
    return r;
  }
}

void install_stop_signals() {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
}
bool stop_requested() { return g_stop.load(); }
int received_signal() { return g_signal.load(); }
int interrupted_status() { return g_signal.load() == SIGINT ? 130 : 143; }
void clear_stop_request() {
  g_signal.store(0);
  g_stop.store(false);
}

// FIPS 180-4 SHA-256.
std::string sha256_hex(const std::string& bytes) {
  static constexpr std::array<std::uint32_t, 64> k = {
      0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
      0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
      0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
      0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
      0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
      0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
      0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
      0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};
  std::array<std::uint32_t, 8> h = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                    0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  auto rotr = [](std::uint32_t x, int n) { return (x >> n) | (x << (32 - n)); };
  std::string msg = bytes;
  const std::uint64_t bits = static_cast<std::uint64_t>(bytes.size()) * 8;
  msg.push_back(static_cast<char>(0x80));
  while (msg.size() % 64 != 56) msg.push_back('\0');
  for (int i = 7; i >= 0; --i) msg.push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
  for (std::size_t off = 0; off < msg.size(); off += 64) {
    std::uint32_t w[64];
    for (int i = 0; i < 16; ++i)
      w[i] = (static_cast<std::uint32_t>(static_cast<unsigned char>(msg[off + 4 * i])) << 24) |
             (static_cast<std::uint32_t>(static_cast<unsigned char>(msg[off + 4 * i + 1])) << 16) |
             (static_cast<std::uint32_t>(static_cast<unsigned char>(msg[off + 4 * i + 2])) << 8) |
             static_cast<std::uint32_t>(static_cast<unsigned char>(msg[off + 4 * i + 3]));
    for (int i = 16; i < 64; ++i) {
      const std::uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
      const std::uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (int i = 0; i < 64; ++i) {
      const std::uint32_t S1 = rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25);
      const std::uint32_t ch = (e & f) ^ (~e & g);
      const std::uint32_t t1 = hh + S1 + ch + k[i] + w[i];
      const std::uint32_t S0 = rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22);
      const std::uint32_t maj = (a & b) ^ (a & c) ^ (b & c);
      const std::uint32_t t2 = S0 + maj;
      hh = g;
      g = f;
      f = e;
      e = d + t1;
      d = c;
      c = b;
      b = a;
      a = t1 + t2;
    }
    h[0] += a;
    h[1] += b;
    h[2] += c;
    h[3] += d;
    h[4] += e;
    h[5] += f;
    h[6] += g;
    h[7] += hh;
  }
  static const char* hex = "0123456789abcdef";
  std::string s;
  for (std::uint32_t v : h)
    for (int i = 7; i >= 0; --i) s.push_back(hex[(v >> (4 * i)) & 0xf]);
  return s;
}

std::string file_sha256(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the packing file to hash it");
  std::stringstream ss;
  ss << in.rdbuf();
  return sha256_hex(ss.str());
}

}  // namespace crumble
