// MeshDistance (geometry/MeshDistance.h): signed distance to closed triangle meshes,
// checked against closed forms (box), brute force over all triangles (icosphere), the
// analytic sphere within the chord error, and the generalized winding number
// (Jacobson et al. 2013) on a non-convex mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "geometry/MeshDistance.h"
#include "geometry/Shape.h"
#include "geometry/TriMesh.h"

using namespace crumble;

namespace {

double analytic_box(const Vec3& h, const Vec3& p) {
  const Vec3 q{std::abs(p.x) - h.x, std::abs(p.y) - h.y, std::abs(p.z) - h.z};
  return norm(cwise_max(q, {0, 0, 0})) + std::min(std::max({q.x, q.y, q.z}), 0.0);
}

// Unsigned distance to one triangle by brute-force minimisation over its parts:
// the interior (if the projection falls inside) and the three segments.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp(dot(p - a, ab) / dot(ab, ab), 0.0, 1.0);
  return norm(p - (a + ab * t));
}
double triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = normalized(cross(b - a, c - a));
  const double h = dot(p - a, n);
  const Vec3 q = p - n * h;
  const bool inside = dot(cross(b - a, q - a), n) >= 0 && dot(cross(c - b, q - b), n) >= 0 &&
                      dot(cross(a - c, q - c), n) >= 0;
  if (inside) return std::abs(h);
  return std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}
double brute_unsigned(const TriMesh& m, const Vec3& p) {
  double d = 1e300;
  for (const auto& t : m.triangles)
    d = std::min(d, triangle_distance(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
  return d;
}

// Generalized winding number: sum of signed solid angles / 4π (Van Oosterom & Strackee 1983).
double winding_number(const TriMesh& m, const Vec3& p) {
  double w = 0;
  for (const auto& t : m.triangles) {
    const Vec3 a = m.vertices[t[0]] - p, b = m.vertices[t[1]] - p, c = m.vertices[t[2]] - p;
    const double la = norm(a), lb = norm(b), lc = norm(c);
    const double num = dot(a, cross(b, c));
    const double den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    w += 2 * std::atan2(num, den);
  }
  return w / (4 * kPi);
}

// A star-shaped, strongly non-convex closed mesh: icosphere with radial bumps.
TriMesh bumpy_sphere(int level) {
  TriMesh m = icosphere(level);
  for (auto& v : m.vertices) {
    const double th = std::acos(std::clamp(v.z, -1.0, 1.0)), ph = std::atan2(v.y, v.x);
    v *= 1.0 + 0.35 * std::sin(3 * th) * std::cos(4 * ph);
  }
  return m;
}

}  // namespace

TEST(MeshDistance, BoxMatchesAnalyticDistance) {
  const Vec3 h{1.0e-3, 0.6e-3, 0.3e-3};
  const TriMesh mesh = Shape::box(h)->mesh();
  const MeshDistance md(mesh);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p{u(rng) * h.x, u(rng) * h.y, u(rng) * h.z};
    ASSERT_NEAR(md.signed_distance(p), analytic_box(h, p), 1e-15) << i;
    ASSERT_EQ(md.contains(p), analytic_box(h, p) < 0) << i;
  }
  // Near the surface (±1e-9 h along the outward normal of a face, also at edges/corners).
  std::uniform_real_distribution<double> s(-1.0, 1.0);
  for (int i = 0; i < 6000; ++i) {
    Vec3 q{s(rng) * h.x, s(rng) * h.y, s(rng) * h.z};
    const int axis = i % 3;
    q[axis] = (i % 2 ? 1 : -1) * h[axis];
    if (i % 5 == 0) q[(axis + 1) % 3] = h[(axis + 1) % 3];  // on an edge
    if (i % 25 == 0) q[(axis + 2) % 3] = -h[(axis + 2) % 3];  // on a corner
    const Vec3 dir = normalized(Vec3{s(rng), s(rng), s(rng)});
    const Vec3 p = q + dir * (1e-9 * h.z);
    const double ref = analytic_box(h, p);
    if (std::abs(ref) < 1e-13 * h.z) continue;  // tangential offset: sign undefined
    ASSERT_NEAR(md.signed_distance(p), ref, 1e-15) << i;
    ASSERT_EQ(md.signed_distance(p) < 0, ref < 0) << i;
  }
}

TEST(MeshDistance, IcosphereMatchesBruteForceAndSphere) {
  const double r = 1e-3;
  TriMesh mesh = icosphere(3);
  mesh.scale(r);
  const MeshDistance md(mesh);
  // Chord error: the polyhedron lies between the spheres of radius r - delta and r.
  double inner = r;
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[t[0]];
    const Vec3 n = normalized(cross(mesh.vertices[t[1]] - a, mesh.vertices[t[2]] - a));
    inner = std::min(inner, dot(a, n));
  }
  const double delta = r - inner;
  ASSERT_GT(delta, 0);
  ASSERT_LT(delta, 0.01 * r);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-2 * r, 2 * r);
  for (int i = 0; i < 3000; ++i) {
    const Vec3 p{u(rng), u(rng), u(rng)};
    const double sd = md.signed_distance(p);
    // Exact polyhedral distance (convex: inside iff behind every face plane).
    double plane_max = -1e300;
    for (const auto& t : mesh.triangles) {
      const Vec3& a = mesh.vertices[t[0]];
      plane_max = std::max(plane_max, dot(p - a, normalized(cross(mesh.vertices[t[1]] - a, mesh.vertices[t[2]] - a))));
    }
    const double ref = (plane_max < 0 ? -1 : 1) * brute_unsigned(mesh, p);
    ASSERT_NEAR(sd, ref, 1e-15) << i;
    // Analytic sphere within the chord error.
    ASSERT_LE(std::abs(sd - (norm(p) - r)), delta * (1 + 1e-9)) << i;
  }
  // Points just off vertices, edge midpoints and face centres, in random directions.
  std::uniform_real_distribution<double> s(-1.0, 1.0);
  int checked = 0;
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    const auto& t = mesh.triangles[k];
    const Vec3 a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    for (const Vec3& q : {a, (a + b) * 0.5, (a + b + c) / 3.0}) {
      const Vec3 p = q + normalized(Vec3{s(rng), s(rng), s(rng)}) * (1e-7 * r);
      double plane_max = -1e300;
      for (const auto& tt : mesh.triangles) {
        const Vec3& aa = mesh.vertices[tt[0]];
        plane_max = std::max(plane_max, dot(p - aa, normalized(cross(mesh.vertices[tt[1]] - aa, mesh.vertices[tt[2]] - aa))));
      }
      if (std::abs(plane_max) < 1e-12 * r) continue;
      ASSERT_EQ(md.contains(p), plane_max < 0) << k;
      ++checked;
    }
  }
  EXPECT_GT(checked, 3000);
}

TEST(MeshDistance, NonConvexSignMatchesWindingNumber) {
  const TriMesh mesh = bumpy_sphere(3);
  std::string why;
  ASSERT_TRUE(is_closed_oriented_manifold(mesh, &why)) << why;
  const MeshDistance md(mesh);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.4, 1.4);
  int inside = 0, outside = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 p{u(rng), u(rng), u(rng)};
    const double w = winding_number(mesh, p);
    ASSERT_TRUE(std::abs(w) < 1e-6 || std::abs(w - 1) < 1e-6) << "winding " << w;
    const double sd = md.signed_distance(p);
    ASSERT_EQ(sd < 0, w > 0.5) << i << " sd " << sd;
    ASSERT_NEAR(std::abs(sd), brute_unsigned(mesh, p), 1e-14) << i;
    (w > 0.5 ? inside : outside)++;
  }
  EXPECT_GT(inside, 300);
  EXPECT_GT(outside, 300);
  // Points very close to the surface, around every vertex (the concave ones included).
  std::uniform_real_distribution<double> s(-1.0, 1.0);
  for (std::size_t k = 0; k < mesh.vertices.size(); ++k) {
    const Vec3 p = mesh.vertices[k] + normalized(Vec3{s(rng), s(rng), s(rng)}) * 1e-6;
    const double w = winding_number(mesh, p);
    if (std::abs(w - 0.5) > 0.45) {
      ASSERT_EQ(md.contains(p), w > 0.5) << "vertex " << k << " w " << w;
    }
  }
}

TEST(MeshDistance, ShapePolyhedronIsConsistent) {
  const Vec3 h{0.8e-3, 0.5e-3, 0.4e-3};
  TriMesh mesh = Shape::box(h)->mesh();
  const Vec3 shift{2e-3, -1e-3, 0.5e-3};
  mesh.translate(shift);  // Shape::polyhedron re-centres it
  const auto shape = Shape::polyhedron(mesh);
  EXPECT_NEAR(norm(shape->recentring() + shift), 0, 1e-15);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int i = 0; i < 5000; ++i) {
    const Vec3 p{u(rng) * h.x, u(rng) * h.y, u(rng) * h.z};
    const double sd = shape->signed_distance(p);
    ASSERT_NEAR(sd, analytic_box(h, p), 1e-15);
    ASSERT_EQ(shape->contains(p), sd < 0);
  }
  // Sphere mesh as polyhedron: same answers as a MeshDistance on the mesh itself.
  TriMesh ico = icosphere(2);
  ico.scale(1e-3);
  const auto sph = Shape::polyhedron(ico);
  const MeshDistance md(ico);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p{u(rng) * 1e-3, u(rng) * 1e-3, u(rng) * 1e-3};
    ASSERT_NEAR(sph->signed_distance(p), md.signed_distance(p), 1e-15);
    ASSERT_EQ(sph->contains(p), md.contains(p));
  }
}

TEST(MeshDistance, ConcurrentQueriesAgreeWithSerial) {
  const TriMesh mesh = bumpy_sphere(4);
  const MeshDistance md(mesh);
  std::vector<Vec3> pts(20000);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.4, 1.4);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  std::vector<double> serial(pts.size()), parallel(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) serial[i] = md.signed_distance(pts[i]);
#pragma omp parallel for num_threads(4)
  for (long i = 0; i < static_cast<long>(pts.size()); ++i) parallel[i] = md.signed_distance(pts[i]);
  EXPECT_EQ(serial, parallel);
}

TEST(MeshDistance, RejectsBadInput) {
  EXPECT_THROW(MeshDistance(TriMesh{}), std::invalid_argument);
  TriMesh bad;
  bad.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  bad.triangles = {{0, 1, 3}};
  EXPECT_THROW(MeshDistance{bad}, std::invalid_argument);
  const MeshDistance md(Shape::box({1, 1, 1})->mesh());
  EXPECT_THROW(md.signed_distance({std::nan(""), 0, 0}), std::invalid_argument);
}
