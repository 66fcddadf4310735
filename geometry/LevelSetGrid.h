// Discrete signed-distance grid of one shape (Harmon et al. 2020 §2): negative inside, sampled on
// a regular grid, interpolated trilinearly (bilinearly in 2D), with surface nodes on the
// zero level carrying an area (2D: length) weight. Immutable once built and shared by
// every grain of the shape.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "geometry/TriMesh.h"
#include "geometry/Vec3.h"

namespace crumble {

// Options of LevelSetGrid::sample (the plain overload keeps the defaults).
struct LevelSetOptions {
  // Surface nodes wanted (approximate, ±15 %); 0 = automatic: about one node per grid cell
  // that the surface crosses (≈ 1.5·area/h² in 3D, ≈ 1.3·length/h in 2D).
  int target_nodes = 0;
  int pad = 2;  // cells of margin each side (>= 2 so that the smoothed Heaviside is 0 there)
  // false: `sdf` has the right zero set and sign but is not a distance (e.g. the radial
  // approximations of ellipsoids and superellipsoids); the grid is then reinitialised to the
  // exact distance to the zero set (closest-point iteration near the surface, closest-point
  // propagation beyond).
  bool exact_distance = true;
  std::string name = "level set";  // named in error messages (e.g. Shape::describe())
};

class LevelSetGrid {
 public:
  using Sdf = std::function<double(const Vec3&)>;

  // The sampling below with LevelSetOptions. `sdf` must be thread-safe.
  static std::shared_ptr<const LevelSetGrid> sample(int dimension, const Aabb& bounds, double h,
                                                    const Sdf& sdf, const LevelSetOptions& options);

  // Samples `sdf` on a grid of spacing `h` covering `bounds` plus `pad` cells each side.
  // dimension 2 uses the x–y plane (one layer). Throws std::invalid_argument on h <= 0,
  // a shape thinner than two cells, or no surface node.
  static std::shared_ptr<const LevelSetGrid> sample(int dimension, const Aabb& bounds, double h,
                                                    const Sdf& sdf, int target_nodes = 0,
                                                    int pad = 2);

  int dimension() const { return dim_; }
  double spacing() const { return h_; }
  Vec3 origin() const { return origin_; }
  std::array<int, 3> counts() const { return n_; }
  const std::vector<double>& values() const { return phi_; }

  // Interpolated value; outside the grid a conservative positive distance.
  double value(const Vec3& p) const;
  // Gradient of the interpolant (not normalised).
  Vec3 gradient(const Vec3& p) const;
  // Value and gradient in one lookup (the contact hot path).
  double value_gradient(const Vec3& p, Vec3& grad) const;
  bool inside_grid(const Vec3& p) const;
  // Fast path for points known to be inside the grid (e.g. within the node box): the
  // interpolated value only, no bounds handling.
  double value_inside(const Vec3& p) const {
    const double fx = (p.x - origin_.x) * inv_h_, fy = (p.y - origin_.y) * inv_h_;
    int i = static_cast<int>(fx), j = static_cast<int>(fy);
    i = i < 0 ? 0 : (i > n_[0] - 2 ? n_[0] - 2 : i);
    j = j < 0 ? 0 : (j > n_[1] - 2 ? n_[1] - 2 : j);
    const double tx = fx - i, ty = fy - j;
    const std::size_t sy = static_cast<std::size_t>(n_[0]);
    if (dim_ == 2) {
      const double* c = &phi_[i + sy * j];
      const double a0 = c[0] + (c[1] - c[0]) * tx, a1 = c[sy] + (c[sy + 1] - c[sy]) * tx;
      return a0 + (a1 - a0) * ty;
    }
    const double fz = (p.z - origin_.z) * inv_h_;
    int k = static_cast<int>(fz);
    k = k < 0 ? 0 : (k > n_[2] - 2 ? n_[2] - 2 : k);
    const double tz = fz - k;
    const std::size_t sz = sy * static_cast<std::size_t>(n_[1]);
    const double* c = &phi_[i + sy * j + sz * k];
    const double c00 = c[0] + (c[1] - c[0]) * tx, c10 = c[sy] + (c[sy + 1] - c[sy]) * tx;
    const double c01 = c[sz] + (c[sz + 1] - c[sz]) * tx, c11 = c[sy + sz] + (c[sy + sz + 1] - c[sy + sz]) * tx;
    const double c0 = c00 + (c10 - c00) * ty, c1 = c01 + (c11 - c01) * ty;
    return c0 + (c1 - c0) * tz;
  }
  Aabb bounds() const;

  // Surface nodes (shape frame) and their area (2D: length) weights.
  const std::vector<Vec3>& nodes() const { return nodes_; }
  const std::vector<double>& node_weights() const { return node_w_; }
  // Spacing of the lattice the nodes were clustered on (children of with_values keep it,
  // so they have the parent's node density).
  double node_spacing() const { return node_h_; }
  // Half width ε of the smoothed Heaviside of mass_properties(): 1.5 grid spacings.
  double heaviside_width() const { return 1.5 * h_; }

  // Harmon et al. 2020 eqs. 24–30: smoothed-Heaviside integrals over the grid (per unit density).
  MassProperties mass_properties() const;

  // Zero level as a closed triangle mesh (marching cubes / tetrahedra); 2D: use outline().
  TriMesh to_mesh() const;
  std::vector<Vec3> outline() const;

  // A grid from stored data (level-set splitting, checkpoints, saved grains): `values` in
  // x-fastest order on `counts` nodes of spacing `h` from `origin` (2D: counts[2] == 1).
  // Surface nodes are built from the zero level at `node_spacing` (0: h) unless
  // `surface_nodes` is false (then the grid has none until with_nodes/with_values).
  // Throws std::invalid_argument naming the defect on inconsistent or non-finite data.
  static std::shared_ptr<const LevelSetGrid> from_values(int dimension, const Vec3& origin, double h,
                                                         const std::array<int, 3>& counts,
                                                         std::vector<double> values, double node_spacing = 0,
                                                         bool surface_nodes = true,
                                                         const std::string& name = "level set");
  // The same grid with the given surface nodes and weights (checked: finite, weights > 0).
  std::shared_ptr<const LevelSetGrid> with_nodes(std::vector<Vec3> nodes, std::vector<double> weights) const;
  // Rigid translation by d (values unchanged, lattice and nodes moved).
  std::shared_ptr<const LevelSetGrid> translated(const Vec3& d) const;
  // Uniform scaling about the coordinate origin by f > 0: φ_f(x) = f·φ(x/f) on the lattice
  // scaled by f. Volumes from mass_properties() scale by exactly f³ (2D: f²), because the
  // smoothed Heaviside's width scales with the spacing.
  std::shared_ptr<const LevelSetGrid> scaled(double f) const;

  // A new grid with values from `fn` on the same lattice (level-set CSG results).
  // Surface nodes are rebuilt from the new zero level at this grid's node spacing.
  // Throws std::invalid_argument on a size mismatch, non-finite values or no zero level.
  std::shared_ptr<const LevelSetGrid> with_values(std::vector<double> phi) const;
  // The same zero level on a lattice of spacing h > 0 covering the surface nodes plus `pad`
  // cells (values interpolated from this grid), with surface nodes rebuilt from the zero
  // level at `node_spacing` (0: h). A piece resampled at its own size (Harmon et al. 2020
  // §3.4: small pieces get a finer discretisation). Throws std::invalid_argument on a bad
  // spacing, a grid without surface nodes or a lattice of more than 2e8 nodes.
  std::shared_ptr<const LevelSetGrid> resampled(double h, double node_spacing, int pad = 3) const;
  // The same zero level with values replaced by the signed distance to it (Harmon et al. 2020
  // eq. 17's purpose; done by closest points instead of the PDE). CSG results
  // (max(φ1, −φ2), eqs. 14–15) are not distances until reinitialised.
  std::shared_ptr<const LevelSetGrid> reinitialised() const;

 private:
  LevelSetGrid() = default;
  int dim_ = 3;
  double h_ = 0, inv_h_ = 0;
  Vec3 origin_;
  std::array<int, 3> n_{0, 0, 0};
  std::vector<double> phi_;
  std::vector<Vec3> nodes_;
  std::vector<double> node_w_;
  double node_h_ = 0;
  std::string name_;
  friend struct LevelSetGridBuilder;
};

}  // namespace crumble
