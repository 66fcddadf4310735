// Small, header-only linear algebra for the public API (no Eigen here: Eigen stays
// inside the few translation units that need decompositions).
#pragma once
#include <array>
#include <cmath>
#include <limits>

namespace crumble {

struct Vec3 {
  double x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  constexpr Vec3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
  constexpr bool operator==(const Vec3& o) const = default;
};
constexpr Vec3 operator*(double s, const Vec3& v) { return v * s; }
constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
constexpr double norm2(const Vec3& a) { return dot(a, a); }
inline Vec3 normalized(const Vec3& a) {
  const double n = norm(a);
  return n > 0 ? a / n : Vec3{};
}
inline bool is_finite(const Vec3& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
constexpr Vec3 cwise_min(const Vec3& a, const Vec3& b) {
  return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
constexpr Vec3 cwise_max(const Vec3& a, const Vec3& b) {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}

// Row-major 3x3 matrix.
struct Mat3 {
  std::array<double, 9> m{};
  static constexpr Mat3 zero() { return Mat3{}; }
  static constexpr Mat3 identity() {
    Mat3 r;
    r.m = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    return r;
  }
  static constexpr Mat3 diagonal(const Vec3& d) {
    Mat3 r;
    r.m = {d.x, 0, 0, 0, d.y, 0, 0, 0, d.z};
    return r;
  }
  static constexpr Mat3 outer(const Vec3& a, const Vec3& b) {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r(i, j) = a[i] * b[j];
    return r;
  }
  constexpr double operator()(int i, int j) const { return m[3 * i + j]; }
  constexpr double& operator()(int i, int j) { return m[3 * i + j]; }
  constexpr Vec3 operator*(const Vec3& v) const {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
            m[6] * v.x + m[7] * v.y + m[8] * v.z};
  }
  constexpr Mat3 operator*(const Mat3& o) const {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double s = 0;
        for (int k = 0; k < 3; ++k) s += (*this)(i, k) * o(k, j);
        r(i, j) = s;
      }
    return r;
  }
  constexpr Mat3 operator+(const Mat3& o) const {
    Mat3 r;
    for (int i = 0; i < 9; ++i) r.m[i] = m[i] + o.m[i];
    return r;
  }
  constexpr Mat3 operator-(const Mat3& o) const {
    Mat3 r;
    for (int i = 0; i < 9; ++i) r.m[i] = m[i] - o.m[i];
    return r;
  }
  constexpr Mat3 operator*(double s) const {
    Mat3 r;
    for (int i = 0; i < 9; ++i) r.m[i] = m[i] * s;
    return r;
  }
  constexpr Mat3& operator+=(const Mat3& o) {
    for (int i = 0; i < 9; ++i) m[i] += o.m[i];
    return *this;
  }
  constexpr Mat3 transposed() const {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r(i, j) = (*this)(j, i);
    return r;
  }
  constexpr double trace() const { return m[0] + m[4] + m[8]; }
};

// Unit quaternion (w, x, y, z) rotating body-frame vectors into the world frame.
struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
  static Quat from_axis_angle(const Vec3& axis, double angle) {
    const Vec3 a = crumble::normalized(axis);
    const double s = std::sin(0.5 * angle);
    return {std::cos(0.5 * angle), a.x * s, a.y * s, a.z * s};
  }
  constexpr Quat operator*(const Quat& q) const {
    return {w * q.w - x * q.x - y * q.y - z * q.z, w * q.x + x * q.w + y * q.z - z * q.y,
            w * q.y - x * q.z + y * q.w + z * q.x, w * q.z + x * q.y - y * q.x + z * q.w};
  }
  constexpr Quat conjugate() const { return {w, -x, -y, -z}; }
  Quat normalized() const {
    const double n = std::sqrt(w * w + x * x + y * y + z * z);
    return {w / n, x / n, y / n, z / n};
  }
  constexpr Vec3 rotate(const Vec3& v) const {
    // v' = v + 2 q_v x (q_v x v + w v)
    const Vec3 qv{x, y, z};
    const Vec3 t = cross(qv, v) * 2.0;
    return v + t * w + cross(qv, t);
  }
  constexpr Mat3 matrix() const {
    Mat3 r;
    r.m = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
           2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
           2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    return r;
  }
};

struct Aabb {
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity()};
  constexpr void extend(const Vec3& p) {
    lo = cwise_min(lo, p);
    hi = cwise_max(hi, p);
  }
  constexpr Vec3 size() const { return hi - lo; }
  constexpr Vec3 center() const { return (lo + hi) * 0.5; }
  constexpr bool empty() const { return hi.x < lo.x; }
};

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace crumble
