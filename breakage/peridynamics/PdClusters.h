// What a peridynamic analysis leaves behind (Zhu & Zhao 2019 §3.2): the pieces are the connected
// components of the lattice over intact nearest-neighbour bonds.
#pragma once
#include <vector>

#include "breakage/peridynamics/PdLattice.h"
#include "core/Fracture.h"

namespace crumble::pd {

struct Components {
  std::vector<int> label;  // per point, in [0, count), numbered by first point
  std::vector<long> size;  // points per component
  int count = 0;
};

// Union–find over the face (nearest-neighbour) bonds whose `alive` factor is non-zero.
Components face_components(const Lattice& L, const std::vector<double>& alive);

// Components with at least `min_fraction` of all points ("major pieces"; Zhu & Zhao 2019 §3.2
// uses 3 % of the parent's volume — every point has the same volume).
int major_count(const Components& c, double min_fraction);

// The hand-over to the fragment builder: majors become clusters 0..k−1 (largest first);
// each minor component (fines) joins the major piece holding the point nearest to any of
// its points, so every point belongs to a cluster and volumes sum to the parent's. When no
// component reaches `min_fraction` the largest one counts as major. Fracture points are
// the midpoints of the broken face bonds whose ends fall in different clusters, given to
// both; on_surface marks points with fewer than 6 face neighbours in the lattice.
PointClusters point_clusters(const Lattice& L, const std::vector<double>& alive, double min_fraction);

}  // namespace crumble::pd
