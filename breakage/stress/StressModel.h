// Breakage model "stress": Harmon, Arthur & Andrade 2020, §3.1 and §3.3.
//
// - Average stress σ̄ = (1/V) Σ x_c ⊗ F_c (eq. 5): x_c from the grain's centroid to the
//   contact point, F_c the force on the grain; V the volume (2D: the area, forces per unit
//   thickness, so σ̄ is in Pa either way). Symmetrised; principal values from the shared
//   eigen-decomposition (geometry/SymmetricEigen). Sign: tension positive — what eq. 5
//   gives with forces on the grain, and what eqs. 7–8 assume (the compressive stress is
//   the minimum principal value). 2D grains are in plane stress: the principal values are
//   the two in-plane ones and 0 (the paper's 2D runs do not say; plane stress is the
//   assumption that needs no Poisson ratio).
// - Criterion (breakage.criterion): max_principal (eqs. 7–8), von_mises (eq. 9), tresca
//   (eq. 10); see Criterion.h.
// - Strength per grain by inverse-transform Weibull sampling (eq. 12), σ0 at d0 =
//   reference_diameter, modulus m; one variate per grain (max_principal: the same variate
//   scales the compressive and the tensile strength). Children: eq. 13.
// - Fracture: one plane (2D: a line) through the contact points of the strongest contacts,
//   one per contact partner (its strongest contact), in the body frame (§3.3, eqs. 18–20).
//   See fracture_plane() for the fallbacks.
#pragma once
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "breakage/stress/Criterion.h"
#include "core/BreakageModel.h"
#include "core/Config.h"
#include "core/Options.h"
#include "core/Engine.h"
#include "geometry/Shape.h"

namespace crumble {

struct StressOptions {
  std::string criterion = "von_mises";  // "criterion"
  double weibull_modulus = 3.0;         // "weibull_modulus" m (Table 2)
  double reference_diameter = 2e-3;     // "reference_diameter" d0, m (Table 2: d_c = 2 mm)
  double strength = 0;                  // "strength" σ0, Pa; 0 = the criterion's Table 2 value
  double tensile_strength = 0;          // "tensile_strength" (max_principal), Pa; 0 = Table 2
  bool weibull = true;                  // "weibull": false = σ0 scaled by eq. 13 from d0 only
  // "min_piece_fraction": the fracture plane is moved along its normal (orientation kept)
  // until each side holds at least this fraction of the grain's volume (2D: area). Our
  // decision, not the paper's: Harmon et al. 2020 §3.3 put the plane through the contacts
  // as is, which shaves a sliver (or misses the grain) when the strongest contacts sit
  // close together; the grain then "breaks" at every check without changing. 0 = off.
  double min_piece_fraction = 0.1;
  // "plane_fallback": what happens first when the plane through the contacts leaves less than
  // min_piece_fraction on one side. "centroid": the centroid replaces the weakest of the
  // points (2D: the line through the strongest contact and the centroid; 3D: the plane
  // through the two strongest and the centroid), as Harmon et al. 2020 §3.3 let it fill in
  // for a missing contact; the shift below applies only if that plane fails too. "shift":
  // keep the orientation and only shift the plane.
  std::string plane_fallback = "centroid";
  // "min_piece_diameter" (m): Harmon et al. 2020 §3.4's first way with pieces as small as
  // their discretisation, breakage halted at a minimum size. Each side of the plane must hold
  // at least the volume (2D: area) of a sphere (disc) of this diameter, as min_piece_fraction
  // does with a fraction; a grain of less than twice that volume is not broken (outcome
  // too_small). 0 = off.
  double min_piece_diameter = 0;
  // "min_piece_thickness" (m): the same first way, by thickness instead of volume. After the
  // moves above, the plane is moved along its normal until each side reaches at least this
  // far from it (the side's extent along the normal). A grain less than twice that thick
  // along the normal is cut across instead in 2D (through its centroid, perpendicular to the
  // plane, with the same limits), and is not broken (outcome too_small) when that fails too
  // or in 3D. A volume alone lets a long slab loaded at its two ends be cut along its length,
  // again and again, into strips thinner than its grid resolves (our decision). 0 = off.
  double min_piece_thickness = 0;
  // "min_contacts" of the default screening: 2D 1 (one contact + the centroid make a line,
  // §3.3), 3D 2 (a single 3D contact holds breakage off anyway).
};

// Reads the "breakage" object (ConfigError naming the key; an unknown criterion lists the
// known ones at /breakage/criterion).
StressOptions stress_options_from_config(const Config& cfg);
// The options of the "breakage" object (`crumble list --options stress`); the criterion's
// choices and the per-criterion default strengths come from stress::criteria().
const OptionTable& stress_options();

// Average stress (eq. 5) of a grain of volume V (2D: area) under `contacts` (world frame),
// about `centroid`, symmetrised, world frame. 2D: only the x–y block is non-zero.
Mat3 average_stress(const Vec3& centroid, double volume, std::span<const Contact> contacts);

// Principal values of a symmetric stress, sorted descending (tension positive); 2D: the
// two x–y values and 0.
stress::Principal principal_stresses(const Mat3& sigma, int dimension);

// The fracture plane in the body frame (centroid at the origin) through `points` (body
// frame, strongest first, one per partner; `strongest_force` the body-frame force at
// points[0]). 3D needs >= 2 points, 2D >= 1; the centroid fills in up to 3 (2D: 2).
// Fallbacks, in order, when the points do not fix a plane (2D: a line):
//   1. collinear points (3D): the plane through the points' line containing the strongest
//      force direction;
//   2. the force along that line too (a diametral load): the plane through the line whose
//      normal is the body axis least aligned with it, made perpendicular to the line
//      (a meridian plane, as a Brazilian split);
//   coincident points: the line is taken along the strongest force (2D: the line through
//   the point along the force). std::nullopt when nothing fixes a direction (outcome
//   degenerate_contacts). The result is finite, with a unit normal.
std::optional<CutPlane> fracture_plane(const std::vector<Vec3>& points, const Vec3& strongest_force, int dimension,
                                       double length_scale);

// `plane` moved along its normal so that each side of it holds at least `fraction` of
// the shape's volume (2D: area), estimated on a lattice of cell centres over the shape's
// bounds (24³ in 3D, 64² in 2D) with Shape::contains; the normal is unchanged. A plane
// that already satisfies it is returned unchanged; fraction <= 0 returns it unchanged.
// fraction must be < 0.5.
CutPlane clamp_plane_to_interior(const Shape& shape, const CutPlane& plane, double fraction);

// `plane` moved along its normal so that each side reaches at least `thickness` from it (the
// extent along the normal of the lattice of clamp_plane_to_interior, cell centres inside the
// shape); std::nullopt when the shape is less than twice that thick along the normal. A plane
// that already satisfies it, one that misses the shape, or thickness <= 0: unchanged.
std::optional<CutPlane> keep_piece_thickness(const Shape& shape, const CutPlane& plane, double thickness);

// The smaller of the two volume fractions (2D: areas) on either side of `plane`, on the
// lattice of clamp_plane_to_interior; 0 when the plane misses the shape.
double smaller_side_fraction(const Shape& shape, const CutPlane& plane);

class StressModel final : public BreakageModel {
 public:
  StressModel(StressOptions o, int dimension);
  std::string name() const override { return "stress"; }
  void assign_strength(Grain& g, const Material& m, Rng& rng) const override;
  void inherit_strength(const Grain& parent, Grain& child, const Material& m, Rng& rng) const override;
  // Outcomes: split (broken, a CuttingSurfaces with one plane), intact, no_load (no contact
  // carries force), single_contact (3D: one partner; held off, §3.3), degenerate_contacts
  // (the contacts fix no plane), too_small (failed, but less than two pieces of
  // min_piece_diameter or min_piece_thickness). Figures: sigma_1_Pa >= sigma_2_Pa (>= sigma_3_Pa in 3D),
  // equivalent_stress_Pa, strength_Pa (and tensile_strength_Pa for max_principal),
  // plane_through_centroid (1 when StressOptions::plane_fallback replaced the plane).
  BreakageAnalysis analyse(const Grain& g, const Material& m, std::span<const Contact> contacts) const override;
  std::vector<std::string> figure_names() const override;
  // Harmon et al. check every grain at every check: no size limit (fines leave through
  // simulation.fines_diameter), no force threshold, no balance ratios; a check every 100
  // steps (the paper checks each step; 100 keeps the cost of contact extraction small).
  ScreeningSettings default_screening() const override;
  ScheduleSettings default_schedule() const override { return {0.0, 100}; }
  // The criterion's equivalent stress of the average stress (eq. 5; eqs. 7–10), the value
  // compared with strength_Pa.
  std::string load_measure_name() const override { return "equivalent_stress_Pa"; }
  double load_measure(const Grain& g, const Material& m, std::span<const Contact> contacts) const override;
  const StressOptions& options() const { return o_; }

 private:
  StressOptions o_;
  int dim_;
  const stress::CriterionEntry* entry_;
  std::unique_ptr<stress::Criterion> criterion_;
  // The smallest fraction of g's volume each side of the plane must hold: min_piece_fraction,
  // or more by min_piece_diameter; >= 0.5 when g cannot give two such pieces.
  double piece_fraction(const Shape& g) const;
  static std::vector<const Contact*> strongest_first(const std::vector<Contact>& loaded);
  std::optional<CutPlane> place_plane(const Shape& shape, CutPlane plane, const std::vector<Vec3>& pts,
                                      const Vec3& f_body, double fraction, bool& centroid_fallback) const;
};

std::unique_ptr<BreakageModel> make_stress(const Config& cfg, const EngineContext& ctx);

}  // namespace crumble
