// Small closed meshes for tests.
#pragma once
#include <utility>

#include "geometry/TriMesh.h"

namespace crumble::testing_support {

// The prism of a U-shaped polygon in the x–z plane: 3 wide, 2 tall, a notch 1 wide and 1 deep
// from the top (x in [1, 2], z in [1, 2]), `length` along y, all times `unit`. Closed,
// outward-oriented: volume 5·length·unit³, its hull 6·length·unit³.
inline TriMesh u_prism(double length, double unit = 1.0) {
  const double ring[10][2] = {{0, 0}, {1, 0}, {2, 0}, {3, 0}, {3, 2}, {2, 2}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  // The end face as triangles of ring indices (three rectangles, no T-junction).
  const int cap[8][3] = {{0, 1, 7}, {0, 7, 8}, {0, 8, 9}, {1, 2, 6}, {1, 6, 7}, {3, 4, 5}, {3, 5, 6}, {3, 6, 2}};
  TriMesh m;
  for (double y : {0.0, length})
    for (const auto& p : ring) m.vertices.push_back(Vec3{p[0], y, p[1]} * unit);
  for (const auto& t : cap) {
    m.triangles.push_back({t[0], t[1], t[2]});
    m.triangles.push_back({10 + t[0], 10 + t[2], 10 + t[1]});
  }
  for (int i = 0; i < 10; ++i) {
    const int j = (i + 1) % 10;
    m.triangles.push_back({i, 10 + i, 10 + j});
    m.triangles.push_back({i, 10 + j, j});
  }
  if (polyhedron_mass_properties(m).volume < 0)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}

}  // namespace crumble::testing_support
