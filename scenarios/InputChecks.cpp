#include "scenarios/InputChecks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/Format.h"

namespace crumble {

void check_packing_materials(const PackingSpec& spec, std::size_t n) {
  for (const auto& g : spec.grains)
    if (g.material < 0 || static_cast<std::size_t>(g.material) >= n)
      throw ConfigError(g.source + "/material",
                        "material index " + std::to_string(g.material) + " does not exist: the scenario defines " +
                            std::to_string(n) + " material" + (n == 1 ? "" : "s") + " (/materials/0" +
                            (n > 1 ? " … /materials/" + std::to_string(n - 1) : std::string()) +
                            "); expected an index in [0, " + std::to_string(n - 1) + "]");
}

namespace {

bool is_round(const Shape& s) { return s.kind() == ShapeKind::Sphere || s.kind() == ShapeKind::Disk; }

// Beyond the tolerance by more than rounding: a grain placed exactly at it (an overlap of
// 1 % of the diameter, from positions and a diameter that are not exact in binary) is
// accepted. 1e-9 relative is far above the rounding of either side and far below any
// physical difference.
bool beyond(double value, double slack) { return value > slack * (1 + 1e-9); }

// Points on the surface of a grain (world frame): mesh vertices and triangle centroids in
// 3D, outline vertices and edge midpoints in 2D (vertices alone miss two flat faces pressed
// into each other).
std::vector<Vec3> surface_points(const PlacedGrain& g) {
  std::vector<Vec3> local;
  if (g.shape->dimension() == 3) {
    const TriMesh& m = g.shape->mesh();
    local = m.vertices;
    for (const auto& t : m.triangles) local.push_back((m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0);
  } else {
    const auto& o = g.shape->outline();
    local = o;
    for (std::size_t i = 0; i < o.size(); ++i) local.push_back(0.5 * (o[i] + o[(i + 1) % o.size()]));
  }
  std::vector<Vec3> out;
  out.reserve(local.size());
  for (const auto& v : local) out.push_back(g.position + g.orientation.rotate(v));
  return out;
}

// How deep the surface of `a` reaches into `b` (m; ≤ 0 when it does not).
double depth_into(const PlacedGrain& a, const std::vector<Vec3>& pa, const PlacedGrain& b) {
  double d = -std::numeric_limits<double>::infinity();
  for (const auto& p : pa) d = std::max(d, -b.shape->signed_distance(b.orientation.conjugate().rotate(p - b.position)));
  return d;
}

}  // namespace

void check_explicit_grains(const PackingSpec& spec, int dim, double tol) {
  if (spec.type != "grains") return;
  const Container& c = spec.container;
  const int up = dim == 3 ? 2 : 1;
  std::vector<std::vector<Vec3>> pts(spec.grains.size());
  for (std::size_t i = 0; i < spec.grains.size(); ++i) {
    const PlacedGrain& g = spec.grains[i];
    const double d = g.shape->equivalent_diameter(), slack = tol * d;
    Vec3 lo, hi;
    if (is_round(*g.shape)) {
      const double r = g.shape->bounding_radius();
      lo = g.position - Vec3{r, r, r};
      hi = g.position + Vec3{r, r, r};
    } else {
      pts[i] = surface_points(g);
      lo = hi = pts[i].front();
      for (const auto& p : pts[i])
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], p[k]);
          hi[k] = std::max(hi[k], p[k]);
        }
    }
    auto outside = [&](const std::string& what, double by) {
      const auto [by_text, slack_text] = fmt_apart(by, slack);
      throw ConfigError(g.source + "/position",
                        "grain " + std::to_string(i) + " (" + g.shape->describe() + ", equivalent diameter " +
                            fmt_num(d) + " m) at [" + fmt_num(g.position.x) + ", " + fmt_num(g.position.y) +
                            (dim == 3 ? ", " + fmt_num(g.position.z) : std::string()) + "] reaches " + by_text +
                            " m " + what + " (tolerance " + slack_text + " m = " + fmt_num(100 * tol) +
                            " % of its diameter); move it inside the container or enlarge /container");
    };
    if (beyond(-lo.x, slack)) outside("beyond the wall x = 0", -lo.x);
    if (beyond(hi.x - c.lx, slack)) outside("beyond the wall x = container.lx = " + fmt_num(c.lx) + " m", hi.x - c.lx);
    if (dim == 3 && beyond(-lo.y, slack)) outside("beyond the wall y = 0", -lo.y);
    if (dim == 3 && beyond(hi.y - c.ly, slack))
      outside("beyond the wall y = container.ly = " + fmt_num(c.ly) + " m", hi.y - c.ly);
    if (beyond(-lo[up], slack)) outside("below the floor", -lo[up]);
    if (beyond(hi[up] - c.height, slack))
      outside("above the platen at container.height = " + fmt_num(c.height) + " m", hi[up] - c.height);
  }
  // Pairs: bounding spheres first, then the exact test.
  for (std::size_t i = 0; i < spec.grains.size(); ++i) {
    const PlacedGrain& a = spec.grains[i];
    const double ra = a.shape->bounding_radius();
    for (std::size_t j = i + 1; j < spec.grains.size(); ++j) {
      const PlacedGrain& b = spec.grains[j];
      const double rb = b.shape->bounding_radius();
      const double dist = norm(a.position - b.position);
      if (dist >= ra + rb) continue;
      const double slack = tol * std::min(a.shape->equivalent_diameter(), b.shape->equivalent_diameter());
      double overlap;
      if (is_round(*a.shape) && is_round(*b.shape)) {
        overlap = ra + rb - dist;
      } else {
        if (pts[i].empty()) pts[i] = surface_points(a);
        if (pts[j].empty()) pts[j] = surface_points(b);
        overlap = std::max(depth_into(a, pts[i], b), depth_into(b, pts[j], a));
      }
      if (!beyond(overlap, slack)) continue;
      const auto [overlap_text, slack_text] = fmt_apart(overlap, slack);
      throw ConfigError(b.source + "/position",
                        "grain " + std::to_string(j) + " overlaps grain " + std::to_string(i) + " (" + a.source +
                            ") by " + overlap_text + " m, more than the tolerance " + slack_text + " m (" +
                            fmt_num(100 * tol) + " % of the smaller diameter); move the grains apart");
    }
  }
}

double packing_stable_dt(Engine& probe, const PackingSpec& spec, const std::vector<Material>& materials) {
  if (spec.grains.empty()) return std::numeric_limits<double>::infinity();
  // The bound depends on the lightest grain and on the extreme sizes (Hertz contacts).
  std::size_t light = 0, small = 0, large = 0;
  auto mass = [&](const PlacedGrain& g) {
    const auto m = static_cast<std::size_t>(g.material);
    return g.shape->volume() * (m < materials.size() ? materials[m].density : 1.0);
  };
  for (std::size_t i = 1; i < spec.grains.size(); ++i) {
    const auto& g = spec.grains[i];
    if (mass(g) < mass(spec.grains[light])) light = i;
    if (g.shape->equivalent_diameter() < spec.grains[small].shape->equivalent_diameter()) small = i;
    if (g.shape->equivalent_diameter() > spec.grains[large].shape->equivalent_diameter()) large = i;
  }
  probe.set_container(spec.container);
  GrainId id = 0;
  for (std::size_t i : {light, small, large}) {
    if (i != light && (i == small ? small == light : (large == light || large == small))) continue;
    Grain g;
    g.id = id++;
    g.shape = spec.grains[i].shape;
    g.position = spec.grains[i].position;
    g.orientation = spec.grains[i].orientation;
    g.material = spec.grains[i].material;
    probe.add_grain(g);
  }
  return probe.max_stable_dt();
}

}  // namespace crumble
