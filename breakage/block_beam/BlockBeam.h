// Breakage model "block_beam": Liu et al. 2019 (§2.1 mesh generation, §2.3 beam elements,
// §4 the plate on 12 concrete spheres). A grain selected by the screening is meshed into
// tetrahedral blocks; every two blocks sharing a face are joined by a beam; the grain's
// contact forces load the blocks at the contacts; the system is relaxed explicitly under
// the growing load, beams whose section stress exceeds the strength disappear, and the
// connected block sets that remain are the pieces.
//
// Our copy of the paper gives the method in words and algorithm titles only (Algorithms 4,
// 5 are figures we do not have) and prints no material table, so the following are our
// decisions, each an option:
// - Mesh: CGAL Mesh_3 on the grain's signed distance (geometry/cgal/TetMesh.h), target edge
//   d_e / blocks_per_diameter; a polyhedral child's sharp edges are approximated to
//   facet_distance. The paper meshes one sphere and copies it to every grain (§2.1.2);
//   we mesh each analysed grain (children are not spheres).
// - Beam: 3D Euler–Bernoulli frame element from centroid to centroid, cross-section = the
//   shared face (area A; J its polar moment; I = J/2 for both bending axes), E and
//   G = E/(2(1+ν)) of the grain's Material.
// - Strength: a beam disappears when the largest normal stress in its face section,
//   N/A + M c/I (tension), reaches the tensile strength, or the largest shear stress
//   V/A + T c/J reaches the shear strength (c: largest centroid–vertex distance of the
//   face). Defaults: a C30-like concrete (3 MPa, 6 MPa); the scenario states its own.
// - Loading: each contact force (body frame) is spread over the blocks whose centroids lie
//   within zone_radius_factor × mean block edge of the contact point (at least the
//   nearest block); the blocks of the largest force are fixed; the load factor grows
//   linearly over ramp_steps and is then held.
// - Time integration: dynamic relaxation (quasi-static, as the 70 mm/min loading of §4 is):
//   fictitious block masses from the stiffness (stable unit step), local non-viscous damping
//   (Cundall) of `damping`. Intact: at full load once the largest out-of-balance force of a
//   free block is below rest_tolerance × the largest block load, or once no beam has broken
//   for quiet_steps steps (a loose block pushed off the grain by its contact load never comes
//   to rest: the engine's contact would have let go of it). Split: the first check
//   where two connected block sets each hold ≥ min_child_fraction of the volume, followed
//   by post_split_steps steps (load held) so the cracks complete.
// - Pieces: connected block sets over intact beams; sets below min_child_fraction of the
//   volume (fines) join the major piece nearest to them (block centroids), so volume is
//   conserved.
// - Strength per grain: the tensile and shear strengths, optionally Weibull-scattered
//   (weibull_modulus > 0: one factor per grain of mean 1); children inherit their parent's
//   values unchanged (the beams are the material; the size effect comes from the mesh).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/BreakageModel.h"
#include "core/Config.h"
#include "core/Engine.h"
#include "core/Options.h"
#include "geometry/cgal/TetMesh.h"

namespace crumble {

struct BbOptions {
  double blocks_per_diameter = 5;  // "blocks_per_diameter": d_e / target block edge
  double facet_distance = 0.05;    // "facet_distance": surface error / target edge
  long min_blocks = 20;            // "min_blocks": fewer blocks → outcome too_few_blocks
  double tensile_strength = 3e6;   // "tensile_strength", Pa
  double shear_strength = 6e6;     // "shear_strength", Pa
  double weibull_modulus = 0;      // "weibull_modulus": 0 = every grain the nominal strengths
  double threshold_factor = 0.3;   // "threshold_factor": screening force = this × tensile × d_e²
  double zone_radius_factor = 1.5; // "zone_radius_factor": contact zone radius / mean block edge
  long ramp_steps = 8000;          // "ramp_steps"
  double damping = 0.7;            // "damping": local damping coefficient α
  double mass_factor = 1.0;        // "mass_factor": fictitious mass / stiffness row sum
  double rest_tolerance = 1e-3;    // "rest_tolerance"
  long post_split_steps = 500;     // "post_split_steps"
  long quiet_steps = 2000;         // "quiet_steps": at full load, intact after this many steps without a beam breaking
  long max_steps = 100000;         // "max_steps"
  long check_interval = 20;        // "check_interval"
  double min_child_fraction = 0.03;  // "min_child_fraction"
};

const OptionTable& block_beam_options();
BbOptions bb_options_from_config(const Config& cfg);
void validate(const BbOptions& o);

// The blocks of a grain's shape (CGAL Mesh_3; geometry/cgal/TetMesh.h), with options o.
TetMesh bb_mesh(const Shape& shape, const BbOptions& o);

class BlockBeamModel final : public BreakageModel {
 public:
  explicit BlockBeamModel(BbOptions o);
  std::string name() const override { return "block_beam"; }
  static constexpr const char* kTensile = "tensile_strength_Pa";
  static constexpr const char* kShear = "shear_strength_Pa";
  static constexpr const char* kThreshold = "threshold_force_N";
  // tensile_strength_Pa, shear_strength_Pa (× one Weibull factor of mean 1 when
  // weibull_modulus > 0) and threshold_force_N = threshold_factor × tensile × d_e².
  void assign_strength(Grain& g, const Material& m, Rng& rng) const override;
  // The parent's strengths; the threshold for the child's size.
  void inherit_strength(const Grain& parent, Grain& child, const Material& m, Rng& rng) const override;
  // Outcomes: split (broken), intact, no_load (fewer than two contacts with force),
  // too_few_blocks, mesh_failed (Mesh_3 gave no cell or a flat block), step_limit,
  // split_into_fines. Figures: blocks, beams, steps,
  // broken_beams, force_at_split_N (largest contact force × load factor at the split, 0
  // otherwise). The fracture is a PointClusters in the body frame: per piece a copy of the
  // vertices of its blocks (on_surface: on the grain's surface) and its block centroids;
  // fracture points = centroid and vertices of every broken face between two pieces;
  // spacing = mean block edge.
  BreakageAnalysis analyse(const Grain& g, const Material& m, std::span<const Contact> contacts) const override;
  std::vector<std::string> figure_names() const override {
    return {"blocks", "beams", "steps", "broken_beams", "force_at_split_N"};
  }
  ScreeningSettings default_screening() const override;
  ScheduleSettings default_schedule() const override { return {0.0, 100}; }
  double threshold_force(const Grain& g) const override { return g.strength.get_or(kThreshold, 0); }
  std::string load_measure_name() const override { return "max_contact_force_N"; }
  double load_measure(const Grain& g, const Material& m, std::span<const Contact> contacts) const override;
  const BbOptions& options() const { return o_; }

 private:
  BbOptions o_;
};

std::unique_ptr<BreakageModel> make_block_beam(const Config& cfg, const EngineContext& ctx);

}  // namespace crumble
