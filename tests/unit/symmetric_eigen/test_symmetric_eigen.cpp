// geometry/SymmetricEigen: the principal axes shared by the Bullet adapter (inertia) and
// the stress breakage model (average stress).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "geometry/SymmetricEigen.h"

using namespace crumble;

TEST(SymmetricEigen, EigenAndQuaternionRoundTrip) {
  std::mt19937_64 rng(9);
  std::normal_distribution<double> n;
  for (int t = 0; t < 200; ++t) {
    const Quat q = Quat{n(rng), n(rng), n(rng), n(rng)}.normalized();
    const Quat p = quat_from_rotation(q.matrix());
    EXPECT_NEAR(std::abs(p.w * q.w + p.x * q.x + p.y * q.y + p.z * q.z), 1.0, 1e-14);  // all four branches
    // R diag(m) Rᵀ has principal moments m and axes R (up to order and sign).
    const Vec3 m{1 + std::abs(n(rng)), 2 + std::abs(n(rng)), 0.1 + std::abs(n(rng))};
    const Mat3 R = q.matrix();
    const Mat3 A = R * Mat3::diagonal(m) * R.transposed();
    const auto pa = principal_axes(A);
    const Mat3 back = pa.axes * Mat3::diagonal(pa.moments) * pa.axes.transposed();
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(back.m[i], A.m[i], 1e-12 * A.trace());
    const Mat3 axes_q = pa.rotation.matrix();
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(axes_q.m[i], pa.axes.m[i], 1e-12);
    EXPECT_NEAR(pa.moments.x + pa.moments.y + pa.moments.z, m.x + m.y + m.z, 1e-12 * A.trace());
  }
  Mat3 bad = Mat3::identity();
  bad(0, 1) = 1;
  EXPECT_THROW(principal_axes(bad), std::invalid_argument);
}

TEST(SymmetricEigen, DiagonalKeepsItsFrame) {
  // A diagonal tensor keeps its axes and order.
  const auto pa = principal_axes(Mat3::diagonal({3, -1, 2}));
  EXPECT_DOUBLE_EQ(pa.moments.x, 3);
  EXPECT_DOUBLE_EQ(pa.moments.y, -1);
  EXPECT_DOUBLE_EQ(pa.moments.z, 2);
  for (int i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(pa.axes.m[i], Mat3::identity().m[i]);
  const auto zero = principal_axes(Mat3{});
  EXPECT_EQ(zero.moments.x, 0);
  EXPECT_EQ(zero.moments.z, 0);
}

TEST(SymmetricEigen, TwoByTwoMohrCircle) {
  // Pure shear τ: principal values ±τ at 45°.
  const auto s = principal_axes_2d(0, 5, 0);
  EXPECT_NEAR(s.values[0], -5, 1e-14);
  EXPECT_NEAR(s.values[1], 5, 1e-14);
  EXPECT_NEAR(std::abs(s.vectors[1].x), std::sqrt(0.5), 1e-14);
  EXPECT_NEAR(std::abs(s.vectors[1].y), std::sqrt(0.5), 1e-14);
  // Against the 3D solver on random tensors.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n;
  for (int t = 0; t < 100; ++t) {
    const double xx = n(rng), xy = n(rng), yy = n(rng);
    Mat3 A;
    A(0, 0) = xx;
    A(0, 1) = A(1, 0) = xy;
    A(1, 1) = yy;
    A(2, 2) = -100;  // below both in-plane values
    const auto p3 = principal_axes(A);
    double m[3] = {p3.moments.x, p3.moments.y, p3.moments.z};
    std::sort(m, m + 3);
    const auto p2 = principal_axes_2d(xx, xy, yy);
    EXPECT_NEAR(p2.values[0], m[1], 1e-12);
    EXPECT_NEAR(p2.values[1], m[2], 1e-12);
    for (int k = 0; k < 2; ++k) {
      const Vec3 v = p2.vectors[k];
      const Vec3 Av{xx * v.x + xy * v.y, xy * v.x + yy * v.y, 0};
      EXPECT_NEAR(norm(Av - v * p2.values[k]), 0, 1e-12);
    }
  }
  EXPECT_THROW(principal_axes_2d(NAN, 0, 0), std::invalid_argument);
}
