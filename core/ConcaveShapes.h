// The options of an engine that collides convex shapes only (bullet, ode) for concave
// polyhedral grains: Zhu & Zhao 2019 §3.2 keep a child concave in the engine when
// d_e >= 0.7 mm and V / V_hull < 0.85. Such a grain collides as convex pieces that cover it
// (geometry/ConvexPieces.h) or as its hull.
#pragma once
#include <string>
#include <vector>

#include "core/Options.h"
#include "geometry/Shape.h"

namespace crumble {

struct ConcaveShapeOptions {
  bool convex_pieces = true;         // "concave_shapes": "convex_pieces" (else "convex_hull")
  double concavity_tolerance = 0.02;
  int max_convex_pieces = 8;
};

// The three table lines; `how` names the engine's compound ("btCompoundShape").
inline OptionTable concave_shape_options(const std::string& how) {
  const ConcaveShapeOptions d;
  return {
      opt::choice("concave_shapes", d.convex_pieces ? "convex_pieces" : "convex_hull", {"convex_pieces", "convex_hull"},
                  "a concave polyhedral grain (a fragment kept concave, Zhu & Zhao 2019 §3.2) collides as convex pieces "
                  "that cover it (" + how + "), or as its convex hull (more solid than the grain, contacts over its "
                  "concavities)"),
      opt::number("concavity_tolerance", d.concavity_tolerance, 0, 1, "",
                  "convex_pieces: a polyhedron whose hull exceeds its volume by more than this fraction is cut into "
                  "pieces until their hulls do (or max_convex_pieces)"),
      opt::integer("max_convex_pieces", d.max_convex_pieces, 1, 64, "convex pieces of one concave grain at most"),
  };
}

inline ConcaveShapeOptions read_concave_shape_options(const Options& r) {
  ConcaveShapeOptions o;
  o.convex_pieces = r.string("concave_shapes") == "convex_pieces";
  o.concavity_tolerance = r.number("concavity_tolerance");
  o.max_convex_pieces = static_cast<int>(r.integer("max_convex_pieces"));
  return o;
}

// The convex pieces (their hulls, shape frame) a polyhedral `shape` collides as: none when
// convex_pieces is off, the shape is not a polyhedron, or its hull is within
// concavity_tolerance of its volume (it collides as its hull). A shape that cannot be cut
// (not expected) gives none too: counted in *failures, with one warning naming `engine`.
std::vector<TriMesh> concave_shape_pieces(const Shape& shape, const ConcaveShapeOptions& o, const std::string& engine,
                                          long* failures);

}  // namespace crumble
