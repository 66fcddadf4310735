#include "geometry/ConvexHull.h"

#include <stdexcept>

namespace crumble {
TriMesh convex_hull(const std::vector<Vec3>&) { throw std::logic_error("convex_hull: not implemented yet"); }
}  // namespace crumble
