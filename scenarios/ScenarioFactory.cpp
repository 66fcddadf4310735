#include "scenarios/ScenarioFactory.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

#include "base/Format.h"
#include "scenarios/Fidelity.h"
#include "scenarios/InputChecks.h"
#include "scenarios/Registry.h"
#include "output/VtkWriter.h"
#include "scenarios/Walls.h"

namespace crumble {

using Json = nlohmann::json;

Json load_scenario_file(const std::string& path) {
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
    Material mat;
    mat.density = m.positive("density", mat.density);
    mat.young = m.positive("young", mat.young);
    mat.poisson = m.number("poisson", mat.poisson, -0.99, 0.5);
    mat.friction = m.number("friction", mat.friction, 0.0);
    mat.wall_friction = m.number("wall_friction", mat.wall_friction, 0.0);
    mat.rolling_friction = m.number("rolling_friction", mat.rolling_friction, 0.0);
    mat.restitution = m.number("restitution", mat.restitution, 0.0, 1.0);
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
      TimeStepRule t{r.number("below_stress", 1e300), r.positive("dt")};
      if (!rules.empty() && t.below_stress <= rules.back().below_stress)
        r.fail("below_stress", "time-step rules must have increasing below_stress");
      rules.push_back(t);
    }
    if (rules.empty()) root.fail("time_step", "needs at least one {below_stress, dt} rule");
  } else {
    rules.push_back({1e300, root.positive("time_step", 5e-5)});
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
                            std::vector<std::string>& notes) {
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
    notes.push_back(section.path() + "/" + it.key() + " is an option of " + owners + "', ignored by '" + active + "'");
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

}  // namespace

Scenario build_scenario(Json doc, const BuildOptions& opt) {
  for (const auto& o : opt.overrides) apply_override(doc, o);
  if (!doc.is_object()) throw ConfigError(opt.source_name, "a scenario must be a JSON object");
  Scenario sc;
  // The preset fills in knobs before anything reads the document, so the file's own values and
  // --set (already applied) win over it.
  for (const auto& w : apply_fidelity(doc)) sc.notes.push_back("fidelity '" + doc["fidelity"].get<std::string>() + "' sets " + w);
  Config root(doc);
  if (root.has("fidelity")) root.accept("fidelity");
  sc.name = root.string("name", "scenario");
  root.string("description", "");
  const int dim = static_cast<int>(root.integer("dimension", 3, 2, 3));
  if (opt.seed) doc["seed"] = *opt.seed;
  if (opt.threads) doc["threads"] = *opt.threads;
  sc.seed = root.unsigned_integer("seed", 1);
  sc.threads = static_cast<int>(root.integer("threads", 1, 1, 1024));

  EngineContext ctx;
  ctx.dimension = dim;
  ctx.gravity = root.vec3("gravity", dim == 3 ? Vec3{0, 0, -9.81} : Vec3{0, -9.81, 0});
  ctx.materials = materials_from(root);
  ctx.threads = sc.threads;
  ctx.seed = sc.seed;

  // The packing first: its errors do not depend on which engine is chosen.
  Rng packing_rng = Rng(sc.seed).derive(0xC10D);
  if (root.has("scene")) {
    if (root.has("packing") || root.has("container"))
      root.fail("scene", "a scene builds its own container and packing: remove 'packing' and 'container'");
    sc.packing = scene_from_config(root.child("scene"), dim, packing_rng);
  } else {
    sc.packing = packing_from_config(root.child("packing"), root.child("container"), dim, packing_rng);
  }
  {
    // Moving walls given by shapes and a prescribed motion (core/MovingWall.h).
    auto wcs = root.children("walls");
    for (std::size_t i = 0; i < wcs.size(); ++i)
      sc.packing.walls.push_back(wall_from_config(wcs[i], dim, "wall_" + std::to_string(i)));
  }
  check_packing_materials(sc.packing, ctx.materials.size());
  check_explicit_grains(sc.packing, dim);

  auto check_dim = [&](const auto& entry, const Config& c) {
    for (int d : entry.dimensions)
      if (d == dim) return;
    c.fail("type", "'" + entry.name + "' does not support " + std::to_string(dim) + "D scenarios");
  };

  Config ec = root.child("engine");
  const std::string et = ec.string("type", "bullet");
  const auto& eentry = engines().find(et, "/engine/type");
  check_dim(eentry, ec);
  Config bc = root.child("breakage");
  const std::string bt = bc.string("type", "none");
  const auto& bentry = breakage_models().find(bt, "/breakage/type");
  check_dim(bentry, bc);
  std::unique_ptr<FragmentBuilder> builder;
  std::string ft = "none";
  if (bt != "none" || root.doc().contains("fragments")) {
    Config fc = root.child("fragments");
    ft = fc.string("type", dim == 3 ? "alpha_shape" : "level_set");
    const auto& fentry = fragment_builders().find(ft, "/fragments/type");
    check_dim(fentry, fc);
    builder = fentry.make(fc, ctx);
  }
  auto engine = eentry.make(ec, ctx);
  // Frictionless settling needs an engine that can change friction (validate says so too).
  if (sc.packing.settle && sc.packing.settle_settings.friction_scale != 1.0) {
    if (!engine->set_friction_scale(sc.packing.settle_settings.friction_scale))
      throw ConfigError("/packing/settle/friction_scale",
                        "the engine '" + et + "' cannot change friction while settling; use 1");
    engine->set_friction_scale(1.0);
  }
  if (!sc.packing.walls.empty()) {
    // An engine without moving walls refuses them now, naming itself, not after settling.
    nlohmann::json copy = ec.doc();
    Config probe_cfg(copy);
    try {
      eentry.make(probe_cfg, ctx)->add_moving_wall(sc.packing.walls.front());
    } catch (const std::invalid_argument& e) {
      throw ConfigError("/engine/type", std::string(e.what()) + " (moving walls come from " +
                                            (root.has("walls") ? "/walls" : "/scene") + ")");
    }
  }
  auto model = bentry.make(bc, ctx);
  accept_sibling_options(ec, engines(), et, sc.notes);
  accept_sibling_options(bc, breakage_models(), bt, sc.notes);
  if (builder) accept_sibling_options(root.child("fragments"), fragment_builders(), ft, sc.notes);
  sc.engine_name = et;
  sc.breakage_name = bt;
  sc.fragments_name = ft;

  SimulationSettings ss;
  ss.time_steps = time_steps_from(root);
  Config simc = root.child("simulation");
  ss.max_steps = simc.integer("max_steps", 0, 0);
  ss.sample_every = simc.integer("sample_every", 100, 1);
  ss.fines_diameter = simc.number("fines_diameter", 0.0, 0.0);
  ss.auto_reduce_dt = simc.boolean("auto_reduce_dt", true);
  ss.stop_after_breakage_events = simc.integer("stop_after_breakage_events", 0, 0);
  {
    Config gc = simc.child("guards");
    GuardSettings& g = ss.guards;
    g.enabled = gc.boolean("enabled", g.enabled);
    g.max_overlap_fraction = gc.number("max_overlap_fraction", g.max_overlap_fraction, 0.0, 1.0);
    g.energy_factor = gc.number("energy_factor", g.energy_factor, 0.0);
    g.small_grain_fraction = gc.number("small_grain_fraction", g.small_grain_fraction, 0.0, 1.0);
    g.containment = gc.boolean("containment", g.containment);
  }
  ss.threads = sc.threads;
  if (!ss.auto_reduce_dt) check_time_step_bound(root, ec, eentry, ctx, sc.packing, ss.time_steps);

  LoadingSettings ls;
  Config lc = root.child("loading");
  if (sc.packing.duration > 0) {
    // The scene fixes the run's length (jaw crusher: scene.cycles revolutions).
    ls.mode = lc.choice("mode", "none", {"none"});
    ls.duration = lc.number("duration", sc.packing.duration, 0.0);
    if (std::abs(ls.duration - sc.packing.duration) > 1e-9 * sc.packing.duration)
      lc.fail("duration", "the scene runs for " + fmt_num(sc.packing.duration) +
                              " s (scene.cycles revolutions); change scene.cycles instead, or leave loading out");
  } else {
    ls.mode = lc.choice("mode", "stress_ramp", {"stress_ramp", "strain_rate", "none"});
  }
  if (ls.mode == "none") {
    ls.duration = lc.number("duration", 0.0, 0.0);
  } else if (ls.mode == "stress_ramp") {
    ls.max_stress = lc.positive("max_stress", 1e6);
    ls.ramp_time = lc.positive("ramp_time", 0.1);
    ls.hold_time = lc.number("hold_time", 0.0, 0.0);
    ls.initial_stress = lc.number("initial_stress", 0.0, 0.0);
  } else {
    ls.strain_rate = lc.positive("strain_rate", 0.1);
  }
  ls.stop_stress = lc.number("stop_stress", 0.0, 0.0);
  ls.stop_force = lc.number("stop_force", 0.0, 0.0);
  ls.stop_strain = lc.number("stop_strain", 0.0, 0.0, 1.0);
  if (ls.mode == "none" && ls.duration == 0 && ss.max_steps == 0)
    lc.fail("mode", "loading mode 'none' needs loading.duration or simulation.max_steps");
  if (ls.mode == "strain_rate" && ls.stop_stress == 0 && ls.stop_force == 0 && ls.stop_strain == 0 &&
      ss.max_steps == 0 && ss.stop_after_breakage_events == 0)
    lc.fail("mode", "strain_rate loading needs a stop: stop_stress, stop_force, stop_strain, "
                    "simulation.max_steps or simulation.stop_after_breakage_events");

  // The breakage model's method fixes the defaults; the scenario may override each value.
  ScheduleSettings sch = model->default_schedule();
  Config schc = root.child("schedule");
  sch.every_stress = schc.number("every_stress", sch.every_stress, 0.0);
  sch.every_steps = schc.integer("every_steps", sch.every_steps, 0);

  ScreeningSettings scr = model->default_screening();
  Config scrc = root.child("screening");
  scr.min_diameter = scrc.number("min_diameter", scr.min_diameter, 0.0);
  scr.force_threshold = scrc.boolean("force_threshold", scr.force_threshold);
  scr.max_unbalanced_force_ratio = scrc.number("max_unbalanced_force_ratio", scr.max_unbalanced_force_ratio);
  scr.max_unbalanced_moment_ratio = scrc.number("max_unbalanced_moment_ratio", scr.max_unbalanced_moment_ratio);
  scr.min_contacts = static_cast<int>(scrc.integer("min_contacts", scr.min_contacts, 1));
  scr.moment_couples = scrc.boolean("moment_couples", scr.moment_couples);
  scr.skip_intact_tolerance = Options(scrc, screening_options()).number("skip_intact_tolerance", scr.skip_intact_tolerance);

  Config oc = root.child("output");
  sc.output.series_every = oc.integer("series_every", 0, 0);
  sc.output.psd_at_stress = oc.numbers("psd_at_stress", {});
  sc.output.psd_at_strain = oc.numbers("psd_at_strain", {});
  for (std::size_t i = 0; i < sc.output.psd_at_strain.size(); ++i)
    if (!(sc.output.psd_at_strain[i] > 0 && sc.output.psd_at_strain[i] < 1))
      oc.fail("psd_at_strain/" + std::to_string(i), "expected an axial strain in (0, 1), e.g. 0.05");
  sc.output.shape_metrics = oc.boolean("shape_metrics", true);
  sc.output.intact_analyses = oc.boolean("intact_analyses", true);
  {
    const Options vo(oc, vtk_output_options());
    sc.output.vtk_every = vo.integer("vtk_every");
    sc.output.vtk_final = vo.boolean("vtk_final");
    sc.output.vtk_contacts = vo.boolean("vtk_contacts");
    sc.output.vtk_analyses = vo.boolean("vtk_analyses");
  }
  sc.output.checkpoint_every = oc.integer("checkpoint_every", 0, 0);
  sc.output.plots = oc.boolean("plots", true);
  sc.output.psd_layers = oc.integer("psd_layers", 0, 0, 100);  // Liu et al. 2019 §4.3.3: sieve curves per layer
  if (sc.output.series_every > 0) ss.sample_every = sc.output.series_every;
  if (sc.output.checkpoint_every > 0 && (!sc.packing.walls.empty() || sc.packing.feed.count > 0))
    oc.fail("checkpoint_every", "checkpoints do not record moving walls, the feed or the product yet: set it to 0 "
                                "for scenarios with walls or a jaw_crusher scene");
  {
    // Checkpoints by wall time, on by default (a run killed after hours loses minutes);
    // scenes that cannot be checkpointed default to off and refuse a value.
    const bool open_scene = !sc.packing.walls.empty() || sc.packing.feed.count > 0;
    sc.output.checkpoint_every_s = oc.number("checkpoint_every_s", open_scene ? 0.0 : kDefaultCheckpointSeconds, 0.0);
    if (open_scene && sc.output.checkpoint_every_s > 0)
      oc.fail("checkpoint_every_s", "checkpoints do not record moving walls, the feed or the product yet: set it to 0 "
                                    "for scenarios with walls or a jaw_crusher scene");
  }


  root.check_unknown();
  sc.sim = std::make_unique<Simulation>(std::move(engine), std::move(model), std::move(builder), ctx, ss, ls, sch,
                                        scr, sc.seed);
  sc.effective = doc;
  return sc;
}

}  // namespace crumble
