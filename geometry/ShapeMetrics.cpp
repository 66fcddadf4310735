#include "geometry/ShapeMetrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "geometry/LevelSetGrid.h"
#include "geometry/Shape.h"
#include "geometry/SymmetricEigen.h"

namespace crumble {

namespace {

double cross2(const Vec3& a, const Vec3& b) { return a.x * b.y - a.y * b.x; }

}  // namespace

double circularity(double area, double perimeter) {
  if (!(area > 0) || !(perimeter > 0)) throw std::invalid_argument("circularity needs area > 0 and perimeter > 0");
  // Harmon et al. 2020 eq. 23.
  return 4 * kPi * area / (perimeter * perimeter);
}

double aspect_ratio_from_second_moments(double sxx, double syy, double sxy) {
  const double mean = 0.5 * (sxx + syy);
  const double rad = std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
  const double lmax = mean + rad, lmin = mean - rad;
  if (!(lmax > 0)) throw std::invalid_argument("aspect ratio needs a non-zero second moment");
  // An ellipse of semi-axes a, b has central second moments ∝ a², b² along its axes.
  return std::sqrt(std::max(0.0, lmin) / lmax);
}

ShapeMetrics2D shape_metrics_2d(const std::vector<Vec3>& poly) {
  const std::size_t n = poly.size();
  if (n < 3) throw std::invalid_argument("shape metrics need an outline of at least 3 vertices");
  // Green's theorem: area, centroid and second moments of a polygon.
  double a2 = 0, cx = 0, cy = 0, per = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& p = poly[i];
    const Vec3& q = poly[(i + 1) % n];
    const double w = cross2(p, q);
    a2 += w;
    cx += (p.x + q.x) * w;
    cy += (p.y + q.y) * w;
    per += std::hypot(q.x - p.x, q.y - p.y);
  }
  if (!(std::abs(a2) > 0)) throw std::invalid_argument("shape metrics need an outline enclosing a non-zero area");
  const double area = 0.5 * a2;  // signed: negative for a clockwise outline
  const Vec3 c{cx / (6 * area), cy / (6 * area), 0};
  double ixx = 0, iyy = 0, ixy = 0;  // ∫x², ∫y², ∫xy about the centroid (signed with area)
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p = poly[i] - c;
    const Vec3 q = poly[(i + 1) % n] - c;
    const double w = cross2(p, q);
    ixx += (p.x * p.x + p.x * q.x + q.x * q.x) * w / 12;
    iyy += (p.y * p.y + p.y * q.y + q.y * q.y) * w / 12;
    ixy += (p.x * q.y + 2 * p.x * p.y + 2 * q.x * q.y + q.x * p.y) * w / 24;
  }
  const double sgn = area > 0 ? 1.0 : -1.0;
  ShapeMetrics2D m;
  m.area = std::abs(area);
  m.perimeter = per;
  m.circularity = circularity(m.area, per);
  m.aspect_ratio = aspect_ratio_from_second_moments(sgn * ixx, sgn * iyy, sgn * ixy);

  // Harmon et al. 2020 eq. 21: p_min, the surface point closest to the centroid.
  double rmin = std::numeric_limits<double>::infinity();
  Vec3 pmin, edge_dir;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p{poly[i].x, poly[i].y, 0};
    const Vec3 q{poly[(i + 1) % n].x, poly[(i + 1) % n].y, 0};
    const Vec3 e = q - p;
    const double l2 = norm2(e);
    const double s = l2 > 0 ? std::clamp(dot(c - p, e) / l2, 0.0, 1.0) : 0.0;
    const Vec3 x = p + e * s;
    const double r = norm(x - c);
    if (r < rmin) {
      rmin = r;
      pmin = x;
      edge_dir = e;
    }
  }
  // The line from the centroid through p_min (a centroid on the outline: along the normal).
  Vec3 u = rmin > 0 ? (pmin - c) / rmin : normalized(Vec3{edge_dir.y, -edge_dir.x, 0});
  // The chord: p_min on one side, the nearest crossing of the outline on the other.
  double back = std::numeric_limits<double>::infinity();
  const double tiny = 1e-12 * std::sqrt(m.area);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p{poly[i].x, poly[i].y, 0};
    const Vec3 e = Vec3{poly[(i + 1) % n].x, poly[(i + 1) % n].y, 0} - p;
    const double den = cross2(u, e);
    if (std::abs(den) <= 1e-300) continue;  // parallel to the line
    const double t = cross2(p - c, e) / den;
    const double s = cross2(p - c, u) / den;
    if (s < 0 || s > 1) continue;
    if (t < -tiny) back = std::min(back, -t);
  }
  m.sieve_size = rmin + (std::isfinite(back) ? back : 0.0);
  return m;
}

double sphericity(double volume, double area) {
  if (!(volume > 0) || !(area > 0)) throw std::invalid_argument("sphericity needs volume > 0 and area > 0");
  return std::cbrt(kPi) * std::pow(6 * volume, 2.0 / 3.0) / area;
}

std::array<double, 3> equivalent_ellipsoid_axes(const Mat3& inertia, double volume) {
  if (!(volume > 0)) throw std::invalid_argument("equivalent ellipsoid needs volume > 0");
  const Vec3 m = principal_axes(inertia).moments;
  const double l[3] = {m.x, m.y, m.z};
  const double sum = l[0] + l[1] + l[2];
  // Solid ellipsoid: I₁ = V(b² + c²)/5 … so a² = 5(I₂ + I₃ − I₁)/(2V) = 5(ΣI − 2I₁)/(2V).
  std::array<double, 3> ax{};
  for (int k = 0; k < 3; ++k) ax[k] = 2 * std::sqrt(std::max(0.0, 5 * (sum - 2 * l[k]) / (2 * volume)));
  std::sort(ax.begin(), ax.end(), std::greater<double>());
  return ax;
}

const char* zingg_class(double ei, double fi) {
  constexpr double k = 2.0 / 3.0;
  if (ei >= k) return fi >= k ? "spheroid" : "disc";
  return fi >= k ? "rod" : "blade";
}

std::array<double, 3> principal_extents(const TriMesh& mesh, const Mat3& inertia) {
  if (mesh.vertices.empty()) throw std::invalid_argument("principal extents need a mesh with vertices");
  // Zhu & Zhao 2019 §5: turn the grain into its principal axes of inertia and measure its
  // extent along each (the columns of `axes` are the unit principal directions).
  const Mat3 a = principal_axes(inertia).axes;
  std::array<double, 3> ext{};
  for (int k = 0; k < 3; ++k) {
    const Vec3 u{a(0, k), a(1, k), a(2, k)};
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& v : mesh.vertices) {
      const double t = dot(v, u);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    ext[k] = hi - lo;
  }
  std::sort(ext.begin(), ext.end(), std::greater<double>());
  return ext;
}

ShapeMetrics3D shape_metrics_3d(const TriMesh& mesh, const MassProperties& mp) {
  ShapeMetrics3D m;
  m.volume = mp.volume;
  m.surface_area = surface_area(mesh);
  m.sphericity = sphericity(mp.volume, m.surface_area);
  m.principal_dimensions = principal_extents(mesh, mp.inertia);
  const auto& d = m.principal_dimensions;
  m.elongation = d[0] > 0 ? d[1] / d[0] : 0;
  m.flatness = d[1] > 0 ? d[2] / d[1] : 0;
  return m;
}

namespace {
// Distance from the centroid (inside) to the surface along the unit direction u: the first
// sign change of the signed distance, marched at `step` and refined by bisection.
double exit_distance(const Shape& s, const Vec3& u, double step, double reach) {
  double a = 0, b = step;
  while (b < reach && s.signed_distance(u * b) < 0) {
    a = b;
    b += step;
  }
  b = std::min(b, reach);
  for (int i = 0; i < 60; ++i) {
    const double m = 0.5 * (a + b);
    (s.signed_distance(u * m) < 0 ? a : b) = m;
  }
  return 0.5 * (a + b);
}
}  // namespace

double sieve_size(const Shape& s) {
  if (!(s.signed_distance({}) < 0)) return s.equivalent_diameter();
  // The chord through the signed distance (analytic for the analytic sources, so a disk
  // gives its diameter to round-off), from the surface node closest to the centroid.
  const auto& nodes = s.level_set().nodes();
  Vec3 pmin;
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : nodes)
    if (norm(p) < best) {
      best = norm(p);
      pmin = p;
    }
  if (!(best > 0) || !std::isfinite(best)) return s.equivalent_diameter();
  const Vec3 u = pmin * (1.0 / best);
  const double reach = 2.0 * s.bounding_radius() + 1e-12;
  // March finely enough not to step over a thin part: a fraction of the distance to p_min.
  const double step = std::max(0.25 * best, 1e-3 * reach);
  return exit_distance(s, u, step, reach) + exit_distance(s, u * -1.0, step, reach);
}

}  // namespace crumble
