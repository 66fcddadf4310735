#include "geometry/Shape.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "base/BuildCounters.h"
#include "geometry/ConvexHull.h"
#include "geometry/LevelSetGrid.h"
#include "geometry/MeshDistance.h"

namespace crumble {

const char* to_string(ShapeKind k) {
  switch (k) {
    case ShapeKind::Sphere: return "sphere";
    case ShapeKind::Ellipsoid: return "ellipsoid";
    case ShapeKind::Superellipsoid: return "superellipsoid";
    case ShapeKind::Box: return "box";
    case ShapeKind::Polyhedron: return "polyhedron";
    case ShapeKind::LevelSet: return "level_set";
    case ShapeKind::Disk: return "disk";
    case ShapeKind::Ellipse: return "ellipse";
    case ShapeKind::Superellipse: return "superellipse";
    case ShapeKind::Polygon: return "polygon";
  }
  return "?";
}

namespace {

void require_positive(double v, const char* what) {
  if (!(v > 0) || !std::isfinite(v))
    throw std::invalid_argument(std::string(what) + " must be a finite number > 0 (got " +
                                std::to_string(v) + ")");
}

// (|x/rx|^(2/e1) + |y/ry|^(2/e1))^(e1/e2) + |z/rz|^(2/e2): the superellipsoid inside
// function, homogeneous of degree 2/e2 in p.
double superellipsoid_f(const Vec3& p, const Vec3& r, double e1, double e2) {
  const double a = std::pow(std::abs(p.x / r.x), 2.0 / e1) + std::pow(std::abs(p.y / r.y), 2.0 / e1);
  return std::pow(a, e1 / e2) + std::pow(std::abs(p.z / r.z), 2.0 / e2);
}

// Radial distance to the surface along the ray from the centre: exact zero set and sign,
// exact for spheres. `scale` is the factor that maps p onto the surface (r(p) = 1 there).
double radial_distance(const Vec3& p, double r_of_p) {
  const double n = norm(p);
  if (r_of_p <= 0) return -1e300;  // the centre itself: deepest point (caller clamps)
  return n * (1.0 - 1.0 / r_of_p);
}

MassProperties polygon_mass_properties(const std::vector<Vec3>& poly) {
  // Shoelace formulas for area, centroid and polar moment (about the centroid).
  double A = 0, cx = 0, cy = 0, Ix = 0, Iy = 0;
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& a = poly[i];
    const Vec3& b = poly[(i + 1) % n];
    const double c = a.x * b.y - b.x * a.y;
    A += c;
    cx += (a.x + b.x) * c;
    cy += (a.y + b.y) * c;
    Iy += (a.x * a.x + a.x * b.x + b.x * b.x) * c;
    Ix += (a.y * a.y + a.y * b.y + b.y * b.y) * c;
  }
  A *= 0.5;
  MassProperties mp;
  mp.volume = A;
  if (A <= 0) return mp;
  cx /= 6 * A;
  cy /= 6 * A;
  Ix /= 12;
  Iy /= 12;
  mp.centroid = {cx, cy, 0};
  const double Ixc = Ix - A * cy * cy, Iyc = Iy - A * cx * cx;
  mp.inertia = Mat3::diagonal({Ixc, Iyc, Ixc + Iyc});
  return mp;
}

TriMesh box_mesh(const Vec3& h) {
  TriMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.push_back({(i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z});
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// Parametric tessellation of a superellipsoid (signed powers of cos/sin).
TriMesh superellipsoid_mesh(const Vec3& r, double e1, double e2, int level) {
  const int nu = 8 << std::max(0, level), nv = nu / 2;
  auto spow = [](double b, double e) { return (b < 0 ? -1.0 : 1.0) * std::pow(std::abs(b), e); };
  TriMesh m;
  m.vertices.push_back({0, 0, -r.z});
  for (int j = 1; j < nv; ++j) {
    const double v = -kPi / 2 + kPi * j / nv;
    for (int i = 0; i < nu; ++i) {
      const double u = 2 * kPi * i / nu;
      m.vertices.push_back({r.x * spow(std::cos(v), e2) * spow(std::cos(u), e1),
                            r.y * spow(std::cos(v), e2) * spow(std::sin(u), e1),
                            r.z * spow(std::sin(v), e2)});
    }
  }
  m.vertices.push_back({0, 0, r.z});
  const int top = static_cast<int>(m.vertices.size()) - 1;
  auto idx = [&](int j, int i) { return 1 + (j - 1) * nu + (i % nu); };
  for (int i = 0; i < nu; ++i) m.triangles.push_back({0, idx(1, i + 1), idx(1, i)});
  for (int j = 1; j < nv - 1; ++j)
    for (int i = 0; i < nu; ++i) {
      m.triangles.push_back({idx(j, i), idx(j, i + 1), idx(j + 1, i + 1)});
      m.triangles.push_back({idx(j, i), idx(j + 1, i + 1), idx(j + 1, i)});
    }
  for (int i = 0; i < nu; ++i) m.triangles.push_back({top, idx(nv - 1, i), idx(nv - 1, i + 1)});
  return m;
}

std::vector<Vec3> superellipse_outline(double rx, double ry, double e, int n) {
  auto spow = [](double b, double ex) { return (b < 0 ? -1.0 : 1.0) * std::pow(std::abs(b), ex); };
  std::vector<Vec3> pts;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * kPi * i / n;
    pts.push_back({rx * spow(std::cos(t), e), ry * spow(std::sin(t), e), 0});
  }
  return pts;
}

double polygon_signed_distance(const std::vector<Vec3>& poly, const Vec3& p) {
  double best = 1e300;
  bool inside = false;
  const std::size_t n = poly.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec3 a = poly[j], b = poly[i];
    const Vec3 ab{b.x - a.x, b.y - a.y, 0}, ap{p.x - a.x, p.y - a.y, 0};
    const double t = std::clamp(dot(ap, ab) / std::max(dot(ab, ab), 1e-300), 0.0, 1.0);
    const Vec3 d = ap - ab * t;
    best = std::min(best, d.x * d.x + d.y * d.y);
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x)
      inside = !inside;
  }
  return inside ? -std::sqrt(best) : std::sqrt(best);
}

}  // namespace

Shape::Ptr Shape::finish(std::shared_ptr<Shape> s) {
  if (!(s->mass_.volume > 0) || !std::isfinite(s->mass_.volume))
    throw std::invalid_argument("shape '" + std::string(to_string(s->kind_)) +
                                "' has no positive volume (is the mesh inside out or degenerate?)");
  return s;
}

Shape::Ptr Shape::sphere(double radius, ShapeResolution res) {
  require_positive(radius, "sphere radius");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Sphere;
  s->res_ = res;
  s->params_ = {radius};
  const double V = 4.0 / 3.0 * kPi * radius * radius * radius;
  s->mass_.volume = V;
  s->mass_.inertia = Mat3::identity() * (0.4 * V * radius * radius);
  s->bounds_ = {{-radius, -radius, -radius}, {radius, radius, radius}};
  return finish(s);
}

Shape::Ptr Shape::ellipsoid(const Vec3& r, ShapeResolution res) {
  require_positive(r.x, "ellipsoid radius x");
  require_positive(r.y, "ellipsoid radius y");
  require_positive(r.z, "ellipsoid radius z");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Ellipsoid;
  s->res_ = res;
  s->params_ = {r.x, r.y, r.z};
  const double V = 4.0 / 3.0 * kPi * r.x * r.y * r.z;
  s->mass_.volume = V;
  s->mass_.inertia = Mat3::diagonal({V / 5 * (r.y * r.y + r.z * r.z), V / 5 * (r.x * r.x + r.z * r.z),
                                     V / 5 * (r.x * r.x + r.y * r.y)});
  s->bounds_ = {-r, r};
  return finish(s);
}

Shape::Ptr Shape::superellipsoid(const Vec3& r, double e1, double e2, ShapeResolution res) {
  require_positive(r.x, "superellipsoid radius x");
  require_positive(r.y, "superellipsoid radius y");
  require_positive(r.z, "superellipsoid radius z");
  require_positive(e1, "superellipsoid exponent eps1");
  require_positive(e2, "superellipsoid exponent eps2");
  if (e1 > 2 || e2 > 2)
    throw std::invalid_argument("superellipsoid exponents must be in (0, 2] for a convex-or-star shape");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Superellipsoid;
  s->res_ = res;
  s->params_ = {r.x, r.y, r.z, e1, e2};
  // Barr (1981) / Jaklič et al. (2000): V = 2 rx ry rz e1 e2 B(e1/2+1, e1) B(e2/2, e2+1)... use
  // the beta-function closed forms for volume and second moments.
  auto beta = [](double a, double b) { return std::exp(std::lgamma(a) + std::lgamma(b) - std::lgamma(a + b)); };
  const double V = 2 * r.x * r.y * r.z * e1 * e2 * beta(e1 / 2, e1 / 2) * beta(e2 / 2, e2 + 1) / 2;
  // Second moments: Jaklič, Leonardis & Solina, "Segmentation and Recovery of
  // Superquadrics" (2000), eq. 2.60ff.
  const double Ixx_int = 0.5 * r.x * r.y * r.z * e1 * e2 *
                         (r.y * r.y * beta(1.5 * e1, 0.5 * e1) * beta(0.5 * e2, 2 * e2 + 1) +
                          4 * r.z * r.z * beta(0.5 * e1, 0.5 * e1 + 1) * beta(1.5 * e2, e2 + 1));
  const double Iyy_int = 0.5 * r.x * r.y * r.z * e1 * e2 *
                         (r.x * r.x * beta(1.5 * e1, 0.5 * e1) * beta(0.5 * e2, 2 * e2 + 1) +
                          4 * r.z * r.z * beta(0.5 * e1, 0.5 * e1 + 1) * beta(1.5 * e2, e2 + 1));
  const double Izz_int = 0.5 * r.x * r.y * r.z * e1 * e2 * (r.x * r.x + r.y * r.y) *
                         beta(1.5 * e1, 0.5 * e1) * beta(0.5 * e2, 2 * e2 + 1);
  s->mass_.volume = V;
  s->mass_.inertia = Mat3::diagonal({Ixx_int, Iyy_int, Izz_int});
  s->bounds_ = {-r, r};
  return finish(s);
}

Shape::Ptr Shape::box(const Vec3& h, ShapeResolution res) {
  require_positive(h.x, "box half extent x");
  require_positive(h.y, "box half extent y");
  require_positive(h.z, "box half extent z");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Box;
  s->res_ = res;
  s->params_ = {h.x, h.y, h.z};
  const double V = 8 * h.x * h.y * h.z;
  s->mass_.volume = V;
  s->mass_.inertia = Mat3::diagonal({V / 3 * (h.y * h.y + h.z * h.z), V / 3 * (h.x * h.x + h.z * h.z),
                                     V / 3 * (h.x * h.x + h.y * h.y)});
  s->bounds_ = {-h, h};
  return finish(s);
}

Shape::Ptr Shape::polyhedron(TriMesh mesh, ShapeResolution res) {
  std::string why;
  if (!is_closed_oriented_manifold(mesh, &why))
    throw std::invalid_argument("polyhedron mesh is not closed and manifold: " + why);
  for (const auto& v : mesh.vertices)
    if (!is_finite(v)) throw std::invalid_argument("polyhedron mesh has a non-finite vertex");
  auto mp = polyhedron_mass_properties(mesh);
  if (!(mp.volume > 0))
    throw std::invalid_argument("polyhedron mesh has non-positive volume (inward-facing triangles?)");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Polyhedron;
  s->res_ = res;
  s->recentring_ = -mp.centroid;
  mesh.translate(-mp.centroid);
  mp.centroid = {};
  s->mass_ = mp;
  s->bounds_ = mesh.bounds();
  s->params_ = {static_cast<double>(mesh.vertices.size()), static_cast<double>(mesh.triangles.size())};
  s->source_mesh_ = std::move(mesh);
  return finish(s);
}

Shape::Ptr Shape::convex_polyhedron(const std::vector<Vec3>& points, ShapeResolution res) {
  return polyhedron(crumble::convex_hull(points), res);
}

Shape::Ptr Shape::from_level_set(std::shared_ptr<const LevelSetGrid> grid, ShapeResolution res) {
  if (!grid) throw std::invalid_argument("level-set shape needs a grid");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::LevelSet;
  s->dimension_ = grid->dimension();
  s->res_ = res;
  s->res_.level_set_spacing = grid->spacing();
  s->mass_ = grid->mass_properties();
  if (!(s->mass_.volume > 0)) throw std::invalid_argument("level-set shape has no inside (no negative value)");
  // Invariant of Shape: centroid at the origin. A grid that is not centred is moved and
  // the shift reported in recentring(), as the polyhedron factory does.
  if (norm(s->mass_.centroid) > 1e-12 * std::max(1e-300, norm(grid->bounds().size()))) {
    s->recentring_ = -s->mass_.centroid;
    grid = grid->translated(-s->mass_.centroid);
  }
  s->mass_.centroid = {};
  s->bounds_ = grid->bounds();
  s->source_grid_ = std::move(grid);
  s->ls_ = s->source_grid_;
  return finish(s);
}

Shape::Ptr Shape::disk(double radius, ShapeResolution res) {
  require_positive(radius, "disk radius");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Disk;
  s->dimension_ = 2;
  s->res_ = res;
  s->params_ = {radius};
  const double A = kPi * radius * radius;
  s->mass_.volume = A;
  s->mass_.inertia = Mat3::diagonal({A * radius * radius / 4, A * radius * radius / 4, A * radius * radius / 2});
  s->bounds_ = {{-radius, -radius, 0}, {radius, radius, 0}};
  return finish(s);
}

Shape::Ptr Shape::ellipse(double rx, double ry, ShapeResolution res) {
  require_positive(rx, "ellipse radius x");
  require_positive(ry, "ellipse radius y");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Ellipse;
  s->dimension_ = 2;
  s->res_ = res;
  s->params_ = {rx, ry};
  const double A = kPi * rx * ry;
  s->mass_.volume = A;
  s->mass_.inertia = Mat3::diagonal({A * ry * ry / 4, A * rx * rx / 4, A * (rx * rx + ry * ry) / 4});
  s->bounds_ = {{-rx, -ry, 0}, {rx, ry, 0}};
  return finish(s);
}

Shape::Ptr Shape::superellipse(double rx, double ry, double e, ShapeResolution res) {
  require_positive(rx, "superellipse radius x");
  require_positive(ry, "superellipse radius y");
  require_positive(e, "superellipse exponent");
  if (e > 2) throw std::invalid_argument("superellipse exponent must be in (0, 2]");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Superellipse;
  s->dimension_ = 2;
  s->res_ = res;
  s->params_ = {rx, ry, e};
  // Area and moments from a fine outline (error ~1e-7 at 4096 vertices).
  auto mp = polygon_mass_properties(superellipse_outline(rx, ry, e, 4096));
  mp.centroid = {};
  s->mass_ = mp;
  s->bounds_ = {{-rx, -ry, 0}, {rx, ry, 0}};
  return finish(s);
}

Shape::Ptr Shape::polygon(std::vector<Vec3> v, ShapeResolution res) {
  if (v.size() < 3) throw std::invalid_argument("polygon needs at least 3 vertices");
  for (auto& p : v) {
    if (!is_finite(p)) throw std::invalid_argument("polygon has a non-finite vertex");
    p.z = 0;
  }
  auto mp = polygon_mass_properties(v);
  if (mp.volume < 0) {
    std::reverse(v.begin(), v.end());
    mp = polygon_mass_properties(v);
  }
  if (!(mp.volume > 0)) throw std::invalid_argument("polygon has zero area");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = ShapeKind::Polygon;
  s->dimension_ = 2;
  s->res_ = res;
  s->recentring_ = -mp.centroid;
  for (auto& p : v) p -= mp.centroid;
  mp.centroid = {};
  s->mass_ = mp;
  Aabb b;
  for (const auto& p : v) b.extend(p);
  s->bounds_ = b;
  s->params_ = {static_cast<double>(v.size())};
  s->source_polygon_ = std::move(v);
  return finish(s);
}

double Shape::equivalent_diameter() const {
  if (dimension_ == 2) return 2.0 * std::sqrt(mass_.volume / kPi);
  return std::cbrt(6.0 * mass_.volume / kPi);
}

double Shape::bounding_radius() const {
  switch (kind_) {
    case ShapeKind::Sphere:
    case ShapeKind::Disk: return params_[0];
    case ShapeKind::Ellipsoid: return std::max({params_[0], params_[1], params_[2]});
    case ShapeKind::Ellipse:
    case ShapeKind::Superellipse: {
      if (kind_ == ShapeKind::Ellipse || params_[2] <= 1) return std::max(params_[0], params_[1]);
      break;  // squarish superellipse: farthest point off the axes
    }
    case ShapeKind::Box: return norm(Vec3{params_[0], params_[1], params_[2]});
    default: break;
  }
  // Polytopes: the farthest point is a vertex. Smooth shapes: vertices of the lazily built
  // surface, which lie on the surface (exact at the extremes for the tessellations here).
  double r = 0;
  if (dimension_ == 3) {
    for (const auto& v : mesh().vertices) r = std::max(r, norm(v));
  } else {
    for (const auto& v : outline()) r = std::max(r, norm(v));
  }
  return r;
}

double Shape::signed_distance(const Vec3& p) const {
  switch (kind_) {
    case ShapeKind::Sphere: return norm(p) - params_[0];
    case ShapeKind::Disk: return std::hypot(p.x, p.y) - params_[0];
    case ShapeKind::Ellipsoid: {
      const Vec3 r{params_[0], params_[1], params_[2]};
      const double f = std::sqrt(norm2({p.x / r.x, p.y / r.y, p.z / r.z}));
      if (f == 0) return -std::min({r.x, r.y, r.z});
      return radial_distance(p, f);
    }
    case ShapeKind::Superellipsoid: {
      const Vec3 r{params_[0], params_[1], params_[2]};
      const double f = superellipsoid_f(p, r, params_[3], params_[4]);
      if (f == 0) return -std::min({r.x, r.y, r.z});
      return radial_distance(p, std::pow(f, params_[4] / 2));
    }
    case ShapeKind::Ellipse: {
      const double f = std::hypot(p.x / params_[0], p.y / params_[1]);
      if (f == 0) return -std::min(params_[0], params_[1]);
      return radial_distance({p.x, p.y, 0}, f);
    }
    case ShapeKind::Superellipse: {
      const double e = params_[2];
      const double f = std::pow(std::pow(std::abs(p.x / params_[0]), 2 / e) +
                                    std::pow(std::abs(p.y / params_[1]), 2 / e), e / 2);
      if (f == 0) return -std::min(params_[0], params_[1]);
      return radial_distance({p.x, p.y, 0}, f);
    }
    case ShapeKind::Box: {
      const Vec3 q{std::abs(p.x) - params_[0], std::abs(p.y) - params_[1], std::abs(p.z) - params_[2]};
      const Vec3 qp = cwise_max(q, {0, 0, 0});
      return norm(qp) + std::min(std::max({q.x, q.y, q.z}), 0.0);
    }
    case ShapeKind::Polygon: return polygon_signed_distance(source_polygon_, p);
    case ShapeKind::Polyhedron: {
      std::call_once(dist_once_, [this] { mesh_dist_ = std::make_shared<MeshDistance>(source_mesh_); });
      return mesh_dist_->signed_distance(p);
    }
    case ShapeKind::LevelSet: return source_grid_->value(p);
  }
  return 0;
}

bool Shape::contains(const Vec3& p) const {
  switch (kind_) {
    case ShapeKind::Polyhedron:
      std::call_once(dist_once_, [this] { mesh_dist_ = std::make_shared<MeshDistance>(source_mesh_); });
      return mesh_dist_->contains(p);
    default: return signed_distance(p) < 0;
  }
}

const TriMesh& Shape::mesh() const {
  if (dimension_ != 3) throw std::logic_error("mesh() asked of a 2D shape; use outline()");
  // A polyhedron is its mesh: no second copy (every alpha-shape and plane-cut child is one).
  if (kind_ == ShapeKind::Polyhedron) return source_mesh_;
  std::call_once(mesh_once_, [this] {
    count_built(Representation::Mesh);
    const int level = std::max(0, res_.mesh_subdivisions);
    switch (kind_) {
      case ShapeKind::Sphere: {
        TriMesh m = icosphere(level);
        m.scale(params_[0]);
        mesh_ = std::move(m);
        break;
      }
      case ShapeKind::Ellipsoid: {
        TriMesh m = icosphere(level);
        for (auto& v : m.vertices) v = {v.x * params_[0], v.y * params_[1], v.z * params_[2]};
        mesh_ = std::move(m);
        break;
      }
      case ShapeKind::Superellipsoid:
        mesh_ = superellipsoid_mesh({params_[0], params_[1], params_[2]}, params_[3], params_[4], level);
        break;
      case ShapeKind::Box: mesh_ = box_mesh({params_[0], params_[1], params_[2]}); break;
      case ShapeKind::LevelSet: mesh_ = source_grid_->to_mesh(); break;
      default: break;
    }
  });
  return *mesh_;
}

const TriMesh& Shape::convex_hull() const {
  std::call_once(hull_once_, [this] { hull_ = crumble::convex_hull(mesh().vertices); });
  return *hull_;
}

const std::vector<Vec3>& Shape::outline() const {
  if (dimension_ != 2) throw std::logic_error("outline() asked of a 3D shape; use mesh()");
  std::call_once(outline_once_, [this] {
    count_built(Representation::Outline);
    const int n = 16 << std::max(0, res_.mesh_subdivisions);
    switch (kind_) {
      case ShapeKind::Disk: outline_ = superellipse_outline(params_[0], params_[0], 1.0, n); break;
      case ShapeKind::Ellipse: outline_ = superellipse_outline(params_[0], params_[1], 1.0, n); break;
      case ShapeKind::Superellipse: outline_ = superellipse_outline(params_[0], params_[1], params_[2], n); break;
      case ShapeKind::Polygon: outline_ = source_polygon_; break;
      case ShapeKind::LevelSet: outline_ = source_grid_->outline(); break;
      default: break;
    }
  });
  return *outline_;
}

std::shared_ptr<const LevelSetGrid> Shape::level_set_ptr() const {
  std::call_once(ls_once_, [this] {
    if (ls_) return;
    const Vec3 ext = bounds_.size();
    const double smallest = dimension_ == 2 ? std::min(ext.x, ext.y) : std::min({ext.x, ext.y, ext.z});
    const double largest = dimension_ == 2 ? std::max(ext.x, ext.y) : std::max({ext.x, ext.y, ext.z});
    // Automatic spacing: 20 cells across the thinnest extent, but at most 400 along the
    // longest, so a needle-like input cannot ask for a grid of 10^7+ nodes (fuzzing found
    // one: 2 m × 1 mm); grains with an aspect ratio up to 20 are unaffected.
    const double h = res_.level_set_spacing > 0 ? res_.level_set_spacing : std::max(smallest / 20.0, largest / 400.0);
    LevelSetOptions opt;
    opt.target_nodes = res_.surface_nodes;
    opt.name = "shape " + describe();
    // The radial distances of the (super)ellipsoids and (super)ellipses have the exact zero
    // set but over-estimate |φ| where the surface is oblique to the ray from the centre
    // (up to 1/cos of that angle: ≈ 40 % at the corners of a boxy superellipsoid). Contact
    // reads penetration = −φ, so their grids are reinitialised to true distances.
    opt.exact_distance = !(kind_ == ShapeKind::Ellipsoid || kind_ == ShapeKind::Superellipsoid ||
                           kind_ == ShapeKind::Ellipse || kind_ == ShapeKind::Superellipse);
    count_built(Representation::LevelSetGrid);
    ls_ = LevelSetGrid::sample(dimension_, bounds_, h, [this](const Vec3& p) { return signed_distance(p); }, opt);
  });
  return ls_;
}

const LevelSetGrid& Shape::level_set() const { return *level_set_ptr(); }

Shape::Ptr Shape::scaled(double f) const {
  require_positive(f, "shape scale factor");
  ShapeResolution res = res_;
  if (res.level_set_spacing > 0) res.level_set_spacing *= f;
  switch (kind_) {
    case ShapeKind::Sphere: return sphere(params_[0] * f, res);
    case ShapeKind::Ellipsoid: return ellipsoid(Vec3{params_[0], params_[1], params_[2]} * f, res);
    case ShapeKind::Superellipsoid:
      return superellipsoid(Vec3{params_[0], params_[1], params_[2]} * f, params_[3], params_[4], res);
    case ShapeKind::Box: return box(Vec3{params_[0], params_[1], params_[2]} * f, res);
    case ShapeKind::Polyhedron: {
      TriMesh m = source_mesh_;
      m.scale(f);
      return polyhedron(std::move(m), res);
    }
    case ShapeKind::Disk: return disk(params_[0] * f, res);
    case ShapeKind::Ellipse: return ellipse(params_[0] * f, params_[1] * f, res);
    case ShapeKind::Superellipse: return superellipse(params_[0] * f, params_[1] * f, params_[2], res);
    case ShapeKind::Polygon: {
      auto v = source_polygon_;
      for (auto& p : v) p *= f;
      return polygon(std::move(v), res);
    }
    case ShapeKind::LevelSet: {
      // Scaling a signed-distance field: phi_f(x) = f * phi(x / f) on the lattice scaled by
      // f; the grid keeps its index layout (LevelSetGrid::scaled).
      return from_level_set(source_grid_->scaled(f), res);
    }
  }
  return nullptr;
}

Shape::Ptr Shape::restored(const Shape& r, const MassProperties& mass, const Aabb& bounds, const Vec3& recentring,
                           std::vector<Vec3> polygon, TriMesh mesh) {
  if (!(mass.volume > 0) || !std::isfinite(mass.volume) ||
      !(std::abs(mass.volume - r.mass_.volume) <= 1e-9 * r.mass_.volume))
    throw std::invalid_argument("saved volume " + std::to_string(mass.volume) + " does not match the shape's " +
                                std::to_string(r.mass_.volume));
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(mass.inertia(i, k))) throw std::invalid_argument("saved inertia is not finite");
  if (!is_finite(bounds.lo) || !is_finite(bounds.hi) || !is_finite(recentring))
    throw std::invalid_argument("saved bounds or recentring are not finite");
  auto s = std::shared_ptr<Shape>(new Shape());
  s->kind_ = r.kind_;
  s->dimension_ = r.dimension_;
  s->res_ = r.res_;
  s->params_ = r.params_;
  s->recentring_ = recentring;
  s->mass_ = mass;
  s->bounds_ = bounds;
  s->source_mesh_ = r.kind_ == ShapeKind::Polyhedron && !mesh.vertices.empty() ? std::move(mesh) : r.source_mesh_;
  if (r.kind_ == ShapeKind::Polygon && !polygon.empty()) {
    if (polygon.size() != r.source_polygon_.size()) throw std::invalid_argument("saved polygon does not match the shape");
    s->source_polygon_ = std::move(polygon);
  } else {
    s->source_polygon_ = r.source_polygon_;
  }
  s->source_grid_ = r.source_grid_;
  if (r.kind_ == ShapeKind::LevelSet) s->ls_ = s->source_grid_;
  return finish(s);
}

std::string Shape::describe() const {
  std::ostringstream os;
  os << to_string(kind_) << "(";
  for (std::size_t i = 0; i < params_.size(); ++i) os << (i ? ", " : "") << params_[i];
  os << ")";
  return os.str();
}

}  // namespace crumble
