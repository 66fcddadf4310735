#include "scenarios/Packing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <unordered_map>

#include "base/Format.h"
#include "output/Checkpoint.h"
#include "core/ShapeSpec.h"
#include "scenarios/Sections.h"

namespace crumble {

using Json = nlohmann::json;

std::vector<double> sample_psd(const std::vector<PsdPoint>& psd, std::size_t count, Rng& rng) {
  if (psd.size() < 2) throw std::invalid_argument("PSD needs at least two points");
  std::vector<double> w;  // number weight per bin
  for (std::size_t i = 1; i < psd.size(); ++i) {
    const double f = psd[i].passing - psd[i - 1].passing;
    const double dm = 0.5 * (psd[i].diameter + psd[i - 1].diameter);
    w.push_back(f / (dm * dm * dm));
  }
  double tot = 0;
  for (double x : w) tot += x;
  std::vector<double> out;
  out.reserve(count);
  for (std::size_t n = 0; n < count; ++n) {
    double u = rng.uniform() * tot;
    std::size_t b = 0;
    while (b + 1 < w.size() && u > w[b]) u -= w[b++];
    out.push_back(rng.uniform(psd[b].diameter, psd[b + 1].diameter));
  }
  return out;
}

namespace {

// The container's cross-section the platen pushes on: m² in 3D, m (per metre of thickness) in 2D.
double platen_area(const Container& c, int dim) { return dim == 2 ? c.lx : c.lx * c.ly; }

Quat random_orientation(Rng& rng, int dim) {
  if (dim == 2) return Quat::from_axis_angle({0, 0, 1}, rng.uniform(0, 2 * kPi));
  // Shoemake's uniform random rotation.
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  return Quat{std::sqrt(1 - u1) * std::sin(2 * kPi * u2), std::sqrt(1 - u1) * std::cos(2 * kPi * u2),
              std::sqrt(u1) * std::sin(2 * kPi * u3), std::sqrt(u1) * std::cos(2 * kPi * u3)}
      .normalized();
}

}  // namespace

Json scaled_spec(const Json& tmpl, double factor) {
  Json j = tmpl;
  j["scale"] = j.value("scale", 1.0) * factor;
  return j;
}

namespace {

// "psd": [[diameter_m, fraction_passing], …], increasing, ending at 1.
std::vector<PsdPoint> psd_from(const Config& pc) {
  std::vector<PsdPoint> psd;
  const auto& pj = pc.raw("psd");
  if (!pj.is_array() || pj.size() < 2) pc.fail("psd", "expected at least two [diameter_m, fraction_passing] pairs");
  for (std::size_t i = 0; i < pj.size(); ++i) {
    const std::string where = "psd/" + std::to_string(i);
    if (!pj[i].is_array() || pj[i].size() != 2 || !pj[i][0].is_number() || !pj[i][1].is_number())
      pc.fail(where, "expected [diameter_m, fraction_passing]");
    PsdPoint p{pj[i][0].get<double>(), pj[i][1].get<double>()};
    if (!(p.diameter > 0) || !std::isfinite(p.diameter)) pc.fail(where + "/0", "diameter must be > 0");
    if (!(p.passing >= 0 && p.passing <= 1)) pc.fail(where + "/1", "fraction passing must be in [0, 1]");
    if (i > 0 && (p.diameter <= psd.back().diameter || p.passing < psd.back().passing))
      pc.fail(where, "PSD must increase in diameter and not decrease in fraction passing");
    psd.push_back(p);
  }
  if (psd.back().passing != 1.0) pc.fail("psd", "the last point must have fraction passing 1");
  return psd;
}

// The shape templates of a cloud (unit size) with their JSON: one template, several drawn
// uniformly per grain, or (2D) a pool of generated outlines ({"type": "pool"}: one each).
struct Templates {
  std::vector<Shape::Ptr> shapes;
  std::vector<Json> specs;
};

Templates templates_from(const Config& pc, int dim) {
  Templates t;
  auto add = [&](const Config& sc) {
    // (A "type" that is not a string is left to shape_from_config's error.)
    const Json& d = sc.doc();
    if (dim == 2 && d.is_object() && d.contains("type") && d["type"].is_string() && d["type"] == "pool") {
      for (Json spec : shape_pool(sc)) {
        Config one(spec);
        t.shapes.push_back(shape_from_config(one, dim, /*unit_size=*/true));
        t.specs.push_back(spec);
      }
      return;
    }
    t.shapes.push_back(shape_from_config(sc, dim, /*unit_size=*/true));
    t.specs.push_back(sc.doc());
  };
  if (pc.doc().contains("shape") && pc.doc()["shape"].is_array()) {
    for (auto& sc : pc.children("shape")) add(sc);
    if (t.shapes.empty()) pc.fail("shape", "needs at least one shape template");
  } else {
    add(pc.child("shape"));
  }
  return t;
}

// Random sequential addition without overlap of bounding spheres, largest first (the grains
// of `shapes` inside the container up to `top`). Placed grains are binned on a grid of cell
// 2·rmax (>= any r + rad[q]), so a trial point is checked against the grains of its own and
// the neighbouring cells only: the same accept/reject decisions as checking every grain, in
// O(N) instead of O(N²). A grain too large for the box fails at `size_key`.
std::vector<Vec3> place_cloud(const Config& pc, const std::vector<Shape::Ptr>& shapes, const std::vector<double>& diam,
                              const Container& box, double top, double rmax, int dim, const std::string& size_key,
                              Rng& rng) {
  std::vector<std::size_t> order(shapes.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return diam[a] > diam[b]; });
  std::vector<Vec3> pos(shapes.size());
  std::vector<double> rad(shapes.size());
  const double cell = 2 * rmax;
  // Clamped before the conversion (a double beyond long's range does not convert).
  auto cell_of = [&](double x) { return static_cast<long>(std::clamp(std::floor(x / cell), -4e18, 4e18)); };
  std::unordered_map<unsigned long long, std::vector<std::size_t>> bins;
  // 2^21 cells per axis, wrapping modulo 2^64 (unsigned: defined) for containers with more
  // cells than that (a 1e9 m box of mm grains would overflow a signed key): two cells sharing a key only add distance checks, never change a decision.
  auto key = [](long i, long j, long k) {
    using U = unsigned long long;
    return (static_cast<U>(i) * 2097152ULL + static_cast<U>(j)) * 2097152ULL + static_cast<U>(k);
  };
  auto free_at = [&](const Vec3& p, double r) {
    const long ci = cell_of(p.x), cj = cell_of(p.y), ck = cell_of(p.z);
    for (long di = -1; di <= 1; ++di)
      for (long dj = -1; dj <= 1; ++dj)
        for (long dk = -1; dk <= 1; ++dk) {
          auto it = bins.find(key(ci + di, cj + dj, ck + dk));
          if (it == bins.end()) continue;
          for (std::size_t q : it->second)
            if (norm2(p - pos[q]) < (r + rad[q]) * (r + rad[q])) return false;
        }
    return true;
  };
  for (std::size_t k : order) {
    const double r = shapes[k]->bounding_radius() * 1.01;
    rad[k] = r;
    if (2 * r > box.lx || (dim == 3 && 2 * r > box.ly) || 2 * r > top) {
      const std::string which = 2 * r > box.lx                ? "container.lx = " + fmt_num(box.lx)
                                : dim == 3 && 2 * r > box.ly ? "container.ly = " + fmt_num(box.ly)
                                                             : "container.height = " + fmt_num(top);
      pc.fail(size_key, "a grain of equivalent diameter " + fmt_num(diam[k]) + " m needs a space " + fmt_num(2 * r) +
                            " m wide (its bounding sphere + 1 %), more than " + which +
                            " m; give a larger container or smaller grains");
    }
    bool ok = false;
    for (int attempt = 0; attempt < 20000 && !ok; ++attempt) {
      Vec3 p{rng.uniform(r, box.lx - r), 0, 0};
      if (dim == 3) {
        p.y = rng.uniform(r, box.ly - r);
        p.z = rng.uniform(r, top - r);
      } else {
        p.y = rng.uniform(r, top - r);
      }
      ok = free_at(p, r);
      if (ok) pos[k] = p;
    }
    if (!ok)
      pc.fail("fill_fraction", "could not place " + std::to_string(shapes.size()) +
                                   " grains without overlap; lower fill_fraction or give a taller container.height");
    bins[key(cell_of(pos[k].x), cell_of(pos[k].y), cell_of(pos[k].z))].push_back(k);
  }
  return pos;
}

// A generated cloud (Zhu & Zhao 2019 §5): sizes from the PSD (or one diameter, or the
// templates' own), shapes from the templates, placed at fill_fraction, then settled.
void cloud_packing(const Config& pc, const PackingSettings& ps, bool height_given, int dim, Rng& rng,
                   PackingSpec& spec) {
  const bool keep_size = ps.keep_template_size;
  const double mono = ps.diameter;
  std::vector<PsdPoint> psd;
  if (!keep_size && mono > 0 && pc.has("psd")) pc.fail("psd", "give either psd or diameter, not both");
  if (!keep_size && !(mono > 0)) psd = psd_from(pc);
  const Templates tmpl = templates_from(pc, dim);
  read_options(pc.child("settle"), settle_options(), spec.settle_settings);
  spec.settle = spec.settle_settings.enabled;

  std::vector<double> diam;
  std::vector<std::size_t> pick;
  for (long n = 0; n < ps.count; ++n)
    pick.push_back(tmpl.shapes.size() == 1 ? 0
                                           : static_cast<std::size_t>(rng.uniform() * tmpl.shapes.size()) % tmpl.shapes.size());
  if (keep_size) {
    for (std::size_t t : pick) diam.push_back(tmpl.shapes[t]->equivalent_diameter());
  } else if (mono > 0) {
    diam.assign(static_cast<std::size_t>(ps.count), mono);
  } else {
    diam = sample_psd(psd, static_cast<std::size_t>(ps.count), rng);
  }
  double vs = 0, rmax = 0;
  std::vector<Shape::Ptr> shapes;
  // Grains of the same template and size share one Shape (and so one level set / hull).
  std::map<std::pair<std::size_t, double>, Shape::Ptr> cache;
  for (std::size_t i = 0; i < diam.size(); ++i) {
    auto& sh = cache[{pick[i], diam[i]}];
    if (!sh) sh = tmpl.shapes[pick[i]]->scaled(diam[i] / tmpl.shapes[pick[i]]->equivalent_diameter());
    shapes.push_back(sh);
    vs += sh->volume();
    rmax = std::max(rmax, sh->bounding_radius() * 1.01);
  }
  const double area = platen_area(spec.container, dim);
  // A cloud at fill_fraction; never lower than the largest grain (a few grains in a wide
  // box would otherwise get a cloud thinner than one of them).
  const double cloud_h = std::max(vs / (ps.fill_fraction * area), 2 * rmax * 1.001);
  if (!height_given) spec.container.height = cloud_h;
  const std::string size_key = keep_size ? "shape" : (mono > 0 ? "diameter" : "psd");
  const std::vector<Vec3> pos =
      place_cloud(pc, shapes, diam, spec.container, spec.container.height, rmax, dim, size_key, rng);
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    PlacedGrain g;
    g.shape = shapes[i];
    g.shape_spec = scaled_spec(tmpl.specs[pick[i]], diam[i] / tmpl.shapes[pick[i]]->equivalent_diameter());
    g.position = pos[i];
    g.orientation = random_orientation(rng, dim);
    g.material = static_cast<int>(ps.material);
    g.source = pc.path();
    spec.grains.push_back(std::move(g));
  }
}

// An explicit list ("grains") or the packing.json of an earlier run ("file").
void explicit_packing(const Config& pc, const Config& cc, const PackingSettings& ps, bool height_given, int dim,
                      PackingSpec& spec) {
  std::vector<Config> entries;
  std::unique_ptr<Json> file_doc;
  std::unique_ptr<Config> file_cfg;
  if (spec.type == "file") {
    if (pc.child("settle").has("enabled"))
      pc.child("settle").fail("enabled", "a file packing is not settled again; packing.relax decides whether it relaxes");
    std::ifstream in(ps.path);
    if (!in) pc.fail("path", "cannot open packing file '" + ps.path + "'");
    std::stringstream ss;
    ss << in.rdbuf();
    file_doc = std::make_unique<Json>(parse_json_text(ss.str(), ps.path));
    file_cfg = std::make_unique<Config>(*file_doc);
    entries = file_cfg->children("grains");
    if (file_cfg->has("container")) {
      Config fc = file_cfg->child("container");
      if (!height_given) spec.container.height = fc.positive("height");
      fc.number("lx", 0);
      fc.number("ly", 0);
      fc.number("platen_mass", 0);
    }
    file_cfg->integer("dimension", dim, dim, dim);
    spec.built_by = file_cfg->string("engine", "");
    spec.relax = ps.relax;
    read_options(pc.child("settle"), relax_options(), spec.settle_settings);
    // Unknown keys are checked once the grain entries are read (below).
  } else {
    entries = pc.children("grains");
    spec.settle = ps.settle;
  }
  if (entries.empty()) pc.fail(spec.type == "file" ? "path" : "grains", "the packing has no grains");
  if (spec.container.height <= 0) cc.fail("height", "required for an explicit packing");
  for (auto& e : entries) {
    PlacedGrain g;
    Config sc = e.required_child("shape");
    g.shape = shape_from_config(sc, dim);
    g.shape_spec = sc.doc();
    const auto ge = read_options<GrainEntrySettings>(e, grain_entry_options());
    if (!is_finite(ge.position)) e.fail("position", "must be finite");
    g.position = ge.position;
    g.orientation = quaternion_from(e, "orientation", ge.orientation);
    g.material = static_cast<int>(ge.material);
    g.source = spec.type == "file" ? pc.path() + "/path (" + ps.path + ": " + e.path() + ")" : e.path();
    spec.grains.push_back(std::move(g));
  }
  if (file_cfg) file_cfg->check_unknown();
}

}  // namespace

Quat quaternion_from(const Config& c, const std::string& key, const std::vector<double>& q) {
  if (q.size() != 4) c.fail(key, "expected a quaternion [w, x, y, z]");
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 0)) c.fail(key, "quaternion must be non-zero");
  return Quat{q[0] / n, q[1] / n, q[2] / n, q[3] / n};
}

PackingSpec packing_from_config(const Config& pc, const Config& cc, int dim, Rng& rng) {
  PackingSpec spec;
  PackingSettings ps;
  ps.dimension = dim;
  // The type first, then the container, then what the type reads.
  read_options(pc, {find_option(packing_options(), "type")}, ps);
  ContainerSettings cs;
  cs.dimension = dim;
  read_options(cc, container_options(), cs);
  const bool height_given = cc.has("height");
  spec.type = ps.type;
  spec.container = cs.box;
  read_options(pc, packing_options(), ps);
  if (spec.type == "cloud") cloud_packing(pc, ps, height_given, dim, rng, spec);
  else explicit_packing(pc, cc, ps, height_given, dim, spec);
  return spec;
}

void place_packing(Simulation& sim, const PackingSpec& spec, bool add_grains) {
  sim.set_container(spec.container);
  for (const auto& w : spec.walls) sim.add_moving_wall(w);
  if (spec.feed.count > 0) sim.set_feed(spec.feed);
  if (!add_grains) return;
  for (const auto& pg : spec.grains) {
    Grain g;
    g.shape = pg.shape;
    g.position = pg.position;
    g.orientation = pg.orientation;
    g.material = pg.material;
    sim.add_grain(std::move(g));
  }
}

namespace {

// The settling's time step and convergence scale, computed once when it begins.
SettleProgress settle_start(Simulation& sim, const SettleSettings& ss) {
  SettleProgress p;
  Engine& e = sim.engine();
  p.dt = std::min(ss.dt > 0 ? ss.dt : sim.settings().time_steps.front().dt, e.max_stable_dt());
  for (const auto& g : sim.grains()) p.mean_diameter += g.shape->equivalent_diameter();
  p.mean_diameter /= static_cast<double>(std::max<std::size_t>(1, sim.grains().size()));
  p.last_platen = e.platen_position();
  return p;
}

}  // namespace

namespace {

// Whether a window ends at rest. A settling cloud: the platen carries at least half the
// settling stress and moved less than settle.tolerance × the mean diameter. A relaxing file
// packing (damped): the platen stress is within 10 % of the settling stress and the platen
// moved less than 1 % of the mean diameter; the heavily damped grains keep creeping into a
// denser packing long after the other engine's overlaps are gone (0.17 s on the quick
// Zhu & Zhao packing for 1.3 % of its height), which is not what relaxing is for.
bool at_rest(double platen_stress, double travel, const SettleSettings& ss, double mean_diameter, bool relaxing) {
  if (!relaxing) return platen_stress > 0.5 * ss.stress && travel < ss.tolerance * mean_diameter;
  return std::abs(platen_stress - ss.stress) <= 0.1 * ss.stress && travel < 0.01 * mean_diameter;
}

}  // namespace

void apply_settle_scales(Engine& e, const SettleSettings& ss) {
  if (!e.set_friction_scale(ss.friction_scale))
    throw ConfigError("/packing/settle/friction_scale",
                      "the engine '" + e.name() + "' cannot change friction while settling; use 1");
  if (!e.set_global_damping_scale(ss.global_damping_scale))
    throw ConfigError("/packing/settle/global_damping_scale",
                      "the engine '" + e.name() + "' has no global damping to scale while settling; use 1");
}

void reset_settle_scales(Engine& e) {
  e.set_friction_scale(1.0);
  e.set_global_damping_scale(1.0);
}

SettleResult settle_packing(Simulation& sim, const PackingSpec& spec, const SettleControl& ctl) {
  SettleResult res;
  if (!spec.settle) return res;
  // Zhu & Zhao 2019 §5: push the cloud down with a plate under a small force until stable.
  Engine& e = sim.engine();
  const auto& ss = spec.settle_settings;
  const double area = platen_area(spec.container, sim.context().dimension);
  SettleProgress p = ctl.from ? *ctl.from : settle_start(sim, ss);
  const long window = std::max(1L, std::lround(ss.window / p.dt));
  const long max_steps = std::max(window, std::lround(ss.max_time / p.dt));
  e.set_platen({PlatenCommand::Mode::Force, ss.stress * area});
  // A relaxing file packing is damped until it is at rest (Engine::set_relaxation_damping):
  // the other engine's overlaps give their energy up without bursting the packing, and the
  // grains stay where that engine left them up to the overlaps (undamped, the released energy
  // kept a 100-grain packing flowing for 0.2 s and moved grains 2.5 mm on average).
  bool damped = spec.type == "file";
  if (damped) e.set_relaxation_damping(true);
  apply_settle_scales(e, ss);
  const long guard_every = std::max(1L, sim.settings().sample_every);
  res.converged = false;
  while (p.steps < max_steps) {
    if (ctl.stop && ctl.stop->load()) {
      res.interrupted = true;
      if (ctl.after_step) ctl.after_step(p, true);
      break;
    }
    const double z0 = e.platen_position();
    e.step(p.dt);
    ++p.steps;
    const double stress = area > 0 ? e.platen_force() / area : 0;
    if (p.steps == 1) p.stress_first = stress;
    p.stress_max = std::max(p.stress_max, stress);
    sim.account_step(e.platen_force(), e.platen_position() - z0);
    sim.check_guards("settling", p.dt, p.steps % guard_every == 0);
    if (p.steps % window == 0) {
      const double z = e.platen_position();
      if (at_rest(area > 0 ? e.platen_force() / area : 0.0, std::abs(p.last_platen - z), ss, p.mean_diameter, damped)) {
        res.converged = true;
        break;
      }
      p.last_platen = z;
    }
    if (ctl.after_step) ctl.after_step(p, false);
  }
  if (damped) e.set_relaxation_damping(false);
  res.steps = p.steps;
  res.stress_first = p.stress_first;
  res.stress_max = p.stress_max;
  reset_settle_scales(e);
  e.set_platen({PlatenCommand::Mode::Velocity, 0.0});
  sim.sync_grains();
  return res;
}

SettleResult build_packing(Simulation& sim, const PackingSpec& spec, const std::atomic<bool>* stop) {
  place_packing(sim, spec);
  SettleControl ctl;
  ctl.stop = stop;
  return settle_packing(sim, spec, ctl);
}

void decide_relaxation(PackingSpec& spec, const std::string& engine) {
  if (spec.type != "file") return;
  spec.settle = spec.relax == "on" || (spec.relax == "auto" && !spec.built_by.empty() && spec.built_by != engine);
}

Json relaxation_report(const Simulation& sim, const PackingSpec& spec, const SettleResult& r) {
  double solid = 0;
  for (const auto& g : spec.grains) solid += g.shape->volume();
  double moved_max = 0, moved_sum = 0;
  for (const auto& g : sim.grains()) {
    const auto i = static_cast<std::size_t>(g.id);
    if (i >= spec.grains.size()) continue;
    const double d = norm(g.position - spec.grains[i].position);
    moved_max = std::max(moved_max, d);
    moved_sum += d;
  }
  const RunState s = sim.state();
  const Container& c = spec.container;
  const double area = platen_area(c, sim.context().dimension);
  return Json{{"built_by", spec.built_by},
              {"steps", r.steps},
              {"converged", r.converged},
              {"platen_stress_first_Pa", r.stress_first},
              {"platen_stress_max_Pa", r.stress_max},
              {"platen_stress_final_Pa", s.platen_stress},
              {"grain_displacement_max_m", moved_max},
              {"grain_displacement_mean_m", moved_sum / static_cast<double>(std::max<std::size_t>(1, sim.grains().size()))},
              {"void_ratio_before", solid > 0 ? (area * c.height - solid) / solid : 0.0},
              {"void_ratio_after", s.void_ratio}};
}

Json packing_to_json(const Simulation& sim, const PackingSpec& spec) {
  Json j;
  j["dimension"] = sim.context().dimension;
  j["engine"] = sim.engine().name();
  j["container"] = {{"lx", spec.container.lx},
                    {"ly", spec.container.ly},
                    {"height", sim.engine().platen_position()},
                    {"platen_mass", spec.container.platen_mass}};
  Json gs = Json::array();
  std::unordered_map<const Shape*, const Json*> specs;
  for (const auto& pg : spec.grains) specs[pg.shape.get()] = &pg.shape_spec;
  for (const auto& g : sim.grains()) {
    auto it = specs.find(g.shape.get());
    // Fragments have no spec of their own: their geometry (mesh or level-set grid) is written.
    const Json shape = it != specs.end() ? *it->second : shape_to_json(*g.shape);
    gs.push_back({{"shape", shape},
                  {"position", {g.position.x, g.position.y, g.position.z}},
                  {"orientation", {g.orientation.w, g.orientation.x, g.orientation.y, g.orientation.z}},
                  {"material", g.material}});
  }
  j["grains"] = gs;
  return j;
}

}  // namespace crumble
