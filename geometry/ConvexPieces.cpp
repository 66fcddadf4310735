#include "geometry/ConvexPieces.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "geometry/ConvexHull.h"
#include "geometry/SymmetricEigen.h"

namespace crumble {
namespace {

using Polygon = std::vector<int>;  // indices into the shared vertex list, in order
using Piece = std::vector<Polygon>;

// Volume of the hull of a point set; 0 when it has none (fewer than 4 points, or flat).
double hull_volume(const std::vector<Vec3>& pts) {
  if (pts.size() < 4) return 0;
  try {
    return polyhedron_mass_properties(convex_hull(pts)).volume;
  } catch (const std::exception&) {  // flat, or too degenerate for the hull (a rejected cut)
    return 0;
  }
}

std::vector<Vec3> points_of(const Piece& piece, const std::vector<Vec3>& v) {
  std::vector<int> ids;
  for (const auto& p : piece) ids.insert(ids.end(), p.begin(), p.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<Vec3> out;
  out.reserve(ids.size());
  for (int i : ids) out.push_back(v[i]);
  return out;
}

// The polygons of `piece` grouped by shared vertices.
std::vector<Piece> components(Piece piece) {
  std::unordered_map<int, int> parent;
  auto find = [&](int a) {
    while (parent.at(a) != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (const auto& p : piece)
    for (int i : p) parent.emplace(i, i);
  for (const auto& p : piece)
    for (std::size_t k = 1; k < p.size(); ++k) {
      const int a = find(p[0]), b = find(p[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::map<int, std::size_t> slot;  // root → component, in order of the first polygon
  std::vector<Piece> out;
  for (auto& p : piece) {
    const int r = find(p[0]);
    auto [it, fresh] = slot.emplace(r, out.size());
    if (fresh) out.emplace_back();
    out[it->second].push_back(std::move(p));
  }
  return out;
}

// The convex hull, in the plane with normal n, of the points `ids` (Andrew's monotone chain
// in a basis of the plane), as a polygon of their indices; fewer than 3 points or collinear: empty.
Polygon planar_hull(const std::vector<int>& ids, const Vec3& n, const std::vector<Vec3>& v) {
  if (ids.size() < 3) return {};
  const Vec3 a = std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 e1 = normalized(cross(n, a)), e2 = normalized(cross(n, e1));
  struct P {
    double x, y;
    int id;
  };
  std::vector<P> p;
  for (int i : ids) p.push_back({dot(e1, v[i]), dot(e2, v[i]), i});
  std::sort(p.begin(), p.end(), [](const P& l, const P& r) { return l.x != r.x ? l.x < r.x : l.y < r.y; });
  auto turn = [](const P& o, const P& a, const P& b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); };
  std::vector<P> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && turn(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && turn(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  Polygon out;
  for (std::size_t i = 0; i + 1 < k; ++i) out.push_back(h[i].id);
  return out.size() >= 3 ? out : Polygon{};
}

// Sutherland–Hodgman clipping of every polygon of `piece` by the plane n·x = offset: the parts
// with n·x <= offset, then those with n·x > offset, each split into connected components. The
// point where an edge crosses the plane is computed once per edge (from its lower index), so
// neighbouring polygons share it and stay connected.
std::pair<std::vector<Piece>, std::vector<Piece>> cut(const Piece& piece, const Vec3& n, double offset,
                                                      double extent, std::vector<Vec3>& v) {
  std::unordered_map<int, double> side;
  // A vertex within 1e-7 of the piece's extent of the plane is on it: no crossing point lands
  // next to a vertex (near-duplicate points defeat the hull's tolerances).
  const double on_plane = 1e-7 * extent;
  auto s_of = [&](int i) {
    auto it = side.find(i);
    if (it != side.end()) return it->second;
    double s = dot(n, v[i]) - offset;
    if (std::abs(s) <= on_plane) s = 0;
    side.emplace(i, s);
    return s;
  };
  std::map<std::pair<int, int>, int> crossing;
  auto cross_point = [&](int a, int b) {
    const double sa = s_of(a), sb = s_of(b);
    if (sa == 0) return a;
    if (sb == 0) return b;
    const int lo = std::min(a, b), hi = std::max(a, b);
    auto [it, fresh] = crossing.emplace(std::make_pair(lo, hi), -1);
    if (fresh) {
      const double slo = s_of(lo), shi = s_of(hi);
      const double t = slo / (slo - shi);
      const Vec3 p = v[lo] + (v[hi] - v[lo]) * t;
      it->second = static_cast<int>(v.size());
      v.push_back(p);
      side.emplace(it->second, 0.0);  // on the plane by construction
    }
    return it->second;
  };
  Piece below, above;
  for (const auto& poly : piece) {
    for (int want_above = 0; want_above < 2; ++want_above) {
      Polygon out;
      const std::size_t k = poly.size();
      for (std::size_t i = 0; i < k; ++i) {
        const int a = poly[i], b = poly[(i + 1) % k];
        const bool ina = want_above ? s_of(a) > 0 : s_of(a) <= 0;
        const bool inb = want_above ? s_of(b) > 0 : s_of(b) <= 0;
        if (ina) out.push_back(a);
        if (ina != inb) out.push_back(cross_point(a, b));
      }
      Polygon clean;
      for (int i : out)
        if (clean.empty() || clean.back() != i) clean.push_back(i);
      while (clean.size() > 1 && clean.front() == clean.back()) clean.pop_back();
      if (clean.size() >= 3) (want_above ? above : below).push_back(std::move(clean));
    }
  }
  // Each part gets its cap: the convex hull (in the plane) of its points on the plane, so that
  // later cuts through the cap find the points where they cross it (without the caps, corners
  // where three cut planes meet are lost and the hulls stop covering the solid). The hull of a
  // non-convex cap only adds to a piece what the piece's own hull already holds.
  auto capped = [&](Piece side) {
    std::vector<Piece> parts = components(std::move(side));
    for (auto& part : parts) {
      std::vector<int> on;
      for (const auto& poly : part)
        for (int i : poly)
          if (s_of(i) == 0) on.push_back(i);
      std::sort(on.begin(), on.end());
      on.erase(std::unique(on.begin(), on.end()), on.end());
      Polygon cap = planar_hull(on, n, v);
      if (cap.size() >= 3) part.push_back(std::move(cap));
    }
    return parts;
  };
  return {capped(std::move(below)), capped(std::move(above))};
}

struct Candidate {
  double gain = -std::numeric_limits<double>::infinity();
  std::vector<Piece> parts;
  std::vector<double> part_volumes;
};

struct Entry {
  Piece piece;
  double hull = 0;
  bool evaluated = false;
  Candidate best;
};

// The best of the twelve cuts of a piece: its three principal axes (of its points' spread), each
// through the piece's deepest point and at a quarter, half and three quarters of the piece's
// extent along the axis.
Candidate best_cut(const Entry& e, std::size_t max_parts, std::vector<Vec3>& v) {
  Candidate best;
  const std::vector<Vec3> pts = points_of(e.piece, v);
  if (pts.size() < 8) return best;
  Vec3 c{0, 0, 0};
  for (const auto& p : pts) c = c + p;
  c = c * (1.0 / static_cast<double>(pts.size()));
  Mat3 cov = Mat3::zero();
  for (const auto& p : pts) cov += Mat3::outer(p - c, p - c);
  PrincipalAxes ax;
  try {
    ax = principal_axes(cov);
  } catch (const std::invalid_argument&) {
    return best;
  }
  // The piece's point deepest inside its hull: the bottom of its largest concavity, where a cut
  // separates what the concavity divides (a U prism cut at the bottom of its notch gives a
  // base and two prongs, all convex).
  Vec3 deepest = c;
  try {
    const TriMesh h = convex_hull(pts);
    double best_depth = -1;
    for (const auto& p : pts) {
      double depth = std::numeric_limits<double>::infinity();
      for (const auto& t : h.triangles) {
        const Vec3 fn = normalized(cross(h.vertices[t[1]] - h.vertices[t[0]], h.vertices[t[2]] - h.vertices[t[0]]));
        depth = std::min(depth, dot(fn, h.vertices[t[0]] - p));
      }
      if (depth > best_depth) best_depth = depth, deepest = p;
    }
  } catch (const std::exception&) {
    return best;
  }
  for (int k = 0; k < 3; ++k) {
    const Vec3 n{ax.axes(0, k), ax.axes(1, k), ax.axes(2, k)};
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& p : pts) {
      lo = std::min(lo, dot(n, p));
      hi = std::max(hi, dot(n, p));
    }
    if (!(hi > lo)) continue;
    const double at_deepest = (dot(n, deepest) - lo) / (hi - lo);
    for (double q : {at_deepest, 0.5, 0.25, 0.75}) {
      if (!(q > 1e-9 && q < 1 - 1e-9)) continue;
      auto [below, above] = cut(e.piece, n, lo + q * (hi - lo), hi - lo, v);
      if (below.empty() || above.empty()) continue;
      Candidate cand;
      double sum = 0;
      bool degenerate = false;
      for (auto* side : {&below, &above})
        for (auto& part : *side) {
          const double hv = hull_volume(points_of(part, v));
          if (!(hv > 0)) degenerate = true;
          sum += hv;
          cand.parts.push_back(std::move(part));
          cand.part_volumes.push_back(hv);
        }
      if (degenerate || cand.parts.size() > max_parts) continue;
      cand.gain = e.hull - sum;
      if (cand.gain > best.gain) best = std::move(cand);
    }
  }
  return best;
}

}  // namespace

ConvexPieces convex_pieces(const TriMesh& mesh, const ConvexPiecesOptions& o) {
  if (!(o.tolerance >= 0) || !(o.min_gain >= 0) || o.max_pieces < 1)
    throw std::invalid_argument("convex_pieces: tolerance and min_gain must be >= 0 and max_pieces >= 1");
  ConvexPieces r;
  r.volume = polyhedron_mass_properties(mesh).volume;
  if (!(r.volume > 0) || !std::isfinite(r.volume))
    throw std::invalid_argument("convex_pieces: the mesh encloses no volume (open, or inward-oriented)");
  r.hull_volume = hull_volume(mesh.vertices);
  std::vector<Vec3> v = mesh.vertices;
  std::vector<Entry> entries(1);
  for (const auto& t : mesh.triangles) entries[0].piece.push_back({t[0], t[1], t[2]});
  entries[0].hull = r.hull_volume;
  double total = r.hull_volume;
  while (static_cast<int>(entries.size()) < o.max_pieces && total > (1 + o.tolerance) * r.volume) {
    std::size_t pick = entries.size();
    // A cut may turn one piece into at most this many.
    const std::size_t room = static_cast<std::size_t>(o.max_pieces) - entries.size() + 1;
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (!entries[i].evaluated || entries[i].best.parts.size() > room) {
        entries[i].best = best_cut(entries[i], room, v);
        entries[i].evaluated = true;
      }
      if (pick == entries.size() || entries[i].best.gain > entries[pick].best.gain) pick = i;
    }
    if (pick == entries.size() || !(entries[pick].best.gain > o.min_gain * r.volume)) break;
    Candidate c = std::move(entries[pick].best);
    total -= c.gain;
    entries.erase(entries.begin() + static_cast<std::ptrdiff_t>(pick));
    for (std::size_t k = 0; k < c.parts.size(); ++k) {
      Entry e;
      e.piece = std::move(c.parts[k]);
      e.hull = c.part_volumes[k];
      entries.push_back(std::move(e));
    }
  }
  r.pieces_hull_volume = 0;
  for (const auto& e : entries) {
    r.pieces.push_back(points_of(e.piece, v));
    r.pieces_hull_volume += e.hull;
  }
  return r;
}

}  // namespace crumble
