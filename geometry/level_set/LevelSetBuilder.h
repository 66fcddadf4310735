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
};

class LevelSetBuilder final : public FragmentBuilder {
 public:
  explicit LevelSetBuilder(LevelSetBuilderOptions opt = {});
  std::string name() const override { return "level_set"; }
  // Thread-safe (const, no shared mutable state). A surface that misses the grain gives
  // no child and method "no_split" (not an error). A plane through the grain that leaves no
  // grid node on one side is moved to leave a row of nodes on each (method
  // "level_set_planes_moved"); if the grain has a single row of nodes along the normal, or
  // the moved cut fails too, no child, removed_volume = V_parent and method
  // "level_set_unresolved" (crushed to fines, Harmon et al. 2020 §3.4).
  FragmentResult build(const Shape& parent, const Fracture& fracture) const override;
  const LevelSetBuilderOptions& options() const { return opt_; }

 private:
  LevelSetBuilderOptions opt_;
};

// The options of the "fragments" object (`crumble list --options level_set`).
const OptionTable& level_set_options();
// Registry factory: cfg is the scenario's "fragments" object, read through level_set_options().
std::unique_ptr<FragmentBuilder> make_level_set_builder(const Config& cfg, const EngineContext& ctx);

}  // namespace crumble
