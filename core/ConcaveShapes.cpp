#include "core/ConcaveShapes.h"

#include <exception>
#include <iostream>

#include "geometry/ConvexHull.h"
#include "geometry/ConvexPieces.h"

namespace crumble {

std::vector<TriMesh> concave_shape_pieces(const Shape& shape, const ConcaveShapeOptions& o, const std::string& engine,
                                          long* failures) {
  std::vector<TriMesh> out;
  if (!o.convex_pieces || shape.kind() != ShapeKind::Polyhedron) return out;
  ConvexPiecesOptions po;
  po.tolerance = o.concavity_tolerance;
  po.max_pieces = o.max_convex_pieces;
  try {
    // Most children are hulls already: cut only what is concave (the same test convex_pieces
    // starts with, on the shape's cached hull).
    if (!(polyhedron_mass_properties(shape.convex_hull()).volume > (1 + po.tolerance) * shape.volume())) return out;
    const ConvexPieces cp = convex_pieces(shape.mesh(), po);
    if (cp.pieces.size() < 2) return out;
    for (const auto& piece : cp.pieces) out.push_back(convex_hull(piece));
  } catch (const std::exception& ex) {
    // Not expected (the pieces' cuts are guarded against degenerate hulls); said once and
    // counted rather than stopping a long run for one fragment.
    out.clear();
    if ((*failures)++ == 0)
      std::cerr << "crumble: warning: " << engine << ": a concave grain could not be cut into convex pieces ("
                << ex.what() << "); it collides as its convex hull (counted in summary.json: "
                << "engine_compound_failures)\n";
  }
  return out;
}

}  // namespace crumble
