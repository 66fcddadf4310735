// Level-set splitting (Harmon, Arthur & Andrade 2020, §3.2–3.3): the children of a grain
// whose level set φ1 is cut by a fracture surface φ2 are
//   φ3 = max(φ1, −φ2)   (eq. 14, the part where φ2 > 0)
//   φ4 = max(φ1,  φ2)   (eq. 15, the part where φ2 < 0),
// so that min(φ3, φ4) = φ1 (eq. 16). Pure geometry (layer 1): no crumble include beyond
// geometry/.
//
// Decisions the paper leaves open:
// - Each child's grid is cropped to the child (its inside nodes plus `pad` cells) on the
//   parent's lattice, and reinitialised to a signed distance (LevelSetGrid::reinitialised;
//   eq. 17's purpose — the paper skips eq. 17 because it only reads φ inside a grain, we
//   reinitialise because contacts and surface nodes also read φ just outside).
// - A piece is a connected component (face neighbours) of the child's inside grid nodes:
//   a cut that leaves disconnected pieces gives one child per piece.
// - Several planes: each non-empty cell of their arrangement is a region (sign pattern).
// - Surface nodes of plane cuts (§3.3): the parent's own nodes on the child's side, plus
//   new nodes on the cut placed on a square lattice of the parent's node spacing along the
//   plane's tangent directions (one node per lattice cell that meets the parent, at the
//   mean of the cell's inside sub-samples, weight = the inside part of the cell's area).
//   Other splits rebuild the nodes from the zero level at the parent's node spacing.
// - A piece thinner than `min_thickness_cells` grid cells (its deepest point less than
//   half that thickness inside) or smaller than `min_volume` is removed; its volume is
//   reported, never dropped silently — unless it lies within `absorb_cells` lattice cells of
//   a kept child: then it is an artefact of cutting a lattice (a row of nodes a plane cut off
//   from its piece, a cap thinner than a cell; Harmon et al. 2020 take φ3 and φ4 whole, with
//   no connectivity test, so such nodes stay part of a child) and that child is rebuilt as
//   the union of the two (the minimum of their values: across a cut plane, φ1 again).
#pragma once
#include <functional>
#include <memory>
#include <vector>

#include "geometry/LevelSetGrid.h"
#include "geometry/Vec3.h"

namespace crumble {

// φ2(x) = normal·x − offset, normal a unit vector.
struct SplitPlane {
  Vec3 normal;
  double offset = 0;
  double value(const Vec3& x) const { return dot(normal, x) - offset; }
};

struct SplitOptions {
  // Spacing of the children's grids; 0 = the parent grid's. Another spacing resamples the
  // parent's level set first (φ1 read by interpolation).
  double spacing = 0;
  // Margin of each child's grid around its inside nodes (>= 3: the smoothed Heaviside of
  // eqs. 24–30 reaches 1.5 cells outside the zero level, which lies within a cell).
  int pad = 3;
  double min_thickness_cells = 1.0;  // thinner pieces are removed
  double min_volume = 0;             // m³ (2D: m²); smaller pieces are removed
  int absorb_cells = 0;              // a piece to remove this near a kept child is absorbed; 0 = off
};

struct SplitPiece {
  std::shared_ptr<const LevelSetGrid> grid;  // parent frame (not re-centred)
  double volume = 0;                         // grid volume (eqs. 24–30)
  Vec3 centroid;                             // parent frame
};

struct SplitResult {
  std::vector<SplitPiece> children;
  std::vector<SplitPiece> removed;  // thin or small pieces (grid volume counted)
  double removed_volume = 0;        // Σ removed[i].volume
  int absorbed = 0;                 // pieces to remove that a kept child took in
  double absorbed_volume = 0;       // their own grid volume (now inside that child)
  // The surfaces missed the grain (a single piece): no split, `children` and `removed`
  // are empty. Not an error.
  bool missed = false;
};

// Children of `parent` cut by one or more planes (each non-empty arrangement cell; each
// connected piece of it). Throws std::invalid_argument on bad input (non-unit normal,
// more than 12 planes, bad options); never on a degenerate piece (it is removed).
SplitResult split_by_planes(const LevelSetGrid& parent, const std::vector<SplitPlane>& planes,
                            const SplitOptions& options = {});

// Children of `parent` cut by any fracture surface φ2 (negative on one side): eqs. 14–15.
SplitResult split_by_surface(const LevelSetGrid& parent, const std::function<double(const Vec3&)>& phi2,
                             const SplitOptions& options = {});

// Partition by nearest cluster (peridynamics output): child i = max(φ1, d_i) with
// d_i(x) = (D_i(x) − min_{j≠i} D_j(x)) / 2, D_j the distance to the nearest point of
// cluster j — the signed distance to the bisector between the two nearest clusters,
// negative in cluster i's Voronoi cell. `points` are in the parent frame.
SplitResult split_by_clusters(const LevelSetGrid& parent, const std::vector<Vec3>& points,
                              const std::vector<int>& cluster, int clusters, const SplitOptions& options = {});

}  // namespace crumble
