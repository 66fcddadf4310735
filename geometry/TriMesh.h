// Closed triangle meshes and their exact mass properties.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "geometry/Vec3.h"

namespace crumble {

// Triangles are counter-clockwise seen from outside (outward normals).
struct TriMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;

  Aabb bounds() const;
  void translate(const Vec3& d);
  void scale(double s);
};

// Mass properties per unit density: volume, centroid, and the inertia tensor about the
// centroid (so multiply by density to get kg·m²). In 2D "volume" is area per unit
// thickness and only I_zz is meaningful.
struct MassProperties {
  double volume = 0;
  Vec3 centroid;
  Mat3 inertia;  // about the centroid, per unit density
};

// Exact integrals over a closed, outward-oriented triangle mesh (divergence theorem,
// Mirtich 1996 / Eberly "Polyhedral mass properties").
MassProperties polyhedron_mass_properties(const TriMesh& mesh);

// Euler characteristic V - E + F.
int euler_characteristic(const TriMesh& mesh);

// True if every edge is shared by exactly two triangles with opposite orientation.
bool is_closed_oriented_manifold(const TriMesh& mesh, std::string* why = nullptr);

double surface_area(const TriMesh& mesh);

// Icosahedron subdivided `level` times and projected on the unit sphere
// (level 1: 42 vertices, 80 faces — the grains of Zhu & Zhao 2019 §5).
TriMesh icosphere(int level);

}  // namespace crumble
