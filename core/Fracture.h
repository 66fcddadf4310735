// The hand-over between a BreakageModel and a FragmentBuilder. All coordinates are in
// the parent's body frame (centroid at the origin).
#pragma once
#include <variant>
#include <vector>

#include "geometry/Vec3.h"

namespace crumble {

// What peridynamics yields (Zhu & Zhao 2019 §3.2): the lattice points of the parent, the
// cluster each belongs to (fines already attached to the nearest major piece), which of
// them lie on the original surface, and the fracture-surface points of each cluster
// (midpoints of broken nearest-neighbour bonds).
struct PointClusters {
  double spacing = 0;
  std::vector<Vec3> points;
  std::vector<int> cluster;        // per point, in [0, clusters)
  std::vector<char> on_surface;    // per point
  int clusters = 0;
  std::vector<std::vector<Vec3>> fracture_points;  // per cluster
  // The points (and fracture points) are given in the lattice's own frame; `frame`
  // rotates them into the parent's body frame (identity: already in the body frame).
  // Builders keep lattice coordinates exact and rotate only their result.
  Quat frame;
};

// Plane n·x = d in the parent frame; n is a unit vector.
struct CutPlane {
  Vec3 normal;
  double offset = 0;
  double signed_distance(const Vec3& p) const { return dot(normal, p) - offset; }
};

// What the stress criteria yield (Harmon et al. 2020 §3): the parent is cut by the surfaces; each
// non-empty cell of the arrangement is a child.
struct CuttingSurfaces {
  std::vector<CutPlane> planes;
};

using Fracture = std::variant<PointClusters, CuttingSurfaces>;

}  // namespace crumble
