// Signed distance to a closed, outward-oriented triangle mesh.
//
// Nearest triangle: a bounding-volume hierarchy (axis-aligned boxes, median split on the
// longest axis of the triangle centroids) traversed nearest-child first with pruning on
// the squared box distance. Closest point on a triangle and the feature it lies on
// (vertex, edge or face): Ericson, "Real-Time Collision Detection" (2005) §5.1.5.
// Sign: angle-weighted pseudo-normals of the feature (Bærentzen & Aanæs, IEEE TVCG 11(3)
// 2005, "Signed distance computation using the angle weighted pseudonormal"): for a
// closed manifold mesh, (p − q)·n_feature > 0 exactly when p is outside.
//
// Everything is built in the constructor; queries only read, so concurrent const calls
// are safe.
#include "geometry/MeshDistance.h"
#include "base/BuildCounters.h"

#include <algorithm>
#include <array>
#include <limits>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

namespace crumble {

namespace {

// Feature of a triangle on which the closest point lies.
enum Feature : int { kVertA, kVertB, kVertC, kEdgeAB, kEdgeBC, kEdgeCA, kFace };

// Closest point to p on triangle (a, b, c), with the feature it lies on (Ericson §5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Feature& f) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) { f = kVertA; return a; }
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) { f = kVertB; return b; }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    f = kEdgeAB;
    return a + ab * (d1 / (d1 - d3));
  }
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) { f = kVertC; return c; }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    f = kEdgeCA;
    return a + ac * (d2 / (d2 - d6));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    f = kEdgeBC;
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) {  // degenerate (zero-area) triangle: nearest of its edges
    f = kEdgeAB;
    return a;
  }
  const double v = vb / denom, w = vc / denom;
  f = kFace;
  return a + ab * v + ac * w;
}

double box_distance2(const Aabb& b, const Vec3& p) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double lo = b.lo[k] - p[k], hi = p[k] - b.hi[k];
    const double e = std::max({lo, hi, 0.0});
    d2 += e * e;
  }
  return d2;
}

}  // namespace

struct MeshDistance::Impl {
  struct Node {
    Aabb box;
    int left = -1, right = -1;  // children (internal node)
    int begin = 0, end = 0;     // range in `order` (leaf: left == -1)
  };
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<Vec3> face_normal;                  // unit (zero for degenerate faces)
  std::vector<Vec3> vertex_normal;                // angle-weighted pseudo-normal (unnormalised)
  std::vector<std::array<Vec3, 3>> edge_normal;   // per triangle, edges ab, bc, ca
  std::vector<int> order;                         // triangle indices, leaf ranges
  std::vector<Node> nodes;

  static constexpr int kLeafSize = 4;

  int build(int begin, int end, const std::vector<Vec3>& centre) {
    Node n;
    Aabb cb;
    for (int i = begin; i < end; ++i) {
      const auto& t = triangles[order[i]];
      for (int k = 0; k < 3; ++k) n.box.extend(vertices[t[k]]);
      cb.extend(centre[order[i]]);
    }
    const int id = static_cast<int>(nodes.size());
    nodes.push_back(n);
    if (end - begin <= kLeafSize) {
      nodes[id].begin = begin;
      nodes[id].end = end;
      return id;
    }
    const Vec3 ext = cb.size();
    const int axis = (ext.x >= ext.y && ext.x >= ext.z) ? 0 : (ext.y >= ext.z ? 1 : 2);
    const int mid = (begin + end) / 2;
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                     [&](int a, int b) { return centre[a][axis] < centre[b][axis]; });
    const int l = build(begin, mid, centre);
    const int r = build(mid, end, centre);
    nodes[id].left = l;
    nodes[id].right = r;
    return id;
  }

  // Nearest point on the mesh: returns squared distance, the point and its pseudo-normal.
  double nearest(const Vec3& p, Vec3& q_best, Vec3& n_best) const {
    double best = std::numeric_limits<double>::infinity();
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes[stack[--top]];
      if (box_distance2(n.box, p) >= best) continue;
      if (n.left < 0) {
        for (int i = n.begin; i < n.end; ++i) {
          const int ti = order[i];
          const auto& t = triangles[ti];
          Feature f;
          const Vec3 q = closest_on_triangle(p, vertices[t[0]], vertices[t[1]], vertices[t[2]], f);
          const double d2 = norm2(p - q);
          if (d2 < best) {
            best = d2;
            q_best = q;
            switch (f) {
              case kVertA: n_best = vertex_normal[t[0]]; break;
              case kVertB: n_best = vertex_normal[t[1]]; break;
              case kVertC: n_best = vertex_normal[t[2]]; break;
              case kEdgeAB: n_best = edge_normal[ti][0]; break;
              case kEdgeBC: n_best = edge_normal[ti][1]; break;
              case kEdgeCA: n_best = edge_normal[ti][2]; break;
              case kFace: n_best = face_normal[ti]; break;
            }
          }
        }
        continue;
      }
      const double dl = box_distance2(nodes[n.left].box, p);
      const double dr = box_distance2(nodes[n.right].box, p);
      // Push the farther child first so the nearer one is visited first.
      if (dl < dr) {
        if (dr < best) stack[top++] = n.right;
        if (dl < best) stack[top++] = n.left;
      } else {
        if (dl < best) stack[top++] = n.left;
        if (dr < best) stack[top++] = n.right;
      }
    }
    return best;
  }
};

MeshDistance::MeshDistance(const TriMesh& mesh) : impl_(std::make_unique<Impl>()) {
  if (mesh.triangles.empty()) throw std::invalid_argument("MeshDistance: the mesh has no triangles");
  count_built(Representation::MeshDistance);
  const int nv = static_cast<int>(mesh.vertices.size());
  for (const auto& v : mesh.vertices)
    if (!is_finite(v)) throw std::invalid_argument("MeshDistance: the mesh has a non-finite vertex");
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv)
        throw std::invalid_argument("MeshDistance: triangle vertex index " + std::to_string(t[k]) +
                                    " out of range [0, " + std::to_string(nv) + ")");
  Impl& m = *impl_;
  m.vertices = mesh.vertices;
  m.triangles = mesh.triangles;
  const int nt = static_cast<int>(m.triangles.size());

  // Pseudo-normals (Bærentzen & Aanæs 2005): faces by their unit normal, edges by the sum
  // of the two incident face normals, vertices by the incident face normals weighted by
  // the incident angle.
  m.face_normal.resize(nt);
  m.vertex_normal.assign(nv, Vec3{});
  std::unordered_map<long long, Vec3> edge_sum;
  edge_sum.reserve(3 * nt);
  auto edge_key = [nv](int a, int b) {
    return static_cast<long long>(std::min(a, b)) * nv + std::max(a, b);
  };
  for (int i = 0; i < nt; ++i) {
    const auto& t = m.triangles[i];
    const Vec3 n = normalized(cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]));
    m.face_normal[i] = n;
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = normalized(m.vertices[t[(k + 1) % 3]] - m.vertices[t[k]]);
      const Vec3 w = normalized(m.vertices[t[(k + 2) % 3]] - m.vertices[t[k]]);
      const double angle = std::acos(std::clamp(dot(u, w), -1.0, 1.0));
      m.vertex_normal[t[k]] += n * angle;
      edge_sum[edge_key(t[k], t[(k + 1) % 3])] += n;
    }
  }
  m.edge_normal.resize(nt);
  for (int i = 0; i < nt; ++i) {
    const auto& t = m.triangles[i];
    for (int k = 0; k < 3; ++k) m.edge_normal[i][k] = edge_sum[edge_key(t[k], t[(k + 1) % 3])];
  }

  std::vector<Vec3> centre(nt);
  for (int i = 0; i < nt; ++i) {
    const auto& t = m.triangles[i];
    centre[i] = (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0;
  }
  m.order.resize(nt);
  for (int i = 0; i < nt; ++i) m.order[i] = i;
  m.nodes.reserve(2 * nt / Impl::kLeafSize + 2);
  m.build(0, nt, centre);
}

MeshDistance::~MeshDistance() = default;
MeshDistance::MeshDistance(MeshDistance&&) noexcept = default;

double MeshDistance::signed_distance(const Vec3& p) const {
  if (!is_finite(p)) throw std::invalid_argument("MeshDistance: query point is not finite");
  Vec3 q, n;
  const double d = std::sqrt(impl_->nearest(p, q, n));
  return dot(p - q, n) < 0 ? -d : d;
}

bool MeshDistance::contains(const Vec3& p) const { return signed_distance(p) < 0; }

}  // namespace crumble
