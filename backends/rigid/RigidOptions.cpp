#include "backends/rigid/RigidOptions.h"

#include <limits>

namespace crumble::rigid_option {

OptionSpec sphere_representation(const std::string& polyhedron, const std::string& sphere) {
  return opt::choice("sphere_representation", "polyhedron", {"polyhedron", "sphere"},
                     "spheres as their " + polyhedron + " or \"sphere\" (exact " + sphere + ")");
}

OptionSpec length_scale(const std::string& why) {
  return opt::number("length_scale", RigidOptions{}.length_scale, 0, std::numeric_limits<double>::infinity(), "",
                     "internal units per metre; 0 = the power of two nearest 1/d of the first grain (" + why + ")");
}

OptionSpec solver_iterations(const std::string& doc) {
  return opt::integer("solver_iterations", RigidOptions{}.solver_iterations, 1, 1000000, doc);
}

OptionSpec erp(const std::string& doc) { return opt::number("erp", RigidOptions{}.erp, 0, 1, "", doc); }

OptionSpec mass_scale(const std::string& note) {
  return opt::positive("mass_scale", RigidOptions{}.mass_scale, "", "mass and inertia ×; weight unchanged (" + note + ")");
}

}  // namespace crumble::rigid_option

namespace crumble {

OptionTable with_concave_shape_options(OptionTable table, const std::string& how) {
  for (auto& spec : concave_shape_options(how)) table.push_back(std::move(spec));
  return table;
}

void read_rigid_options(const Options& r, RigidOptions& o) {
  o.exact_spheres = r.string("sphere_representation") == "sphere";
  o.length_scale = r.number("length_scale");
  o.solver_iterations = static_cast<int>(r.integer("solver_iterations"));
  o.erp = r.number("erp");
  o.mass_scale = r.number("mass_scale");
  o.concave = read_concave_shape_options(r);
}

}  // namespace crumble
