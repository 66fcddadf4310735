// FragmentBuilder "level_set" (Harmon, Arthur & Andrade 2020, §3.2–3.3):
// children as level-set grains. CuttingSurfaces: φ3 = max(φ1, −φ2), φ4 = max(φ1, φ2)
// (eqs. 14–15) per plane, every non-empty cell of the arrangement and every connected
// piece a child. PointClusters (peridynamics): the parent's level set partitioned by
// nearest cluster. Any parent shape: analytic shapes go through Shape::level_set().
//
// Mass bookkeeping. A grid cannot reproduce the parent's volume exactly (the smoothed
// Heaviside of eqs. 24–30 and the crop give errors of order h²), so the builder rescales:
// with v_i the grid volumes of the kept children and r_j those of the removed pieces,
// k = V_parent / (Σ v_i + Σ r_j); every kept child grid is scaled uniformly about the
// parent's centroid by k^(1/3) (2D: k^(1/2)), which multiplies its grid volume by exactly
// k, and removed_volume = k·Σ r_j. Hence Σ children + removed = V_parent (to rounding).
//
// Pieces the lattice cannot resolve (thinner than min_thickness_cells, or without a zero
// level) that lie within absorb_cells cells of a kept child are artefacts of the cut, not
// fragments: the child is rebuilt as the union of the two, so their volume stays in the
// grains (split_by_planes). Harmon et al. 2020 take φ3 and φ4 (eqs. 14–15) whole, so such
// nodes stay part of a child there; our connectivity test would otherwise drop them as fines
// (docs/validation.md, "Where the removed mass goes"). FragmentResult::absorbed counts them.
// Off by default (absorb_cells 0) until measured beyond single runs of the quick file.
// A cut that leaves one child and only absorbed pieces (a cap thinner than a cell) splits
// nothing: one child and no removed volume, which the simulation records as no_split and
// leaves the grain as it was. With cells_across > 0 a split with absorbed pieces is refined
// first, like one with removed pieces.
//
// fines_policy "halt" (Harmon et al. 2020 §3.4, first method: breakage halted at a minimum
// size): a split that would still remove a piece (after absorb_cells), give a child finer than
// resolve_diameter, or give no resolved piece at all is not made; the builder returns it
// unresolved and the grain stays whole. "remove" (the default) lets those pieces, or the whole
// grain, leave as fines (§3.4, third method).
//
// Resolution that follows the pieces (Harmon et al. 2020 §3.4 name three ways to treat
// pieces as small as their discretisation: stop breaking them, refine their discretisation,
// remove them; this is the second). Off by default (measured: docs/validation.md). With
// cells_across > 0:
// - a split that removes a piece the grid cannot resolve (thinner than min_thickness_cells,
//   a cut that leaves no grid node on one side) is repeated on the parent resampled at half
//   the spacing, down to resolve_diameter / cells_across (and the max_grid_nodes cap);
// - every child is resampled at its own spacing: its thickness (twice its deepest inside
//   distance) / cells_across, never coarser than the parent's grid nor finer than
//   resolve_diameter / cells_across (a long slab thinner than resolve_diameter keeps that
//   grid, not one that follows its thickness), its surface nodes at the parent's node spacing
//   per grid spacing; a child finer than resolve_diameter (which the run removes as fines)
//   keeps the grid it was cut on.
#pragma once
#include <memory>
#include <string>

#include "core/Config.h"
#include "core/Options.h"
#include "core/Engine.h"
#include "core/FragmentBuilder.h"
#include "geometry/LevelSetSplit.h"

namespace crumble {

struct LevelSetBuilderOptions {
  double spacing = 0;                      // m; children's grid spacing, 0 = the parent grid's
  double min_thickness_cells = 1.0;        // thinner pieces are removed (fines)
  double min_piece_volume_fraction = 1e-4; // smaller pieces (× V_parent) are removed (fines)
  double cells_across = 0;                 // grid cells across a child's thickness; 0 = off
  double resolve_diameter = 0;             // m; splits are refined down to this / cells_across
  long max_grid_nodes = 1000000;           // nodes of one grid (a split's or a child's) at most
  int absorb_cells = 0;                    // a piece to remove this near a kept child is absorbed
  // "remove": pieces the grid cannot resolve and children finer than resolve_diameter leave
  // as fines (Harmon et al. 2020 §3.4, third method); "halt": such a split is not made, the
  // grain stays whole (unresolved; §3.4, first method).
  std::string fines_policy = "remove";
};

class LevelSetBuilder final : public FragmentBuilder {
 public:
  explicit LevelSetBuilder(LevelSetBuilderOptions opt = {});
  std::string name() const override { return "level_set"; }
  // Thread-safe (const, no shared mutable state). A surface that misses the grain gives
  // no child and method "no_split" (not an error). A plane through the grain that leaves no
  // grid node on one side is moved to leave a row of nodes on each (method
  // "level_set_planes_moved"); if the grain has a single row of nodes along the normal, the
  // moved cut fails too, or every piece is thinner than min_thickness_cells: no child and
  // method "level_set_unresolved" — with fines_policy "remove" removed_volume = V_parent
  // (crushed to fines, Harmon et al. 2020 §3.4, third method), with "halt" no removed volume
  // and FragmentResult::unresolved (the grain stays whole, first method).
  // FragmentResult::grid_nodes: the children's grid nodes; refinements: the splits repeated
  // on a finer grid.
  FragmentResult build(const Shape& parent, const Fracture& fracture) const override;
  const LevelSetBuilderOptions& options() const { return opt_; }

 private:
  SplitResult refined_split(const LevelSetGrid& phi1, const Fracture& fracture, SplitOptions& so, bool through,
                            FragmentResult& out) const;
  std::shared_ptr<const LevelSetGrid> own_resolution(const std::shared_ptr<const LevelSetGrid>& g, double coarsest,
                                                     double node_ratio) const;
  void finish_children(const Shape& parent, SplitResult& sr, FragmentResult& out) const;
  bool leaves_fines(const FragmentResult& out) const;
  LevelSetBuilderOptions opt_;
};

// The options of the "fragments" object (`crumble list --options level_set`).
const OptionTable& level_set_options();
// Registry factory: cfg is the scenario's "fragments" object, read through level_set_options();
// resolve_diameter 0 takes the scenario's simulation.fines_diameter (ctx.fines_diameter).
std::unique_ptr<FragmentBuilder> make_level_set_builder(const Config& cfg, const EngineContext& ctx);

}  // namespace crumble
