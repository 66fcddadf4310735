#include "scenarios/ScenarioFactory.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

#include "base/Format.h"
#include "scenarios/Fidelity.h"
#include "scenarios/InputChecks.h"
#include "scenarios/Methods.h"
#include "scenarios/Registry.h"
#include "output/VtkWriter.h"
#include "scenarios/Walls.h"

namespace crumble {

using Json = nlohmann::json;

Json load_scenario_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw ConfigError(path, "is a folder, not a scenario file: give a JSON file (e.g. scenarios/oedometer_rigid_quick.json)");
  std::ifstream in(path);
  if (!in) throw ConfigError(path, "cannot open scenario file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_json_text(ss.str(), path);
}

namespace {

std::vector<Material> materials_from(const Config& root) {
  std::vector<Material> out;
  auto list = root.children("materials");
  if (list.empty() && root.has("materials"))
    root.fail("materials", "expected at least one material (an empty array would leave every grain without one; "
                           "leave 'materials' out for the default material of Zhu & Zhao 2019, Table 1)");
  if (list.empty()) {
    // No "materials": one default material (Zhu & Zhao 2019 Table 1), recorded in the effective scenario.
    Json& doc = const_cast<Json&>(root.doc());
    doc["materials"] = Json::array({Json::object()});
    list = root.children("materials");
  }
  for (auto& m : list) {
    const auto mat = read_options<Material>(m, material_options());
    // No built-in engine models restitution (Bullet and ODE contacts are perfectly plastic,
    // lsdem's energy loss is its contact damping): a value other than 0 would be ignored.
    if (mat.restitution != 0.0)
      m.fail("restitution",
             "no engine models a coefficient of restitution, so only 0 is accepted (Zhu & Zhao 2019 Table 1); "
             "on lsdem the contact damping sets it (engine.damping_ratio, Harmon et al. 2020 Table 2)");
    out.push_back(mat);
  }
  return out;
}

std::vector<TimeStepRule> time_steps_from(const Config& root) {
  std::vector<TimeStepRule> rules;
  const Json& d = root.doc();
  if (d.contains("time_step") && d["time_step"].is_array()) {
    for (auto& r : root.children("time_step")) {
      TimeStepRule t{r.number("below_stress", SimulationSettings{}.time_steps.back().below_stress), r.positive("dt")};
      if (!rules.empty() && t.below_stress <= rules.back().below_stress)
        r.fail("below_stress", "time-step rules must have increasing below_stress");
      rules.push_back(t);
    }
    if (rules.empty()) root.fail("time_step", "needs at least one {below_stress, dt} rule");
  } else {
    rules.push_back({SimulationSettings{}.time_steps.back().below_stress, Options(root, scenario_options()).number("time_step")});
  }
  return rules;
}

// A scenario switched to another implementation with `--set engine.type=lsdem` still
// carries the options of the one it was written for. A key that another registered
// implementation of the same seam declares (RegistryEntry::options) is accepted with a note
// when its value is valid for that implementation (a wrong type or range is an error naming
// the path and the range); a key that no implementation declares stays unknown, so typos
// are still caught. Only the tables are read: no sibling is constructed (validating an
// lsdem scenario builds no Bullet world).
template <class T>
void accept_sibling_options(const Config& section, const T& table, const std::string& active,
                            std::vector<Note>& notes) {
  const std::set<std::string> used = section.read_keys();
  for (auto it = section.doc().begin(); it != section.doc().end(); ++it) {
    if (used.count(it.key())) continue;
    std::string owners;
    std::optional<ConfigError> invalid;
    for (const auto& e : table.entries()) {
      if (e.name == active) continue;
      for (const auto& spec : e.options) {
        if (spec.key != it.key()) continue;
        nlohmann::json one = nlohmann::json::object({{it.key(), it.value()}});
        try {
          check_option(Config(one), spec);
          owners += (owners.empty() ? "'" : "' and '") + e.name;
        } catch (const ConfigError& err) {
          const std::string what = err.what(), msg = what.substr(std::min(what.size(), err.path().size() + 2));
          if (!invalid)
            invalid.emplace(section.path() + err.path(),
                            msg + " (an option of '" + e.name + "', ignored by '" + active + "')");
        }
      }
    }
    if (owners.empty()) {
      if (invalid) throw *invalid;
      continue;  // declared by no implementation: check_unknown() reports it
    }
    section.accept(it.key());
    const std::string path = section.path() + "/" + it.key();
    notes.push_back({path, path + " is an option of " + owners + "', ignored by '" + active + "'", ""});
  }
}

// With simulation.auto_reduce_dt false a step above an explicit engine's stable step is an
// error; the bound depends on the grains, so ask a probe engine given the packing's extreme
// grains now instead of failing after settling.
void check_time_step_bound(const Config& root, const Config& ec, const RegistryEntry<EngineFactory>& entry,
                           const EngineContext& ctx, const PackingSpec& packing,
                           const std::vector<TimeStepRule>& rules) {
  nlohmann::json copy = ec.doc();
  Config probe_cfg(copy);
  const double bound = packing_stable_dt(*entry.make(probe_cfg, ctx), packing, ctx.materials);
  if (!std::isfinite(bound)) return;
  for (std::size_t i = 0; i < rules.size(); ++i) {
    if (rules[i].dt <= bound) continue;
    const std::string where = root.doc()["time_step"].is_array() ? "/time_step/" + std::to_string(i) + "/dt" : "/time_step";
    throw ConfigError(where, "time step " + fmt_num(rules[i].dt) + " s exceeds the " + entry.name +
                                 " engine's stable step " + fmt_num(bound) +
                                 " s for this packing, and /simulation/auto_reduce_dt is false; give a time step <= " +
                                 fmt_num(bound) + " s or set simulation.auto_reduce_dt to true");
  }
}

// The packing (or scene) and the moving walls; their errors do not depend on the engine.
void read_packing(const Config& root, int dim, Scenario& sc, const EngineContext& ctx) {
  Rng packing_rng = Rng(sc.seed).derive(0xC10D);
  if (root.has("scene")) {
    if (root.has("packing") || root.has("container"))
      root.fail("scene", "a scene builds its own container and packing: remove 'packing' and 'container'");
    sc.packing = scene_from_config(root.child("scene"), dim, packing_rng);
  } else {
    sc.packing = packing_from_config(root.child("packing"), root.child("container"), dim, packing_rng);
  }
  // Moving walls given by shapes and a prescribed motion (core/MovingWall.h).
  auto wcs = root.children("walls");
  for (std::size_t i = 0; i < wcs.size(); ++i)
    sc.packing.walls.push_back(wall_from_config(wcs[i], dim, "wall_" + std::to_string(i)));
  check_packing_materials(sc.packing, ctx.materials.size());
  check_explicit_grains(sc.packing, dim);
}

template <class Entry>
void check_dimension(const Entry& entry, const Config& c, int dim) {
  for (int d : entry.dimensions)
    if (d == dim) return;
  c.fail("type", "'" + entry.name + "' does not support " + std::to_string(dim) + "D scenarios");
}

struct Implementations {
  std::unique_ptr<Engine> engine;
  std::unique_ptr<BreakageModel> model;
  std::unique_ptr<FragmentBuilder> builder;
  const RegistryEntry<EngineFactory>* engine_entry = nullptr;
  std::vector<Note> notes;  // options of other implementations, accepted but not used
};

// An engine that cannot do what the packing asks (frictionless settling, moving walls) refuses
// now, naming itself, not after settling.
void check_engine_can(Engine& engine, const RegistryEntry<EngineFactory>& entry, const Config& root, const Config& ec,
                      const EngineContext& ctx, const PackingSpec& packing) {
  if (packing.settle) {
    apply_settle_scales(engine, packing.settle_settings);
    reset_settle_scales(engine);
  }
  if (packing.walls.empty()) return;
  nlohmann::json copy = ec.doc();
  Config probe_cfg(copy);
  try {
    entry.make(probe_cfg, ctx)->add_moving_wall(packing.walls.front());
  } catch (const std::invalid_argument& e) {
    throw ConfigError("/engine/type", std::string(e.what()) + " (moving walls come from " +
                                          (root.has("walls") ? "/walls" : "/scene") + ")");
  }
}

// The engine, breakage model and fragment builder the scenario names (the dimension's
// defaults when it names none), each checked for the dimension.
Implementations make_implementations(const Config& root, int dim, Scenario& sc, const EngineContext& ctx) {
  const DefaultImplementations& def = default_implementations(dim);
  Implementations im;
  Config ec = root.child("engine");
  sc.engine_name = ec.string("type", def.engine);
  im.engine_entry = &engines().find(sc.engine_name, "/engine/type");
  check_dimension(*im.engine_entry, ec, dim);
  Config bc = root.child("breakage");
  sc.breakage_name = bc.string("type", def.breakage);
  const auto& bentry = breakage_models().find(sc.breakage_name, "/breakage/type");
  check_dimension(bentry, bc, dim);
  sc.fragments_name = "none";
  if (sc.breakage_name != "none" || root.doc().contains("fragments")) {
    Config fc = root.child("fragments");
    sc.fragments_name = fc.string("type", def.fragments);
    const auto& fentry = fragment_builders().find(sc.fragments_name, "/fragments/type");
    check_dimension(fentry, fc, dim);
    im.builder = fentry.make(fc, ctx);
  }
  im.engine = im.engine_entry->make(ec, ctx);
  check_engine_can(*im.engine, *im.engine_entry, root, ec, ctx, sc.packing);
  im.model = bentry.make(bc, ctx);
  accept_sibling_options(ec, engines(), sc.engine_name, im.notes);
  accept_sibling_options(bc, breakage_models(), sc.breakage_name, im.notes);
  if (im.builder) accept_sibling_options(root.child("fragments"), fragment_builders(), sc.fragments_name, im.notes);
  return im;
}

SimulationSettings simulation_from(const Config& root, int threads) {
  SimulationSettings ss;
  ss.time_steps = time_steps_from(root);
  Config simc = root.child("simulation");
  read_options(simc, simulation_options(), ss);
  read_options(simc.child("guards"), guard_options(), ss.guards);
  ss.threads = threads;
  return ss;
}

LoadingSettings loading_from(const Config& root, const PackingSpec& packing, const SimulationSettings& ss) {
  LoadingSettings ls;
  Config lc = root.child("loading");
  if (packing.duration > 0) {
    // The scene fixes the run's length (jaw crusher: scene.cycles revolutions): mode none, that duration.
    lc.choice("mode", "none", {"none"});
    const double duration = lc.number("duration", packing.duration, 0.0);
    if (std::abs(duration - packing.duration) > 1e-9 * packing.duration)
      lc.fail("duration", "the scene runs for " + fmt_num(packing.duration) +
                              " s (scene.cycles revolutions); change scene.cycles instead, or leave loading out");
  }
  read_options(lc, loading_options(), ls);
  if (ls.mode == "none" && ls.duration == 0 && ss.max_steps == 0)
    lc.fail("mode", "loading mode 'none' needs loading.duration or simulation.max_steps");
  if (ls.mode == "strain_rate" && ls.stop_stress == 0 && ls.stop_force == 0 && ls.stop_strain == 0 &&
      ss.max_steps == 0 && ss.stop_after_breakage_events == 0)
    lc.fail("mode", "strain_rate loading needs a stop: stop_stress, stop_force, stop_strain, "
                    "simulation.max_steps or simulation.stop_after_breakage_events");
  return ls;
}

OutputSettings output_from(const Config& root) {
  Config oc = root.child("output");
  OutputSettings out;
  read_options(oc, output_options(), out);
  for (std::size_t i = 0; i < out.psd_at_strain.size(); ++i)
    if (!(out.psd_at_strain[i] > 0 && out.psd_at_strain[i] < 1))
      oc.fail("psd_at_strain/" + std::to_string(i), "expected an axial strain in (0, 1), e.g. 0.05");
  return out;
}

// The top level: name, dimension, seed (the command line's first), threads, gravity, materials.
EngineContext context_from(const Config& root, Json& doc, const BuildOptions& opt, Scenario& sc) {
  if (opt.seed) doc["seed"] = *opt.seed;
  if (opt.threads) doc["threads"] = *opt.threads;
  ScenarioSettings top;
  read_options(root, scenario_options(), top);
  sc.name = top.name;
  sc.seed = top.seed;
  sc.threads = static_cast<int>(top.threads);
  EngineContext ctx;
  ctx.dimension = static_cast<int>(top.dimension);
  ctx.gravity = top.gravity;
  ctx.materials = materials_from(root);
  ctx.threads = sc.threads;
  ctx.seed = sc.seed;
  ctx.fines_diameter = read_options<SimulationSettings>(root.child("simulation"), simulation_options()).fines_diameter;
  return ctx;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// What the method set, as notes and as the summary's record.
void report_method(const PresetReport& m, Scenario& sc) {
  if (m.name.empty()) return;
  for (const auto& w : m.set) sc.notes.push_back("method '" + m.name + "' sets " + w);
  if (!m.left.empty())
    sc.notes.push_back("method '" + m.name + "' leaves " + joined(m.left) + " as the scenario or --set gives them");
  sc.presets["method"] = {{"name", m.name}, {"sets", m.set}, {"left_as_given", m.left}};
}

// What the fidelity preset set and left, and why it changed nothing when it did not.
void report_fidelity(const PresetReport& f, const std::string& method, Scenario& sc) {
  if (f.name.empty()) return;
  const std::string who = "fidelity '" + f.name + "'";
  for (const auto& w : f.set) sc.notes.push_back(who + " sets " + w);
  std::string why;
  if (!f.left.empty()) why = joined(f.left) + " given by the scenario or --set";
  if (!f.left_by_method.empty())
    why += (why.empty() ? "" : "; ") + joined(f.left_by_method) + " set by method '" + method + "'";
  if (f.governed == 0)
    sc.notes.push_back(who + " changes nothing: it has no knob for the engine, breakage model and fragment builder "
                             "this scenario selects (crumble list)");
  else if (f.set.empty())
    sc.notes.push_back(who + " changes nothing: every key it governs here is already set (" + why + ")");
  else if (!why.empty())
    sc.notes.push_back(who + " leaves " + why);
  Json j = {{"preset", f.name}, {"sets", f.set}, {"left_as_given", f.left}, {"left_as_method_set", f.left_by_method},
            {"changes_nothing", f.set.empty()}};
  if (f.set.empty()) j["note"] = sc.notes.back();
  sc.presets["fidelity"] = j;
}

void apply_presets(Json& doc, Scenario& sc) {
  const PresetReport m = apply_method(doc);
  report_method(m, sc);
  report_fidelity(apply_fidelity_report(doc, m), m.name, sc);
}

}  // namespace

Scenario build_scenario(Json doc, const BuildOptions& opt) {
  for (const auto& o : opt.overrides) apply_override_lapsing(doc, o);
  if (!doc.is_object()) throw ConfigError(opt.source_name, "a scenario must be a JSON object");
  Scenario sc;
  // The method, then the preset, fill in values before anything reads the document, so the
  // file's own values and --set (already applied) win over both, and the method's over the preset's.
  apply_presets(doc, sc);
  Config root(doc);
  if (root.has("method")) root.accept("method");
  if (root.has("fidelity")) root.accept("fidelity");
  const EngineContext ctx = context_from(root, doc, opt, sc);
  const int dim = ctx.dimension;
  read_packing(root, dim, sc, ctx);
  Implementations im = make_implementations(root, dim, sc, ctx);
  decide_relaxation(sc.packing, sc.engine_name);

  SimulationSettings ss = simulation_from(root, sc.threads);
  if (!ss.auto_reduce_dt)
    check_time_step_bound(root, root.child("engine"), *im.engine_entry, ctx, sc.packing, ss.time_steps);
  const LoadingSettings ls = loading_from(root, sc.packing, ss);
  // The breakage model's method fixes the defaults; the scenario may override each value.
  ScheduleSettings sch = im.model->default_schedule();
  read_options(root.child("schedule"), schedule_options(), sch);
  ScreeningSettings scr = im.model->default_screening();
  read_options(root.child("screening"), screening_options(), scr);
  sc.output = output_from(root);
  if (sc.output.series_every > 0) ss.sample_every = sc.output.series_every;

  // A note about a setting the file declares deliberate goes to summary.json only (core/Notes.h).
  const DeliberateSettings deliberate = read_deliberate(doc);
  if (root.has("deliberate")) (void)root.raw("deliberate");  // read whole: its keys are JSON paths
  for (const Note& n : im.notes) {
    sc.setting_notes.push_back(make_note(deliberate, n.setting, n.text));
    if (sc.setting_notes.back().deliberate.empty()) sc.notes.push_back(n.text);
  }
  root.check_unknown();
  sc.sim = std::make_unique<Simulation>(std::move(im.engine), std::move(im.model), std::move(im.builder), ctx, ss, ls,
                                        sch, scr, sc.seed);
  sc.sim->set_deliberate(deliberate);
  sc.effective = doc;
  return sc;
}

}  // namespace crumble
