// The fragment-geometry seam: turn a Fracture into child shapes. Children are returned
// in the parent's body frame (offset = child centroid). Mass budget (the builder enforces
// it, Simulation checks it to 1e-9): Σ child volumes + removed_volume = parent volume.
#pragma once
#include <string>
#include <vector>

#include "core/Fracture.h"
#include "geometry/Shape.h"

namespace crumble {

struct Fragment {
  Shape::Ptr shape;   // centred on its own centroid
  Vec3 offset;        // child centroid in the parent's body frame
};

struct FragmentResult {
  std::vector<Fragment> children;
  std::string method;     // e.g. "alpha_shape", "convex_hull", "plane_cut"
  int fallbacks = 0;      // documented fallbacks taken (counted in summary.json)
  // Volume of pieces the builder dropped (e.g. level-set pieces thinner than a grid cell):
  // counted as removed mass (fines), never lost. 0 children and 0 removed = no split
  // (unresolved below says why).
  double removed_volume = 0;
  // Cost figures of resolution-refining builders (summary.json fragment_grid_nodes_per_child,
  // fragment_refinements): nodes of the children's grids, splits repeated on a finer grid.
  long grid_nodes = 0;
  int refinements = 0;
  // Pieces too small to resolve that the builder gave to a kept child instead of removing
  // (summary.json fragment_pieces_absorbed).
  int absorbed = 0;
  // The builder could not cut the grain into a piece it can resolve: no child and no removed
  // volume, and the simulation leaves the grain whole (events.csv outcome unresolved;
  // summary.json fragment_unresolved).
  bool unresolved = false;
};

class FragmentBuilder {
 public:
  virtual ~FragmentBuilder() = default;
  virtual std::string name() const = 0;
  virtual FragmentResult build(const Shape& parent, const Fracture& fracture) const = 0;
};

}  // namespace crumble
