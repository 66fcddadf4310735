// How many representations of each kind this process has built ("model only what a scene
// requires"). Counted where each is built: geometry/ counts its own (shape
// meshes, outlines, level-set grids, hulls, alpha shapes, clips, splits), the layers above
// count theirs (peridynamics lattices). It lives in geometry/ because geometry/ includes
// nothing else of crumble and every other layer includes geometry/.
//
// The counters are process totals (lock-free, thread-safe); a run reports the difference
// between the totals at its start and at its end (scenarios/RunPipeline: summary.json
// `representations_built`). One run per process (compare and sweep fork one per setting).
#pragma once
#include <array>
#include <cstddef>
#include <vector>

namespace crumble {

enum class Representation : int {
  LevelSetGrid,   // a shape's signed-distance grid + surface nodes (Shape::level_set)
  Mesh,           // a shape's closed triangle mesh (Shape::mesh)
  Outline,        // a 2D shape's polygon (Shape::outline)
  ConvexHull,     // a 3D convex hull of a point set (convex_hull)
  MeshDistance,   // the distance tree of a polyhedron (signed distance, containment)
  AlphaShape,     // an alpha-shape polyhedron of a point cluster (alpha_shape_polyhedron)
  MeshClip,       // a mesh cut by planes (split_by_planes on a TriMesh)
  LevelSetSplit,  // a level set split by planes, a surface or clusters (LevelSetSplit)
  PdLattice,      // a peridynamics lattice of a grain (breakage/peridynamics)
  Count
};
inline constexpr std::size_t kRepresentationKinds = static_cast<std::size_t>(Representation::Count);

// The name in summary.json ("level_set_grids", "pd_lattices", …).
const char* to_string(Representation r);

void count_built(Representation r, long n = 1) noexcept;

struct RepresentationCounts {
  std::array<long, kRepresentationKinds> n{};
  long operator[](Representation r) const { return n[static_cast<std::size_t>(r)]; }
  RepresentationCounts operator-(const RepresentationCounts& o) const {
    RepresentationCounts d;
    for (std::size_t i = 0; i < n.size(); ++i) d.n[i] = n[i] - o.n[i];
    return d;
  }
};

// This process's totals so far.
RepresentationCounts representations_built();

}  // namespace crumble
