// Engine `bullet`: Bullet 3 (double precision) rigid bodies with projected Gauss–Seidel
// contact dynamics, set up as Zhu & Zhao 2019 (§2.2, §5) ran it. No Bullet
// header appears here: the adapter lives behind a pimpl in BulletEngine.cpp.
//
// Scenario options ("engine": {"type": "bullet", ...}), all optional:
//   sphere_representation  "polyhedron" | "sphere"  default "polyhedron": a Sphere shape
//                          enters as the convex hull of its mesh (icosphere, 42 vertices at
//                          the default resolution, as Zhu & Zhao 2019 §5) or as an exact sphere
//   length_scale           1/m, >= 0, default 0 = automatic: the power of two nearest to
//                          1/d_e of the first grain added (a grain is then ≈ 1 unit)
//   margin_fraction        (0, 0.1], default 0.01: collision margin per grain as a fraction
//                          of its equivalent diameter (hulls are inset by it)
//   solver_iterations      >= 1, default 100: PGS iterations per step (Zhu & Zhao 2019: 2000)
//   solver_tolerance       [0, 1], default 2e-4: stop the iterations once the contact
//                          impulses change by at most this fraction between two iterations,
//                          ε = |f^k − f^(k−1)|/|f^k| (Zhu & Zhao 2019 §2.2's measure; they
//                          ran a fixed 2000 iterations, ε ≲ 2e-4 after them); 0 = off
//   solver_residual        [0, 1], default 0 = off: Bullet's own early exit
//                          (m_leastSquaresResidualThreshold) once no contact's relative
//                          velocity changes by more than this many length units per step
//                          (|Δv|·dt·length_scale) in an iteration
//   erp                    [0, 1], default 0.003: penetration correction β (Zhu & Zhao 2019 eq. 8)
//   deep_penetration       [0, 1], default 0 = off: contact points deeper than this × the first
//                          grain's d are corrected at deep_erp (default 0.2) by Bullet's split
//                          impulse, which moves the bodies without adding velocity (not in the
//                          paper: against fragments creeping into neighbours under load)
//   mass_scale             > 0, default 1: grain and platen masses and inertias are
//                          multiplied by it (Zhu & Zhao 2019 §5: 70); weights stay physical
//
// Model: restitution 0; friction √μ per grain (Bullet multiplies the
// pair), Material::wall_friction against walls; rolling friction in Bullet's convention
// (lever arm μr in the internal length unit, geometric mean for grain pairs); two
// friction directions; contact force = impulse/Δt summed over a manifold's points. Floor
// and side walls are static planes, the platen a box (kinematic under a velocity command,
// dynamic along z only under a force command, mass Container::platen_mass or the grains'
// total). Deterministic: deterministic pair order, no randomised solver order,
// deactivation off. Not thread-safe (Debian's Bullet is built without BT_THREADSAFE, and
// the friction-combination hooks are process-wide); EngineContext::threads is ignored.
//
// contacts() lists one Contact per manifold that carried a positive normal impulse in the
// last step (force = summed impulses / Δt on `a`, point = normal-impulse-weighted mean of
// its points, normal from b to a; grain pairs once with `a` the smaller id).
//
// Bullet behaviours worth knowing: PGS does not converge in 100 iterations under load
// (ε ≈ 2e-3–4e-3 on the 48-grain packing test at 0.1 MPa), so grains creep into each
// other as the load grows (exact spheres there: mean overlap 0.6 % of d, max 4 %; with 10
// iterations the packing sinks to half its height); a free body keeps its world angular
// velocity (gyroscopic terms are applied only to bodies in contact); the rolling
// resistance impulse per step is also capped at μr in internal units by the solver.
#pragma once
#include <map>
#include <memory>
#include <string>

#include "backends/rigid/RigidEngine.h"
#include "backends/rigid/RigidOptions.h"
#include "core/Config.h"
#include "core/Options.h"

namespace crumble {

class BulletEngine final : public RigidEngine {
 public:
  // The shared keys (backends/rigid/RigidOptions.h) and Bullet's own.
  struct Options : RigidOptions {
    double margin_fraction = 0.01;
    double solver_tolerance = 2e-4;
    double solver_residual = 0;
    double deep_penetration = 0;  // fraction of the first grain's d; 0 = off
    double deep_erp = 0.2;
  };
  static Options read_options(const Config& cfg);

  BulletEngine(const Options& opts, const EngineContext& ctx);

  // On the Zhu & Zhao oedometer (docs/validation.md) a smaller step or more iterations did not
  // stop a fragment creeping into a neighbour; the deep-penetration correction did.
  std::string guard_advice() const override {
    return "Push deep overlaps apart (engine.deep_penetration, e.g. 0.1), converge the contact forces "
           "(engine.solver_iterations, engine.solver_tolerance 0), reduce the time step (time_step), or lower "
           "loading.max_stress; a run stopped here resumes with any of these from its last checkpoint.";
  }
  SolverReport solver_report() const override;

  // Diagnostics.
  // Zhu's relative impulse change ε at the last iteration of the last step (largest island).
  double last_solver_change() const;
  int last_solver_iterations() const;      // most PGS iterations an island needed in the last step (-1 before any)
  // The world's settings and the last step's contact work (backends/bullet/BulletWorldReport.h).
  std::map<std::string, double> world_settings() const;
  std::map<std::string, double> contact_work() const;

 private:
  struct Impl;
  Impl* impl_;  // owned by RigidEngine
};

// The options of the "engine" object (`crumble list --options bullet`).
const OptionTable& bullet_options();
std::unique_ptr<Engine> make_bullet_engine(const Config& cfg, const EngineContext& ctx);

// Checks that this build uses Bullet's double-precision libraries consistently: btScalar
// is double in our translation units and the linked library computes in double. Returns
// false with the reason in `why` otherwise.
bool bullet_double_precision_ok(std::string* why = nullptr);

}  // namespace crumble
