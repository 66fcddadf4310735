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

// The three table lines, bound to the ConcaveShapeOptions member `m` of the engine's settings
// struct S (opt::nested); `how` names the engine's compound ("btCompoundShape").
template <class S>
OptionTable concave_shape_options(const std::string& how, ConcaveShapeOptions S::*m) {
  using C = ConcaveShapeOptions;
  return {
      opt::mapped_choice("concave_shapes", opt::nested(m, &C::convex_pieces),
                         {{"convex_pieces", true}, {"convex_hull", false}},
                         "a concave polyhedral grain (a fragment kept concave, Zhu & Zhao 2019 §3.2) collides as convex "
                         "pieces that cover it (" + how + "), or as its convex hull (more solid than the grain, contacts "
                         "over its concavities)"),
      opt::number("concavity_tolerance", opt::nested(m, &C::concavity_tolerance), 0, 1, "",
                  "convex_pieces: a polyhedron whose hull exceeds its volume by more than this fraction is cut into "
                  "pieces until their hulls do (or max_convex_pieces)"),
      opt::integer("max_convex_pieces", opt::nested(m, &C::max_convex_pieces), 1, 64,
                    "convex pieces of one concave grain at most"),
  };
}

// The convex pieces (their hulls, shape frame) a polyhedral `shape` collides as: none when
// convex_pieces is off, the shape is not a polyhedron, or its hull is within
// concavity_tolerance of its volume (it collides as its hull). A shape that cannot be cut
// (not expected) gives none too: counted in *failures, with one warning naming `engine`.
std::vector<TriMesh> concave_shape_pieces(const Shape& shape, const ConcaveShapeOptions& o, const std::string& engine,
                                          long* failures);

}  // namespace crumble
