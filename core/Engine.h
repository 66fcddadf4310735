// The rigid-body engine seam. An engine owns the dynamic state of the grains it was
// given (by id) and the container walls; the Simulation keeps the Grain records
// (shape, strength, lineage) and pulls poses and velocities with read_state() when it
// needs them. Units are SI; an engine that prefers other units scales internally.
#pragma once
#include <limits>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/Contact.h"
#include "core/Grain.h"
#include "core/Loading.h"
#include "core/MovingWall.h"

namespace crumble {

// Rigid box with a floor at z = 0 (2D: y = 0), side walls at x = 0, lx and y = 0, ly
// (2D: x = 0, lx only), and a horizontal platen starting at `height` that the loading
// moves. Wall friction comes from the materials.
struct Container {
  double lx = 0, ly = 0;
  double height = 0;
  double platen_mass = 0;  // kg, for force control; 0 = the grains' total (unscaled) mass
  // An open scene (a jaw crusher): no floor, side walls or platen; the grains move among
  // moving walls inside `domain`. A grain whose centroid falls below the domain's bottom
  // has left through the discharge (product, see Simulation); one outside its other faces
  // is a guard failure. `height` is then the domain's height (energy bookkeeping).
  bool open = false;
  Aabb domain;
  // The open scene's frame (Harmon et al. 2020 §4.1 send a grain "to output once [it] left the
  // frame"): a grain whose centroid is below `discharge_level` and outside the domain sideways
  // has passed the discharge too (product); one whose centroid rises above `eject_above` was
  // thrown out of the top (ejected: removed, counted apart from the product).
  double discharge_level = -std::numeric_limits<double>::infinity();
  double eject_above = std::numeric_limits<double>::infinity();
  // An open scene: p is outside the domain along an axis other than the vertical one.
  bool beside_domain(const Vec3& p, int dimension) const {
    const int up = dimension == 3 ? 2 : 1;
    for (int a = 0; a < dimension; ++a)
      if (a != up && (p[a] < domain.lo[a] || p[a] > domain.hi[a])) return true;
    return false;
  }
};

// What the Simulation hands every engine at construction.
struct EngineContext {
  int dimension = 3;
  Vec3 gravity{0, 0, -9.81};
  std::vector<Material> materials{Material{}};
  int threads = 1;
  std::uint64_t seed = 1;
  // m: simulation.fines_diameter, the size below which children leave the run (a fragment
  // builder that refines its resolution need not resolve pieces finer than this).
  double fines_diameter = 0;
};

class Engine {
 public:
  virtual ~Engine() = default;
  virtual std::string name() const = 0;

  virtual void set_container(const Container& c) = 0;
  virtual void add_grain(const Grain& g) = 0;
  virtual void remove_grain(GrainId id) = 0;
  // Children occupy the parent's space; their velocities are already set by the caller
  // (v + ω × (c_child − c_parent)).
  virtual void replace_grain(GrainId parent, std::span<const Grain> children) {
    remove_grain(parent);
    for (const auto& c : children) add_grain(c);
  }
  virtual std::size_t grain_count() const = 0;

  virtual void step(double dt) = 0;
  // Largest stable time step for explicit engines (infinity when the engine has none).
  virtual double max_stable_dt() const;
  // Multiply every friction coefficient (grain–grain and wall) by `scale` until called again
  // (packing generation: frictionless settling gives a dense packing). Returns false when
  // the engine cannot, which is the default for scale != 1.
  virtual bool set_friction_scale(double scale) { return scale == 1.0; }
  // Multiply the engine's global (mass-proportional) damping by `scale` until called again
  // (settling a cloud under gravity, which a strong global damping would hold back). Returns
  // false when the engine has no global damping, which is the default for scale != 1.
  virtual bool set_global_damping_scale(double scale) { return scale == 1.0; }
  // Relaxing a packing another engine built (scenarios/Packing.h): an explicit engine meets the
  // other engine's overlaps as stored elastic energy and must dissipate it while the grains push
  // apart, or the packing bursts. `on` adds a damping that makes every grain overdamped until
  // called with false. Returns false when the engine needs none (Bullet and ODE remove overlaps
  // by position correction, without adding momentum), which is the default.
  virtual bool set_relaxation_damping(bool on) { (void)on; return false; }

  // Copy engine poses and velocities into the records (matched by id).
  virtual void read_state(std::span<Grain> grains) const = 0;
  // Elastic energy (J; 2D: J/m) stored in the contacts' normal springs at the last force
  // evaluation (a penalty engine: lsdem, ½·k_n·δ² per contact, (2/5)·F_n·δ for Hertz). 0 for
  // an engine whose contacts are constraints (Bullet, ODE): it stores none.
  virtual double elastic_energy() const { return 0; }
  // Kinetic energy (J; 2D: J/m) carried by mass the engine added to its grains for a
  // larger stable step (lsdem's selective mass scaling), beyond their true masses. The
  // energy guard adds it to the grains' kinetic energy (core/Guards.h). 0 by default.
  virtual double added_kinetic_energy() const { return 0; }
  // Every active contact, grain–grain once (force on `a`) and grain–wall.
  virtual std::vector<Contact> contacts() const = 0;

  // Platen control along the vertical axis: a kinematic velocity (negative = down), or a
  // force pushing the platen down while it moves freely (vertical translation only).
  virtual void set_platen(const PlatenCommand& cmd) = 0;
  virtual double platen_position() const = 0;
  // Total force (N) the grains exert on the platen along the vertical axis, positive when
  // they push it up (compression).
  virtual double platen_force() const = 0;
  // The same for the floor (positive when the grains push it down).
  virtual double floor_force() const = 0;
  // Normal force (N; 2D: N/m) the grains exert on the container wall `wall` (a WallId:
  // kFloor, kPlaten, kWallXMin … kWallYMax), positive when they push it outwards, i.e.
  // along minus the wall's inward normal (core/Platen.h wall_inward_normal). 0 for a wall
  // the scene does not have. wall_force(kFloor) == floor_force() and wall_force(kPlaten) ==
  // platen_force(). The side walls give the lateral stress of a confined sample (K0).
  // The default sums contacts(): the normal component of every contact with that wall.
  virtual double wall_force(int wall) const;

  // Moving walls (core/MovingWall.h), indexed in the order added. The Simulation sets
  // each wall's pose at the start of every step and its mean velocities over the step.
  // The defaults refuse with a message naming the engine.
  virtual int add_moving_wall(const MovingWall& w);
  virtual void set_moving_wall(int index, const WallKinematics& k);
  // Total force (N; 2D: N/m) the grains exert on the wall.
  virtual Vec3 moving_wall_force(int index) const;

  // The contact solver's convergence in the last step, for an engine with an iterative one
  // (Bullet's projected Gauss-Seidel): the most iterations an island used, and whether one
  // stopped at the iteration limit with its tolerance unmet (`change`: its relative impulse
  // change in the last iteration). iterations < 0: no iterative solver, or no contact yet.
  struct SolverReport {
    int iterations = -1;
    bool limit_before_tolerance = false;
    double change = 0;
  };
  virtual SolverReport solver_report() const { return {}; }

  // The engine's own figures for summary.json, each written as "engine_<key>" (Bullet: how
  // many concave grain shapes it collides as convex pieces).
  virtual std::map<std::string, double> summary_figures() const { return {}; }

  // What a user can change when a physical guard stops a run on this engine (core/Guards.h):
  // a sentence or two naming the settings that keep its grains apart at the stress reached.
  virtual std::string guard_advice() const {
    return "Reduce the time step (time_step), stiffen the contacts, or lower loading.max_stress.";
  }

  // Checkpoints (output/Checkpoint.h): the engine's own state beyond what the grain
  // records carry (contact history, velocities at half steps, exact orientations, the
  // platen's motion and the forces last measured), so that a resumed run continues the
  // uninterrupted one bit for bit. save_state() fills `out` with a JSON object whose
  // doubles round-trip exactly and returns true; an engine that cannot returns false (the
  // default) and a resume rebuilds it from the grains alone. restore_state() is called on
  // an engine holding the checkpoint's grains and container, with what save_state() wrote;
  // it throws std::invalid_argument naming what does not fit.
  virtual bool save_state(nlohmann::json& out) const {
    (void)out;
    return false;
  }
  virtual void restore_state(const nlohmann::json& state) {
    (void)state;
    throw std::invalid_argument("engine '" + name() + "' cannot restore a saved engine state");
  }
};

}  // namespace crumble
