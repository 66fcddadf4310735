#include "geometry/TriMesh.h"

#include <algorithm>
#include <cstdint>
#include <map>
#include <set>
#include <utility>

namespace crumble {

Aabb TriMesh::bounds() const {
  Aabb b;
  for (const auto& v : vertices) b.extend(v);
  return b;
}

void TriMesh::translate(const Vec3& d) {
  for (auto& v : vertices) v += d;
}

void TriMesh::scale(double s) {
  for (auto& v : vertices) v *= s;
}

MassProperties polyhedron_mass_properties(const TriMesh& mesh) {
  // Integrals of 1, x, y, z, x², y², z², xy, yz, zx over the solid, via the divergence
  // theorem on each triangle (Eberly, "Polyhedral Mass Properties (Revisited)").
  double intg[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  auto subexp = [](double w0, double w1, double w2, double& f1, double& f2, double& f3,
                   double& g0, double& g1, double& g2) {
    const double t0 = w0 + w1;
    f1 = t0 + w2;
    const double t1 = w0 * w0;
    const double t2 = t1 + w1 * t0;
    f2 = t2 + w2 * f1;
    f3 = w0 * t1 + w1 * t2 + w2 * f2;
    g0 = f2 + w0 * (f1 + w0);
    g1 = f2 + w1 * (f1 + w1);
    g2 = f2 + w2 * (f1 + w2);
  };
  for (const auto& t : mesh.triangles) {
    const Vec3& p0 = mesh.vertices[t[0]];
    const Vec3& p1 = mesh.vertices[t[1]];
    const Vec3& p2 = mesh.vertices[t[2]];
    const Vec3 d = cross(p1 - p0, p2 - p0);
    double f1x, f2x, f3x, g0x, g1x, g2x, f1y, f2y, f3y, g0y, g1y, g2y, f1z, f2z, f3z, g0z, g1z,
        g2z;
    subexp(p0.x, p1.x, p2.x, f1x, f2x, f3x, g0x, g1x, g2x);
    subexp(p0.y, p1.y, p2.y, f1y, f2y, f3y, g0y, g1y, g2y);
    subexp(p0.z, p1.z, p2.z, f1z, f2z, f3z, g0z, g1z, g2z);
    intg[0] += d.x * f1x;
    intg[1] += d.x * f2x;
    intg[2] += d.y * f2y;
    intg[3] += d.z * f2z;
    intg[4] += d.x * f3x;
    intg[5] += d.y * f3y;
    intg[6] += d.z * f3z;
    intg[7] += d.x * (p0.y * g0x + p1.y * g1x + p2.y * g2x);
    intg[8] += d.y * (p0.z * g0y + p1.z * g1y + p2.z * g2y);
    intg[9] += d.z * (p0.x * g0z + p1.x * g1z + p2.x * g2z);
  }
  const double mult[10] = {1.0 / 6,  1.0 / 24, 1.0 / 24, 1.0 / 24,  1.0 / 60,
                           1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (int i = 0; i < 10; ++i) intg[i] *= mult[i];
  MassProperties mp;
  mp.volume = intg[0];
  if (mp.volume <= 0) return mp;
  const Vec3 c{intg[1] / mp.volume, intg[2] / mp.volume, intg[3] / mp.volume};
  mp.centroid = c;
  const double V = mp.volume;
  Mat3 I;
  I(0, 0) = intg[5] + intg[6] - V * (c.y * c.y + c.z * c.z);
  I(1, 1) = intg[4] + intg[6] - V * (c.z * c.z + c.x * c.x);
  I(2, 2) = intg[4] + intg[5] - V * (c.x * c.x + c.y * c.y);
  I(0, 1) = I(1, 0) = -(intg[7] - V * c.x * c.y);
  I(1, 2) = I(2, 1) = -(intg[8] - V * c.y * c.z);
  I(0, 2) = I(2, 0) = -(intg[9] - V * c.z * c.x);
  mp.inertia = I;
  return mp;
}

int euler_characteristic(const TriMesh& mesh) {
  std::set<std::pair<int, int>> edges;
  std::set<int> used;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      edges.insert({std::min(a, b), std::max(a, b)});
      used.insert(a);
    }
  return static_cast<int>(used.size()) - static_cast<int>(edges.size()) +
         static_cast<int>(mesh.triangles.size());
}

bool is_closed_oriented_manifold(const TriMesh& mesh, std::string* why) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (a < 0 || b < 0 || a >= static_cast<int>(mesh.vertices.size()) ||
          b >= static_cast<int>(mesh.vertices.size())) {
        if (why) *why = "triangle refers to a vertex index out of range";
        return false;
      }
      if (a == b) {
        if (why) *why = "degenerate triangle (repeated vertex)";
        return false;
      }
      if (++directed[{a, b}] > 1) {
        if (why) *why = "edge " + std::to_string(a) + "-" + std::to_string(b) +
                        " used twice in the same direction (non-manifold or inconsistent orientation)";
        return false;
      }
    }
  }
  for (const auto& [e, n] : directed) {
    if (!directed.count({e.second, e.first})) {
      if (why) *why = "open boundary edge " + std::to_string(e.first) + "-" + std::to_string(e.second);
      return false;
    }
  }
  if (mesh.triangles.empty()) {
    if (why) *why = "mesh has no triangles";
    return false;
  }
  return true;
}

double surface_area(const TriMesh& mesh) {
  double a = 0;
  for (const auto& t : mesh.triangles)
    a += 0.5 * norm(cross(mesh.vertices[t[1]] - mesh.vertices[t[0]],
                          mesh.vertices[t[2]] - mesh.vertices[t[0]]));
  return a;
}

TriMesh icosphere(int level) {
  TriMesh m;
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  m.vertices = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  for (auto& v : m.vertices) v = normalized(v);
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.vertices.push_back(normalized(m.vertices[a] + m.vertices[b]));
      const int idx = static_cast<int>(m.vertices.size()) - 1;
      mid[key] = idx;
      return idx;
    };
    std::vector<std::array<int, 3>> next;
    next.reserve(m.triangles.size() * 4);
    for (const auto& t : m.triangles) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  return m;
}

}  // namespace crumble
