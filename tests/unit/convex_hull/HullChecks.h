// Checks shared by the convex-hull tests: the saved point clouds (data/*.txt) and what a
// valid hull of a cloud is.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "geometry/ConvexHull.h"
#include "geometry/TriMesh.h"

namespace crumble::testing_support {

// One point "x y z" per line.
inline std::vector<Vec3> read_cloud(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<Vec3> pts;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    Vec3 p;
    if (s >> p.x >> p.y >> p.z) pts.push_back(p);
  }
  return pts;
}

inline std::vector<std::filesystem::path> saved_clouds() {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(CRUMBLE_SOURCE_DIR) /
                                                           "tests/unit/convex_hull/data"))
    if (e.path().extension() == ".txt") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

// How far p lies above the face (a, b, c): 0 when it is on or below it (exact orientation),
// else the rounded plane distance (normal from the two edges at the vertex opposite the
// longest edge).
inline double distance_above(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  if (orientation(a, b, c, p) <= 0) return 0;
  const Vec3 e0 = b - a, e1 = c - b, e2 = a - c;
  const double l0 = norm2(e0), l1 = norm2(e1), l2 = norm2(e2);
  const Vec3 n = l0 >= l1 && l0 >= l2 ? cross(e1, e2) : (l1 >= l2 ? cross(e2, e0) : cross(e0, e1));
  return dot(n, p - a) / norm(n);
}

// Largest distance of a point of `pts` above a face of `h` (0: all inside).
inline double worst_outside(const TriMesh& h, const std::vector<Vec3>& pts) {
  double worst = 0;
  for (const auto& p : pts)
    for (const auto& t : h.triangles)
      worst = std::max(worst, distance_above(h.vertices[t[0]], h.vertices[t[1]], h.vertices[t[2]], p));
  return worst;
}

// Closed, outward, of positive volume, its vertices input points, every input point inside
// within 1e-9 of the cloud's size.
inline void expect_hull_of(const TriMesh& h, const std::vector<Vec3>& pts, const std::string& what) {
  std::string why;
  EXPECT_TRUE(is_closed_oriented_manifold(h, &why)) << what << ": " << why;
  EXPECT_EQ(euler_characteristic(h), 2) << what;
  EXPECT_GT(polyhedron_mass_properties(h).volume, 0) << what;
  for (const auto& v : h.vertices) EXPECT_NE(std::find(pts.begin(), pts.end(), v), pts.end()) << what;
  Aabb box;
  for (const auto& p : pts) box.extend(p);
  EXPECT_LE(worst_outside(h, pts), 1e-9 * norm(box.size())) << what;
}

}  // namespace crumble::testing_support

#include <random>

#include "geometry/Vec3.h"

namespace crumble::testing_support {

// Degenerate clouds of about 1 mm, each with its name: points on a rotated grid (many
// coplanar and collinear points, none exactly so after the rotation), many points on the
// faces of a rotated box, near-duplicates 1e-9 of the size apart, and points on the cut
// planes of a ball (what geometry/ConvexPieces makes).
inline std::vector<std::pair<std::string, std::vector<Vec3>>> degenerate_clouds(unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> g;
  const Quat q = Quat::from_axis_angle({u(rng), u(rng), 1}, 3 * u(rng));
  const Vec3 shift{1e-3 * u(rng), 1e-3 * u(rng), 1e-3 * u(rng)};
  std::vector<std::pair<std::string, std::vector<Vec3>>> out;
  std::vector<Vec3> grid;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 4; ++k) grid.push_back(q.rotate(Vec3{i * 2e-4, j * 2.5e-4, k * 1e-4}) + shift);
  out.emplace_back("grid", grid);
  std::vector<Vec3> box;
  for (int f = 0; f < 6; ++f)
    for (int i = 0; i < 40; ++i) {
      Vec3 p{u(rng), u(rng), u(rng)};
      p[f / 2] = f % 2 ? 1 : -1;
      box.push_back(q.rotate(p * 5e-4) + shift);
    }
  for (int c = 0; c < 8; ++c) box.push_back(q.rotate(Vec3{c & 1 ? 5e-4 : -5e-4, c & 2 ? 5e-4 : -5e-4, c & 4 ? 5e-4 : -5e-4}) + shift);
  out.emplace_back("box_faces", box);
  std::vector<Vec3> dup;
  for (int i = 0; i < 150; ++i) {
    const Vec3 p = normalized(Vec3{g(rng), g(rng), g(rng)}) * 5e-4 + shift;
    dup.push_back(p);
    dup.push_back(p + normalized(Vec3{g(rng), g(rng), g(rng)}) * 1e-12);  // 1e-9 of 1 mm
  }
  out.emplace_back("near_duplicates", dup);
  std::vector<Vec3> cut;
  const Vec3 n1 = normalized(Vec3{u(rng), u(rng), u(rng)}), n2 = normalized(Vec3{u(rng), u(rng), u(rng)});
  for (int i = 0; i < 300; ++i) {
    const Vec3 p = normalized(Vec3{g(rng), g(rng), g(rng)}) * 5e-4 * std::cbrt(0.5 + 0.5 * u(rng));
    if (dot(p, n1) <= 1e-4 && dot(p, n2) <= 0) cut.push_back(p + shift);
  }
  for (const Vec3& n : {n1, n2}) {
    const double h = n == n1 ? 1e-4 : 0;
    const Vec3 t1 = normalized(cross(n, Vec3{0.3, 0.5, 0.7})), t2 = cross(n, t1);
    for (int i = 0; i < 60; ++i) {
      const Vec3 p = n * h + t1 * (4e-4 * u(rng)) + t2 * (4e-4 * u(rng));
      if (dot(p, n1) <= 1e-4 && dot(p, n2) <= 0) cut.push_back(p + shift);  // rounded: on the plane within ulps
    }
  }
  out.emplace_back("cut_planes", cut);
  return out;
}

}  // namespace crumble::testing_support
