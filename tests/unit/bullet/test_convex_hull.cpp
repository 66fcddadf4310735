// geometry/ConvexHull: closed, outward, extreme points only; exact volume on a cube.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "geometry/ConvexHull.h"
#include "geometry/Shape.h"
#include "geometry/TriMesh.h"

using namespace crumble;

namespace {
// Largest signed distance of p above any face plane of the hull (negative: strictly inside).
double max_plane_distance(const TriMesh& h, const Vec3& p) {
  double worst = -1e300;
  for (const auto& t : h.triangles) {
    const Vec3 n = normalized(cross(h.vertices[t[1]] - h.vertices[t[0]], h.vertices[t[2]] - h.vertices[t[0]]));
    worst = std::max(worst, dot(n, p - h.vertices[t[0]]));
  }
  return worst;
}

void expect_valid(const TriMesh& h) {
  std::string why;
  EXPECT_TRUE(is_closed_oriented_manifold(h, &why)) << why;
  EXPECT_EQ(euler_characteristic(h), 2);
  EXPECT_GT(polyhedron_mass_properties(h).volume, 0);  // outward orientation
}
}  // namespace

TEST(ConvexHull, CubeCornersWithInteriorAndFacePointsGiveEightVertices) {
  std::vector<Vec3> pts;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.999, 0.999);
  for (int i = 0; i < 200; ++i) pts.push_back({u(rng), u(rng), u(rng)});
  // Points on faces and edges (not extreme) and the 8 corners of [-1,1]^3 (+ offset).
  for (int i = 0; i < 30; ++i) {
    pts.push_back({1, u(rng), u(rng)});
    pts.push_back({u(rng), -1, 1});
    pts.push_back({0, 0, -1});
  }
  for (int x : {-1, 1})
    for (int y : {-1, 1})
      for (int z : {-1, 1}) pts.push_back({double(x), double(y), double(z)});
  for (int i = 0; i < 8; ++i) pts.push_back({0.5, 1, 0});  // duplicates on a face
  for (auto& p : pts) p += Vec3{10, -3, 2};
  const TriMesh h = convex_hull(pts);
  EXPECT_EQ(h.vertices.size(), 8u);
  EXPECT_EQ(h.triangles.size(), 12u);
  expect_valid(h);
  const auto mp = polyhedron_mass_properties(h);
  EXPECT_NEAR(mp.volume, 8.0, 1e-12);
  EXPECT_NEAR(mp.centroid.x, 10.0, 1e-12);
  for (const auto& v : h.vertices) {
    EXPECT_DOUBLE_EQ(std::abs(v.x - 10), 1.0);
    EXPECT_DOUBLE_EQ(std::abs(v.y + 3), 1.0);
    EXPECT_DOUBLE_EQ(std::abs(v.z - 2), 1.0);
  }
}

TEST(ConvexHull, RandomPointsOnSphereAreAllOnOrInsideAndHullIsClosed) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> g;
  std::vector<Vec3> pts;
  for (int i = 0; i < 2000; ++i) pts.push_back(normalized(Vec3{g(rng), g(rng), g(rng)}) * 1e-3);
  const TriMesh h = convex_hull(pts);
  expect_valid(h);
  // Every point of a sphere sample is extreme.
  EXPECT_EQ(h.vertices.size(), pts.size());
  for (const auto& p : pts) EXPECT_LE(max_plane_distance(h, p), 1e-15);
  // Volume approaches the ball's from below.
  const double vball = 4.0 / 3.0 * kPi * 1e-9;
  const double v = polyhedron_mass_properties(h).volume;
  EXPECT_LT(v, vball);
  EXPECT_GT(v, 0.99 * vball);
}

TEST(ConvexHull, InteriorPointsOfARandomCloudAreInside) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> pts;
  for (int i = 0; i < 3000; ++i) pts.push_back({u(rng), 0.3 * u(rng), 2 * u(rng)});
  const TriMesh h = convex_hull(pts);
  expect_valid(h);
  for (const auto& p : pts) EXPECT_LE(max_plane_distance(h, p), 1e-12);
  EXPECT_LT(h.vertices.size(), pts.size());
}

TEST(ConvexHull, IcosphereLevelOneHullHas42Vertices) {
  const TriMesh ico = icosphere(1);
  const TriMesh h = convex_hull(ico.vertices);
  EXPECT_EQ(h.vertices.size(), 42u);
  EXPECT_EQ(h.triangles.size(), 80u);
  expect_valid(h);
  EXPECT_NEAR(polyhedron_mass_properties(h).volume, polyhedron_mass_properties(ico).volume, 1e-12);
  // Through Shape: the lazily built hull of a sphere grain.
  const auto s = Shape::sphere(1e-3);
  EXPECT_EQ(s->convex_hull().vertices.size(), 42u);
}

TEST(ConvexHull, RejectsTooFewAndFlatClouds) {
  EXPECT_THROW(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), std::invalid_argument);
  std::vector<Vec3> flat;
  for (int i = 0; i < 20; ++i) flat.push_back({std::cos(i * 0.3), std::sin(i * 0.7), 0.0});
  EXPECT_THROW(convex_hull(flat), std::invalid_argument);
  std::vector<Vec3> line;
  for (int i = 0; i < 20; ++i) line.push_back({i * 1.0, 2.0 * i, -1.0 * i});
  EXPECT_THROW(convex_hull(line), std::invalid_argument);
  std::vector<Vec3> same(10, Vec3{1, 2, 3});
  EXPECT_THROW(convex_hull(same), std::invalid_argument);
  EXPECT_THROW(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, NAN}}), std::invalid_argument);
}

TEST(ConvexHull, LatticeWithManyCoplanarPointsGivesTheBox) {
  // 7x5x9 lattice: every face holds many coplanar and collinear points.
  std::vector<Vec3> pts;
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 9; ++k) pts.push_back({0.1 * i, 0.3 * j - 7.0, 1e3 + 0.05 * k});
  const TriMesh h = convex_hull(pts);
  EXPECT_EQ(h.vertices.size(), 8u);
  expect_valid(h);
  EXPECT_NEAR(polyhedron_mass_properties(h).volume, 0.6 * 1.2 * 0.4, 1e-9);
  // A box shape's hull and a rotated lattice, too.
  EXPECT_EQ(Shape::box({1e-3, 2e-3, 0.5e-3})->convex_hull().vertices.size(), 8u);
  const Quat q = Quat::from_axis_angle({1, 2, 3}, 0.7);
  for (auto& p : pts) p = q.rotate(p);
  const TriMesh hr = convex_hull(pts);
  EXPECT_EQ(hr.vertices.size(), 8u);
  expect_valid(hr);
}

TEST(ConvexHull, InsetMovesEveryFacePlaneInwardsByTheDistance) {
  // Largest shift of each original face plane after the inset, over all faces (min, max).
  auto plane_shifts = [](const TriMesh& h, const std::vector<Vec3>& moved) {
    double lo = 1e300, hi = -1e300;
    for (const auto& t : h.triangles) {
      const Vec3 n = normalized(cross(h.vertices[t[1]] - h.vertices[t[0]], h.vertices[t[2]] - h.vertices[t[0]]));
      double top = -1e300;
      for (const auto& p : moved) top = std::max(top, dot(n, p - h.vertices[t[0]]));
      lo = std::min(lo, top);
      hi = std::max(hi, top);
    }
    return std::pair{lo, hi};
  };
  // Box: three faces per corner, exact.
  const TriMesh box = Shape::box({1.0, 2.0, 0.5})->convex_hull();
  const auto in = inset_convex_vertices(box, 0.1);
  ASSERT_EQ(in.size(), 8u);
  EXPECT_NEAR(polyhedron_mass_properties(convex_hull(in)).volume, 8 * 0.9 * 1.9 * 0.4, 1e-10);
  auto [blo, bhi] = plane_shifts(box, in);
  EXPECT_NEAR(blo, -0.1, 1e-12);
  EXPECT_NEAR(bhi, -0.1, 1e-12);
  // Icosphere grain (5 or 6 faces per vertex): every face plane moves in by the distance
  // within 2 % of it, and the vertex count stays 42.
  const TriMesh ico = Shape::sphere(1e-3)->convex_hull();
  const double d = 2e-5;
  const auto ii = inset_convex_vertices(ico, d);
  ASSERT_EQ(ii.size(), 42u);
  auto [ilo, ihi] = plane_shifts(ico, ii);
  EXPECT_NEAR(ilo, -d, 0.02 * d);
  EXPECT_NEAR(ihi, -d, 0.02 * d);
  EXPECT_NEAR(convex_inradius_about_centroid(box), 0.5, 1e-15);
  EXPECT_THROW(inset_convex_vertices(box, 0.5), std::invalid_argument);
  EXPECT_THROW(inset_convex_vertices(box, -0.1), std::invalid_argument);
}
