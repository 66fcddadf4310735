#include "scenarios/Packing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <unordered_map>

#include "base/Format.h"
#include "output/Checkpoint.h"
#include "core/ShapeSpec.h"

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

PackingSpec packing_from_config(const Config& pc, const Config& cc, int dim, Rng& rng) {
  PackingSpec spec;
  spec.type = pc.choice("type", "cloud", {"cloud", "grains", "file"});
  spec.container.lx = cc.positive("lx");
  spec.container.ly = dim == 3 ? cc.positive("ly") : cc.number("ly", 0.0, 0.0, 0.0);
  spec.container.platen_mass = cc.number("platen_mass", 0.0, 0.0);
  const bool height_given = cc.has("height");
  if (height_given) spec.container.height = cc.positive("height");

  if (spec.type == "cloud") {
    // At most 1e6 grains: far beyond what one machine runs (the full Zhu & Zhao 2019 run ends near
    // 27 400), and 8e6 grains take minutes only to build their shapes.
    const long count = pc.integer("count", 100, 1, 1000000);
    // Sizes: a PSD by mass, or one "diameter" for all grains.
    std::vector<PsdPoint> psd;
    double mono = 0;
    const bool keep_size = pc.boolean("keep_template_size", false);
    if (keep_size) {
      // Grains keep the sizes their templates give (e.g. YADE's discharge scene).
    } else if (pc.has("diameter")) {
      mono = pc.positive("diameter");
      if (pc.has("psd")) pc.fail("psd", "give either psd or diameter, not both");
    } else {
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
    }
    // One template, or several drawn uniformly per grain; each scaled to the drawn size.
    std::vector<Shape::Ptr> tmpls;
    std::vector<Json> tmpl_json;
    // A template, or a pool of generated outlines ({"type": "pool"}: one template each).
    auto add_template = [&](const Config& sc) {
      // (A "type" that is not a string is left to shape_from_config's error.)
      const Json& d = sc.doc();
      if (dim == 2 && d.is_object() && d.contains("type") && d["type"].is_string() && d["type"] == "pool") {
        for (Json spec : shape_pool(sc)) {
          Config one(spec);
          tmpls.push_back(shape_from_config(one, dim, /*unit_size=*/true));
          tmpl_json.push_back(spec);
        }
        return;
      }
      tmpls.push_back(shape_from_config(sc, dim, /*unit_size=*/true));
      tmpl_json.push_back(sc.doc());
    };
    if (pc.doc().contains("shape") && pc.doc()["shape"].is_array()) {
      for (auto& sc : pc.children("shape")) add_template(sc);
      if (tmpls.empty()) pc.fail("shape", "needs at least one shape template");
    } else {
      add_template(pc.child("shape"));
    }
    const double fill = pc.number("fill_fraction", dim == 3 ? 0.2 : 0.35, 0.01, 0.5);
    const int material = static_cast<int>(pc.integer("material", 0, 0));
    Config st = pc.child("settle");
    spec.settle = st.boolean("enabled", true);
    spec.settle_settings.stress = st.number("stress", 10e3, 0.0);
    spec.settle_settings.max_time = st.positive("max_time", 0.5);
    spec.settle_settings.dt = st.number("dt", 0.0, 0.0);
    spec.settle_settings.tolerance = st.positive("tolerance", 1e-3);
    spec.settle_settings.window = st.positive("window", 0.01);
    spec.settle_settings.friction_scale = st.number("friction_scale", 1.0, 0.0, 1.0);

    std::vector<double> diam;
    std::vector<std::size_t> pick;
    for (long n = 0; n < count; ++n)
      pick.push_back(tmpls.size() == 1 ? 0 : static_cast<std::size_t>(rng.uniform() * tmpls.size()) % tmpls.size());
    if (keep_size) {
      for (std::size_t t : pick) diam.push_back(tmpls[t]->equivalent_diameter());
    } else if (mono > 0) {
      diam.assign(static_cast<std::size_t>(count), mono);
    } else {
      diam = sample_psd(psd, static_cast<std::size_t>(count), rng);
    }
    double vs = 0;
    std::vector<Shape::Ptr> shapes;
    std::vector<std::size_t> which;
    // Grains of the same template and size share one Shape (and so one level set / hull).
    std::map<std::pair<std::size_t, double>, Shape::Ptr> cache;
    for (std::size_t i = 0; i < diam.size(); ++i) {
      const std::size_t t = pick[i];
      const double d = diam[i];
      auto& sh = cache[{t, d}];
      if (!sh) sh = tmpls[t]->scaled(d / tmpls[t]->equivalent_diameter());
      shapes.push_back(sh);
      which.push_back(t);
      vs += sh->volume();
    }
    const double area = dim == 3 ? spec.container.lx * spec.container.ly : spec.container.lx;
    double rmax = 0;
    for (const auto& sh : shapes) rmax = std::max(rmax, sh->bounding_radius() * 1.01);
    // A cloud at fill_fraction; never lower than the largest grain (a few grains in a wide
    // box would otherwise get a cloud thinner than one of them).
    const double cloud_h = std::max(vs / (fill * area), 2 * rmax * 1.001);
    if (!height_given) spec.container.height = cloud_h;
    // Random sequential addition without overlap of bounding spheres, largest first.
    std::vector<std::size_t> order(shapes.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return diam[a] > diam[b]; });
    std::vector<Vec3> pos(shapes.size());
    std::vector<double> rad(shapes.size());
    // Placed grains binned on a grid of cell 2·rmax (>= any r + rad[q]), so a trial point is
    // checked against the grains of its own and the neighbouring cells only: the same
    // accept/reject decisions as checking every grain, in O(N) instead of O(N²).
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
    const double top = spec.container.height;
    for (std::size_t k : order) {
      const double r = shapes[k]->bounding_radius() * 1.01;
      rad[k] = r;
      if (2 * r > spec.container.lx || (dim == 3 && 2 * r > spec.container.ly) || 2 * r > top) {
        const std::string which = 2 * r > spec.container.lx                ? "container.lx = " + fmt_num(spec.container.lx)
                                  : dim == 3 && 2 * r > spec.container.ly ? "container.ly = " + fmt_num(spec.container.ly)
                                                                          : "container.height = " + fmt_num(top);
        pc.fail(keep_size ? "shape" : (mono > 0 ? "diameter" : "psd"),
                "a grain of equivalent diameter " + fmt_num(diam[k]) + " m needs a space " + fmt_num(2 * r) +
                    " m wide (its bounding sphere + 1 %), more than " + which +
                    " m; give a larger container or smaller grains");
      }
      bool ok = false;
      for (int attempt = 0; attempt < 20000 && !ok; ++attempt) {
        Vec3 p{rng.uniform(r, spec.container.lx - r), 0, 0};
        if (dim == 3) {
          p.y = rng.uniform(r, spec.container.ly - r);
          p.z = rng.uniform(r, top - r);
        } else {
          p.y = rng.uniform(r, top - r);
        }
        ok = true;
        const long ci = cell_of(p.x), cj = cell_of(p.y), ck = cell_of(p.z);
        for (long di = -1; di <= 1 && ok; ++di)
          for (long dj = -1; dj <= 1 && ok; ++dj)
            for (long dk = -1; dk <= 1 && ok; ++dk) {
              auto it = bins.find(key(ci + di, cj + dj, ck + dk));
              if (it == bins.end()) continue;
              for (std::size_t q : it->second)
                if (norm2(p - pos[q]) < (r + rad[q]) * (r + rad[q])) {
                  ok = false;
                  break;
                }
            }
        if (ok) pos[k] = p;
      }
      if (!ok)
        pc.fail("fill_fraction", "could not place " + std::to_string(count) +
                                     " grains without overlap; lower fill_fraction or give a taller container.height");
      bins[key(cell_of(pos[k].x), cell_of(pos[k].y), cell_of(pos[k].z))].push_back(k);
    }
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      PlacedGrain g;
      g.shape = shapes[i];
      g.shape_spec = scaled_spec(tmpl_json[which[i]], diam[i] / tmpls[which[i]]->equivalent_diameter());
      g.position = pos[i];
      g.orientation = random_orientation(rng, dim);
      g.material = material;
      g.source = pc.path();
      spec.grains.push_back(std::move(g));
    }
    return spec;
  }

  if (spec.type == "grains" || spec.type == "file") {
    Json loaded;
    std::vector<Config> entries;
    std::unique_ptr<Json> file_doc;
    std::unique_ptr<Config> file_cfg;
    if (spec.type == "file") {
      const std::string path = pc.string("path");
      std::ifstream in(path);
      if (!in) pc.fail("path", "cannot open packing file '" + path + "'");
      std::stringstream ss;
      ss << in.rdbuf();
      file_doc = std::make_unique<Json>(parse_json_text(ss.str(), path));
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
      // Unknown keys are checked once the grain entries are read (below).
    } else {
      entries = pc.children("grains");
      spec.settle = pc.boolean("settle", false);
    }
    if (entries.empty()) pc.fail(spec.type == "file" ? "path" : "grains", "the packing has no grains");
    if (spec.container.height <= 0) cc.fail("height", "required for an explicit packing");
    for (auto& e : entries) {
      PlacedGrain g;
      Config sc = e.required_child("shape");
      g.shape = shape_from_config(sc, dim);
      g.shape_spec = sc.doc();
      const Vec3 p = e.vec3("position", {0, 0, 0});
      if (!is_finite(p)) e.fail("position", "must be finite");
      g.position = p;
      auto q = e.numbers("orientation", {1, 0, 0, 0});
      if (q.size() != 4) e.fail("orientation", "expected a quaternion [w, x, y, z]");
      const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      if (!(n > 0)) e.fail("orientation", "quaternion must be non-zero");
      g.orientation = Quat{q[0] / n, q[1] / n, q[2] / n, q[3] / n};
      g.material = static_cast<int>(e.integer("material", 0, 0));
      g.source = spec.type == "file" ? pc.path() + "/path (" + pc.doc()["path"].get<std::string>() + ": " + e.path() + ")"
                                     : e.path();
      spec.grains.push_back(std::move(g));
    }
    if (spec.type == "file" && file_cfg) file_cfg->check_unknown();
    return spec;
  }
  return spec;
}

SettleResult build_packing(Simulation& sim, const PackingSpec& spec, const std::atomic<bool>* stop) {
  sim.set_container(spec.container);
  for (const auto& w : spec.walls) sim.add_moving_wall(w);
  if (spec.feed.count > 0) sim.set_feed(spec.feed);
  for (const auto& pg : spec.grains) {
    Grain g;
    g.shape = pg.shape;
    g.position = pg.position;
    g.orientation = pg.orientation;
    g.material = pg.material;
    sim.add_grain(std::move(g));
  }
  SettleResult res;
  if (!spec.settle) return res;
  // Zhu & Zhao 2019 §5: push the cloud down with a plate under a small force until stable.
  Engine& e = sim.engine();
  const auto& ss = spec.settle_settings;
  const double area = sim.context().dimension == 2 ? spec.container.lx : spec.container.lx * spec.container.ly;
  double dt = ss.dt > 0 ? ss.dt : sim.settings().time_steps.front().dt;
  dt = std::min(dt, e.max_stable_dt());
  double dmean = 0;
  for (const auto& g : sim.grains()) dmean += g.shape->equivalent_diameter();
  dmean /= std::max<std::size_t>(1, sim.grains().size());
  double last = e.platen_position();
  long steps = 0;
  const long window = std::max(1L, std::lround(ss.window / dt));
  const long max_steps = std::max(window, std::lround(ss.max_time / dt));
  e.set_platen({PlatenCommand::Mode::Force, ss.stress * area});
  if (!e.set_friction_scale(ss.friction_scale))
    throw ConfigError("/packing/settle/friction_scale", "the engine '" + e.name() +
                                                            "' cannot change friction while settling; use 1");
  const long guard_every = std::max(1L, sim.settings().sample_every);
  res.converged = false;
  while (steps < max_steps) {
    if (stop && stop->load()) {
      res.interrupted = true;
      break;
    }
    const double z0 = e.platen_position();
    e.step(dt);
    ++steps;
    sim.account_platen_work(e.platen_force(), e.platen_position() - z0);
    sim.check_guards("settling", dt, steps % guard_every == 0);
    if (steps % window == 0) {
      const double z = e.platen_position();
      const bool loaded = e.platen_force() > 0.5 * ss.stress * area;
      if (loaded && std::abs(last - z) < ss.tolerance * dmean) {
        res.converged = true;
        break;
      }
      last = z;
    }
  }
  res.steps = steps;
  e.set_friction_scale(1.0);
  e.set_platen({PlatenCommand::Mode::Velocity, 0.0});
  sim.sync_grains();
  return res;
}

Json packing_to_json(const Simulation& sim, const PackingSpec& spec) {
  Json j;
  j["dimension"] = sim.context().dimension;
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
