#include "core/ShapeSpec.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

namespace crumble {

namespace {

ShapeResolution resolution_from(const Config& c) {
  ShapeResolution r;
  if (!c.is_object("resolution") && !c.has("resolution")) return r;
  read_options(c.child("resolution"), shape_resolution_options(), r);
  return r;
}

std::vector<Vec3> point_list(const Config& c, const std::string& key, int dims) {
  const auto& j = c.raw(key);
  if (!j.is_array()) c.fail(key, "expected an array of points");
  std::vector<Vec3> out;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const auto& p = j[i];
    const std::string where = key + "/" + std::to_string(i);
    if (!p.is_array() || static_cast<int>(p.size()) != dims)
      c.fail(where, "expected an array of " + std::to_string(dims) + " numbers");
    Vec3 v;
    for (int k = 0; k < dims; ++k) {
      if (!p[k].is_number()) c.fail(where, "expected numbers");
      v[k] = p[k].get<double>();
      if (!std::isfinite(v[k])) c.fail(where, "expected finite numbers");
    }
    out.push_back(v);
  }
  return out;
}

template <class F>
Shape::Ptr guarded(const Config& c, F&& f) {
  try {
    return f();
  } catch (const std::invalid_argument& e) {
    c.fail("", std::string("invalid shape: ") + e.what());
  }
}

}  // namespace

TriMesh read_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot open mesh file '" + path + "'");
  TriMesh m;
  std::string line;
  int ln = 0;
  while (std::getline(in, line)) {
    ++ln;
    std::istringstream is(line);
    std::string tag;
    if (!(is >> tag)) continue;
    if (tag == "v") {
      Vec3 v;
      if (!(is >> v.x >> v.y >> v.z) || !is_finite(v))
        throw std::invalid_argument(path + ":" + std::to_string(ln) + ": malformed vertex line");
      m.vertices.push_back(v);
    } else if (tag == "f") {
      std::vector<int> idx;
      std::string tok;
      while (is >> tok) {
        const auto slash = tok.find('/');
        int k = 0;
        try {
          k = std::stoi(tok.substr(0, slash));
        } catch (...) {
          throw std::invalid_argument(path + ":" + std::to_string(ln) + ": malformed face index '" + tok + "'");
        }
        if (k < 0) k = static_cast<int>(m.vertices.size()) + 1 + k;
        if (k < 1 || k > static_cast<int>(m.vertices.size()))
          throw std::invalid_argument(path + ":" + std::to_string(ln) + ": face index out of range");
        idx.push_back(k - 1);
      }
      if (idx.size() < 3) throw std::invalid_argument(path + ":" + std::to_string(ln) + ": face with < 3 vertices");
      for (std::size_t i = 1; i + 1 < idx.size(); ++i) m.triangles.push_back({idx[0], idx[i], idx[i + 1]});
    }
  }
  if (m.triangles.empty()) throw std::invalid_argument("mesh file '" + path + "' has no faces");
  return m;
}

nlohmann::json level_set_to_json(const LevelSetGrid& g) {
  using Json = nlohmann::json;
  const Vec3 o = g.origin();
  const auto n = g.counts();
  Json nodes = Json::array();
  for (const auto& x : g.nodes()) nodes.push_back({x.x, x.y, x.z});
  return Json{{"type", "level_set"},
              {"dimension", g.dimension()},
              {"origin", {o.x, o.y, o.z}},
              {"spacing", g.spacing()},
              {"counts", {n[0], n[1], n[2]}},
              {"values", g.values()},
              {"node_spacing", g.node_spacing()},
              {"nodes", nodes},
              {"node_weights", g.node_weights()}};
}

namespace {

// {"type": "level_set", ...}: the grid as written by level_set_to_json.
Shape::Ptr level_set_from_config(const Config& c, int dim, const ShapeResolution& res) {
  c.integer("dimension", dim, dim, dim);
  const auto o = c.numbers("origin");
  if (o.size() != 3) c.fail("origin", "expected [x, y, z] (m)");
  for (std::size_t i = 0; i < 3; ++i)
    if (!std::isfinite(o[i])) c.fail("origin/" + std::to_string(i), "expected a finite number");
  const double h = c.positive("spacing");
  const auto& nj = c.raw("counts");
  if (!nj.is_array() || nj.size() != 3) c.fail("counts", "expected 3 integer node counts [nx, ny, nz]");
  std::array<int, 3> n{};
  double total = 1;
  for (int a = 0; a < 3; ++a) {
    const int need = (a == 2 && dim == 2) ? 1 : 2;
    if (!nj[a].is_number_integer() || nj[a].get<long>() < need || nj[a].get<long>() > 100000 ||
        (a == 2 && dim == 2 && nj[a].get<long>() != 1))
      c.fail("counts/" + std::to_string(a),
             a == 2 && dim == 2 ? "expected 1 in 2D" : "expected an integer >= 2");
    n[a] = nj[a].get<int>();
    total *= n[a];
  }
  const auto& vj = c.raw("values");
  if (!vj.is_array() || static_cast<double>(vj.size()) != total)
    c.fail("values", "expected an array of " + std::to_string(static_cast<long>(total)) +
                         " numbers (counts[0]·counts[1]·counts[2], x fastest)");
  std::vector<double> v(vj.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!vj[i].is_number() || !std::isfinite(vj[i].get<double>()))
      c.fail("values/" + std::to_string(i), "expected a finite number");
    v[i] = vj[i].get<double>();
  }
  const double hs = c.number("node_spacing", 0.0, 0.0);
  const bool given_nodes = c.has("nodes");
  std::vector<Vec3> nodes;
  std::vector<double> w;
  if (given_nodes) {
    nodes = point_list(c, "nodes", 3);
    w = c.numbers("node_weights");
    if (w.size() != nodes.size())
      c.fail("node_weights", "expected one weight per node (" + std::to_string(nodes.size()) + ")");
    for (std::size_t i = 0; i < w.size(); ++i)
      if (!(w[i] > 0) || !std::isfinite(w[i])) c.fail("node_weights/" + std::to_string(i), "expected a number > 0");
  } else if (c.has("node_weights")) {
    c.fail("node_weights", "given without nodes");
  }
  return guarded(c, [&] {
    auto g = LevelSetGrid::from_values(dim, {o[0], o[1], o[2]}, h, n, std::move(v), hs, !given_nodes, "level_set shape");
    if (given_nodes) g = g->with_nodes(std::move(nodes), std::move(w));
    return Shape::from_level_set(std::move(g), res);
  });
}

}  // namespace

std::vector<Vec3> random_outline(const RandomOutlineSpec& spec) {
  if (spec.vertices < 3) throw std::invalid_argument("random outline needs at least 3 vertices");
  if (!(spec.irregularity >= 0 && spec.irregularity < 1)) throw std::invalid_argument("irregularity must be in [0, 1)");
  if (spec.modes < 2) throw std::invalid_argument("random outline needs modes >= 2");
  if (!(spec.radius > 0)) throw std::invalid_argument("random outline needs a radius > 0");
  // Own generator (not core's Rng): the outline depends on this spec's seed only, and the
  // doubles come from the raw 64-bit draws, identical on every standard library.
  std::mt19937_64 gen(spec.seed);
  auto uniform = [&gen] { return static_cast<double>(gen() >> 11) * 0x1.0p-53; };
  // r(θ) = R (1 + Σ_{k=2..K} a_k cos(kθ + φ_k)): smooth random radii (mode 1 would only
  // shift the centroid), a_k = irregularity · u_k k^-decay / Σ_j j^-decay with u_k uniform in
  // [0, 1], so Σ a_k ≤ irregularity, r ≥ R (1 − irregularity) > 0 and the outline is
  // star-shaped about the origin: a simple CCW polygon; outlines of one pool differ in how
  // irregular they are, not only in their phases.
  std::vector<double> amp, phase;
  double wsum = 0;
  for (int k = 2; k <= spec.modes; ++k) wsum += std::pow(static_cast<double>(k), -spec.decay);
  for (int k = 2; k <= spec.modes; ++k) {
    amp.push_back(spec.irregularity * uniform() * std::pow(static_cast<double>(k), -spec.decay) / wsum);
    phase.push_back(2 * kPi * uniform());
  }
  std::vector<Vec3> v;
  v.reserve(static_cast<std::size_t>(spec.vertices));
  for (int i = 0; i < spec.vertices; ++i) {
    const double t = 2 * kPi * i / spec.vertices;
    double r = 1;
    for (std::size_t m = 0; m < amp.size(); ++m) r += amp[m] * std::cos(static_cast<double>(m + 2) * t + phase[m]);
    v.push_back({spec.radius * r * std::cos(t), spec.radius * r * std::sin(t), 0});
  }
  return v;
}

namespace {

// A template's radius defaults (its table's); a grain's must be given.
RandomOutlineSpec random_outline_spec(const Config& c, bool unit) {
  if (!unit) c.positive("radius");
  return read_options<RandomOutlineSpec>(c, random_polygon_options());
}

}  // namespace

std::vector<nlohmann::json> shape_pool(const Config& c) {
  c.choice("type", "pool", {"pool"});
  const long count = read_options<PoolSettings>(c, pool_options()).count;
  const RandomOutlineSpec s = random_outline_spec(c, /*unit=*/true);
  std::vector<nlohmann::json> out;
  for (long i = 0; i < count; ++i)
    out.push_back({{"type", "random_polygon"},
                   {"vertices", s.vertices},
                   {"irregularity", s.irregularity},
                   {"modes", s.modes},
                   {"decay", s.decay},
                   {"seed", s.seed + static_cast<std::uint64_t>(i)},
                   {"radius", s.radius}});
  return out;
}

Shape::Ptr shape_from_config(const Config& c, int dim, bool unit) {
  const std::vector<std::string> kinds3 = {"sphere", "ellipsoid", "superellipsoid", "box", "polyhedron", "level_set"};
  const std::vector<std::string> kinds2 = {"disk", "ellipse", "superellipse", "polygon", "random_polygon", "level_set"};
  const std::string type = c.choice("type", dim == 3 ? "sphere" : "disk", dim == 3 ? kinds3 : kinds2);
  const ShapeResolution res = resolution_from(c);
  // Unit templates: sizes default so that the equivalent diameter is about 1 m; the
  // packing rescales each grain exactly to its drawn diameter.
  auto length = [&](const std::string& key, double def) { return unit ? c.positive(key, def) : c.positive(key); };
  auto lengths = [&](const std::string& key, std::vector<double> def, std::size_t n) {
    auto v = unit ? c.numbers(key, def) : c.numbers(key);
    if (v.size() != n) c.fail(key, "expected " + std::to_string(n) + " numbers");
    for (std::size_t i = 0; i < n; ++i)
      if (!(v[i] > 0)) c.fail(key + "/" + std::to_string(i), "expected a length > 0");
    return v;
  };
  const double scale = read_options<ShapeSettings>(c, shape_options()).scale;
  Shape::Ptr base = guarded(c, [&]() -> Shape::Ptr {
    if (type == "level_set") return level_set_from_config(c, dim, res);
    if (type == "sphere") return Shape::sphere(length("radius", 0.5), res);
    if (type == "ellipsoid") {
      auto r = lengths("radii", {0.5, 0.5, 0.5}, 3);
      return Shape::ellipsoid({r[0], r[1], r[2]}, res);
    }
    if (type == "superellipsoid") {
      auto r = lengths("radii", {0.5, 0.5, 0.5}, 3);
      const auto e = read_options<SuperellipsoidSettings>(c, superellipsoid_options());
      return Shape::superellipsoid({r[0], r[1], r[2]}, e.eps1, e.eps2, res);
    }
    if (type == "box") {
      auto h = lengths("half_extents", {0.4, 0.4, 0.4}, 3);
      return Shape::box({h[0], h[1], h[2]}, res);
    }
    if (type == "polyhedron") {
      TriMesh m;
      if (c.has("file")) {
        m = read_obj(c.string("file"));
      } else {
        m.vertices = point_list(c, "vertices", 3);
        const auto& t = c.raw("triangles");
        if (!t.is_array()) c.fail("triangles", "expected an array of index triples");
        for (std::size_t i = 0; i < t.size(); ++i) {
          if (!t[i].is_array() || t[i].size() != 3 || !t[i][0].is_number_integer() ||
              !t[i][1].is_number_integer() || !t[i][2].is_number_integer())
            c.fail("triangles/" + std::to_string(i), "expected 3 integer vertex indices");
          m.triangles.push_back({t[i][0].get<int>(), t[i][1].get<int>(), t[i][2].get<int>()});
        }
      }
      return Shape::polyhedron(std::move(m), res);
    }
    if (type == "disk") return Shape::disk(length("radius", 0.5), res);
    if (type == "ellipse") {
      auto r = lengths("radii", {0.5, 0.5}, 2);
      return Shape::ellipse(r[0], r[1], res);
    }
    if (type == "superellipse") {
      auto r = lengths("radii", {0.5, 0.5}, 2);
      return Shape::superellipse(r[0], r[1], read_options<SuperellipseSettings>(c, superellipse_options()).eps, res);
    }
    if (type == "random_polygon") return Shape::polygon(random_outline(random_outline_spec(c, unit)), res);
    return Shape::polygon(point_list(c, "vertices", 2), res);
  });
  return scale == 1.0 ? base : guarded(c, [&] { return base->scaled(scale); });
}

// ------------------------------------------------------------------ option tables

const OptionTable& shape_options() {
  static const OptionTable t{opt::positive("scale", &ShapeSettings::scale, "", "uniform factor on the shape's size")};
  return t;
}

const OptionTable& shape_resolution_options() {
  using S = ShapeResolution;
  static const OptionTable t{
      opt::integer("mesh_subdivisions", &S::mesh_subdivisions, 0, 6,
                   "icosphere level of round shapes (1 → 42 vertices, as Zhu & Zhao 2019)"),
      opt::number("level_set_spacing", &S::level_set_spacing, 0, std::numeric_limits<double>::infinity(), "m",
                  "grid spacing of the shape's level set; 0 = its smallest extent / 20"),
      opt::integer("surface_nodes", &S::surface_nodes, 0, 10000000, "surface points of its level set; 0 = automatic"),
  };
  return t;
}

const OptionTable& superellipsoid_options() {
  using S = SuperellipsoidSettings;
  static const OptionTable t{
      opt::number("eps1", &S::eps1, 1e-3, 2, "", "ε1: squareness in the xy-plane (1 = ellipse, → 0 = box)"),
      opt::number("eps2", &S::eps2, 1e-3, 2, "", "ε2: squareness along z"),
  };
  return t;
}

const OptionTable& superellipse_options() {
  static const OptionTable t{
      opt::number("eps", &SuperellipseSettings::eps, 1e-3, 2, "", "squareness (1 = ellipse, → 0 = rectangle)")};
  return t;
}

const OptionTable& random_polygon_options() {
  using S = RandomOutlineSpec;
  static const OptionTable t{
      opt::integer("vertices", &S::vertices, 3, 100000, "outline vertices, equally spaced in angle"),
      opt::number("irregularity", &S::irregularity, 0, 0.9, "", "radii stay within radius·(1 ± irregularity)"),
      opt::integer("modes", &S::modes, 2, 1000, "highest Fourier mode k of the radius"),
      opt::number("decay", &S::decay, 0, 10, "", "mode amplitudes fall as k^−decay"),
      opt::unsigned_integer("seed", &S::seed, "draws the amplitudes and phases"),
      opt::positive("radius", &S::radius, "m", "mean radius; a grain must give it, a packing template defaults"),
  };
  return t;
}

const OptionTable& pool_options() {
  static const OptionTable t{
      opt::integer("count", &PoolSettings::count, 1, 100000, "random_polygon outlines, seeds seed, seed + 1, …")};
  return t;
}

}  // namespace crumble
