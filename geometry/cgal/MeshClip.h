// Cutting a closed triangle mesh by planes (the CuttingSurfaces of Harmon et al. 2020 §3 applied
// to polyhedral grains). Pure geometry, implemented with CGAL: compiled into the
// crumble_alpha_shape library only (CRUMBLE_WITH_CGAL), not into crumble_geometry.
#pragma once
#include <vector>

#include "geometry/TriMesh.h"

namespace crumble {

// Plane n·x = offset; n need not be normalised (only its direction matters).
struct ClipPlane {
  Vec3 normal;
  double offset = 0;
};

// The solid bounded by `mesh` (closed, outward-oriented, manifold, free of
// self-intersections) cut into the cells of the arrangement of `planes`: every non-empty
// cell, and within a cell every connected component, becomes one closed,
// outward-oriented piece (CGAL Polygon_mesh_processing::clip with clip_volume). Pieces
// are in the frame of `mesh`, in a deterministic order (cells by the sign vector over
// the planes, negative side first). A plane that misses the solid changes nothing.
// Throws std::invalid_argument for an open, non-manifold or self-intersecting mesh or a
// zero/non-finite plane normal.
std::vector<TriMesh> split_by_planes(const TriMesh& mesh, const std::vector<ClipPlane>& planes);

// Connected components of a triangle mesh (by shared vertices), each compacted, in the
// order of their first triangle.
std::vector<TriMesh> connected_components(const TriMesh& mesh);

}  // namespace crumble
