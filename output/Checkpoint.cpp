#include "output/Checkpoint.h"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "core/ShapeSpec.h"
#include "output/Writers.h"

namespace crumble {

using Json = nlohmann::json;

namespace {
Json vec(const Vec3& v) { return {v.x, v.y, v.z}; }
Json quat(const Quat& q) { return {q.w, q.x, q.y, q.z}; }
}  // namespace

Json shape_to_json(const Shape& s) {
  const auto& p = s.parameters();
  Json j;
  switch (s.kind()) {
    case ShapeKind::Sphere: j = {{"type", "sphere"}, {"radius", p[0]}}; break;
    case ShapeKind::Ellipsoid: j = {{"type", "ellipsoid"}, {"radii", {p[0], p[1], p[2]}}}; break;
    case ShapeKind::Superellipsoid:
      j = {{"type", "superellipsoid"}, {"radii", {p[0], p[1], p[2]}}, {"eps1", p[3]}, {"eps2", p[4]}};
      break;
    case ShapeKind::Box: j = {{"type", "box"}, {"half_extents", {p[0], p[1], p[2]}}}; break;
    case ShapeKind::Polyhedron: {
      const TriMesh& m = s.mesh();
      Json v = Json::array(), t = Json::array();
      for (const auto& x : m.vertices) v.push_back(vec(x));
      for (const auto& x : m.triangles) t.push_back({x[0], x[1], x[2]});
      j = {{"type", "polyhedron"}, {"vertices", v}, {"triangles", t}};
      break;
    }
    case ShapeKind::Disk: j = {{"type", "disk"}, {"radius", p[0]}}; break;
    case ShapeKind::Ellipse: j = {{"type", "ellipse"}, {"radii", {p[0], p[1]}}}; break;
    case ShapeKind::Superellipse: j = {{"type", "superellipse"}, {"radii", {p[0], p[1]}}, {"eps", p[2]}}; break;
    case ShapeKind::Polygon: {
      Json v = Json::array();
      for (const auto& x : s.outline()) v.push_back({x.x, x.y});
      j = {{"type", "polygon"}, {"vertices", v}};
      break;
    }
    case ShapeKind::LevelSet: j = level_set_to_json(s.level_set()); break;
  }
  const auto& r = s.resolution();
  j["resolution"] = {{"mesh_subdivisions", r.mesh_subdivisions},
                     {"level_set_spacing", r.level_set_spacing},
                     {"surface_nodes", r.surface_nodes}};
  return j;
}

Json shape_saved_json(const Shape& s) {
  Json sj = shape_to_json(s);
  // What the factories would compute again from the (centred) source, as the run had
  // it: rebuilding recomputes the mass properties from centred vertices and differs in
  // the last bits, which a bit-identical resume cannot afford (Shape::restored).
  const MassProperties& mp = s.mass_properties();
  Json I = Json::array();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) I.push_back(mp.inertia(a, b));
  const Aabb bb = s.bounds();
  sj["saved"] = {{"volume", mp.volume},
                 {"inertia", I},
                 {"bounds", {bb.lo.x, bb.lo.y, bb.lo.z, bb.hi.x, bb.hi.y, bb.hi.z}},
                 {"recentring", vec(s.recentring())}};
  return sj;
}

Shape::Ptr shape_from_saved_config(const Config& sc, int dim) {
  Shape::Ptr sh = shape_from_config(sc, dim);
  if (!sc.has("saved")) return sh;
  const Config sv = sc.child("saved");
  MassProperties mp;
  mp.volume = sv.positive("volume");
  const auto I = sv.numbers("inertia");
  if (I.size() != 9) sv.fail("inertia", "expected the 9 components of the inertia tensor, row by row");
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) mp.inertia(a, b) = I[3 * a + b];
  const auto B = sv.numbers("bounds");
  if (B.size() != 6) sv.fail("bounds", "expected [lo x, lo y, lo z, hi x, hi y, hi z]");
  const Aabb bounds{{B[0], B[1], B[2]}, {B[3], B[4], B[5]}};
  const Vec3 rc = sv.vec3("recentring", {});
  // The saved source as written (already checked by shape_from_config).
  std::vector<Vec3> poly;
  TriMesh mesh;
  const Json& d = sc.doc();
  if (sh->kind() == ShapeKind::Polygon)
    for (const auto& v : d.at("vertices")) poly.push_back({v[0].get<double>(), v[1].get<double>(), 0.0});
  if (sh->kind() == ShapeKind::Polyhedron && d.contains("vertices") && d.contains("triangles")) {
    for (const auto& v : d.at("vertices")) mesh.vertices.push_back({v[0].get<double>(), v[1].get<double>(), v[2].get<double>()});
    for (const auto& t : d.at("triangles")) mesh.triangles.push_back({t[0].get<int>(), t[1].get<int>(), t[2].get<int>()});
  }
  try {
    return Shape::restored(*sh, mp, bounds, rc, std::move(poly), std::move(mesh));
  } catch (const std::invalid_argument& e) {
    sv.fail("volume", e.what());
  }
  return sh;
}

namespace {

// What an open scene has fed and discharged so far; a product grain as
// [id, origin, generation, time, volume, mass, diameter, sieve].
Json product_json(const std::vector<ProductGrain>& grains) {
  Json out = Json::array();
  for (const auto& p : grains) out.push_back({p.id, p.origin, p.generation, p.time, p.volume, p.mass, p.diameter, p.sieve});
  return out;
}

Json open_scene_json(const SimulationState& st) {
  return {{"rocks_fed", st.rocks_fed},          {"mass_fed", st.mass_fed},
          {"product_mass", st.product_mass},    {"product", product_json(st.product)},
          {"ejected_mass", st.ejected_mass},    {"ejected", product_json(st.ejected)}};
}

}  // namespace

Json checkpoint_json(Simulation& sim, const std::string& scenario, const Json& run_info, const SettleProgress* settling) {
  sim.sync_grains();
  const SimulationState st = sim.saved_state();
  Json j;
  j["format"] = "crumble-checkpoint";
  j["version"] = 1;
  j["scenario"] = scenario;
  j["dimension"] = sim.context().dimension;
  j["state"] = {{"time", st.time},
                {"step", st.step},
                {"initial_height", st.initial_height},
                {"platen_position", st.platen_position},
                {"removed_volume", st.removed_volume},
                {"removed_mass", st.removed_mass},
                {"removed_mass_crushed", st.removed_by_path.crushed},
                {"removed_mass_chip", st.removed_by_path.chip},
                {"removed_mass_split_pieces", st.removed_by_path.split_pieces},
                {"removed_mass_fines_diameter", st.removed_by_path.fines_diameter},
                {"removed_mass_guard", st.removed_by_path.guard},
                {"fragment_grid_nodes", st.fragment_counts.grid_nodes},
                {"fragment_children", st.fragment_counts.children},
                {"fragment_refinements", st.fragment_counts.refinements},
                {"fragment_absorbed", st.fragment_counts.absorbed},
                {"fragment_unresolved", st.fragment_counts.unresolved},
                {"events", st.events},
                {"analyses", st.analyses},
                {"analyses_skipped", st.analyses_skipped},
                {"fallbacks", st.fallbacks},
                {"dt_reductions", st.dt_reductions},
                {"next_id", st.next_id},
                {"schedule_last_stress", st.schedule_last_stress},
                {"energy_in", st.energy_in},
                {"reference_diameter", st.reference_diameter},
                {"small_grain_overlaps", st.small_grain_overlaps},
                {"small_grains_removed", st.small_grains_removed},
                {"grains_initial", st.grains_initial},
                {"mass_initial", st.mass_initial},
                {"void_ratio_initial", st.void_ratio_initial},
                {"max_platen_stress", st.max_platen_stress},
                {"platen_stress", st.platen_stress},
                {"guard_max_overlap_fraction", st.guard_max_overlap_fraction},
                {"guard_max_energy_ratio", st.guard_max_energy_ratio}};
  for (const auto& [reason, n] : st.screened.items()) j["state"][std::string("screened_") + reason] = n;
  if (!st.analysis_failures.empty()) j["state"]["analyses_failed"] = st.analysis_failures;
  if (sim.container().open || sim.feed().count > 0) j["state"]["open_scene"] = open_scene_json(st);
  // Shared shapes are written once.
  std::map<const Shape*, std::size_t> index;
  Json shapes = Json::array(), grains = Json::array();
  for (const auto& g : sim.grains()) {
    auto it = index.find(g.shape.get());
    if (it == index.end()) {
      it = index.emplace(g.shape.get(), shapes.size()).first;
      shapes.push_back(shape_saved_json(*g.shape));
    }
    Json gj = {{"id", g.id},
                      {"parent", g.parent},
                      {"origin", g.origin},
                      {"generation", g.generation},
                      {"shape", it->second},
                      {"material", g.material},
                      {"position", vec(g.position)},
                      {"orientation", quat(g.orientation)},
                      {"velocity", vec(g.velocity)},
                      {"angular_velocity", vec(g.angular_velocity)},
                      {"strength", Json(g.strength.values)},
                      {"crush_count", g.crush_count}};
    // The skip rule's memory (Grain::intact_load): [partner, fx, fy, fz] per partner.
    if (!g.intact_load.empty()) {
      Json il = Json::array();
      for (const auto& p : g.intact_load) il.push_back({p.partner, p.force.x, p.force.y, p.force.z});
      gj["intact_load"] = std::move(il);
    }
    grains.push_back(std::move(gj));
  }
  j["shapes"] = shapes;
  j["grains"] = grains;
  Json es;
  if (sim.engine().save_state(es)) j["engine_state"] = std::move(es);
  if (run_info.is_object() && !run_info.empty()) j["run"] = run_info;
  if (settling)
    j["settling"] = {{"steps", settling->steps},
                     {"last_platen_position", settling->last_platen},
                     {"dt", settling->dt},
                     {"mean_diameter", settling->mean_diameter},
                     {"platen_stress_first_Pa", settling->stress_first},
                     {"platen_stress_max_Pa", settling->stress_max}};
  return j;
}

namespace {

// The product (or ejected) grains `key` of a checkpoint's "open_scene" object (open_scene_json).
std::vector<ProductGrain> read_product(const Config& oc, const std::string& key) {
  std::vector<ProductGrain> out;
  const Json& pr = oc.raw(key);
  const std::string form = "expected an array of [id, origin, generation, time, volume, mass, diameter, sieve]";
  if (!pr.is_array()) oc.fail(key, form);
  for (std::size_t k = 0; k < pr.size(); ++k) {
    const Json& e = pr[k];
    const std::string at = key + "/" + std::to_string(k);
    if (!e.is_array() || e.size() != 8) oc.fail(at, form);
    for (int i = 0; i < 3; ++i)
      if (!e[i].is_number_integer()) oc.fail(at, "id, origin and generation must be integers");
    double v[5];
    for (int i = 0; i < 5; ++i) {
      if (!e[i + 3].is_number() || !std::isfinite(e[i + 3].get<double>()) || e[i + 3].get<double>() < 0)
        oc.fail(at, "time, volume, mass, diameter and sieve must be finite numbers >= 0");
      v[i] = e[i + 3].get<double>();
    }
    ProductGrain p;
    p.id = e[0].get<GrainId>();
    p.origin = e[1].get<GrainId>();
    p.generation = e[2].get<int>();
    p.time = v[0];
    p.volume = v[1];
    p.mass = v[2];
    p.diameter = v[3];
    p.sieve = v[4];
    out.push_back(p);
  }
  return out;
}

// An open scene's feed and product, and the analyses that failed, into `st`.
void read_scene_and_failures(const Config& s, SimulationState& st) {
  if (s.has("open_scene")) {
    const Config oc = s.required_child("open_scene");
    st.rocks_fed = oc.integer("rocks_fed", 0, 0);
    st.mass_fed = oc.number("mass_fed", 0, 0);
    st.product_mass = oc.number("product_mass", 0, 0);
    st.product = read_product(oc, "product");
    // Checkpoints written before grains could be ejected have none.
    if (oc.has("ejected")) {
      st.ejected_mass = oc.number("ejected_mass", 0, 0);
      st.ejected = read_product(oc, "ejected");
    }
  }
  if (s.has("analyses_failed")) {
    if (!s.is_object("analyses_failed")) s.fail("analyses_failed", "expected an object {reason: count}");
    const Config fc = s.child("analyses_failed");
    for (auto it = fc.doc().begin(); it != fc.doc().end(); ++it)
      st.analysis_failures[it.key()] = fc.integer(it.key(), 0, 0);
  }
}

// The loop state of a checkpoint's "state" object.
SimulationState read_state(const Config& s) {
  SimulationState st;
  st.time = s.number("time", 0, 0);
  st.step = s.integer("step", 0, 0);
  st.initial_height = s.positive("initial_height");
  st.platen_position = s.positive("platen_position");
  st.removed_volume = s.number("removed_volume", 0, 0);
  st.removed_mass = s.number("removed_mass", 0, 0);
  st.removed_by_path.crushed = s.number("removed_mass_crushed", 0, 0);
  st.removed_by_path.chip = s.number("removed_mass_chip", 0, 0);
  st.removed_by_path.split_pieces = s.number("removed_mass_split_pieces", 0, 0);
  st.removed_by_path.fines_diameter = s.number("removed_mass_fines_diameter", 0, 0);
  st.removed_by_path.guard = s.number("removed_mass_guard", 0, 0);
  st.fragment_counts.grid_nodes = s.integer("fragment_grid_nodes", 0, 0);
  st.fragment_counts.children = s.integer("fragment_children", 0, 0);
  st.fragment_counts.refinements = s.integer("fragment_refinements", 0, 0);
  st.fragment_counts.absorbed = s.integer("fragment_absorbed", 0, 0);
  st.fragment_counts.unresolved = s.integer("fragment_unresolved", 0, 0);
  st.events = s.integer("events", 0, 0);
  st.analyses = s.integer("analyses", 0, 0);
  st.analyses_skipped = s.integer("analyses_skipped", 0, 0);
  st.fallbacks = s.integer("fallbacks", 0, 0);
  st.dt_reductions = s.integer("dt_reductions", 0, 0);
  st.next_id = s.integer("next_id", 0, 0);
  st.schedule_last_stress = s.number("schedule_last_stress", 0);
  st.energy_in = s.number("energy_in", 0, 0);
  st.reference_diameter = s.number("reference_diameter", 0, 0);
  st.small_grain_overlaps = s.integer("small_grain_overlaps", 0, 0);
  st.small_grains_removed = s.integer("small_grains_removed", 0, 0);
  st.grains_initial = static_cast<std::size_t>(s.integer("grains_initial", 0, 0));
  st.mass_initial = s.number("mass_initial", 0, 0);
  st.void_ratio_initial = s.number("void_ratio_initial", 0);
  st.max_platen_stress = s.number("max_platen_stress", 0);
  st.platen_stress = s.number("platen_stress", -1);
  st.guard_max_overlap_fraction = s.number("guard_max_overlap_fraction", 0, 0);
  st.guard_max_energy_ratio = s.number("guard_max_energy_ratio", 0, 0);
  for (const auto& [reason, n] : ScreeningCounts{}.items())  // absent in older checkpoints: 0
    *st.screened.find(reason) = s.integer(std::string("screened_") + reason, 0, 0);
  read_scene_and_failures(s, st);
  return st;
}

// The skip rule's memory (Grain::intact_load): [partner, fx, fy, fz] per partner, partners
// increasing.
std::vector<PartnerForce> read_intact_load(const Config& gc) {
  std::vector<PartnerForce> out;
  const Json& il = gc.raw("intact_load");
  auto bad = [&](const std::string& why) { gc.fail("intact_load", why); };
  if (!il.is_array()) bad("expected an array of [partner, fx, fy, fz] (partner: grain id, or -1 - wall index)");
  for (std::size_t k = 0; k < il.size(); ++k) {
    const Json& e = il[k];
    const std::string at = "entry " + std::to_string(k) + ": ";
    if (!e.is_array() || e.size() != 4 || !e[0].is_number_integer())
      bad(at + "expected [partner, fx, fy, fz] with an integer partner");
    PartnerForce p;
    p.partner = e[0].get<GrainId>();
    double f[3];
    for (int d = 0; d < 3; ++d) {
      if (!e[d + 1].is_number()) bad(at + "force components must be numbers (N)");
      f[d] = e[d + 1].get<double>();
      if (!std::isfinite(f[d])) bad(at + "force components must be finite (N)");
    }
    p.force = {f[0], f[1], f[2]};
    if (!out.empty() && !(out.back().partner < p.partner)) bad(at + "partners must be in increasing order, each once");
    out.push_back(p);
  }
  return out;
}

// One grain of the checkpoint; its shape is an index into `shapes`.
Grain read_grain(const Config& gc, const std::vector<Shape::Ptr>& shapes) {
  Grain g;
  g.id = gc.integer("id", 0, 0);
  g.parent = gc.integer("parent", -1, -1);
  g.generation = static_cast<int>(gc.integer("generation", 0, 0));
  g.origin = gc.integer("origin", g.generation == 0 ? g.id : g.parent, -1);
  const long si = gc.integer("shape", 0, 0, static_cast<long>(shapes.size()) - 1);
  g.shape = shapes[static_cast<std::size_t>(si)];
  g.material = static_cast<int>(gc.integer("material", 0, 0));
  g.position = gc.vec3("position", {});
  auto q = gc.numbers("orientation", {1, 0, 0, 0});
  if (q.size() != 4) gc.fail("orientation", "expected [w, x, y, z]");
  g.orientation = Quat{q[0], q[1], q[2], q[3]}.normalized();
  g.velocity = gc.vec3("velocity", {});
  g.angular_velocity = gc.vec3("angular_velocity", {});
  // Every named strength value of the model (Grain::strength), by name.
  if (gc.is_object("strength")) {
    Config sv = gc.child("strength");
    for (auto it = sv.doc().begin(); it != sv.doc().end(); ++it) g.strength.set(it.key(), sv.number(it.key()));
  } else if (gc.has("strength")) {
    // Checkpoints written before strength values had names came from peridynamics only.
    g.strength.set("gc_J_m2", gc.number("strength", 0));
    g.strength.set("threshold_force_N", gc.number("threshold_force", 0));
  }
  g.crush_count = static_cast<int>(gc.integer("crush_count", 0, 0));
  if (gc.has("intact_load")) g.intact_load = read_intact_load(gc);
  return g;
}

}  // namespace

Checkpoint read_checkpoint(const std::string& path, const std::string& scenario, int dim) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, "cannot open checkpoint (a run writes one when output.checkpoint_every or output.checkpoint_every_s is > 0)");
  std::stringstream ss;
  ss << in.rdbuf();
  Json doc = parse_json_text(ss.str(), path);
  if (!doc.is_object()) throw ConfigError(path, "a checkpoint must be a JSON object");
  Config c(doc);
  if (c.string("format") != "crumble-checkpoint") c.fail("format", "not a crumble checkpoint");
  c.integer("version", 1, 1, 1);
  const std::string name = c.string("scenario");
  if (name != scenario) c.fail("scenario", "checkpoint of scenario '" + name + "', not '" + scenario + "'");
  c.integer("dimension", dim, dim, dim);
  Checkpoint cp;
  cp.state = read_state(c.required_child("state"));
  std::vector<Shape::Ptr> shapes;
  for (auto& sc : c.children("shapes")) {
    Shape::Ptr sh = shape_from_saved_config(sc, dim);
    shapes.push_back(std::move(sh));
  }
  for (auto& gc : c.children("grains")) cp.grains.push_back(read_grain(gc, shapes));
  if (c.has("engine_state")) cp.engine_state = c.raw("engine_state");
  if (c.has("settling")) {
    const Config s = c.required_child("settling");
    SettleProgress p;
    p.steps = s.integer("steps", 0, 0);
    p.last_platen = s.number("last_platen_position");
    p.dt = s.positive("dt");
    p.mean_diameter = s.positive("mean_diameter");
    p.stress_first = s.number("platen_stress_first_Pa", 0);  // absent in checkpoints before 0.2.0
    p.stress_max = s.number("platen_stress_max_Pa", 0);
    cp.settling = p;
  }
  if (c.has("run")) {
    cp.run_info = c.raw("run");
    if (!cp.run_info.is_object()) c.fail("run", "expected an object");
  }
  c.check_unknown();
  return cp;
}

void restore_engine_state(Engine& engine, const Checkpoint& cp, const std::string& path) {
  if (cp.engine_state.is_null()) return;
  try {
    engine.restore_state(cp.engine_state);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(path, "/engine_state", e.what());
  }
}

CheckpointWriter::CheckpointWriter(std::string dir, std::string scenario, long every, double every_s, Json run_info)
    : dir_(std::move(dir)), scenario_(std::move(scenario)), every_(every), every_s_(every_s), info_(std::move(run_info)) {}

void CheckpointWriter::on_start(const Simulation&, const RunState& s) {
  last_ = s.step;
  last_time_ = std::chrono::steady_clock::now();
}

void CheckpointWriter::write(const Simulation& sim) {
  write_file_atomic(dir_ + "/checkpoint.json",
                    checkpoint_json(const_cast<Simulation&>(sim), scenario_, info_).dump() + "\n");
  last_time_ = std::chrono::steady_clock::now();
}

void CheckpointWriter::on_sample(const Simulation& sim, const RunState& s) {
  const bool by_steps = every_ > 0 && s.step - last_ >= every_;
  const bool by_time =
      every_s_ > 0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - last_time_).count() >= every_s_;
  if (!by_steps && !by_time) return;
  if (by_steps) last_ = s.step;  // wall-time writes leave the step schedule as it was
  write(sim);
}

void CheckpointWriter::on_finish(const Simulation& sim, const RunState&, RunSummary&) {
  if (every_ <= 0 && every_s_ <= 0) return;
  write(sim);
}

}  // namespace crumble
