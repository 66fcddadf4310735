// The options both rigid-body adapters (bullet, ode) have: the same keys, defaults and
// ranges; the documentation names each library's own shapes and reasons. Each adapter lays
// these lines out in its own option table among its own keys; each line is bound to the
// RigidOptions member of the adapter's settings struct S (which derives from RigidOptions).
#pragma once
#include <limits>
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

// A RigidOptions member as a member of the adapter's settings S.
template <class S, class M>
M S::*member(M RigidOptions::*m) {
  return static_cast<M S::*>(m);
}

// "spheres as their <polyhedron> or \"sphere\" (exact <sphere>)".
template <class S>
OptionSpec sphere_representation(const std::string& polyhedron, const std::string& sphere) {
  return opt::mapped_choice("sphere_representation", member<S>(&RigidOptions::exact_spheres),
                            {{"polyhedron", false}, {"sphere", true}},
                            "spheres as their " + polyhedron + " or \"sphere\" (exact " + sphere + ")");
}

// "internal units per metre; 0 = the power of two nearest 1/d of the first grain (<why>)".
template <class S>
OptionSpec length_scale(const std::string& why) {
  return opt::number("length_scale", member<S>(&RigidOptions::length_scale), 0, std::numeric_limits<double>::infinity(),
                     "", "internal units per metre; 0 = the power of two nearest 1/d of the first grain (" + why + ")");
}

template <class S>
OptionSpec solver_iterations(const std::string& doc) {
  return opt::integer("solver_iterations", member<S>(&RigidOptions::solver_iterations), 1, 1000000, doc);
}

template <class S>
OptionSpec erp(const std::string& doc) {
  return opt::number("erp", member<S>(&RigidOptions::erp), 0, 1, "", doc);
}

// "mass and inertia ×; weight unchanged (<note>)".
template <class S>
OptionSpec mass_scale(const std::string& note) {
  return opt::positive("mass_scale", member<S>(&RigidOptions::mass_scale), "",
                       "mass and inertia ×; weight unchanged (" + note + ")");
}

}  // namespace rigid_option

// An adapter's table: its lines, then the three concave-shape lines (`how` names its compound).
template <class S>
OptionTable with_concave_shape_options(OptionTable table, const std::string& how) {
  for (auto& spec : concave_shape_options(how, rigid_option::member<S>(&RigidOptions::concave)))
    table.push_back(std::move(spec));
  return table;
}

// An adapter's settings from its "engine" object: the type checked, then every option of
// its table read into S (defaults and ranges from the table).
template <class S>
S read_rigid_engine_options(const Config& cfg, const std::string& type, const OptionTable& table) {
  cfg.string("type", type);
  return read_options<S>(cfg, table);
}

}  // namespace crumble
