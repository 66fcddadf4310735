// Breakage model "bonded_particles": the densely arrayed bonded-particle model (DA-BPM).
// A grain selected by the screening is filled with equal elements arrayed in the densest way
// (hexagonal discs in 2D, face-centred cubic spheres in 3D; DA-BPM, "Densely arrayed BPM"),
// neighbours joined by parallel bonds, loaded by its contact forces and integrated
// explicitly with local damping until the bonds settle or break; the pieces are the
// connected components over the intact bonds.
//
// What the paper fixes and what we decided (our copy of the paper has lost its equations
// and most of its parameter table; see docs/scenarios.md, "bonded_particles"):
// - Elements of one size arrayed densely, parallel bonds with normal and shear strength
//   (DA-BPM, "Parallel bond"). The elements' size is absolute (element_diameter) as in the
//   paper, where fragments keep their elements; 0 = d_e / elements_across per grain.
// - Stiffness from the grain's Material: kn from Young's modulus through the array's
//   Cauchy–Born modulus along the load axis, ks/kn from Poisson's ratio (BpmSystem.h).
// - Strengths: normal_strength, shear_strength (Pa). Our copy's parameter table reads
//   "48.0 | 30.0 | 12.0 | 8.0 | 5.0e−3" without its headers; the defaults (30 MPa each) are
//   ours. The paper gives no per-grain Weibull scatter; weibull_modulus > 0 adds one (a
//   strength factor per grain, mean 1, children inherit it: the size effect comes from the
//   element count, as in the paper).
// - The corrections of the paper: (1) fragment equivalent diameter (DECA) from the element
//   count n and the densest packing fraction η: the area (volume) of a piece is n elements'
//   cells, n·A_e/η, not n·A_e (figure largest_piece_deca_m; the level_set builder's
//   nearest-element partition gives every piece exactly its elements' cells inside the
//   grain); (2) inner pores: the grain's volume includes the pores between its elements,
//   (1 − η) of it; when it crushes these pores stay with the pieces (they are too small for
//   any fragment to fill), so the children's volumes sum to the parent's and the void ratio
//   does not jump (figure inner_pore_volume_m3 = N·(A_cell − A_e)).
// - Loads: each contact force (body frame) acts on the elements within zone_radius_factor
//   element diameters of the element nearest the contact point; the zone of the largest
//   force is fixed. All forces grow together over ramp_steps steps, then are held; with
//   elastic_preload the ramp starts from the static state at preload_fraction of the load
//   that breaks the first bond (a grain whose static state breaks no bond at the full load
//   is intact at once).
// - Stop: split (two components with >= min_child_fraction of the elements and at least
//   min_piece_elements elements each, then
//   post_split_steps more), intact (full load held >= hold_steps and kinetic energy <=
//   ke_tolerance × the work of the loads, or no bond broken for quiet_steps at the full
//   load), or max_steps (outcome step_limit).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/BreakageModel.h"
#include "core/Config.h"
#include "core/Engine.h"
#include "core/Options.h"

namespace crumble {

struct BpmOptions {
  // Discretisation.
  double element_diameter = 0;   // "element_diameter", m; 0 = d_e / elements_across
  double elements_across = 12;   // "elements_across"
  long min_elements = 7;         // "min_elements": fewer → outcome too_few_elements (unbreakable)
  // Parallel bonds.
  double normal_strength = 30e6;   // "normal_strength", Pa
  double shear_strength = 30e6;    // "shear_strength", Pa
  double radius_multiplier = 1.0;  // "radius_multiplier": bond radius / element radius
  double ks_kn_ratio = -1;         // "ks_kn_ratio": < 0 = from the Poisson ratio
  // Strength scatter per grain (crumble's addition; 0 = none).
  double weibull_modulus = 0;      // "weibull_modulus"
  // Screening.
  double threshold_fraction = 0.3;  // "threshold_fraction": of the diametral crushing estimate
  // Loading and integration.
  double zone_radius_factor = 1.0;        // "zone_radius_factor", element diameters
  double contact_tolerance_factor = 2.0;  // "contact_tolerance_factor", element diameters
  double damping = 0.7;                   // "damping": local damping coefficient α
  long ramp_steps = 12000;                // "ramp_steps"
  bool elastic_preload = true;            // "elastic_preload"
  double preload_fraction = 0.9;          // "preload_fraction"
  long hold_steps = 500;                  // "hold_steps"
  double ke_tolerance = 1e-4;             // "ke_tolerance"
  long quiet_steps = 3000;                // "quiet_steps"
  long post_split_steps = 200;            // "post_split_steps"
  long max_steps = 100000;                // "max_steps"
  long check_interval = 10;               // "check_interval"
  double min_child_fraction = 0.03;       // "min_child_fraction"
  long min_piece_elements = 1;            // "min_piece_elements": smaller components are fines
};

const OptionTable& bonded_particles_options();
BpmOptions bpm_options_from_config(const Config& cfg);
void validate(const BpmOptions& o);

// Diametral crushing force estimate of a grain of equivalent diameter d whose bonds have
// normal strength σ: the tensile stress at the centre of a disc under a diametral pair P
// (per metre) is 2P/(πd), so P ≈ (π/2)·σ·d (2D, N/m); a sphere (Hiramatsu & Oka 1966)
// σ = 0.9·P/d², P ≈ σ·d²/0.9 (3D, N).
double bpm_crush_estimate(int dimension, double sigma, double d);

class BondedParticlesModel final : public BreakageModel {
 public:
  explicit BondedParticlesModel(BpmOptions o);
  std::string name() const override { return "bonded_particles"; }
  static constexpr const char* kFactor = "bond_strength_factor";        // × normal/shear_strength
  static constexpr const char* kThreshold = "threshold_force_N";         // screening force (2D: N/m)
  void assign_strength(Grain& g, const Material& m, Rng& rng) const override;
  void inherit_strength(const Grain& parent, Grain& child, const Material& m, Rng& rng) const override;
  // Outcomes: split (broken), intact, no_load (fewer than two contacts carrying force),
  // too_few_elements, contact_off_grain, split_into_fines, step_limit.
  BreakageAnalysis analyse(const Grain& g, const Material& m, std::span<const Contact> contacts) const override;
  std::vector<std::string> figure_names() const override {
    return {"elements", "bonds", "steps", "broken_bonds", "force_at_split_N", "pieces", "largest_piece_deca_m",
            "inner_pore_volume_m3"};
  }
  // Screening: at least two contacts, the force threshold; no unbalanced-force rule (the
  // paper's grains are analysed in the DEM itself, every step).
  ScreeningSettings default_screening() const override;
  ScheduleSettings default_schedule() const override { return {0.0, 100}; }
  double threshold_force(const Grain& g) const override { return g.strength.get_or(kThreshold, 0); }
  std::string load_measure_name() const override { return "max_contact_force_N"; }
  double load_measure(const Grain& g, const Material& m, std::span<const Contact> contacts) const override;
  const BpmOptions& options() const { return o_; }

 private:
  BpmOptions o_;
};

std::unique_ptr<BreakageModel> make_bonded_particles(const Config& cfg, const EngineContext& ctx);

// One grain between two plates (the paper's single-particle crushing test): the elements
// nearest the top (+y in 2D, +z in 3D) pushed down with a growing force, those at the bottom
// fixed, until the grain splits.
struct BpmCrushResult {
  bool split = false;
  double force = 0;  // N (2D: N/m) at the split
  long elements = 0, bonds = 0, steps = 0, broken_bonds = 0;
  int pieces = 0;
  std::string outcome;
  PointClusters clusters;
};
BpmCrushResult bpm_crush_single_grain(const Shape& shape, const Material& m, const BpmOptions& o,
                                      double strength_factor = 1.0);

}  // namespace crumble
