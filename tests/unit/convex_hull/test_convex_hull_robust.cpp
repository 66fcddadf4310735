// geometry/ConvexHull on point clouds that made the tolerance quickhull fail, and the exact
// orientation predicate it falls back on.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "HullChecks.h"

using namespace crumble;
using namespace crumble::testing_support;

// data/: the clouds that stopped stress-model runs (breakage.type=stress on the quick Zhu &
// Zhao oedometer and the 12-sphere plate, 2026-12-04). The tolerance quickhull threw
// "horizon is not a closed loop" (the faces an eye point saw were no disc) or found no
// convex hull at any tolerance.
TEST(ConvexHullRobust, SavedCloudsGiveAClosedHullHoldingEveryPoint) {
  const auto files = saved_clouds();
  ASSERT_FALSE(files.empty());
  for (const auto& f : files) {
    const std::vector<Vec3> pts = read_cloud(f);
    ASSERT_GE(pts.size(), 4u) << f;
    TriMesh h;
    ASSERT_NO_THROW(h = convex_hull(pts)) << f;
    expect_hull_of(h, pts, f.filename().string());
    const TriMesh again = convex_hull(pts);  // deterministic
    EXPECT_EQ(again.vertices, h.vertices) << f;
    EXPECT_EQ(again.triangles, h.triangles) << f;
  }
}

TEST(ConvexHullRobust, DegenerateCloudsGiveAClosedHullHoldingEveryPoint) {
  for (unsigned seed = 1; seed <= 20; ++seed)
    for (const auto& [name, pts] : degenerate_clouds(seed)) {
      TriMesh h;
      ASSERT_NO_THROW(h = convex_hull(pts)) << name << " seed " << seed;
      expect_hull_of(h, pts, name + " seed " + std::to_string(seed));
    }
}

// The determinant is alternating: an even permutation of (a, b, c, p) keeps its sign, an odd
// one flips it. Rounding breaks that for nearly coplanar points; the exact sign cannot.
TEST(ConvexHullRobust, OrientationIsExactOnNearlyCoplanarPoints) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  int zeros = 0, nonzero = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    // Four points on a plane: on odd trials exactly (small integers on z = x + 2y, scaled by a
    // power of two), on even ones rounded (the plane with normal (1, 2, 3), within an ulp).
    std::array<Vec3, 4> p;
    for (auto& x : p) {
      if (trial % 2) {
        const double a = std::round(8 * u(rng)), b = std::round(8 * u(rng));
        x = Vec3{a, b, a + 2 * b} * 0.125 + Vec3{0.5, -0.25, 1};
      } else {
        const double a = u(rng), b = u(rng);
        x = Vec3{a, b, -(a + 2 * b) / 3} * 1e-3 + Vec3{0.7, -0.2, 0.1};
      }
    }
    std::array<int, 4> perm{0, 1, 2, 3};
    const int s0 = orientation(p[0], p[1], p[2], p[3]);
    (s0 == 0 ? zeros : nonzero)++;
    do {
      int parity = 0;  // inversions
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) parity += perm[i] > perm[j];
      const int s = orientation(p[perm[0]], p[perm[1]], p[perm[2]], p[perm[3]]);
      ASSERT_EQ(s, parity % 2 ? -s0 : s0) << "trial " << trial;
    } while (std::next_permutation(perm.begin(), perm.end()));
  }
  EXPECT_GT(zeros, 100);
  EXPECT_GT(nonzero, 100);
  // Far from the plane the filter decides.
  EXPECT_EQ(orientation({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.3, 1e-3}), 1);
  EXPECT_EQ(orientation({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.3, -1e-300}), -1);
  EXPECT_EQ(orientation({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.3, 0}), 0);
}
