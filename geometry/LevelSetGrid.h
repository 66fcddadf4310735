// Discrete signed-distance grid of one shape (seeds/004 §2): negative inside, sampled on
// a regular grid, interpolated trilinearly (bilinearly in 2D), with surface nodes on the
// zero level carrying an area (2D: length) weight. Immutable once built and shared by
// every grain of the shape.
#pragma once
#include <functional>
#include <memory>
#include <vector>

#include "geometry/TriMesh.h"
#include "geometry/Vec3.h"

namespace crumble {

class LevelSetGrid {
 public:
  using Sdf = std::function<double(const Vec3&)>;

  // Samples `sdf` on a grid of spacing `h` covering `bounds` plus `pad` cells each side.
  // dimension 2 uses the x–y plane (one layer). Throws std::invalid_argument on h <= 0,
  // a shape thinner than two cells, or fewer than `min_nodes` surface nodes.
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
  bool inside_grid(const Vec3& p) const;
  Aabb bounds() const;

  // Surface nodes (shape frame) and their area (2D: length) weights.
  const std::vector<Vec3>& nodes() const { return nodes_; }
  const std::vector<double>& node_weights() const { return node_w_; }

  // seeds/004 eqs. 24–30: smoothed-Heaviside integrals over the grid (per unit density).
  MassProperties mass_properties() const;

  // Zero level as a closed triangle mesh (marching cubes / tetrahedra); 2D: use outline().
  TriMesh to_mesh() const;
  std::vector<Vec3> outline() const;

  // A new grid with values from `fn` on the same lattice (level-set CSG results).
  std::shared_ptr<const LevelSetGrid> with_values(std::vector<double> phi) const;

 private:
  LevelSetGrid() = default;
  int dim_ = 3;
  double h_ = 0;
  Vec3 origin_;
  std::array<int, 3> n_{0, 0, 0};
  std::vector<double> phi_;
  std::vector<Vec3> nodes_;
  std::vector<double> node_w_;
  friend struct LevelSetGridBuilder;
};

}  // namespace crumble
