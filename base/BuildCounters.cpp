#include "base/BuildCounters.h"

#include <atomic>

namespace crumble {

namespace {
std::array<std::atomic<long>, kRepresentationKinds> g_built{};
}

const char* to_string(Representation r) {
  switch (r) {
    case Representation::LevelSetGrid: return "level_set_grids";
    case Representation::Mesh: return "meshes";
    case Representation::Outline: return "outlines";
    case Representation::ConvexHull: return "convex_hulls";
    case Representation::MeshDistance: return "mesh_distance_trees";
    case Representation::AlphaShape: return "alpha_shapes";
    case Representation::MeshClip: return "meshes_clipped";
    case Representation::LevelSetSplit: return "level_set_splits";
    case Representation::PdLattice: return "pd_lattices";
    case Representation::Count: break;
  }
  return "unknown";
}

void count_built(Representation r, long n) noexcept {
  const auto i = static_cast<std::size_t>(r);
  if (i < g_built.size()) g_built[i].fetch_add(n, std::memory_order_relaxed);
}

RepresentationCounts representations_built() {
  RepresentationCounts c;
  for (std::size_t i = 0; i < g_built.size(); ++i) c.n[i] = g_built[i].load(std::memory_order_relaxed);
  return c;
}

}  // namespace crumble
