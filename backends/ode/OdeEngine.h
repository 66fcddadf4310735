// Engine `ode`: the Open Dynamics Engine 0.16 (Debian's libode, double precision) with its
// QuickStep solver (projected SOR on the contact LCP, a velocity-level method like
// Bullet's), as a second non-smooth contact dynamics engine for Zhu & Zhao 2019's
// coupling. 3D only. No ODE header appears here: the adapter lives in OdeEngine.cpp.
//
// Scenario options ("engine": {"type": "ode", ...}), all optional:
//   sphere_representation  "polyhedron" | "sphere"  default "polyhedron": a Sphere shape
//                          enters as the convex hull of its mesh (dConvex) or as an exact
//                          dSphere
//   length_scale           1/m, >= 0, default 0 = automatic: the power of two nearest to
//                          1/d_e of the first grain added (ODE's and libccd's tolerances are
//                          absolute lengths, so a grain is made ≈ 1 unit)
//   solver_iterations      >= 1, default 100: QuickStep SOR iterations per step
//   sor_w                  (0, 2), default 1: QuickStep's over-relaxation factor (ODE's own
//                          default 1.3 overshoots in dense packings)
//   erp                    [0, 1], default 0.003: contact error reduction (penetration
//                          correction per step, as Bullet's erp; ODE's default 0.2 launches
//                          grains at Δt ≈ 5e-5 s)
//   cfm                    >= 0, default 1e-9: contact constraint force mixing (internal
//                          units), a small regularisation of the contact LCP
//   max_correcting_velocity m/s, >= 0, default 0 = unlimited: cap of the velocity ODE uses to
//                          push overlapping bodies apart
//   contacts_per_pair      1..16, default 4: most contact points between two polyhedra (the
//                          libccd collider gives one; flat-on-flat contacts get up to this
//                          many from the clipped contact faces, so stacks stand)
//   mass_scale             > 0, default 1: grain and platen masses and inertias are
//                          multiplied by it (Zhu & Zhao 2019 §5: 70); weights stay physical
//   concave_shapes         "convex_pieces" | "convex_hull", default "convex_pieces": a concave
//                          polyhedron collides as convex pieces covering it (one dConvex geom
//                          each on its body, geometry/ConvexPieces.h, as bullet), or as its hull
//   concavity_tolerance    [0, 1], default 0.02; max_convex_pieces 1..64, default 8: as bullet's
//
// Model: restitution 0; Coulomb friction μ with dContactApprox1 (the friction pyramid is
// scaled by the normal force, so μ is a Coulomb coefficient): the grain
// material's friction between grains (√(μa·μb) for mixed materials) and its wall_friction
// against walls and the platen; rolling friction (dContactRolling, ODE ≥ 0.13) as a lever
// arm μr in the internal length unit — the Bullet convention, so both engines resist
// rolling alike at the same length scale. Floor and side walls are static planes; the
// platen a box body, kinematic under a velocity command and dynamic on a slider along z
// under a force command, with the command and mass rule of core/Platen.h. Contact forces
// from dJointFeedback. Deterministic with one thread: fixed collision and joint order, and
// ODE's constraint-reordering random generator reseeded from the scenario seed and the
// step number before every step. EngineContext::threads is ignored.
//
// contacts() lists one Contact per touching pair that carried a positive normal force in
// the last step: force = sum over the pair's points of the joint forces on `a`, point =
// normal-force-weighted mean, normal from b to a, overlap = the deepest point's depth;
// grain pairs once with `a` the smaller id.
#pragma once
#include <memory>

#include "backends/rigid/RigidEngine.h"
#include "backends/rigid/RigidOptions.h"
#include "core/Config.h"
#include "core/Options.h"

namespace crumble {

// The options of the "engine" object (`crumble list --options ode`).
const OptionTable& ode_options();
std::unique_ptr<Engine> make_ode_engine(const Config& cfg, const EngineContext& ctx);

class OdeEngine final : public RigidEngine {
 public:
  // The shared keys (backends/rigid/RigidOptions.h) and ODE's own.
  struct Options : RigidOptions {
    int contacts_per_pair = 4;  // collision: points per pair of polyhedra
    double sor_w = 1.0;         // QuickStep: over-relaxation, regularisation, correction cap
    double cfm = 1e-9;
    double max_correcting_velocity = 0;
  };
  static Options read_options(const Config& cfg);

  OdeEngine(const Options& opts, const EngineContext& ctx);

  std::string guard_advice() const override {
    return "Reduce the time step (time_step), raise engine.solver_iterations, or lower loading.max_stress.";
  }
};

// True when dReal is double here and the linked libode was built in double precision.
bool ode_double_precision_ok(std::string* why = nullptr);

}  // namespace crumble
