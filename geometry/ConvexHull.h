#pragma once
#include <vector>

#include "geometry/TriMesh.h"

namespace crumble {

// 3D convex hull of a point cloud as a closed, outward-oriented triangle mesh whose
// vertices are the hull's extreme points. Throws std::invalid_argument for fewer than 4
// points or a (nearly) flat cloud.
TriMesh convex_hull(const std::vector<Vec3>& points);

}  // namespace crumble
