#include "geometry/LevelSetGrid.h"

#include <stdexcept>

namespace crumble {
std::shared_ptr<const LevelSetGrid> LevelSetGrid::sample(int, const Aabb&, double, const Sdf&, int, int) {
  throw std::logic_error("LevelSetGrid: not implemented yet");
}
double LevelSetGrid::value(const Vec3&) const { return 0; }
Vec3 LevelSetGrid::gradient(const Vec3&) const { return {}; }
bool LevelSetGrid::inside_grid(const Vec3&) const { return false; }
Aabb LevelSetGrid::bounds() const { return {}; }
MassProperties LevelSetGrid::mass_properties() const { return {}; }
TriMesh LevelSetGrid::to_mesh() const { return {}; }
std::vector<Vec3> LevelSetGrid::outline() const { return {}; }
std::shared_ptr<const LevelSetGrid> LevelSetGrid::with_values(std::vector<double>) const { return nullptr; }
}  // namespace crumble
