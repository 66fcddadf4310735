// Engine `bullet`: Bullet 3 (double precision) rigid bodies with projected Gauss–Seidel
// contact dynamics, set up as Zhu & Zhao 2019 (seeds/000 §2.2, §5) ran it. No Bullet
// header appears here: the adapter lives behind a pimpl in BulletEngine.cpp.
//
// Scenario options ("engine": {"type": "bullet", ...}), all optional:
//   sphere_representation  "polyhedron" | "sphere"  default "polyhedron": a Sphere shape
//                          enters as the convex hull of its mesh (icosphere, 42 vertices at
//                          the default resolution, as seeds/000 §5) or as an exact sphere
//   length_scale           1/m, >= 0, default 0 = automatic: the power of two nearest to
//                          1/d_e of the first grain added (a grain is then ≈ 1 unit)
//   margin_fraction        (0, 0.1], default 0.01: collision margin per grain as a fraction
//                          of its equivalent diameter (hulls are inset by it)
//   solver_iterations      >= 1, default 100: PGS iterations per step (seeds/000: 2000)
//   solver_tolerance       [0, 1], default 2e-4: stop the iterations once the contact
//                          impulses change by at most this fraction between two iterations,
//                          ε = |f^k − f^(k−1)|/|f^k| (seeds/000 §2.2); 0 = off
//   solver_residual        [0, 1], default 0 = off: Bullet's own early exit
//                          (m_leastSquaresResidualThreshold) once no contact's relative
//                          velocity changes by more than this many length units per step
//                          (|Δv|·dt·length_scale) in an iteration
//   erp                    [0, 1], default 0.003: penetration correction β (seeds/000 eq. 8)
//   mass_scale             > 0, default 1: grain and platen masses and inertias are
//                          multiplied by it (seeds/000 §5: 70); weights stay physical
#pragma once
#include <memory>

#include "core/Config.h"
#include "core/Engine.h"

namespace crumble {

std::unique_ptr<Engine> make_bullet_engine(const Config& cfg, const EngineContext& ctx);

class BulletEngine final : public Engine {
 public:
  struct Options {
    bool exact_spheres = false;
    double length_scale = 0;
    double margin_fraction = 0.01;
    int solver_iterations = 100;
    double solver_tolerance = 2e-4;
    double solver_residual = 0;
    double erp = 0.003;
    double mass_scale = 1;
  };
  static Options read_options(const Config& cfg);

  BulletEngine(const Options& opts, const EngineContext& ctx);
  ~BulletEngine() override;

  std::string name() const override { return "bullet"; }
  void set_container(const Container& c) override;
  void add_grain(const Grain& g) override;
  void remove_grain(GrainId id) override;
  std::size_t grain_count() const override;
  void step(double dt) override;
  void read_state(std::span<Grain> grains) const override;
  std::vector<Contact> contacts() const override;
  void set_platen(const PlatenCommand& cmd) override;
  double platen_position() const override;
  double platen_force() const override;
  double floor_force() const override;

  // Diagnostics.
  double length_scale() const;             // internal units per metre (0 until fixed)
  // Zhu's relative impulse change ε at the last iteration of the last step (largest island).
  double last_solver_change() const;
  int last_solver_iterations() const;      // most PGS iterations an island needed in the last step (-1 before any)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Checks that this build uses Bullet's double-precision libraries consistently: btScalar
// is double in our translation units and the linked library computes in double. Returns
// false with the reason in `why` otherwise.
bool bullet_double_precision_ok(std::string* why = nullptr);

}  // namespace crumble
