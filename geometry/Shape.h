// Shape: immutable grain geometry shared by every grain of the same form.
//
// Representations (closed triangle mesh, convex hull, level-set grid) are built lazily
// and cached, so an engine only pays for what it asks for (a Bullet run never builds a
// level set; an LS-DEM run never builds a convex hull). Thread-safe: the caches are
// filled under std::call_once.
//
// Invariant: the shape's local frame has its centroid at the origin. Factories re-centre
// their input and report the shift in `recentring()`.
#pragma once
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "geometry/TriMesh.h"
#include "geometry/Vec3.h"

namespace crumble {

class LevelSetGrid;
class MeshDistance;

enum class ShapeKind {
  Sphere, Ellipsoid, Superellipsoid, Box, Polyhedron, LevelSet,  // 3D
  Disk, Ellipse, Superellipse, Polygon                            // 2D (x–y plane)
};
const char* to_string(ShapeKind k);

// How finely the lazily built representations resolve the shape.
struct ShapeResolution {
  int mesh_subdivisions = 1;      // icosphere level for round shapes (1 → 42 vertices)
  double level_set_spacing = 0;   // m; 0 = automatic (smallest extent / 20)
  int surface_nodes = 0;          // 0 = automatic
};

class Shape {
 public:
  using Ptr = std::shared_ptr<const Shape>;

  // 3D sources. Lengths in metres; all must be > 0 (std::invalid_argument otherwise).
  static Ptr sphere(double radius, ShapeResolution res = {});
  static Ptr ellipsoid(const Vec3& radii, ShapeResolution res = {});
  // inside where (|x/rx|^(2/e1) + |y/ry|^(2/e1))^(e1/e2) + |z/rz|^(2/e2) <= 1
  static Ptr superellipsoid(const Vec3& radii, double eps1, double eps2, ShapeResolution res = {});
  static Ptr box(const Vec3& half_extents, ShapeResolution res = {});
  // Closed, outward-oriented, manifold mesh (checked: std::invalid_argument naming the
  // defect otherwise).
  static Ptr polyhedron(TriMesh mesh, ShapeResolution res = {});
  // Convex hull of a point cloud.
  static Ptr convex_polyhedron(const std::vector<Vec3>& points, ShapeResolution res = {});
  // A shape defined by its signed-distance grid (children of level-set splitting).
  static Ptr from_level_set(std::shared_ptr<const LevelSetGrid> grid, ShapeResolution res = {});

  // 2D sources in the x–y plane; "volume" is area (per metre of thickness).
  static Ptr disk(double radius, ShapeResolution res = {});
  static Ptr ellipse(double rx, double ry, ShapeResolution res = {});
  static Ptr superellipse(double rx, double ry, double eps, ShapeResolution res = {});
  static Ptr polygon(std::vector<Vec3> ccw_vertices, ShapeResolution res = {});

  ShapeKind kind() const { return kind_; }
  int dimension() const { return dimension_; }
  const ShapeResolution& resolution() const { return res_; }
  // Source parameters (radii, exponents, half extents) as given, for output.
  const std::vector<double>& parameters() const { return params_; }
  Vec3 recentring() const { return recentring_; }

  // Mass properties per unit density, about the centroid (≈ origin). Exact for the
  // analytic and polyhedral sources, grid-based (Harmon et al. 2020 eqs. 24–30) for level sets.
  const MassProperties& mass_properties() const { return mass_; }
  double volume() const { return mass_.volume; }
  // Diameter of the sphere (3D) or disk (2D) of equal volume (area).
  double equivalent_diameter() const;
  Aabb bounds() const { return bounds_; }
  // Radius of the smallest origin-centred sphere (2D: disk) containing the shape.
  double bounding_radius() const;

  // Negative inside. Exact for sphere, disk, box, polygon and meshes; for the other
  // analytic shapes a consistent approximation (exact zero set and sign); level_set()
  // reinitialises their grids to true distances.
  double signed_distance(const Vec3& p) const;
  bool contains(const Vec3& p) const;

  // Lazily built representations.
  const TriMesh& mesh() const;         // closed surface (3D)
  const TriMesh& convex_hull() const;  // hull of mesh() vertices (3D)
  const std::vector<Vec3>& outline() const;  // closed CCW polygon (2D)
  const LevelSetGrid& level_set() const;
  std::shared_ptr<const LevelSetGrid> level_set_ptr() const;

  // The same shape uniformly scaled about its centroid (children's volume correction).
  Ptr scaled(double factor) const;

  // A shape as a checkpoint saved it, bit for bit: `rebuilt` is the shape made again from
  // the saved (centred) source, whose factory recomputed the mass properties and may have
  // moved the source by a rounding-sized re-centring; the result has rebuilt's kind,
  // parameters and grid, the saved polygon vertices or mesh (when given: Polygon,
  // Polyhedron) and the saved mass properties, bounds and recentring, so a resumed run
  // computes with the same numbers as the run that saved it. Throws std::invalid_argument
  // when the saved figures do not belong to the rebuilt shape (volume off by > 1e-9).
  static Ptr restored(const Shape& rebuilt, const MassProperties& mass, const Aabb& bounds, const Vec3& recentring,
                      std::vector<Vec3> polygon = {}, TriMesh mesh = {});

  std::string describe() const;

  Shape(const Shape&) = delete;
  Shape& operator=(const Shape&) = delete;

 private:
  Shape() = default;
  static Ptr finish(std::shared_ptr<Shape> s);

  ShapeKind kind_ = ShapeKind::Sphere;
  int dimension_ = 3;
  ShapeResolution res_;
  std::vector<double> params_;
  Vec3 recentring_;
  MassProperties mass_;
  Aabb bounds_;

  // Source data (only the one matching kind_ is used).
  TriMesh source_mesh_;                          // Polyhedron
  std::vector<Vec3> source_polygon_;             // Polygon
  std::shared_ptr<const LevelSetGrid> source_grid_;  // LevelSet

  mutable std::once_flag mesh_once_, hull_once_, outline_once_, ls_once_, dist_once_;
  mutable std::shared_ptr<const MeshDistance> mesh_dist_;
  mutable std::optional<TriMesh> mesh_, hull_;
  mutable std::optional<std::vector<Vec3>> outline_;
  mutable std::shared_ptr<const LevelSetGrid> ls_;
};

}  // namespace crumble
