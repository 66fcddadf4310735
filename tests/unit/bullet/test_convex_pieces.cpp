// geometry/ConvexPieces: a concave polyhedron as convex pieces whose hulls cover it (what the
// Bullet adapter collides for a concave fragment, Zhu & Zhao 2019 §3.2).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "geometry/ConvexHull.h"
#include "geometry/ConvexPieces.h"
#include "geometry/Shape.h"
#include "geometry/TriMesh.h"
#include "tests/support/Meshes.h"

using namespace crumble;
using crumble::testing_support::u_prism;

namespace {

bool in_hull(const TriMesh& h, const Vec3& p, double tol) {
  for (const auto& t : h.triangles) {
    const Vec3 n = normalized(cross(h.vertices[t[1]] - h.vertices[t[0]], h.vertices[t[2]] - h.vertices[t[0]]));
    if (dot(n, p - h.vertices[t[0]]) > tol) return false;
  }
  return true;
}

}  // namespace

TEST(ConvexPieces, AConvexShapeIsOnePiece) {
  const TriMesh m = Shape::sphere(1e-3)->mesh();
  const ConvexPieces r = convex_pieces(m);
  ASSERT_EQ(r.pieces.size(), 1u);
  EXPECT_EQ(r.pieces[0].size(), m.vertices.size());
  EXPECT_NEAR(r.pieces_hull_volume, r.hull_volume, 1e-12 * r.hull_volume);
  EXPECT_NEAR(r.hull_volume, r.volume, 1e-12 * r.volume);  // the icosphere mesh is its own hull
}

// One cut through the bottom of the notch gives the base and the two prongs: three boxes whose
// hulls add up to the solid exactly, and none of them reaches into the notch.
TEST(ConvexPieces, AUPrismIsCutAtTheBottomOfItsNotch) {
  const TriMesh m = u_prism(3.0);
  std::string why;
  ASSERT_TRUE(is_closed_oriented_manifold(m, &why)) << why;
  const ConvexPieces r = convex_pieces(m);
  EXPECT_NEAR(r.volume, 15.0, 1e-12);
  EXPECT_NEAR(r.hull_volume, 18.0, 1e-12);
  ASSERT_EQ(r.pieces.size(), 3u);
  EXPECT_NEAR(r.pieces_hull_volume, 15.0, 1e-9);
  for (const auto& p : r.pieces) EXPECT_FALSE(in_hull(convex_hull(p), {1.5, 1.5, 1.5}, 1e-9));
}

// A star-shaped blob with deep dents (an icosphere with its radii modulated by ±35 %): every
// point of the solid lies in some piece's hull, and the pieces' hulls hold much less volume
// than the blob's hull.
TEST(ConvexPieces, ThePiecesCoverADentedBlobAndHoldLessThanItsHull) {
  ShapeResolution res;
  res.mesh_subdivisions = 3;
  TriMesh m = Shape::sphere(1.0, res)->mesh();
  for (auto& v : m.vertices) {
    const double th = std::acos(std::clamp(v.z / norm(v), -1.0, 1.0)), ph = std::atan2(v.y, v.x);
    v = v * (1.0 + 0.35 * std::sin(3 * th) * std::cos(2 * ph));
  }
  const auto blob = Shape::polyhedron(m);  // checks: closed, outward, manifold
  const TriMesh& bm = blob->mesh();
  const ConvexPieces r = convex_pieces(bm);
  EXPECT_LT(r.volume / r.hull_volume, 0.85);  // as concave as the fragments kept concave
  EXPECT_GE(r.pieces.size(), 2u);
  EXPECT_LE(r.pieces.size(), 8u);
  EXPECT_GE(r.pieces_hull_volume, r.volume * (1 - 1e-12));
  EXPECT_LT(r.pieces_hull_volume - r.volume, 0.5 * (r.hull_volume - r.volume));
  std::vector<TriMesh> hulls;
  for (const auto& p : r.pieces) hulls.push_back(convex_hull(p));
  std::mt19937_64 rng(3);
  const Aabb bb = blob->bounds();
  std::uniform_real_distribution<double> ux(bb.lo.x, bb.hi.x), uy(bb.lo.y, bb.hi.y), uz(bb.lo.z, bb.hi.z);
  int inside = 0, covered = 0;
  for (int k = 0; k < 4000; ++k) {
    const Vec3 p{ux(rng), uy(rng), uz(rng)};
    if (!blob->contains(p)) continue;
    ++inside;
    for (const auto& h : hulls)
      if (in_hull(h, p, 1e-12)) {
        ++covered;
        break;
      }
  }
  EXPECT_GT(inside, 500);
  EXPECT_EQ(covered, inside);
}

TEST(ConvexPieces, RejectsAnInwardMeshAndBadOptions) {
  TriMesh m = u_prism(1.0);
  ConvexPiecesOptions bad;
  bad.max_pieces = 0;
  EXPECT_THROW(convex_pieces(m, bad), std::invalid_argument);
  bad = {};
  bad.tolerance = -0.1;
  EXPECT_THROW(convex_pieces(m, bad), std::invalid_argument);
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  EXPECT_THROW(convex_pieces(m), std::invalid_argument);
}

// The limit holds even when the tolerance cannot be met.
TEST(ConvexPieces, MaxPiecesBoundsTheCount) {
  ConvexPiecesOptions o;
  o.max_pieces = 2;
  const ConvexPieces r = convex_pieces(u_prism(3.0), o);
  EXPECT_LE(r.pieces.size(), 2u);
  EXPECT_LT(r.pieces_hull_volume, r.hull_volume);
}

// Robustness: blobs with random dents in random orientations on a coarse mesh (cut points land
// next to vertices, and coplanar points abound) decompose without an error, and their pieces
// hold at least the blob's volume.
TEST(ConvexPieces, RandomDentedBlobsDecomposeWithoutError) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 30; ++k) {
    ShapeResolution res;
    res.mesh_subdivisions = 2;
    TriMesh m = Shape::sphere(1e-3, res)->mesh();
    const double a = 0.1 + 0.3 * u(rng), f1 = 1 + std::floor(4 * u(rng)), f2 = 1 + std::floor(4 * u(rng));
    const Quat q = Quat::from_axis_angle(normalized(Vec3{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5}), 6.28 * u(rng));
    for (auto& v : m.vertices) {
      const double th = std::acos(std::clamp(v.z / norm(v), -1.0, 1.0)), ph = std::atan2(v.y, v.x);
      v = q.rotate(v * (1.0 + a * std::sin(f1 * th) * std::cos(f2 * ph)));
    }
    const ConvexPieces r = convex_pieces(m);
    EXPECT_GE(r.pieces.size(), 1u) << k;
    EXPECT_GE(r.pieces_hull_volume, r.volume * (1 - 1e-9)) << k;
    for (const auto& p : r.pieces) EXPECT_NO_THROW(convex_hull(p)) << k;
  }
}
