// geometry/ConvexHull against CGAL's convex_hull_3 (exact predicates): the same volume and
// the same extreme points, within 1e-9 of the cloud's size, on the saved clouds (data/) and
// on degenerate ones; orientation() against CGAL::orientation.
#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <random>

#include "HullChecks.h"

using namespace crumble;
using namespace crumble::testing_support;

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = K::Point_3;

TriMesh cgal_hull(const std::vector<Vec3>& pts) {
  std::vector<P3> in;
  for (const auto& p : pts) in.emplace_back(p.x, p.y, p.z);
  CGAL::Surface_mesh<P3> sm;
  CGAL::convex_hull_3(in.begin(), in.end(), sm);
  TriMesh m;
  for (auto v : sm.vertices()) {
    const P3& p = sm.point(v);
    m.vertices.push_back({p.x(), p.y(), p.z()});
  }
  for (auto f : sm.faces()) {
    std::vector<int> ring;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) ring.push_back(static_cast<int>(v.idx()));
    for (std::size_t i = 1; i + 1 < ring.size(); ++i) m.triangles.push_back({ring[0], ring[i], ring[i + 1]});
  }
  return m;
}

// Signed distance of p to the hull's boundary along the nearest face plane: ≈ 0 on it.
double depth_below(const TriMesh& h, const Vec3& p) {
  double best = -1e300;
  for (const auto& t : h.triangles) {
    const Vec3 a = h.vertices[t[0]];
    const Vec3 c = cross(h.vertices[t[1]] - a, h.vertices[t[2]] - a);
    const double longest = std::max({norm2(h.vertices[t[1]] - a), norm2(h.vertices[t[2]] - a),
                                     norm2(h.vertices[t[2]] - h.vertices[t[1]])});
    if (norm(c) > 1e-6 * longest) best = std::max(best, dot(c / norm(c), p - a));
  }
  return -best;
}

void expect_as_cgal(const std::vector<Vec3>& pts, const std::string& what) {
  const TriMesh h = convex_hull(pts);
  const TriMesh ref = cgal_hull(pts);
  const double size = norm(ref.bounds().size());
  const double v = polyhedron_mass_properties(h).volume, vref = polyhedron_mass_properties(ref).volume;
  EXPECT_NEAR(v, vref, 1e-9 * vref) << what;
  // Every extreme point is on the hull's boundary, and every hull vertex on CGAL's.
  for (const auto& p : ref.vertices) EXPECT_LE(std::abs(depth_below(h, p)), 1e-9 * size) << what;
  for (const auto& p : h.vertices) EXPECT_LE(std::abs(depth_below(ref, p)), 1e-9 * size) << what;
  EXPECT_LE(h.vertices.size(), ref.vertices.size() + ref.vertices.size() / 2) << what;
}

}  // namespace

TEST(ConvexHullCgal, SavedCloudsGiveCgalsHull) {
  for (const auto& f : saved_clouds()) expect_as_cgal(read_cloud(f), f.filename().string());
}

TEST(ConvexHullCgal, DegenerateCloudsGiveCgalsHull) {
  for (unsigned seed = 1; seed <= 20; ++seed)
    for (const auto& [name, pts] : degenerate_clouds(seed)) expect_as_cgal(pts, name + " seed " + std::to_string(seed));
}

TEST(ConvexHullCgal, OrientationAgreesWithCgal) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 100000; ++trial) {
    // Three random points and a fourth on (or within rounding of) their plane.
    const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)}, c{u(rng), u(rng), u(rng)};
    const double s = u(rng), t = u(rng);
    const Vec3 p = a + (b - a) * s + (c - a) * t + Vec3{u(rng), u(rng), u(rng)} * (trial % 3 ? 0.0 : 1e-15);
    const auto ref = CGAL::orientation(P3(a.x, a.y, a.z), P3(b.x, b.y, b.z), P3(c.x, c.y, c.z), P3(p.x, p.y, p.z));
    ASSERT_EQ(orientation(a, b, c, p), static_cast<int>(ref)) << "trial " << trial;
  }
}
