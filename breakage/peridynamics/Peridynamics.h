// Breakage model "peridynamics": Zhu & Zhao 2019 (§2.1, §3, §4).
// A grain selected by the screening is discretised on a cubic lattice, loaded by its
// contact forces (ramped in time, the zone of the largest force fixed) and integrated
// explicitly with the linear peridynamic solid and critical-stretch bonds until it splits
// into two or more major pieces or the full load has been carried at rest.
//
// Decisions where the paper is silent (measured figures: tests/unit/peridynamics):
// - Lattice through the grain's centroid (body frame), axes = body axes; any Shape via
//   Shape::contains. Point volume = grain volume / number of points (volume_correction),
//   so mass and forces per volume are the grain's; the stiffness does not depend on it.
// - Bond family: the plain rule of the paper's discretisation by default (all offsets
//   within 3.0002 spacings, weight 1: K and the orientation average of μ exact, but E is
//   0.87 E along the lattice axes and 1.08 E along the diagonals). partial_volumes = true
//   weights neighbour cells by their volume inside the horizon: isotropic, E within 0.5 %,
//   twice the bonds; it crushes the reference grain at ≈ 196 N instead of ≈ 178 N.
// - Critical stretch: eq. 5 with the actual horizon, times √(d/d_ref) (eq. 16).
// - Loads: every contact force (world) is rotated into the body frame; its zone is the
//   lattice points within zone_radius_factor spacings of the point nearest the contact
//   point; the force is split equally between the zone's free points. The zone of the
//   largest force is fixed. All forces grow together, λ(t) = min(1, rate·t / F_max): the
//   largest one at the size-dependent rate of §5; the system stays balanced throughout.
// - Time integration: velocity Verlet (leapfrog form). Step = dt_safety × the stable
//   step from power iteration on the linearised operator (dt_rule "spectral"; the
//   Silling–Askari/Gershgorin bound is 2.2× smaller on this lattice). No damping by
//   default: the paper's dynamic ramp; damping delays the crack and raises the crushing
//   force (ζ = 0.1: +6 %, ζ = 0.5: +30 % on the reference grain).
// - Accelerations (defaults): density ×4 (steps ×1/2), elastic preload (the ramp starts
//   from the static solution just below the first bond break; a grain that stays below it
//   at full load is intact without dynamics). Reference grain: 180.2 N in 0.48 s versus
//   178.4 N in 2.3 s without either (physical density, ramp from 0, Silling–Askari step).
// - Stop: post_split_transits P-wave transits (load held at its value) after the first
//   check where two components over intact face bonds hold ≥ min_child_fraction of the
//   points each (split; criterion = the force then). On the reference grain the first such
//   check sees the crushed column under the contacts (7 %) come loose while the meridian
//   cracks are a few steps from complete: at the first check 93 % + 7 %, one transit later
//   four wedges (27, 23, 23, 20 %) + the column, unchanged over the next 8 transits.
//   Intact: after holding the full load for hold_transits P-wave transits once the
//   kinetic energy is below ke_tolerance × the elastic work (at most max_hold_transits).
//   Or at max_steps (outcome step_limit).
#pragma once
#include <algorithm>
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "core/BreakageModel.h"
#include "core/Config.h"
#include "core/Options.h"
#include "core/Engine.h"

namespace crumble {

// Every option, with its scenario key (the "breakage" object) and default.
struct PdOptions {
  // Discretisation (Zhu & Zhao 2019 §3.1 stage 2).
  double spacing_fraction = 0.062;  // "spacing_fraction": lattice spacing / d_e
  double horizon_factor = 3.0002;   // "horizon_factor": δ / spacing
  bool partial_volumes = false;     // "partial_volumes": neighbour cells weighted by their volume inside δ
  bool volume_correction = true;    // "volume_correction": point volume = grain volume / points (else spacing³)
  // "lattice_alignment": "load" builds the cubic lattice with one axis along the largest
  // contact force, so a diametral load meets the lattice the same way whatever the grain's
  // orientation (the LPS lattice is anisotropic: 179 N along an axis, 144–151 N along
  // generic directions for the 2 mm reference grain); "body" fixes it to the body axes.
  bool align_lattice_to_load = true;
  long min_points = 100;            // "min_points": fewer lattice points → outcome too_few_points
  // Critical stretch (eqs. 5, 16).
  double d_ref = 2e-3;  // "d_ref", m
  // Loading (§3.1, §5).
  double zone_radius_factor = 2.0;        // "zone_radius_factor": contact zone radius / spacing
  double contact_tolerance_factor = 2.0;  // "contact_tolerance_factor": contact → nearest point, / spacing
  double rate_large = 2.0e6;              // "loading_rate_large", N/s, d_e >= size_large
  double rate_medium = 1.2e6;             // "loading_rate_medium", N/s, size_small <= d_e < size_large
  double rate_small = 1.0e6;              // "loading_rate_small", N/s, d_e < size_small
  double size_large = 1.0e-3;             // "loading_rate_size_large", m
  double size_small = 0.6e-3;             // "loading_rate_size_small", m
  // Time integration.
  double dt_safety = 0.8;        // "dt_safety": fraction of the stable step
  // "dt_rule": stable step from "spectral" (power iteration on the linearised operator) or
  // "silling_askari" (Gershgorin row-sum bound; guaranteed but ≈ 2.2× smaller here).
  std::string dt_rule = "spectral";
  double damping_ratio = 0.0;    // "damping_ratio": ζ of mass-proportional damping at ω_ref = π c_p / d_e
  double density_scale = 4.0;    // "density_scale": mass scaling of the PD analysis (1 = none)
  double hold_transits = 4.0;    // "hold_transits": min hold at full load, in P-wave transits of d_e
  double max_hold_transits = 20; // "max_hold_transits": give up waiting for rest after this
  double ke_tolerance = 1e-3;    // "ke_tolerance": at rest when kinetic energy <= this × elastic work
  double post_split_transits = 2; // "post_split_transits": keep integrating (load held) after the split
  bool elastic_preload = true;     // "elastic_preload": start from the static state just before the first break
  double preload_fraction = 0.9;   // "preload_fraction": of the load factor that breaks the first bond
  double preload_tolerance = 1e-6; // "preload_tolerance": relative residual of the static solve
  long max_steps = 2'000'000;    // "max_steps": hard cap per analysis (outcome step_limit)
  long check_interval = 5;       // "check_interval": steps between connectivity/rest checks
  int threads = 1;               // "threads": OpenMP threads inside one analysis (bitwise independent)
  // Outcome (§3.2).
  double min_child_fraction = 0.03;  // "min_child_fraction"
  // Strength (§4, eqs. 12–15).
  bool weibull = true;               // "weibull": false = every grain G_c0 with eq. 15's size effect only
  double gc0 = 30.0;                 // "gc0", J/m² at d0
  double d0 = 2e-3;                  // "d0", m
  double weibull_modulus = 3.1;      // "weibull_modulus" ψ
  double weibull_a = -0.76;          // "weibull_a"
  double weibull_b = 1.13;           // "weibull_b"
  double threshold_force_ref = 80.0; // "threshold_force_ref", N for G_c0 at d0
};

// The options of the "breakage" object: every key above with its default and range
// (`crumble list --options peridynamics`).
const OptionTable& peridynamics_options();
// Reads every key above from the scenario's "breakage" object through peridynamics_options()
// (and marks "type").
PdOptions pd_options_from_config(const Config& cfg);
// Checks ranges (std::invalid_argument naming the option).
void validate(const PdOptions& o);

// Zhu & Zhao 2019 eq. 13: G_c = G_c0 ((U − b)/a)² (d/d0)^(−6/ψ) for U in [0, 1).
double pd_sample_gc(const PdOptions& o, double d, double u);
// Zhu & Zhao 2019 eq. 15: G_c of a child of size d_child from a parent of size d_parent.
double pd_child_gc(const PdOptions& o, double gc_parent, double d_child, double d_parent);
// Screening force (N), eqs. 12/14 with σ ∝ √G_c and F = σ d²:
// threshold = threshold_force_ref · √(G_c / G_c0) · (d / d0)².
double pd_threshold_force(const PdOptions& o, double gc, double d);
// Force ramp rate (N/s) for a grain of equivalent diameter d (§5).
double pd_loading_rate(const PdOptions& o, double d);

class PeridynamicsModel final : public BreakageModel {
 public:
  explicit PeridynamicsModel(PdOptions o);
  std::string name() const override { return "peridynamics"; }
  // Per-grain strength values (Grain::strength).
  static constexpr const char* kGc = "gc_J_m2";                 // G_c, eqs. 13, 15
  static constexpr const char* kThreshold = "threshold_force_N";  // screening force, eqs. 12, 14
  void assign_strength(Grain& g, const Material& m, Rng& rng) const override;
  void inherit_strength(const Grain& parent, Grain& child, const Material& m, Rng& rng) const override;
  // Outcomes (BreakageAnalysis::outcome): split (broken), intact, no_load (fewer than two
  // contacts carrying force), too_few_points (lattice below min_points),
  // contact_off_grain (a contact point farther than contact_tolerance_factor spacings from
  // every lattice point), step_limit (max_steps reached). Only split is broken; the others
  // keep the grain as it is. Figures: force_at_split_N = largest contact force reached at
  // the split (N), 0 otherwise; points, bonds (directed CSR entries: each bond counted at
  // both ends) and steps (explicit steps; 0 when the static preload shows no bond can
  // break) describe the cost. load = largest contact force given. The fracture is a
  // PointClusters in the body frame (reference positions). A split also sets `points`: the
  // lattice with damage (broken share of each point's bonds), piece and displacement_m.
  BreakageAnalysis analyse(const Grain& g, const Material& m, std::span<const Contact> contacts) const override;
  // first_break_force_N: the largest contact force at which the static solution breaks its
  // first bond (elastic_preload; 0 without it): force_at_split_N / first_break_force_N says how
  // far past its first broken bond a grain split. hold_steps: steps at full load (to the split or
  // the end); quiet_transits_max: the longest stretch at full load without a newly broken bond,
  // in P-wave transits (docs/performance.md, "Fewer analyses": why no rule cuts the hold).
  std::vector<std::string> figure_names() const override {
    return {"points", "bonds", "steps", "force_at_split_N", "first_break_force_N", "hold_steps", "quiet_transits_max",
            "threads"};
  }
  // Zhu & Zhao 2019, §5: their screening, and a check every 0.08 MPa of platen stress.
  // Zhu & Zhao 2019 §5. The skip rule for grains analysed whole (Screening.h) stays off: it
  // delays splits, and one pair of runs cannot bound by how much (docs/performance.md,
  // "Fewer analyses").
  ScreeningSettings default_screening() const override { return zhu_zhao_screening(); }
  ScheduleSettings default_schedule() const override { return {0.08e6, 0}; }
  double threshold_force(const Grain& g) const override { return g.strength.get_or(kThreshold, 0); }
  // The largest contact force on the grain: what Zhu & Zhao 2019 §3.1 compare with the
  // grain's threshold_force_N (eqs. 12, 14) before any analysis.
  std::string load_measure_name() const override { return "max_contact_force_N"; }
  double load_measure(const Grain& g, const Material& m, std::span<const Contact> contacts) const override;
  const PdOptions& options() const { return o_; }
  // An analysis runs on max(breakage.threads, this) threads; results do not depend on it.
  void set_analysis_threads(int threads) const override { analysis_threads_.store(std::max(1, threads)); }

 private:
  PdOptions o_;
  mutable std::atomic<int> analysis_threads_{1};
};

std::unique_ptr<BreakageModel> make_peridynamics(const Config& cfg, const EngineContext& ctx);

// Uniaxial crushing of one grain (Zhu & Zhao 2019 §4.2, Fig. 9): the zone around the lattice
// point nearest the top of the grain (+z) is pushed down with a force growing at the
// size-dependent loading rate, the zone at the bottom is fixed, until the grain splits.
struct CrushResult {
  bool split = false;
  double force = 0;      // N, applied force when the grain split
  double strength = 0;   // Pa, characteristic strength F / d_e²
  double diameter = 0;   // m, d_e
  int fragments = 0;     // major pieces
  std::vector<double> fragment_volumes;  // m³, fines attached; sums to the grain's
  long points = 0, bonds = 0, steps = 0, broken_bonds = 0;
  int static_iterations = 0;  // conjugate-gradient iterations of the elastic preload
  double dt = 0;            // s
  double wall_seconds = 0;
  std::string outcome;      // split, step_limit
  PointClusters clusters;   // the pieces
};
CrushResult crush_single_grain(const Shape& shape, const Material& m, double gc, const PdOptions& o);

// The LPS kernel on the lattice of LAMMPS's examples/peri cylinder (sc 0.5 mm, radius
// 5 mm, y in [−5, 0] mm: 3487 points; horizon 1.5001 mm, plain neighbour rule as LAMMPS)
// for `steps` steps on `threads` threads. One JSON line: points, bonds (directed CSR
// entries), steps, wall_seconds, bond_visits_per_second (bonds × steps / wall; each step
// runs the dilatation and the force pass over every bond).
std::string pd_kernel_bench(long steps, int threads);

}  // namespace crumble
