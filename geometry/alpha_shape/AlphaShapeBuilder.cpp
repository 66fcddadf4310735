#include "geometry/alpha_shape/AlphaShapeBuilder.h"
#include "base/Format.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "base/BuildCounters.h"
#include "geometry/ConvexHull.h"
#include "geometry/cgal/MeshClip.h"

namespace crumble {

namespace {

// Vertices in lexicographic order, each triangle starting at its smallest index, triangles
// sorted: a canonical form of a mesh that keeps its orientation.
void canonicalize(TriMesh& m) {
  std::vector<int> order(m.vertices.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const Vec3 &p = m.vertices[a], &q = m.vertices[b];
    return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z);
  });
  std::vector<int> rank(order.size());
  std::vector<Vec3> v(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<int>(i);
    v[i] = m.vertices[order[i]];
  }
  m.vertices = std::move(v);
  for (auto& t : m.triangles) {
    t = {rank[t[0]], rank[t[1]], rank[t[2]]};
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};  // rotate: orientation kept
  }
  std::sort(m.triangles.begin(), m.triangles.end());
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double diameter_of_volume(double v) { return std::cbrt(6.0 * v / kPi); }

void validate(const PointClusters& pc) {
  const std::size_t n = pc.points.size();
  if (!(pc.spacing > 0) || !std::isfinite(pc.spacing))
    throw std::invalid_argument("PointClusters: spacing must be > 0 (got " + fmt_num(pc.spacing) + ")");
  if (pc.clusters < 1) throw std::invalid_argument("PointClusters: clusters must be >= 1");
  const Quat& q = pc.frame;
  const double qn = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  if (!std::isfinite(qn) || std::abs(qn - 1) > 1e-9)
    throw std::invalid_argument("PointClusters: frame must be a unit quaternion");
  if (pc.cluster.size() != n)
    throw std::invalid_argument("PointClusters: cluster has " + std::to_string(pc.cluster.size()) +
                                " entries for " + std::to_string(n) + " points");
  if (!pc.on_surface.empty() && pc.on_surface.size() != n)
    throw std::invalid_argument("PointClusters: on_surface has " + std::to_string(pc.on_surface.size()) +
                                " entries for " + std::to_string(n) + " points");
  if (!pc.fracture_points.empty() && pc.fracture_points.size() != static_cast<std::size_t>(pc.clusters))
    throw std::invalid_argument("PointClusters: fracture_points has " + std::to_string(pc.fracture_points.size()) +
                                " lists for " + std::to_string(pc.clusters) + " clusters");
  for (std::size_t i = 0; i < n; ++i) {
    if (pc.cluster[i] < 0 || pc.cluster[i] >= pc.clusters)
      throw std::invalid_argument("PointClusters: point " + std::to_string(i) + " has cluster " +
                                  std::to_string(pc.cluster[i]) + " outside [0, " + std::to_string(pc.clusters) + ")");
    if (!is_finite(pc.points[i])) throw std::invalid_argument("PointClusters: point " + std::to_string(i) + " is not finite");
  }
  for (const auto& fp : pc.fracture_points)
    for (const auto& p : fp)
      if (!is_finite(p)) throw std::invalid_argument("PointClusters: a fracture point is not finite");
}

// Last resort for clusters whose points are (nearly) flat or too few for a hull: the
// hull of the cubes of side `spacing` around each material point (the volume each
// lattice point stands for), so a cluster never loses its child.
TriMesh cube_hull(const std::vector<Vec3>& pts, double spacing) {
  std::vector<Vec3> corners;
  corners.reserve(8 * pts.size());
  const double h = 0.5 * spacing;
  for (const auto& p : pts)
    for (int k = 0; k < 8; ++k) corners.push_back(p + Vec3{(k & 1) ? h : -h, (k & 2) ? h : -h, (k & 4) ? h : -h});
  return convex_hull(corners);  // geometry/ConvexHull: deterministic, allocation-order free
}

}  // namespace

AlphaShapeBuilder::AlphaShapeBuilder(AlphaShapeBuilderOptions opt) : opt_(std::move(opt)) {
  // Every option in its declared range (alpha_shape_options).
  check_options(alpha_shape_options(), opt_, "AlphaShapeBuilder");
}

FragmentResult AlphaShapeBuilder::build(const Shape& parent, const Fracture& fracture) const {
  return build(parent, fracture, nullptr);
}

FragmentResult AlphaShapeBuilder::build(const Shape& parent, const Fracture& fracture,
                                        std::vector<ChildReport>* reports) const {
  if (parent.dimension() != 3)
    throw std::invalid_argument("fragment builder 'alpha_shape' is 3D only (parent is " + parent.describe() + ")");
  if (reports) reports->clear();
  return std::visit(
      [&](const auto& f) {
        using T = std::decay_t<decltype(f)>;
        if constexpr (std::is_same_v<T, PointClusters>)
          return from_clusters(parent, f, reports);
        else
          return from_planes(parent, f, reports);
      },
      fracture);
}

// Zhu & Zhao 2019 §3.2: boundary vertices = original surface points + fracture-surface points;
// alpha shape with Euler characteristic 2 and no self-intersection; convex hull when
// d_e < 0.7 mm or convexity >= 0.85; uniform rescaling to the parent's volume.
FragmentResult AlphaShapeBuilder::from_clusters(const Shape& parent, const PointClusters& pc,
                                                std::vector<ChildReport>* rep) const {
  validate(pc);
  FragmentResult out;
  std::vector<std::vector<Vec3>> boundary(pc.clusters), material(pc.clusters);
  for (std::size_t i = 0; i < pc.points.size(); ++i) {
    const int c = pc.cluster[i];
    material[c].push_back(pc.points[i]);
    // Boundary vertices (Zhu & Zhao 2019 §3.2): surface points + fracture points. They feed the
    // convex hulls and the alpha shape with alpha_boundary_only; without surface flags
    // every point of the cluster counts as a boundary vertex (same hull, slower).
    if (pc.on_surface.empty() || pc.on_surface[i]) boundary[c].push_back(pc.points[i]);
  }
  if (!pc.fracture_points.empty())
    for (int c = 0; c < pc.clusters; ++c)
      boundary[c].insert(boundary[c].end(), pc.fracture_points[c].begin(), pc.fracture_points[c].end());

  const double n_total = static_cast<double>(pc.points.size());
  AlphaShapeOptions aopt = opt_.alpha;
  aopt.spacing = pc.spacing;
  std::vector<TriMesh> meshes;
  std::vector<ChildReport> reports;
  int n_alpha = 0, n_hull = 0;
  for (int c = 0; c < pc.clusters; ++c) {
    if (material[c].empty()) continue;  // no material, no child (nothing is lost)
    const auto t0 = std::chrono::steady_clock::now();
    ChildReport r;
    r.boundary_points = static_cast<int>(boundary[c].size());
    r.cluster_points = static_cast<int>(material[c].size());
    // The size rule uses the child's final size, estimated from its share of the
    // parent's material points (the alpha shape itself is shrunk by the lattice).
    const double d_est = diameter_of_volume(parent.volume() * material[c].size() / n_total);
    TriMesh mesh;
    bool have = false;
    // The hull of the boundary points, once: the convexity test and the hull child share it.
    std::optional<TriMesh> boundary_hull;
    if (d_est < opt_.hull_diameter) {
      r.method = "convex_hull";
      r.note = "d_e " + fmt_num(d_est) + " m < convex_hull_diameter";
    } else if (boundary[c].size() >= 4) {
      std::vector<Vec3> input = boundary[c];
      if (!opt_.alpha_boundary_only) {
        input = material[c];
        if (!pc.fracture_points.empty())
          input.insert(input.end(), pc.fracture_points[c].begin(), pc.fracture_points[c].end());
      }
      count_built(Representation::AlphaShape);
      const AlphaShapeResult a = alpha_shape_polyhedron(input, aopt);
      r.alpha = a.alpha;
      r.alpha_steps = a.steps;
      if (a.ok) {
        try {
          boundary_hull = convex_hull(boundary[c]);
          const double v_hull = polyhedron_mass_properties(*boundary_hull).volume;
          r.convexity = polyhedron_mass_properties(a.mesh).volume / v_hull;
        } catch (const std::invalid_argument&) {
          r.convexity = 1;  // cannot happen for a closed alpha shape; treat as convex
        }
        if (r.convexity >= opt_.hull_convexity) {
          r.method = "convex_hull";
          r.note = "convexity " + fmt_num(r.convexity) + " >= convex_hull_convexity";
        } else {
          r.method = "alpha_shape";
          mesh = a.mesh;
          have = true;
        }
      } else {
        r.method = "hull_fallback";
        r.note = "no valid alpha: " + a.failure;
      }
    } else {
      r.method = "hull_fallback";
      r.note = "fewer than 4 boundary points";
    }
    if (!have) {
      try {
        if (boundary_hull && boundary[c].size() >= 4)
          mesh = std::move(*boundary_hull);
        else
          mesh = convex_hull(boundary[c].size() >= 4 ? boundary[c] : material[c]);
      } catch (const std::invalid_argument& e) {
        // Flat or tiny cluster: hull of the points' lattice cells.
        std::vector<Vec3> pts = material[c];
        if (!pc.fracture_points.empty()) pts.insert(pts.end(), pc.fracture_points[c].begin(), pc.fracture_points[c].end());
        mesh = cube_hull(pts, pc.spacing);
        r.method = "hull_fallback";
        r.note += std::string(r.note.empty() ? "" : "; ") + e.what() + " -> hull of the points' lattice cells";
      }
    }
    if (r.method == "hull_fallback") ++out.fallbacks;
    (r.method == "alpha_shape" ? n_alpha : n_hull)++;
    r.seconds = seconds_since(t0);
    meshes.push_back(std::move(mesh));
    reports.push_back(std::move(r));
  }
  out.method = n_hull == 0 ? "alpha_shape" : (n_alpha == 0 ? "convex_hull" : "alpha_shape+convex_hull");
  out.children = finish(std::move(meshes), parent.volume(), &reports, pc.frame);
  if (rep) *rep = std::move(reports);
  return out;
}

FragmentResult AlphaShapeBuilder::from_planes(const Shape& parent, const CuttingSurfaces& cs,
                                              std::vector<ChildReport>* rep) const {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<ClipPlane> planes;
  for (const auto& p : cs.planes) {
    if (!is_finite(p.normal) || !std::isfinite(p.offset) || !(norm(p.normal) > 0))
      throw std::invalid_argument("split_by_planes: a cutting plane has a zero or non-finite normal/offset");
    planes.push_back({p.normal, p.offset});
  }
  FragmentResult out;
  out.method = "plane_cut";
  std::vector<TriMesh> pieces;
  try {
    count_built(Representation::MeshClip);
    pieces = split_by_planes(parent.mesh(), planes);
  } catch (const std::exception&) {
    // The parent's mesh cannot be cut (an alpha-shape child that CGAL finds
    // self-intersecting, or a degenerate cut): cut its convex hull instead, which is
    // always a valid solid. Counted as a fallback; the rescaling below restores the volume.
    ++out.fallbacks;
    out.method = "plane_cut_hull";
    try {
      count_built(Representation::MeshClip);
      pieces = split_by_planes(parent.convex_hull(), planes);
    } catch (const std::exception&) {
      out.method = "no_split";  // nothing can be cut: the grain stays whole
      return out;
    }
  }
  // Pieces are dropped as removed volume (fines, FragmentBuilder.h) when smaller than
  // min_piece_volume_fraction × V_parent or thinner than min_piece_thickness_fraction ×
  // d_parent (thickness = twice the distance from the piece's centroid to the nearest face
  // of its convex hull): a plane grazing the surface leaves slivers that no engine can
  // take as a body (Bullet insets a hull by its collision margin). The mesh volumes are
  // scaled by V_parent / Σ mesh volumes (the parent's mesh may differ from its analytic
  // volume, e.g. a sphere's icosphere), so children + removed = V_parent exactly.
  const double d_parent = parent.equivalent_diameter();
  double v_all = 0, v_removed = 0;
  std::vector<TriMesh> kept;
  for (auto& m : pieces) {
    const double v = polyhedron_mass_properties(m).volume;
    v_all += v;
    double thickness = 0;
    try {
      thickness = 2 * convex_inradius_about_centroid(convex_hull(m.vertices));
    } catch (const std::invalid_argument&) {
      thickness = 0;  // flat: no hull
    }
    if (v < opt_.min_piece_volume_fraction * parent.volume() ||
        !(thickness >= opt_.min_piece_thickness_fraction * d_parent)) {
      ++out.fallbacks;
      v_removed += v;
      continue;
    }
    kept.push_back(std::move(m));
  }
  if (kept.empty() || !(v_all > 0)) {
    out.method = "no_split";
    return out;
  }
  const double k = parent.volume() / v_all;
  out.removed_volume = k * v_removed;
  std::vector<ChildReport> reports(kept.size());
  const double dt = seconds_since(t0);
  for (auto& r : reports) {
    r.method = out.method;
    r.seconds = dt / static_cast<double>(reports.size());
  }
  out.children = finish(std::move(kept), parent.volume() - out.removed_volume, &reports);
  if (rep) *rep = std::move(reports);
  return out;
}

std::vector<Fragment> AlphaShapeBuilder::finish(std::vector<TriMesh> meshes, double target,
                                                std::vector<ChildReport>* rep, const Quat& frame) const {
  const bool rotate = !(frame.w == 1 && frame.x == 0 && frame.y == 0 && frame.z == 0);
  if (meshes.empty()) throw std::runtime_error("fragment builder 'alpha_shape': no child could be built");
  // CGAL walks its cells in an order that follows heap addresses; sort each mesh so the
  // children (and every sum over their vertices) do not depend on the allocator's history.
  for (auto& m : meshes) canonicalize(m);
  double sum = 0;
  std::vector<Vec3> centroid(meshes.size());
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const MassProperties mp = polyhedron_mass_properties(meshes[i]);
    sum += mp.volume;
    centroid[i] = mp.centroid;
    if (rep) (*rep)[i].raw_volume = mp.volume;
  }
  if (!(sum > 0)) throw std::runtime_error("fragment builder 'alpha_shape': children have no volume");
  // Uniform scaling of all children (Zhu & Zhao 2019 §3.2: "shrunken slightly until the total
  // volume of child particles equals the volume of the parent"; alpha shapes through
  // lattice points grow instead).
  const double f = std::cbrt(target / sum);
  if (rep)
    for (auto& r : *rep) r.scale = f;
  std::vector<Fragment> out;
  out.reserve(meshes.size());
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const Vec3 centre = opt_.scale_about_parent ? Vec3{} : centroid[i];
    for (auto& v : meshes[i].vertices) v = centre + (v - centre) * f;
    if (rotate)
      for (auto& v : meshes[i].vertices) v = frame.rotate(v);  // lattice frame → parent body frame
    Fragment fr;
    fr.shape = Shape::polyhedron(std::move(meshes[i]));
    fr.offset = -fr.shape->recentring();  // centroid in the parent frame before re-centring
    out.push_back(std::move(fr));
  }
  // Rounding of the re-centred meshes leaves ~1e-15; correct it about each centroid.
  for (int pass = 0; pass < 3; ++pass) {
    double s = 0;
    for (const auto& fr : out) s += fr.shape->volume();
    if (std::abs(s - target) <= 1e-13 * target) break;
    const double g = std::cbrt(target / s);
    for (auto& fr : out) fr.shape = fr.shape->scaled(g);
  }
  return out;
}

const OptionTable& alpha_shape_options() {
  using S = AlphaShapeBuilderOptions;
  using A = AlphaShapeOptions;
  static const OptionTable t = [] {
    return OptionTable{
        opt::number("convex_hull_diameter", &S::hull_diameter, 0, std::numeric_limits<double>::infinity(), "m",
                    "children smaller than this become convex hulls (Zhu & Zhao 2019 §3.2)"),
        opt::number("convex_hull_convexity", &S::hull_convexity, 0, 2, "",
                    "children with V/V_hull at least this become convex hulls (> 1 disables)"),
        opt::number("alpha_start_spacings", opt::nested(&S::alpha, &A::start_spacings), 0.5, 100, "",
                    "the alpha walk starts at √α = this × lattice spacing"),
        opt::number("alpha_max_spacings", opt::nested(&S::alpha, &A::max_spacings), 0.5, 1e6, "",
                    "the walk gives up (convex-hull fallback) beyond √α = this × spacing; ≥ alpha_start_spacings"),
        opt::integer("max_alpha_steps", opt::nested(&S::alpha, &A::max_steps), 1, 1000000, "candidate alphas examined before the fallback"),
        opt::number("alpha_min_growth", opt::nested(&S::alpha, &A::min_growth), 0, 10, "", "least relative alpha increase between candidates"),
        opt::mapped_choice("alpha_input", &S::alpha_boundary_only, {{"all_points", false}, {"boundary_points", true}},
                    "points handed to the alpha shape: every cluster point and the fracture points, or the surface "
                    "and fracture points only"),
        opt::mapped_choice("scale_about", &S::scale_about_parent,
                           {{"parent_centroid", true}, {"child_centroid", false}},
                    "volume rescale about the parent's or each child's centroid"),
        opt::number("min_piece_volume_fraction", &S::min_piece_volume_fraction, 0, 0.1, "",
                    "plane cuts: pieces below this × the parent's volume are removed as fines (counted as a fragment "
                    "fallback)"),
        opt::number("min_piece_thickness_fraction", &S::min_piece_thickness_fraction, 0, 0.5, "",
                    "plane cuts: pieces thinner than this × the parent's equivalent diameter are removed as fines "
                    "(an engine cannot take such a sliver as a body)"),
    };
  }();
  return t;
}

std::unique_ptr<FragmentBuilder> make_alpha_shape_builder(const Config& cfg, const EngineContext& ctx) {
  cfg.string("type", "alpha_shape");
  AlphaShapeBuilderOptions o;
  read_options(cfg, alpha_shape_options(), o);
  if (o.alpha.max_spacings < o.alpha.start_spacings)
    cfg.fail("alpha_max_spacings", "must be >= alpha_start_spacings (" + fmt_num(o.alpha.start_spacings) + ")");
  if (ctx.dimension != 3) cfg.fail("type", "fragment builder 'alpha_shape' is 3D only (scenario dimension " +
                                               std::to_string(ctx.dimension) + ")");
  return std::make_unique<AlphaShapeBuilder>(o);
}

}  // namespace crumble
