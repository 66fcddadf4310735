// Internal to the CGAL translation units of crumble_alpha_shape (AlphaShape.cpp,
// MeshClip.cpp): conversions between TriMesh and CGAL::Surface_mesh. Never include this
// from a public header — CGAL stays inside .cpp files.
#pragma once
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <stdexcept>
#include <vector>

#include "geometry/TriMesh.h"

namespace crumble::cgal {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

inline Point to_point(const Vec3& v) { return {v.x, v.y, v.z}; }
inline Vec3 to_vec(const Point& p) { return {p.x(), p.y(), p.z()}; }

inline Mesh to_surface_mesh(const TriMesh& m) {
  Mesh out;
  std::vector<Mesh::Vertex_index> vi;
  vi.reserve(m.vertices.size());
  for (const auto& v : m.vertices) vi.push_back(out.add_vertex(to_point(v)));
  for (const auto& t : m.triangles)
    if (out.add_face(vi[t[0]], vi[t[1]], vi[t[2]]) == Mesh::null_face())
      throw std::invalid_argument("mesh is not an oriented 2-manifold (CGAL Surface_mesh refused a triangle)");
  return out;
}

// Only the vertices used by faces are kept (compacted).
inline TriMesh to_trimesh(const Mesh& m) {
  TriMesh out;
  std::vector<int> index(m.number_of_vertices() + m.number_of_removed_vertices(), -1);
  for (auto f : m.faces()) {
    std::array<int, 3> tri{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) {
      if (k == 3) throw std::logic_error("to_trimesh: the surface mesh has a non-triangular face");
      int& id = index[v.idx()];
      if (id < 0) {
        id = static_cast<int>(out.vertices.size());
        out.vertices.push_back(to_vec(m.point(v)));
      }
      tri[k++] = id;
    }
    out.triangles.push_back(tri);
  }
  return out;
}

}  // namespace crumble::cgal
