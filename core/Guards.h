// Physical invariants that every engine must keep (a run that breaks one stops with a
// message instead of writing an impossible result): grains inside the container, the
// platen above the floor, a positive void ratio, contact overlaps small against the grains,
// and kinetic energy bounded by the energy put in. Checked by the Simulation cheaply at the
// sampling interval (the O(1) ones every step) and while a packing settles.
#pragma once
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/Contact.h"
#include "core/Engine.h"

namespace crumble {

struct GuardSettings {
  bool enabled = true;
  // Largest overlap per contact, as a fraction of the smaller grain's equivalent diameter
  // (a wall contact: of the grain's). Rigid-grain DEM is meaningful only while overlaps
  // stay small; rigid packings stay below 0.08, but a fragment replaced by its hull may be
  // born overlapping a neighbour by ~0.3 of its own size, so the default is 0.5.
  double max_overlap_fraction = 0.5;
  // Contacts whose smaller grain is below this fraction of the initial mean diameter are
  // counted (summary.json: guard_small_grain_overlaps) instead of stopping the run: Bullet
  // cannot keep a tiny hull fragment out of a large neighbour under load, and its volume is
  // negligible in the void ratio (which is guarded on its own).
  double small_grain_fraction = 0.25;
  // Kinetic energy may not exceed this multiple of the energy that can have entered the
  // system (initial kinetic energy + platen work + the weight of every grain falling the
  // container's height). A blow-up exceeds it by orders of magnitude.
  double energy_factor = 10;
  // Grain centroids must stay inside the container (walls, floor and platen); a centroid
  // outside means a grain has passed more than half-way through a wall. A grain below
  // small_grain_fraction that leaves a closed container does not stop the run: the
  // Simulation takes it out as fines (its volume stays in the void ratio, its mass goes to
  // mass_removed_kg) and counts it (summary.json: guard_small_grains_removed). Bullet pushes
  // sub-millimetre hull fragments through the floor under load (Zhu & Zhao oedometer at
  // 19.3 MPa: a 0.18 mm fragment 0.6 µm below the floor).
  bool containment = true;
};

// A broken invariant: the run stops (exit 1) with this message.
class PhysicsGuardError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What the guards need to know about the moment they check.
struct GuardContext {
  const char* phase = "loading";  // "settling" or "loading"
  long step = 0;
  double time = 0;
  double platen_stress = 0;
  double dt = 0;
  std::string advice;         // what to change, from the engine (Engine::guard_advice)
  double energy_budget = 0;   // J (2D: J/m): energy that can have entered the system
  double reference_diameter = 0;  // m: mean equivalent diameter of the initial grains
  bool open = false;          // an open scene: no platen or void ratio; containment in the domain
  // J (2D: J/m): kinetic energy of the mass an engine added for its stable step
  // (Engine::added_kinetic_energy). The energy guard bounds the grains' kinetic energy plus
  // this: no energy source feeds the added mass (weight acts on the true mass), so the
  // scaled system's kinetic energy is bounded by the same budget, and an unstable scaled
  // grain is caught at its scaled energy, not the smaller energy of its true mass.
  double added_kinetic_energy = 0;
};

// O(1) checks on the state the loop already has: finite values, platen above the floor,
// void ratio > 0. Throws PhysicsGuardError.
// At the end of a stress ramp that ran its course: the packing must carry at least half the
// stress the platen is driven with. Less means the platen is falling through a packing that
// gave way (ode, 1000 MPa on 8 crushable grains in 4 steps: 0 Pa measured at the end against
// 1000 MPa commanded, and exit 0 before this check).
void check_stress_carried(const GuardSettings& s, const GuardContext& at, double commanded_stress);

void check_scalar_invariants(const GuardSettings& s, const GuardContext& at, double platen_height,
                             double void_ratio, double platen_force);

// The margins seen by a check (reported in summary.json so a user sees how close a run came).
struct GuardReading {
  double max_overlap_fraction = 0;  // largest overlap / smaller diameter
  double energy_ratio = 0;          // kinetic energy / energy budget
  long small_grain_overlaps = 0;    // contacts over the limit whose smaller grain is tiny
  long small_grains_removed = 0;    // running total kept by the Simulation (summary.json)
  std::vector<GrainId> escaped_small;  // tiny grains outside a closed container: to take out
};

// O(grains + contacts) checks: every centroid inside the container, overlaps, kinetic
// energy. `grains` must hold current poses and velocities.
GuardReading check_invariants(const GuardSettings& s, const GuardContext& at, const Container& box, int dimension,
                      double platen_height, std::span<const Grain> grains, std::span<const Material> materials,
                      std::span<const Contact> contacts);

// Kinetic energy (translational + rotational) of the grains at their physical masses.
double kinetic_energy(std::span<const Grain> grains, std::span<const Material> materials, int dimension);

}  // namespace crumble
