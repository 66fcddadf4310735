// Alpha-shape polyhedra from point clouds (Zhu & Zhao 2019 §3.2).
//
// Pure geometry (no core/ include), but implemented with CGAL: it is compiled into the
// crumble_alpha_shape library only (CRUMBLE_WITH_CGAL), not into crumble_geometry.
#pragma once
#include <string>
#include <vector>

#include "geometry/TriMesh.h"

namespace crumble {

struct AlphaShapeOptions {
  // Sampling spacing of the points (m), > 0: the walk over alpha starts at
  // sqrt(alpha) = start_spacings * spacing (smaller alphas cannot close a surface sampled
  // at that spacing).
  double spacing = 0;
  double start_spacings = 2.0;
  // Give up (ok = false) after this many candidate alphas, or once sqrt(alpha) exceeds
  // max_spacings * spacing.
  int max_steps = 400;
  double max_spacings = 20.0;
  // Minimum relative increase of alpha between two candidates; 0 tries every value of
  // the alpha spectrum in turn.
  double min_growth = 0.0;
};

struct AlphaShapeResult {
  bool ok = false;
  // When ok: closed, consistently outward-oriented, 2-manifold, connected,
  // V - E + F = 2, free of self-intersections. Vertices are input points (exact copies).
  TriMesh mesh;
  double alpha = 0;      // squared radius of the accepted alpha (m²)
  int steps = 0;         // candidate alphas examined
  int delaunay_vertices = 0;
  bool lattice = false;  // combinatorics computed on exact lattice coordinates (see .cpp)
  std::string failure;   // why no alpha was accepted (when !ok)
};

// Walks the alpha spectrum of the REGULARIZED 3D alpha shape (CGAL Alpha_shape_3)
// upwards from (start_spacings * spacing)² and returns the first alpha whose REGULAR
// facets, oriented towards the exterior cells, form a closed, manifold, connected,
// genus-0 (V - E + F = 2), non-self-intersecting polyhedron without zero-area facets
// (Zhu & Zhao 2019 §3.2). Enclosed exterior cells (internal voids) are counted as solid.
// Points of a cubic lattice of the given spacing and midpoints of its bonds are
// processed in exact integer coordinates (see AlphaShape.cpp).
// Throws std::invalid_argument for fewer than 4 points, non-finite points or bad options.
AlphaShapeResult alpha_shape_polyhedron(const std::vector<Vec3>& points, const AlphaShapeOptions& opt);

// True if two non-adjacent triangles of the mesh intersect (CGAL
// Polygon_mesh_processing::does_self_intersect, exact predicates).
bool mesh_self_intersects(const TriMesh& mesh);

}  // namespace crumble
