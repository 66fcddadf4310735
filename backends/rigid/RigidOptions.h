// The options both rigid-body adapters (bullet, ode) have: the same keys, defaults and
// ranges; the documentation names each library's own shapes and reasons. Each adapter lays
// these lines out in its own option table among its own keys.
#pragma once
#include <string>

#include "core/ConcaveShapes.h"
#include "core/Config.h"
#include "core/Options.h"

namespace crumble {

struct RigidOptions {
  bool exact_spheres = false;  // "sphere_representation": "sphere" (else "polyhedron")
  double length_scale = 0;     // internal units per metre; 0 = automatic (RigidWorld::fix_scale)
  int solver_iterations = 100;
  double erp = 0.003;          // penetration correction per step (Zhu & Zhao 2019, eq. 8)
  double mass_scale = 1;       // mass and inertia ×; weights stay physical
  ConcaveShapeOptions concave; // "concave_shapes", "concavity_tolerance", "max_convex_pieces"
};

// The table lines of the shared keys. Each takes the engine's words for its documentation.
namespace rigid_option {
// "spheres as their <polyhedron> or \"sphere\" (exact <sphere>)".
OptionSpec sphere_representation(const std::string& polyhedron, const std::string& sphere);
// "internal units per metre; 0 = the power of two nearest 1/d of the first grain (<why>)".
OptionSpec length_scale(const std::string& why);
OptionSpec solver_iterations(const std::string& doc);
OptionSpec erp(const std::string& doc);
// "mass and inertia ×; weight unchanged (<note>)".
OptionSpec mass_scale(const std::string& note);
}  // namespace rigid_option

// An adapter's table: its lines, then the three concave-shape lines (`how` names its compound).
OptionTable with_concave_shape_options(OptionTable table, const std::string& how);

// Reads the shared keys (the table must hold every line above and the concave-shape ones).
void read_rigid_options(const Options& r, RigidOptions& o);

// An adapter's options from its "engine" object: the type checked, the shared keys read,
// then `read_own(r, o)` reads the adapter's own.
template <class EngineOptions, class ReadOwn>
EngineOptions read_rigid_engine_options(const Config& cfg, const std::string& type, const OptionTable& table,
                                        ReadOwn read_own) {
  cfg.string("type", type);
  const Options r(cfg, table);
  EngineOptions o;
  read_rigid_options(r, o);
  read_own(r, o);
  return o;
}

}  // namespace crumble
