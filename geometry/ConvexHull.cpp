// 3D convex hull: incremental quickhull (Barber, Dobkin & Huhdanpaa 1996) with a relative
// distance tolerance, without facet merging. Coplanar neighbours stay separate triangles;
// points on or within the tolerance of the hull are never vertices, and a final pass drops
// hull vertices that are not extreme (a point in the middle of a face or an edge that was
// picked before the corners around it) and rebuilds from the extreme points only. When no
// tolerance gives a convex hull holding every point, the same quickhull decides visibility
// by the exact sign of the orientation determinant (Shewchuk 1997) instead.
#include "geometry/ConvexHull.h"
#include "base/BuildCounters.h"
#include "base/Format.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace crumble {
namespace {

// Exact arithmetic on floating-point expansions (Shewchuk 1997, "Adaptive precision
// floating-point arithmetic and fast robust geometric predicates"): a number is held as a
// sum of doubles, non-overlapping and in increasing magnitude, zeros dropped; its sign is
// the sign of its largest component.
using Expansion = std::vector<double>;

// s + e = a + b exactly, s = fl(a + b) (Shewchuk 1997, Theorem 7, Two-Sum).
void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bv = s - a;
  const double av = s - bv;
  e = (a - av) + (b - bv);
}

// The exact a − b as an expansion.
Expansion exact_difference(double a, double b) {
  double s, e;
  two_sum(a, -b, s, e);
  Expansion x;
  if (e != 0) x.push_back(e);
  if (s != 0) x.push_back(s);
  return x;
}

// e + b (Shewchuk 1997, Grow-Expansion, with zero elimination).
Expansion grow(const Expansion& e, double b) {
  Expansion h;
  h.reserve(e.size() + 1);
  double q = b;
  for (const double c : e) {
    double s, err;
    two_sum(q, c, s, err);
    if (err != 0) h.push_back(err);
    q = s;
  }
  if (q != 0) h.push_back(q);
  return h;
}

// e + f, growing e by each component of f.
Expansion add(Expansion e, const Expansion& f) {
  for (const double c : f) e = grow(e, c);
  return e;
}

Expansion negated(Expansion e) {
  for (double& c : e) c = -c;
  return e;
}

// e × b (Shewchuk 1997, Scale-Expansion, with zero elimination); a × b = p + err exactly,
// the rounding error of the product given by a fused multiply-add.
Expansion scale(const Expansion& e, double b) {
  Expansion h;
  if (e.empty() || b == 0) return h;
  h.reserve(2 * e.size());
  double q = e[0] * b;
  const double h0 = std::fma(e[0], b, -q);
  if (h0 != 0) h.push_back(h0);
  for (std::size_t i = 1; i < e.size(); ++i) {
    const double t_hi = e[i] * b;
    const double t_lo = std::fma(e[i], b, -t_hi);
    double s, err;
    two_sum(q, t_lo, s, err);
    if (err != 0) h.push_back(err);
    two_sum(t_hi, s, q, err);
    if (err != 0) h.push_back(err);
  }
  if (q != 0) h.push_back(q);
  return h;
}

Expansion multiply(const Expansion& e, const Expansion& f) {
  Expansion out;
  for (const double c : f) out = add(std::move(out), scale(e, c));
  return out;
}

int sign(const Expansion& e) { return e.empty() ? 0 : (e.back() > 0 ? 1 : -1); }

// ((b − a) × (c − a)) · (p − a) from the exact differences.
int orientation_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  std::array<Expansion, 3> u, v, w;
  for (int k = 0; k < 3; ++k) {
    u[k] = exact_difference(b[k], a[k]);
    v[k] = exact_difference(c[k], a[k]);
    w[k] = exact_difference(p[k], a[k]);
  }
  // u · (v × w), one component of the cross product at a time.
  Expansion det;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    const Expansion cross_k = add(multiply(v[k1], w[k2]), negated(multiply(v[k2], w[k1])));
    det = add(std::move(det), multiply(u[k], cross_k));
  }
  return sign(det);
}

}  // namespace

int orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  // Floating-point filter: the rounded determinant's error, the differences' rounding
  // included, is below (7 + 56ε)ε times the permanent (Shewchuk 1997, §4.3, orient3d's
  // bound A, ε = 2^−53); 1e-15 is above that. Only a determinant within the bound goes to
  // the exact expansions.
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
  const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  const double wx = p.x - a.x, wy = p.y - a.y, wz = p.z - a.z;
  const double det = ux * (vy * wz - vz * wy) + uy * (vz * wx - vx * wz) + uz * (vx * wy - vy * wx);
  const double permanent = std::abs(ux) * (std::abs(vy * wz) + std::abs(vz * wy)) +
                           std::abs(uy) * (std::abs(vz * wx) + std::abs(vx * wz)) +
                           std::abs(uz) * (std::abs(vx * wy) + std::abs(vy * wx));
  const double bound = 1e-15 * permanent;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return orientation_exact(a, b, c, p);
}

namespace {

struct Face {
  std::array<int, 3> v;    // point indices, counter-clockwise seen from outside
  std::array<int, 3> nb;   // neighbour across edge (v[i], v[i+1])
  Vec3 n;                  // unit outward normal
  double off = 0;          // n·x = off on the plane
  std::vector<int> outside;  // conflict list: points strictly above this face
  bool alive = true;
};

class Quickhull {
 public:
  // `rel_tol`: a point within rel_tol × the cloud's size of a face counts as on it (besides
  // the few ulps below). `exact`: whether a point is above a face is decided by the exact
  // orientation() of the input points instead (rel_tol is then unused past the flatness
  // checks): the faces a point sees then form a disc on a convex hull, and the horizon is
  // one loop, which the tolerance test does not guarantee for nearly coplanar points.
  Quickhull(const std::vector<Vec3>& pts, const std::vector<int>& use, double rel_tol, bool exact = false)
      : use_(use), in_(pts), exact_(exact) {
    // Work in coordinates centred on the bounding box: rounding of the plane tests then
    // scales with the cloud's size, not with its distance from the origin.
    Aabb box;
    for (int i : use_) box.extend(pts[i]);
    const Vec3 c = box.center();
    p_.resize(pts.size());
    double maxabs[3] = {0, 0, 0};
    for (int i : use_) {
      p_[i] = pts[i] - c;
      for (int k = 0; k < 3; ++k) maxabs[k] = std::max(maxabs[k], std::abs(pts[i][k]));
    }
    size_ = norm(box.size());
    // Relative tolerance as in qhull: a few ulps of the input coordinates' magnitudes
    // (points far from the origin carry that much rounding from whoever computed them).
    eps_ = std::max(8 * std::numeric_limits<double>::epsilon() * (maxabs[0] + maxabs[1] + maxabs[2]), rel_tol * size_);
  }

  void run() {
    initial_simplex();
    // Only faces created by add_point receive points, so every face before the last one
    // processed has an empty conflict list for good: the scan resumes from there.
    std::size_t cursor = 0;
    for (;;) {
      int f = -1;
      for (std::size_t i = cursor; i < faces_.size(); ++i)
        if (faces_[i].alive && !faces_[i].outside.empty()) {
          f = static_cast<int>(i);
          break;
        }
      if (f < 0) break;
      cursor = static_cast<std::size_t>(f);
      // Eye point: the farthest point above f (lowest index on ties → deterministic).
      int eye = -1;
      double best = -1;
      for (int q : faces_[f].outside) {
        const double d = dist(faces_[f], q);
        if (d > best) {
          best = d;
          eye = q;
        }
      }
      add_point(f, eye);
    }
  }

  // Hull with original point indices.
  std::vector<std::array<int, 3>> triangles() const {
    std::vector<std::array<int, 3>> t;
    for (const auto& f : faces_)
      if (f.alive) t.push_back(f.v);
    return t;
  }

  double eps() const { return eps_; }

 private:
  double dist(const Face& f, int q) const { return dot(f.n, p_[q]) - f.off; }

  // Whether q is above f, given its rounded distance d.
  bool above(const Face& f, int q, double d) const {
    if (!exact_) return d > eps_;
    return orientation(in_[f.v[0]], in_[f.v[1]], in_[f.v[2]], in_[q]) > 0;
  }

  bool make_plane(Face& f) const {
    const Vec3& a = p_[f.v[0]];
    const Vec3& b = p_[f.v[1]];
    const Vec3& c = p_[f.v[2]];
    // Cross product of the two edges leaving the vertex opposite the longest edge keeps
    // the rounding error smallest.
    const Vec3 e0 = b - a, e1 = c - b, e2 = a - c;
    const double l0 = norm2(e0), l1 = norm2(e1), l2 = norm2(e2);
    Vec3 n;
    if (l0 >= l1 && l0 >= l2) n = cross(e1, e2);       // longest a-b: use vertex c
    else if (l1 >= l0 && l1 >= l2) n = cross(e2, e0);  // longest b-c: use vertex a
    else n = cross(e0, e1);                            // longest c-a: use vertex b
    const double len = norm(n);
    if (!(len > 0)) return false;
    f.n = n / len;
    f.off = (dot(f.n, a) + dot(f.n, b) + dot(f.n, c)) / 3.0;
    return true;
  }

  void initial_simplex() {
    // Two points far apart: extremes along the axis of largest spread.
    int i0 = use_[0], i1 = use_[0];
    double spread = -1;
    for (int k = 0; k < 3; ++k) {
      int lo = use_[0], hi = use_[0];
      for (int i : use_) {
        if (p_[i][k] < p_[lo][k]) lo = i;
        if (p_[i][k] > p_[hi][k]) hi = i;
      }
      if (p_[hi][k] - p_[lo][k] > spread) {
        spread = p_[hi][k] - p_[lo][k];
        i0 = lo;
        i1 = hi;
      }
    }
    const double flat_tol = 1e-10 * size_;
    if (!(spread > flat_tol)) throw std::invalid_argument("convex_hull: all points coincide");
    // Farthest from the line i0-i1.
    const Vec3 dir = normalized(p_[i1] - p_[i0]);
    int i2 = -1;
    double best = -1;
    for (int i : use_) {
      const Vec3 r = p_[i] - p_[i0];
      const double d = norm(r - dir * dot(r, dir));
      if (d > best) {
        best = d;
        i2 = i;
      }
    }
    if (!(best > flat_tol)) throw std::invalid_argument("convex_hull: the points are collinear (flat cloud)");
    // Farthest from the plane i0-i1-i2.
    const Vec3 pn = normalized(cross(p_[i1] - p_[i0], p_[i2] - p_[i0]));
    int i3 = -1;
    best = -1;
    for (int i : use_) {
      const double d = std::abs(dot(pn, p_[i] - p_[i0]));
      if (d > best) {
        best = d;
        i3 = i;
      }
    }
    if (!(best > flat_tol) || !(best > 4 * eps_))
      throw std::invalid_argument("convex_hull: the points are coplanar (flat cloud)");
    // Orient so that i3 is below the face (i0, i1, i2).
    if (exact_) {
      const int side = orientation(in_[i0], in_[i1], in_[i2], in_[i3]);
      if (side == 0) throw std::runtime_error("convex_hull: internal error (flat initial simplex)");
      if (side > 0) std::swap(i1, i2);
    } else if (dot(pn, p_[i3] - p_[i0]) > 0) {
      std::swap(i1, i2);
    }
    const int a = i0, b = i1, c = i2, d = i3;
    // Faces of the tetrahedron, outward: (a,b,c) has d below it.
    const std::array<std::array<int, 3>, 4> tv = {{{a, b, c}, {a, d, b}, {b, d, c}, {c, d, a}}};
    for (const auto& v : tv) {
      Face f;
      f.v = v;
      f.nb = {-1, -1, -1};
      if (!make_plane(f)) throw std::invalid_argument("convex_hull: degenerate initial simplex");
      faces_.push_back(std::move(f));
    }
    link_all();
    std::vector<int> rest;
    for (int i : use_)
      if (i != a && i != b && i != c && i != d) rest.push_back(i);
    assign(rest, {0, 1, 2, 3});
  }

  // Neighbour links of the live faces by matching opposite directed edges.
  void link_all() {
    std::map<std::pair<int, int>, std::pair<int, int>> edge;  // (u,v) -> (face, slot)
    for (std::size_t fi = 0; fi < faces_.size(); ++fi) {
      if (!faces_[fi].alive) continue;
      for (int k = 0; k < 3; ++k) edge[{faces_[fi].v[k], faces_[fi].v[(k + 1) % 3]}] = {static_cast<int>(fi), k};
    }
    for (std::size_t fi = 0; fi < faces_.size(); ++fi) {
      if (!faces_[fi].alive) continue;
      for (int k = 0; k < 3; ++k) {
        auto it = edge.find({faces_[fi].v[(k + 1) % 3], faces_[fi].v[k]});
        faces_[fi].nb[k] = it == edge.end() ? -1 : it->second.first;
      }
    }
  }

  void assign(const std::vector<int>& pts, const std::vector<int>& candidates) {
    for (int q : pts) {
      // The face the point is farthest above (ties → first), so conflict lists stay small.
      int best_f = -1;
      double best_d = exact_ ? -std::numeric_limits<double>::infinity() : eps_;
      for (int f : candidates) {
        const double d = dist(faces_[f], q);
        if (d > best_d && above(faces_[f], q, d)) {
          best_d = d;
          best_f = f;
        }
      }
      if (best_f >= 0) faces_[best_f].outside.push_back(q);
    }
  }

  void add_point(int start, int eye) {
    // Faces visible from the eye, by flood fill from `start` (connected by construction).
    std::vector<int> visible{start};
    std::vector<char> is_vis(faces_.size(), 0);
    is_vis[start] = 1;
    for (std::size_t k = 0; k < visible.size(); ++k) {
      const Face& f = faces_[visible[k]];
      for (int j = 0; j < 3; ++j) {
        const int g = f.nb[j];
        if (g >= 0 && !is_vis[g] && above(faces_[g], eye, dist(faces_[g], eye))) {
          is_vis[g] = 1;
          visible.push_back(g);
        }
      }
    }
    // Horizon edges (u, v) as oriented in the visible face, with the hidden face across.
    struct HEdge {
      int u, v, hidden;
    };
    std::vector<HEdge> horizon;
    for (int fi : visible)
      for (int j = 0; j < 3; ++j) {
        const int g = faces_[fi].nb[j];
        if (g < 0 || !is_vis[g]) horizon.push_back({faces_[fi].v[j], faces_[fi].v[(j + 1) % 3], g});
      }
    std::vector<int> orphans;
    for (int fi : visible) {
      faces_[fi].alive = false;
      for (int q : faces_[fi].outside)
        if (q != eye) orphans.push_back(q);
      faces_[fi].outside.clear();
      faces_[fi].outside.shrink_to_fit();
    }
    std::vector<int> created;
    std::map<std::pair<int, int>, std::pair<int, int>> open;  // directed edge -> (face, slot)
    for (const auto& h : horizon) {
      Face f;
      f.v = {h.u, h.v, eye};
      f.nb = {h.hidden, -1, -1};
      if (!make_plane(f)) {
        // Eye collinear with a horizon edge: keep the hidden face's plane so the mesh
        // stays closed; the triangle has zero area and is dropped by the cleanup pass.
        f.n = h.hidden >= 0 ? faces_[h.hidden].n : Vec3{0, 0, 1};
        f.off = dot(f.n, p_[h.u]);
      }
      const int id = static_cast<int>(faces_.size());
      faces_.push_back(std::move(f));
      created.push_back(id);
      if (h.hidden >= 0) {
        Face& hf = faces_[h.hidden];
        for (int j = 0; j < 3; ++j)
          if (hf.v[j] == h.v && hf.v[(j + 1) % 3] == h.u) hf.nb[j] = id;
      }
      // Side edges (v, eye) and (eye, u) pair with the neighbouring new faces.
      const std::pair<int, int> e1{h.v, eye}, e2{eye, h.u};
      for (auto [e, slot] : {std::pair{e1, 1}, std::pair{e2, 2}}) {
        auto it = open.find({e.second, e.first});
        if (it != open.end()) {
          faces_[id].nb[slot] = it->second.first;
          faces_[it->second.first].nb[it->second.second] = id;
          open.erase(it);
        } else {
          open[e] = {id, slot};
        }
      }
    }
    if (!open.empty()) throw std::runtime_error("convex_hull: internal error (horizon is not a closed loop)");
    assign(orphans, created);
  }

  std::vector<int> use_;
  const std::vector<Vec3>& in_;  // the input points (exact tests)
  bool exact_ = false;
  std::vector<Vec3> p_;
  std::vector<Face> faces_;
  double eps_ = 0;
  double size_ = 0;
};

// Vertices whose incident face normals do not span 3D lie inside a face or on an edge of
// the hull: they are not extreme points.
std::vector<int> non_extreme_vertices(const std::vector<Vec3>& pts, const std::vector<std::array<int, 3>>& tris) {
  std::map<int, std::vector<Vec3>> normals;
  for (const auto& t : tris) {
    const Vec3 n = cross(pts[t[1]] - pts[t[0]], pts[t[2]] - pts[t[0]]);
    const double len = norm(n);
    const double longest = std::max({norm2(pts[t[1]] - pts[t[0]]), norm2(pts[t[2]] - pts[t[1]]),
                                     norm2(pts[t[0]] - pts[t[2]])});
    // Slivers (height < 1e-6 of the base) have no reliable normal: they say nothing.
    const bool reliable = len > 1e-6 * longest;
    for (int k = 0; k < 3; ++k) {
      auto& list = normals[t[k]];
      if (reliable) list.push_back(n / len);
    }
  }
  constexpr double tol = 1e-9;
  std::vector<int> out;
  for (const auto& [v, ns] : normals) {
    bool extreme = false;
    if (!ns.empty()) {
      const Vec3& a = ns[0];
      Vec3 axis;
      double best = 0;
      for (const auto& n : ns) {
        const Vec3 c = cross(a, n);
        if (norm2(c) > best) {
          best = norm2(c);
          axis = c;
        }
      }
      if (std::sqrt(best) > tol) {
        axis = normalized(axis);
        for (const auto& n : ns)
          if (std::abs(dot(n, axis)) > tol) {
            extreme = true;
            break;
          }
      }
    }
    if (!extreme) out.push_back(v);
  }
  return out;
}

// The hull's triangles as a mesh of its vertices only, in increasing input order.
TriMesh compact(const std::vector<Vec3>& points, const std::vector<std::array<int, 3>>& tris) {
  std::vector<int> remap(points.size(), -1);
  for (const auto& t : tris)
    for (int v : t) remap[v] = 0;
  TriMesh m;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = static_cast<int>(m.vertices.size());
      m.vertices.push_back(points[i]);
    }
  m.triangles.reserve(tris.size());
  for (const auto& t : tris) m.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
  return m;
}

// The hull vertices of `tris` that are not in `drop`, in increasing order.
std::vector<int> hull_vertices_except(std::size_t n, const std::vector<std::array<int, 3>>& tris,
                                      const std::vector<int>& drop) {
  std::vector<char> on_hull(n, 0);
  for (const auto& t : tris)
    for (int v : t) on_hull[v] = 1;
  for (int v : drop) on_hull[v] = 0;
  std::vector<int> out;
  for (std::size_t i = 0; i < n; ++i)
    if (on_hull[i]) out.push_back(static_cast<int>(i));
  return out;
}

// The hull of `points` with the relative on-face tolerance `rel_tol`.
TriMesh hull_with_tolerance(const std::vector<Vec3>& points, double rel_tol) {
  std::vector<int> use(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) use[i] = static_cast<int>(i);
  std::vector<std::array<int, 3>> tris;
  // At most a few rounds: each drops vertices that turned out not to be extreme.
  for (int round = 0; round < 8; ++round) {
    Quickhull qh(points, use, rel_tol);
    qh.run();
    tris = qh.triangles();
    const std::vector<int> drop = non_extreme_vertices(points, tris);
    if (drop.empty()) break;
    std::vector<int> next = hull_vertices_except(points.size(), tris, drop);
    if (next.size() < 4) throw std::invalid_argument("convex_hull: the points are coplanar (flat cloud)");
    use = std::move(next);
  }
  return compact(points, tris);
}

std::vector<std::array<int, 3>> exact_triangles(const std::vector<Vec3>& points, const std::vector<int>& use) {
  Quickhull qh(points, use, 0.0, true);
  qh.run();
  return qh.triangles();
}

// Whether point q is on or below every face of `tris`, exactly.
bool inside_exactly(const std::vector<Vec3>& points, const std::vector<std::array<int, 3>>& tris, int q) {
  for (const auto& t : tris)
    if (orientation(points[t[0]], points[t[1]], points[t[2]], points[q]) > 0) return false;
  return true;
}

// The hull by the quickhull with exact visibility. Its vertices that non_extreme_vertices()
// flags (in the middle of a face or an edge, or with only slivers around them) are dropped
// when the hull rebuilt without them still holds them exactly; those it does not hold (a
// corner with only slivers around it) are put back.
TriMesh exact_hull(const std::vector<Vec3>& points) {
  std::vector<int> all(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) all[i] = static_cast<int>(i);
  std::vector<std::array<int, 3>> tris = exact_triangles(points, all);
  std::vector<int> drop = non_extreme_vertices(points, tris);
  const std::vector<std::array<int, 3>> full = tris;
  for (int round = 0; round < 3 && !drop.empty(); ++round) {
    const std::vector<int> keep = hull_vertices_except(points.size(), full, drop);
    std::vector<std::array<int, 3>> fewer;
    try {
      if (keep.size() < 4) break;
      fewer = exact_triangles(points, keep);
    } catch (const std::invalid_argument&) {
      break;  // the kept vertices are flat: keep every vertex
    }
    std::vector<int> still;  // dropped and held by the rebuilt hull
    for (int v : drop)
      if (inside_exactly(points, fewer, v)) still.push_back(v);
    if (still.size() == drop.size()) {
      tris = std::move(fewer);
      break;
    }
    drop = std::move(still);
  }
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!inside_exactly(points, tris, static_cast<int>(i)))
      throw std::runtime_error("convex_hull: internal error (point " + std::to_string(i) +
                               " outside the exact hull)");
  return compact(points, tris);
}

// Whether the mesh is convex and outward: no vertex above any face's plane by more than
// 1e-9 of its size, positive volume. Catches a hull folded over itself, where a face ended
// up facing inwards.
bool is_convex_outward(const TriMesh& m) {
  const double tol = 1e-9 * norm(m.bounds().size());
  for (const auto& t : m.triangles) {
    const Vec3 a = m.vertices[t[0]];
    const Vec3 c = cross(m.vertices[t[1]] - a, m.vertices[t[2]] - a);
    const double len = norm(c);
    if (!(len > 0)) continue;  // zero area: no plane
    const Vec3 n = c / len;
    for (const auto& v : m.vertices)
      if (dot(n, v - a) > tol) return false;
  }
  return polyhedron_mass_properties(m).volume > 0;
}

// Whether every point lies below every face plane of the mesh, within 1e-9 of the mesh's
// size. Slivers (height < 1e-6 of the longest edge) are skipped: their rounded normal may be
// off by more than that tolerance over the mesh's size.
bool contains_points(const TriMesh& m, const std::vector<Vec3>& points) {
  const double tol = 1e-9 * norm(m.bounds().size());
  std::vector<std::pair<Vec3, double>> planes;  // unit normal, offset
  for (const auto& t : m.triangles) {
    const Vec3 a = m.vertices[t[0]];
    const Vec3 c = cross(m.vertices[t[1]] - a, m.vertices[t[2]] - a);
    const double longest = std::max({norm2(m.vertices[t[1]] - a), norm2(m.vertices[t[2]] - a),
                                     norm2(m.vertices[t[2]] - m.vertices[t[1]])});
    const double len = norm(c);
    if (len > 1e-6 * longest) planes.push_back({c / len, dot(c / len, a)});
  }
  for (const auto& p : points)
    for (const auto& [n, h] : planes)
      if (dot(n, p) - h > tol) return false;
  return true;
}

}  // namespace

TriMesh convex_hull(const std::vector<Vec3>& points) {
  if (points.size() < 4)
    throw std::invalid_argument("convex_hull: needs at least 4 points, got " + std::to_string(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!is_finite(points[i]))
      throw std::invalid_argument("convex_hull: point " + std::to_string(i) + " is not finite");
  count_built(Representation::ConvexHull);
  // A few ulps decide what is on a face. Nearly coplanar points (the cuts of
  // geometry/ConvexPieces put many points on one plane) can then fold the hull over itself
  // (two faces of a 72-point piece facing inwards, 0.1 of its size off), make the faces an
  // eye point sees a ring instead of a disc (the horizon is then no loop), or leave a point
  // outside; a tolerance of 1e-12 or 1e-10 of the cloud's size, which drops points that
  // close to the hull, mostly does not. A hull that is not convex or does not hold every
  // point is not taken; when no tolerance gives one, the quickhull with exact visibility
  // (orientation()) does, and it also tells a flat cloud (std::invalid_argument).
  for (const double rel_tol : {0.0, 1e-12, 1e-10}) {
    try {
      TriMesh m = hull_with_tolerance(points, rel_tol);
      if (is_convex_outward(m) && contains_points(m, points)) return m;
    } catch (const std::runtime_error&) {
    } catch (const std::invalid_argument&) {
    }
  }
  return exact_hull(points);
}

}  // namespace crumble

namespace crumble {

double convex_inradius_about_centroid(const TriMesh& convex) {
  const Vec3 o = polyhedron_mass_properties(convex).centroid;
  double r = std::numeric_limits<double>::infinity();
  for (const auto& t : convex.triangles) {
    const Vec3 n = cross(convex.vertices[t[1]] - convex.vertices[t[0]], convex.vertices[t[2]] - convex.vertices[t[0]]);
    const double len = norm(n);
    if (len > 0) r = std::min(r, dot(n / len, convex.vertices[t[0]] - o));
  }
  return r;
}

namespace {

struct FacePlane {
  Vec3 n;      // unit outward normal
  double h;    // n·x = h on the face
};

std::vector<FacePlane> face_planes(const TriMesh& convex) {
  std::vector<FacePlane> planes;
  planes.reserve(convex.triangles.size());
  for (const auto& t : convex.triangles) {
    const Vec3 n = cross(convex.vertices[t[1]] - convex.vertices[t[0]], convex.vertices[t[2]] - convex.vertices[t[0]]);
    const double len = norm(n);
    if (!(len > 0)) continue;
    planes.push_back({n / len, dot(n / len, convex.vertices[t[0]])});
  }
  return planes;
}

// The exact inset (erosion) of a convex polyhedron: the vertices of ∩_j {n_j·x <= h_j −
// distance}, found as the convex hull of the dual points n_j / (h_j − distance − n_j·o)
// about the interior point o (the polar duality of a convex polytope: each face of the
// dual hull is a vertex of the inset polytope, dual points inside the hull are face
// planes the inset drops). o is strictly inside every inset plane (distance < inradius).
std::vector<Vec3> exact_inset(const std::vector<FacePlane>& planes, const Vec3& o, double distance) {
  std::vector<Vec3> dual;
  dual.reserve(planes.size());
  double qmax = 0;
  for (const auto& p : planes) {
    const double e = p.h - distance - dot(p.n, o);
    if (!(e > 0)) throw std::invalid_argument("inset_convex_vertices: the centroid is not inside an inset face plane");
    dual.push_back(p.n / e);
    qmax = std::max(qmax, norm(dual.back()));
  }
  // Coplanar triangles of one face give (nearly) the same dual point; convex_hull() is
  // not reliable on such near-duplicates (a hull that leaves points outside was seen), so
  // keep one of each.
  std::vector<Vec3> distinct;
  for (const auto& q : dual) {
    bool seen = false;
    for (const auto& u : distinct)
      if (norm(u - q) <= 1e-9 * qmax) {
        seen = true;
        break;
      }
    if (!seen) distinct.push_back(q);
  }
  const TriMesh dh = convex_hull(distinct);
  std::vector<Vec3> out;
  out.reserve(dh.triangles.size());
  for (const auto& t : dh.triangles) {
    const Vec3 a = dh.vertices[t[0]];
    const Vec3 m = cross(dh.vertices[t[1]] - a, dh.vertices[t[2]] - a);
    const double k = dot(m, a);  // > 0: the origin is inside the dual hull
    if (!(k > 0)) throw std::invalid_argument("inset_convex_vertices: degenerate dual hull");
    out.push_back(o + m / k);
  }
  // Coplanar dual triangles give the same primal vertex up to rounding: keep one.
  Aabb box;
  for (const auto& v : out) box.extend(v);
  const double tol = 1e-9 * std::max(norm(box.size()), distance);
  std::vector<Vec3> unique;
  for (const auto& v : out) {
    bool seen = false;
    for (const auto& u : unique)
      if (norm(u - v) <= tol) {
        seen = true;
        break;
      }
    if (!seen) unique.push_back(v);
  }
  return unique;
}

}  // namespace

std::vector<Vec3> inset_convex_vertices(const TriMesh& convex, double distance) {
  if (!(distance >= 0) || !std::isfinite(distance))
    throw std::invalid_argument("inset_convex_vertices: distance must be finite and >= 0");
  const double inradius = convex_inradius_about_centroid(convex);
  if (!(distance < inradius))
    throw std::invalid_argument("inset_convex_vertices: inset distance " + fmt_num(distance) +
                                " is not smaller than the distance from the centroid to the nearest face (" +
                                fmt_num(inradius) + ")");
  if (distance == 0) return convex.vertices;
  // Per vertex, the displacement d minimising Σ_j (n_j·d + distance)² over its incident
  // triangles j (normal equations, lightly regularised so that a vertex whose faces are
  // nearly coplanar moves along their common normal and not sideways).
  const std::size_t nv = convex.vertices.size();
  std::vector<Mat3> normal_matrix(nv, Mat3::zero());
  std::vector<Vec3> rhs(nv);
  for (const auto& t : convex.triangles) {
    const Vec3 n = cross(convex.vertices[t[1]] - convex.vertices[t[0]], convex.vertices[t[2]] - convex.vertices[t[0]]);
    const double len = norm(n);
    if (!(len > 0)) continue;
    const Vec3 u = n / len;
    for (int k = 0; k < 3; ++k) {
      normal_matrix[t[k]] += Mat3::outer(u, u);
      rhs[t[k]] -= u * distance;
    }
  }
  std::vector<Vec3> out(convex.vertices);
  for (std::size_t v = 0; v < nv; ++v) {
    Mat3 a = normal_matrix[v] + Mat3::identity() * (1e-12 * normal_matrix[v].trace());
    // Solve the 3x3 system by the adjugate (a is symmetric positive definite).
    const Vec3 c0{a(0, 0), a(1, 0), a(2, 0)}, c1{a(0, 1), a(1, 1), a(2, 1)}, c2{a(0, 2), a(1, 2), a(2, 2)};
    const double det = dot(c0, cross(c1, c2));
    if (!(std::abs(det) > 0)) continue;  // isolated vertex: no incident face
    const Vec3& b = rhs[v];
    out[v] += Vec3{dot(b, cross(c1, c2)), dot(c0, cross(b, c2)), dot(c0, cross(c1, b))} / det;
  }
  // The per-vertex solution only looks at a vertex's own faces. At an acute vertex (a
  // thin plate cut at a shallow angle, a wedge) the inset faces meet far from the
  // vertex, beyond the opposite faces: the moved vertex leaves the solid (it flew 17 mm
  // out of a 0.5 mm fragment, and the engine saw a contact 30 diameters deep). Any moved
  // vertex outside the original hull (more than `distance` outside an inset face plane:
  // the inflated hull would stick out by more than the margin itself) sends the whole hull
  // to the exact inset instead. Round grains stay within 2 % of `distance`, alpha-shape
  // fragments of the peridynamics runs within 30 %: they keep the least-squares result.
  const std::vector<FacePlane> planes = face_planes(convex);
  const double slack = distance;
  for (const auto& x : out)
    for (const auto& p : planes)
      if (dot(p.n, x) > p.h - distance + slack)
        return exact_inset(planes, polyhedron_mass_properties(convex).centroid, distance);
  return out;
}

}  // namespace crumble
