// Alpha-shape polyhedra (Zhu & Zhao 2019 §3.2) and the CGAL convex
// hull used by the alpha-shape FragmentBuilder. The single translation unit holding
// CGAL's Alpha_shape_3 (it compiles slowly).
#include "geometry/cgal/AlphaShape.h"
#include "base/Format.h"

#include <CGAL/Alpha_shape_3.h>
#include <CGAL/Alpha_shape_cell_base_3.h>
#include <CGAL/Alpha_shape_vertex_base_3.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <utility>

#include "geometry/cgal/CgalMesh.h"

namespace crumble {

namespace PMP = CGAL::Polygon_mesh_processing;
using cgal::K;
using cgal::Point;

namespace {

using Vb0 = CGAL::Triangulation_vertex_base_with_info_3<int, K>;
using Vb = CGAL::Alpha_shape_vertex_base_3<K, Vb0>;
using Cb0 = CGAL::Triangulation_cell_base_with_info_3<int, K, CGAL::Delaunay_triangulation_cell_base_3<K>>;
using Cb = CGAL::Alpha_shape_cell_base_3<K, Cb0>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
using Delaunay = CGAL::Delaunay_triangulation_3<K, Tds, CGAL::Fast_location>;
using AlphaShape3 = CGAL::Alpha_shape_3<Delaunay>;

// A cell is flat when |6 V| < kFlatCell * (longest edge)³; a facet is degenerate when
// |2 A| < kFlatFacet * (longest edge)².
constexpr double kFlatCell = 1e-8;
constexpr double kFlatFacet = 1e-8;

void check_points(const std::vector<Vec3>& points, const char* who) {
  if (points.size() < 4)
    throw std::invalid_argument(std::string(who) + ": need at least 4 points, got " + std::to_string(points.size()));
  for (const auto& p : points)
    if (!is_finite(p)) throw std::invalid_argument(std::string(who) + ": a point is not finite");
}

// Coordinates the combinatorics are computed in. Points of a cubic lattice of spacing s
// and midpoints of its bonds (the PointClusters of Zhu & Zhao 2019 §3.2) are exactly
// coplanar, collinear and cospherical in many ways, but not in floating point: CGAL's
// exact predicates then see slivers of ~1e-16 relative thickness, zero-area facets that
// pass every exact test and fold as soon as the coordinates are rounded (rescaling,
// re-centring). When every point lies within 1e-6 half-spacings of the half-spacing
// lattice through the first point, they are replaced by exact integer coordinates in
// units of s/2, so degeneracies are exact and CGAL's symbolic perturbation resolves them;
// output vertices are still the caller's points.
struct Working {
  std::vector<Point> pts;
  double unit = 1;  // metres per working unit
  bool lattice = false;
};

Working working_coordinates(const std::vector<Vec3>& points, double spacing) {
  Working w;
  w.pts.reserve(points.size());
  if (spacing > 0) {
    const double h = 0.5 * spacing;
    const Vec3 o = points.front();
    bool ok = true;
    for (const auto& p : points) {
      const Vec3 t = (p - o) / h;
      const Vec3 q{std::round(t.x), std::round(t.y), std::round(t.z)};
      if (!(norm(t - q) < 1e-6) || !(std::abs(q.x) + std::abs(q.y) + std::abs(q.z) < 1e12)) {
        ok = false;
        break;
      }
      w.pts.emplace_back(q.x, q.y, q.z);
    }
    if (ok) {
      w.unit = h;
      w.lattice = true;
      return w;
    }
    w.pts.clear();
  }
  for (const auto& p : points) w.pts.push_back(cgal::to_point(p));
  return w;
}

// Union-find over vertex indices (connectivity of the candidate surface).
int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Cheap combinatorial screening of an oriented triangle soup over n input points:
// every directed edge exactly once with its reverse present (closed, no edge shared by
// more than two triangles, consistent orientation), V - E + F = 2 and one connected
// component. Returns an empty string when it passes, otherwise the reason.
std::string screen_soup(const std::vector<std::array<int, 3>>& tris, int n) {
  if (tris.size() < 4) return "fewer than 4 regular facets";
  std::vector<std::uint64_t> directed;
  directed.reserve(3 * tris.size());
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k)
      directed.push_back(static_cast<std::uint64_t>(t[k]) * static_cast<std::uint64_t>(n) +
                         static_cast<std::uint64_t>(t[(k + 1) % 3]));
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end())
    return "an edge is shared by more than two facets";
  for (const auto e : directed) {
    const std::uint64_t a = e / n, b = e % n;
    if (!std::binary_search(directed.begin(), directed.end(), b * n + a)) return "open boundary edge";
  }
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> used(n, 0);
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) {
      used[t[k]] = 1;
      const int a = find_root(parent, t[k]), b = find_root(parent, t[(k + 1) % 3]);
      if (a != b) parent[a] = b;
    }
  long V = 0;
  int roots = 0;
  for (int i = 0; i < n; ++i)
    if (used[i]) {
      ++V;
      if (find_root(parent, i) == i) ++roots;
    }
  const long F = static_cast<long>(tris.size()), E = 3 * F / 2;
  if (V - E + F != 2) return "Euler characteristic " + std::to_string(V - E + F) + " != 2";
  if (roots != 1) return std::to_string(roots) + " connected components";
  return {};
}

bool degenerate_facet(const Point& a, const Point& b, const Point& c) {
  if (CGAL::collinear(a, b, c)) return true;
  const Vec3 p = cgal::to_vec(a), q = cgal::to_vec(b), r = cgal::to_vec(c);
  const double l2 = std::max({norm2(q - p), norm2(r - q), norm2(p - r)});
  return norm(cross(q - p, r - p)) < kFlatFacet * l2;
}

// The alpha shape's cells: handle, alpha value (squared circumradius; +inf for infinite
// cells), neighbours, and whether the cell is infinite or (nearly) flat.
struct CellTable {
  std::vector<AlphaShape3::Cell_handle> cells;
  std::vector<double> alpha;
  std::vector<std::array<int, 4>> nb;
  std::vector<char> infinite, flat;
  int size() const { return static_cast<int>(cells.size()); }
};

CellTable cell_table(AlphaShape3& as) {
  CellTable t;
  for (auto c = as.all_cells_begin(); c != as.all_cells_end(); ++c) {
    c->info() = t.size();
    t.cells.push_back(c);
  }
  const int nc = t.size();
  t.alpha.assign(nc, std::numeric_limits<double>::infinity());
  t.nb.resize(nc);
  t.infinite.assign(nc, 0);
  t.flat.assign(nc, 0);
  for (int i = 0; i < nc; ++i) {
    for (int j = 0; j < 4; ++j) t.nb[i][j] = t.cells[i]->neighbor(j)->info();
    t.infinite[i] = as.is_infinite(t.cells[i]);
    if (t.infinite[i]) continue;
    t.alpha[i] = CGAL::to_double(t.cells[i]->get_alpha());
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = cgal::to_vec(t.cells[i]->vertex(k)->point());
    double l2 = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) l2 = std::max(l2, norm2(p[a] - p[b]));
    t.flat[i] = std::abs(dot(p[1] - p[0], cross(p[2] - p[0], p[3] - p[0]))) < kFlatCell * l2 * std::sqrt(l2);
  }
  return t;
}

// Nearly flat cells (only with non-lattice input; exact lattice coordinates have none):
// a sliver of ~zero volume and huge circumradius stays EXTERIOR until alpha is huge
// and dents the surface. Having no volume of its own, it joins the solid once three
// of its four neighbours have (so it is never a fin sticking out of the solid).
void lower_flat_cells(CellTable& t) {
  constexpr int kth = 3;
  for (int pass = 0; pass < 100; ++pass) {
    bool changed = false;
    for (int i = 0; i < t.size(); ++i) {
      if (!t.flat[i]) continue;
      double a[4];
      for (int j = 0; j < 4; ++j) a[j] = t.alpha[t.nb[i][j]];
      std::sort(a, a + 4);
      if (a[kth - 1] < t.alpha[i]) {
        t.alpha[i] = a[kth - 1];
        changed = true;
      }
    }
    if (!changed) break;
  }
}

// In REGULARIZED mode a cell is INTERIOR exactly when alpha >= its own alpha value, and
// the REGULAR facets are those between INTERIOR and EXTERIOR cells: the shape changes
// only at the cells' values of the alpha spectrum, so those are the candidates. The
// first candidate is the starting alpha a0 itself (if every cell is smaller, the shape
// there is already the whole triangulation, i.e. the convex hull).
std::vector<double> alpha_candidates(const CellTable& t, double a0) {
  std::vector<double> candidates{a0};
  for (double a : t.alpha)
    if (std::isfinite(a) && a > a0) candidates.push_back(a);
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  return candidates;
}

// EXTERIOR cells connected to infinity through EXTERIOR cells are outside; enclosed
// EXTERIOR cells (voids) are filled — a fragment has no internal cavity. (With the
// boundary points only, the inside of a piece is tiled by large cells that stay
// EXTERIOR up to alpha ~ inradius².)
void mark_outside(const CellTable& t, double alpha, std::vector<char>& outside, std::vector<int>& queue) {
  std::fill(outside.begin(), outside.end(), 0);
  queue.clear();
  for (int i = 0; i < t.size(); ++i)
    if (t.infinite[i]) {
      outside[i] = 1;
      queue.push_back(i);
    }
  while (!queue.empty()) {
    const int i = queue.back();
    queue.pop_back();
    for (int j = 0; j < 4; ++j) {
      const int k = t.nb[i][j];
      if (!outside[k] && t.alpha[k] > alpha) {
        outside[k] = 1;
        queue.push_back(k);
      }
    }
  }
}

// REGULAR facets (solid | outside), each oriented so its normal points outside, as
// triangles of input point indices. False at the first (nearly) zero-area facet: such
// facets pass CGAL's self-intersection test but fold as soon as the coordinates are rounded.
bool regular_facets(const CellTable& t, const std::vector<char>& outside, std::vector<std::array<int, 3>>& tris) {
  tris.clear();
  for (int i = 0; i < t.size(); ++i) {
    if (outside[i]) continue;
    const auto c = t.cells[i];
    for (int j = 0; j < 4; ++j) {
      if (!outside[t.nb[i][j]]) continue;
      auto v0 = c->vertex((j + 1) & 3), v1 = c->vertex((j + 2) & 3), v2 = c->vertex((j + 3) & 3);
      if (CGAL::orientation(v0->point(), v1->point(), v2->point(), c->vertex(j)->point()) == CGAL::POSITIVE)
        std::swap(v1, v2);
      if (degenerate_facet(v0->point(), v1->point(), v2->point())) return false;
      tris.push_back({v0->info(), v1->info(), v2->info()});
    }
  }
  return true;
}

// The triangles as a polygon soup over the points they use (`original`: the input index of
// each soup point).
struct Soup {
  std::vector<Point> pts;
  std::vector<int> original;
  std::vector<std::vector<std::size_t>> polys;
};

Soup make_soup(const std::vector<std::array<int, 3>>& tris, const std::vector<Point>& pts) {
  Soup s;
  std::vector<int> remap(pts.size(), -1);
  s.polys.reserve(tris.size());
  for (const auto& t : tris) {
    std::vector<std::size_t> poly(3);
    for (int k = 0; k < 3; ++k) {
      if (remap[t[k]] < 0) {
        remap[t[k]] = static_cast<int>(s.pts.size());
        s.pts.push_back(pts[t[k]]);
        s.original.push_back(t[k]);
      }
      poly[k] = static_cast<std::size_t>(remap[t[k]]);
    }
    s.polys.push_back(std::move(poly));
  }
  return s;
}

// The candidate surface `tris` as a closed, outward-oriented mesh of the caller's points;
// empty when it passes, otherwise why it is not one.
std::string candidate_mesh(const std::vector<std::array<int, 3>>& tris, const Working& w,
                           const std::vector<Vec3>& points, TriMesh& mesh) {
  std::string reason = screen_soup(tris, static_cast<int>(points.size()));
  if (!reason.empty()) return reason;
  // The recipe's manifoldness test: orient_polygon_soup returns false when it has to
  // duplicate a non-manifold vertex (or edge).
  Soup s = make_soup(tris, w.pts);
  if (!PMP::orient_polygon_soup(s.pts, s.polys)) return "non-manifold vertex";
  cgal::Mesh sm;
  PMP::polygon_soup_to_polygon_mesh(s.pts, s.polys, sm);
  if (!CGAL::is_closed(sm)) return "not closed";
  if (PMP::does_self_intersect(sm)) return "self-intersecting";
  for (int idx : s.original) mesh.vertices.push_back(points[idx]);
  for (const auto& p : s.polys)
    mesh.triangles.push_back({static_cast<int>(p[0]), static_cast<int>(p[1]), static_cast<int>(p[2])});
  const double vol = polyhedron_mass_properties(mesh).volume;
  if (vol < 0) {
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  } else if (!(vol > 0)) {
    return "zero volume";
  }
  return {};
}

}  // namespace

AlphaShapeResult alpha_shape_polyhedron(const std::vector<Vec3>& points, const AlphaShapeOptions& opt) {
  check_points(points, "alpha_shape_polyhedron");
  if (!(opt.spacing > 0) || !std::isfinite(opt.spacing))
    throw std::invalid_argument("alpha_shape_polyhedron: spacing must be > 0");
  if (!(opt.start_spacings > 0) || !(opt.max_spacings >= opt.start_spacings) || opt.max_steps < 1 ||
      !(opt.min_growth >= 0))
    throw std::invalid_argument("alpha_shape_polyhedron: need 0 < start_spacings <= max_spacings, max_steps >= 1, "
                                "min_growth >= 0");
  AlphaShapeResult res;
  const int n = static_cast<int>(points.size());
  const Working w = working_coordinates(points, opt.spacing);
  res.lattice = w.lattice;
  std::vector<std::pair<Point, int>> pts;
  pts.reserve(n);
  for (int i = 0; i < n; ++i) pts.emplace_back(w.pts[i], i);
  Delaunay dt(pts.begin(), pts.end());
  if (dt.dimension() < 3) {
    res.failure = "the points are coplanar";
    return res;
  }
  res.delaunay_vertices = static_cast<int>(dt.number_of_vertices());
  AlphaShape3 as(dt, 0, AlphaShape3::REGULARIZED);
  CellTable cells = cell_table(as);
  lower_flat_cells(cells);
  const double unit2 = w.unit * w.unit;
  const double a_max = std::pow(opt.max_spacings * opt.spacing, 2) / unit2;
  const std::vector<double> candidates = alpha_candidates(cells, std::pow(opt.start_spacings * opt.spacing, 2) / unit2);

  std::vector<std::array<int, 3>> tris;
  std::vector<char> outside(cells.size());
  std::vector<int> queue;
  double last = -1;
  std::string why = "no alpha value in [" + fmt_num(opt.start_spacings) + ", " +
                    fmt_num(opt.max_spacings) + "] spacings";
  for (const double alpha : candidates) {
    if (alpha > a_max) break;
    if (last > 0 && alpha < last * (1 + opt.min_growth)) continue;
    if (res.steps >= opt.max_steps) {
      why += " (stopped after max_steps = " + std::to_string(opt.max_steps) + ")";
      break;
    }
    last = alpha;
    ++res.steps;
    mark_outside(cells, alpha, outside, queue);
    TriMesh mesh;
    const std::string reason = regular_facets(cells, outside, tris) ? candidate_mesh(tris, w, points, mesh)
                                                                      : "zero-area facet";
    if (!reason.empty()) {
      why = "last candidate: " + reason;
      continue;
    }
    res.ok = true;
    res.mesh = std::move(mesh);
    res.alpha = alpha * unit2;
    return res;
  }
  res.failure = why;
  return res;
}

bool mesh_self_intersects(const TriMesh& mesh) {
  const cgal::Mesh sm = cgal::to_surface_mesh(mesh);
  return PMP::does_self_intersect(sm);
}

}  // namespace crumble
