// The peridynamic discretisation of a grain (Zhu & Zhao 2019 §3.1 stage 2): material points on
// a cubic lattice, and each point's full bond family in CSR form (every point owns the
// list of its neighbours, so force sums need no atomics and no write races).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "geometry/Shape.h"
#include "geometry/Vec3.h"

namespace crumble::pd {

// One lattice offset inside the horizon, in units of the spacing.
struct StencilEntry {
  int dx = 0, dy = 0, dz = 0;
  double length = 0;  // |offset| / spacing
  double weight = 1;  // fraction of the neighbour's cell inside the horizon sphere
};

// The neighbour offsets of a cubic lattice for a horizon of `horizon_factor` spacings.
// partial_volumes = false: every offset with |offset| <= horizon_factor, weight 1 (the
// plain rule; with 3.0002 that is the 122 offsets of |offset| <= 3).
// partial_volumes = true: every offset whose cell (a unit cube centred on the point)
// meets the horizon sphere, weighted by the exact fraction of the cell inside it. This is
// a quadrature of the integrals of Zhu & Zhao 2019 eqs. 1, 3, 4 (dV_x'), not a change of the
// influence function (still 1): it removes the cubic-lattice anisotropy of the plain rule
// (its two shear moduli are 0.83 μ and 1.11 μ at δ = 3h; with partial volumes 1.006 μ and
// 0.996 μ). Cached per horizon factor; thread-safe.
const std::vector<StencilEntry>& horizon_stencil(double horizon_factor, bool partial_volumes);

struct Lattice {
  double spacing = 0;       // m
  double horizon = 0;       // m
  double point_volume = 0;  // m³, the same for every point
  std::vector<Vec3> points;                 // reference positions (body frame), m
  std::vector<std::array<int, 3>> cell;     // integer lattice coordinates
  // CSR: bonds of point i are [offsets[i], offsets[i+1]); sorted by neighbour index.
  std::vector<std::int32_t> offsets;
  std::vector<std::int32_t> neighbours;
  std::vector<double> length;   // reference bond length, m
  std::vector<double> weight;   // partial-volume fraction of the neighbour
  // Per point, the CSR index of the bond to each of its 6 face neighbours (±x, ±y, ±z),
  // or -1 where that lattice site is empty (the point is on the original surface).
  std::vector<std::array<std::int32_t, 6>> face_bond;

  std::size_t size() const { return points.size(); }
  long bonds() const { return static_cast<long>(neighbours.size()); }
  bool on_surface(std::size_t i) const;
};

// Lattice from points that lie on the cubic lattice of `spacing` through the origin
// (checked: std::invalid_argument for a point off the lattice or a duplicate).
// `point_volume` <= 0 means spacing³.
Lattice build_lattice(const std::vector<Vec3>& points, double spacing, double horizon_factor,
                      bool partial_volumes, double point_volume = 0);

// Lattice points i·spacing (i integer, through the shape's centroid) inside `shape`
// (Shape::contains), any 3D shape.
std::vector<Vec3> lattice_points(const Shape& shape, double spacing);
// The same with the lattice axis-aligned in a frame F: points are returned in F, the shape
// is tested at frame.rotate(p) (F → body).
std::vector<Vec3> lattice_points(const Shape& shape, double spacing, const Quat& frame);

}  // namespace crumble::pd
