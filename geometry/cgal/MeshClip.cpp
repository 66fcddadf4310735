// Plane cutting of closed meshes (see MeshClip.h). The single translation unit holding
// CGAL's corefinement-based clipping.
#include "geometry/cgal/MeshClip.h"

#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "geometry/cgal/CgalMesh.h"

namespace crumble {

namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

int root_of(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Keeps the part of `m` on the negative (side < 0) or positive (side > 0) side of the
// plane. Returns false if nothing is left.
bool keep_side(cgal::Mesh& m, const ClipPlane& p, int side) {
  // Half-space kept: n·x - o < 0 with (n, o) = -side * (normal, offset).
  const Vec3 n = p.normal * static_cast<double>(-side);
  const double o = p.offset * -side;
  // Quick decisions without CGAL when every vertex is on one side.
  bool any_below = false, any_above = false;
  for (auto v : m.vertices()) {
    const double s = dot(n, cgal::to_vec(m.point(v))) - o;  // > 0: to be removed
    if (s > 0) any_above = true;
    if (s < 0) any_below = true;
  }
  if (!any_above) return true;
  if (!any_below) {
    m.clear();
    return false;
  }
  // CGAL keeps the negative side of the plane a x + b y + c z + d = 0, here n·x - o < 0.
  const cgal::K::Plane_3 keep(n.x, n.y, n.z, -o);
  if (!PMP::clip(m, keep, CGAL::parameters::clip_volume(true)))
    throw std::runtime_error("split_by_planes: CGAL clip produced a non-manifold surface");
  m.collect_garbage();
  return m.number_of_faces() > 0;
}

void split_recursive(const cgal::Mesh& m, const std::vector<ClipPlane>& planes, std::size_t j,
                     std::vector<TriMesh>& out) {
  if (j == planes.size()) {
    for (auto& c : connected_components(cgal::to_trimesh(m))) out.push_back(std::move(c));
    return;
  }
  for (int side : {-1, 1}) {
    cgal::Mesh piece = m;
    if (keep_side(piece, planes[j], side)) split_recursive(piece, planes, j + 1, out);
  }
}

}  // namespace

std::vector<TriMesh> connected_components(const TriMesh& mesh) {
  const int nv = static_cast<int>(mesh.vertices.size());
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& t : mesh.triangles)
    for (int k = 1; k < 3; ++k) {
      const int a = root_of(parent, t[0]), b = root_of(parent, t[k]);
      if (a != b) parent[a] = b;
    }
  std::vector<int> comp_of_root(nv, -1), local(nv, -1);
  std::vector<TriMesh> comps;
  for (const auto& t : mesh.triangles) {
    const int r = root_of(parent, t[0]);
    if (comp_of_root[r] < 0) {
      comp_of_root[r] = static_cast<int>(comps.size());
      comps.emplace_back();
    }
    TriMesh& c = comps[comp_of_root[r]];
    std::array<int, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      if (local[t[k]] < 0) {
        local[t[k]] = static_cast<int>(c.vertices.size());
        c.vertices.push_back(mesh.vertices[t[k]]);
      }
      tri[k] = local[t[k]];
    }
    c.triangles.push_back(tri);
  }
  return comps;
}

std::vector<TriMesh> split_by_planes(const TriMesh& mesh, const std::vector<ClipPlane>& planes) {
  std::string why;
  if (!is_closed_oriented_manifold(mesh, &why))
    throw std::invalid_argument("split_by_planes: the mesh is not closed and manifold: " + why);
  for (const auto& p : planes)
    if (!is_finite(p.normal) || !std::isfinite(p.offset) || !(norm(p.normal) > 0))
      throw std::invalid_argument("split_by_planes: a cutting plane has a zero or non-finite normal/offset");
  const cgal::Mesh sm = cgal::to_surface_mesh(mesh);
  if (PMP::does_self_intersect(sm)) throw std::invalid_argument("split_by_planes: the mesh self-intersects");
  std::vector<TriMesh> out;
  split_recursive(sm, planes, 0, out);
  for (const auto& piece : out)
    if (!(polyhedron_mass_properties(piece).volume > 0))
      throw std::runtime_error("split_by_planes: a piece has no positive volume (cavity or degenerate cut)");
  return out;
}

}  // namespace crumble
