#include "geometry/SymmetricEigen.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace crumble {

PrincipalAxes principal_axes(const Mat3& m) {
  double scale = 0;
  for (double x : m.m) {
    if (!std::isfinite(x)) throw std::invalid_argument("principal_axes: tensor has a non-finite entry");
    scale = std::max(scale, std::abs(x));
  }
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if (std::abs(m(i, j) - m(j, i)) > 1e-10 * scale)
        throw std::invalid_argument("principal_axes: tensor is not symmetric");
  Mat3 a = m;
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) a(i, j) = a(j, i) = 0.5 * (m(i, j) + m(j, i));
  Mat3 v = Mat3::identity();
  // Cyclic Jacobi: each rotation zeroes one off-diagonal entry; converges quadratically.
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = a(0, 1) * a(0, 1) + a(0, 2) * a(0, 2) + a(1, 2) * a(1, 2);
    if (off <= 1e-34 * scale * scale || off == 0) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a(p, q) == 0) continue;
        const double theta = (a(q, q) - a(p, p)) / (2 * a(p, q));
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        // a <- Jᵀ a J with J the rotation in the (p, q) plane.
        for (int k = 0; k < 3; ++k) {
          const double akp = a(k, p), akq = a(k, q);
          a(k, p) = c * akp - s * akq;
          a(k, q) = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a(p, k), aqk = a(q, k);
          a(p, k) = c * apk - s * aqk;
          a(q, k) = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v(k, p), vkq = v(k, q);
          v(k, p) = c * vkp - s * vkq;
          v(k, q) = s * vkp + c * vkq;
        }
      }
  }
  PrincipalAxes r;
  r.moments = {a(0, 0), a(1, 1), a(2, 2)};
  // Right-handed: flip the last axis if needed (an eigenvector's sign is free).
  const Vec3 c0{v(0, 0), v(1, 0), v(2, 0)}, c1{v(0, 1), v(1, 1), v(2, 1)}, c2{v(0, 2), v(1, 2), v(2, 2)};
  if (dot(cross(c0, c1), c2) < 0)
    for (int k = 0; k < 3; ++k) v(k, 2) = -v(k, 2);
  r.axes = v;
  r.rotation = quat_from_rotation(v);
  return r;
}

PrincipalAxes2 principal_axes_2d(double xx, double xy, double yy) {
  if (!std::isfinite(xx) || !std::isfinite(xy) || !std::isfinite(yy))
    throw std::invalid_argument("principal_axes_2d: tensor has a non-finite entry");
  PrincipalAxes2 r;
  const double mean = 0.5 * (xx + yy), half = 0.5 * (xx - yy);
  const double radius = std::hypot(half, xy);  // Mohr's circle
  r.values[0] = mean - radius;
  r.values[1] = mean + radius;
  // Direction of the larger value at angle θ, tan 2θ = 2 xy / (xx − yy).
  const double theta = 0.5 * std::atan2(xy, half);
  r.vectors[1] = {std::cos(theta), std::sin(theta), 0};
  r.vectors[0] = {-std::sin(theta), std::cos(theta), 0};
  return r;
}

Quat quat_from_rotation(const Mat3& r) {
  const double tr = r.trace();
  Quat q;
  if (tr > 0) {
    const double s = 2 * std::sqrt(1 + tr);
    q = {0.25 * s, (r(2, 1) - r(1, 2)) / s, (r(0, 2) - r(2, 0)) / s, (r(1, 0) - r(0, 1)) / s};
  } else if (r(0, 0) > r(1, 1) && r(0, 0) > r(2, 2)) {
    const double s = 2 * std::sqrt(1 + r(0, 0) - r(1, 1) - r(2, 2));
    q = {(r(2, 1) - r(1, 2)) / s, 0.25 * s, (r(0, 1) + r(1, 0)) / s, (r(0, 2) + r(2, 0)) / s};
  } else if (r(1, 1) > r(2, 2)) {
    const double s = 2 * std::sqrt(1 + r(1, 1) - r(0, 0) - r(2, 2));
    q = {(r(0, 2) - r(2, 0)) / s, (r(0, 1) + r(1, 0)) / s, 0.25 * s, (r(1, 2) + r(2, 1)) / s};
  } else {
    const double s = 2 * std::sqrt(1 + r(2, 2) - r(0, 0) - r(1, 1));
    q = {(r(1, 0) - r(0, 1)) / s, (r(0, 2) + r(2, 0)) / s, (r(1, 2) + r(2, 1)) / s, 0.25 * s};
  }
  return q.normalized();
}

}  // namespace crumble
