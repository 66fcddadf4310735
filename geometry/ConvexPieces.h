// A concave polyhedron as a few convex pieces, for engines that collide convex shapes only
// (Bullet's btCompoundShape of hulls). Zhu & Zhao 2019 §3.2 keep a child concave in the
// physics engine when d_e >= 0.7 mm and its convexity V / V_hull < 0.85; colliding such a
// child as its convex hull instead gives the engine more solid than the grain has (the void
// ratio counts the grain's own volume) and puts contact points over the concavities, away
// from the grain's material (the peridynamic analysis cannot load them: contact_off_grain).
//
// The method: the solid is cut by planes, greedily. Each cut takes the piece and the plane
// (normal to one of the piece's three principal axes, through the piece's point deepest inside
// its hull, or at a quarter, half or three quarters of its extent) that lower the summed hull
// volume of the pieces most; a side that falls
// apart into several connected parts gives several pieces. It stops when the summed hull
// volume is within `tolerance` of the solid's volume, when no cut lowers it by more than
// `min_gain` of the solid's volume, or at `max_pieces`. The pieces are a partition of the
// solid, so the union of their hulls covers it and exceeds it by (summed hull volume − V).
// A piece is the point set whose hull it is: the original vertices on its side, the points where
// the cut planes cross the mesh edges, and those where they cross earlier cuts (each cut
// surface is kept as the convex hull, in its plane, of its points).
// Deterministic; no CGAL.
#pragma once
#include <vector>

#include "geometry/TriMesh.h"

namespace crumble {

struct ConvexPiecesOptions {
  double tolerance = 0.02;  // stop when Σ V_hull(piece) <= (1 + tolerance) V
  double min_gain = 0.005;  // a cut must lower Σ V_hull by more than this × V
  int max_pieces = 8;
};

struct ConvexPieces {
  std::vector<std::vector<Vec3>> pieces;  // each piece's points (its hull is the convex piece)
  double volume = 0;                      // of the solid (the mesh)
  double hull_volume = 0;                 // of the mesh's convex hull
  double pieces_hull_volume = 0;          // Σ over the pieces of their hulls' volumes
};

// `mesh` closed and outward-oriented. A mesh whose hull is within `tolerance` of its volume
// gives one piece (all its vertices). Throws std::invalid_argument for a mesh without
// volume or options out of range (tolerance < 0, min_gain < 0, max_pieces < 1).
ConvexPieces convex_pieces(const TriMesh& mesh, const ConvexPiecesOptions& options = {});

}  // namespace crumble
