// CGAL Mesh_3 behind geometry/cgal/TetMesh.h (the only translation unit of crumble that
// includes Mesh_3).
#include "geometry/cgal/TetMesh.h"

// Mesh_3 seeds its initial surface points from CGAL's default random generator (per
// thread, seeded from the clock): reset it to a fixed seed for every mesh.
#define CGAL_MESH_3_INITIAL_POINTS_NO_RANDOM_SHOOTING
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>

#include <cmath>
#include <map>
#include <stdexcept>

namespace crumble {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;
}  // namespace

TetMesh tetrahedralise(const std::function<double(const Vec3&)>& sdf, double bounding_radius,
                       const TetMeshOptions& opt) {
  if (!(bounding_radius > 0) || !std::isfinite(bounding_radius))
    throw std::invalid_argument("tetrahedralise: bounding_radius must be > 0");
  if (!(opt.edge > 0) || !std::isfinite(opt.edge) || !(opt.facet_distance >= 0) || !(opt.facet_angle > 0) ||
      !(opt.facet_angle <= 30) || !(opt.radius_edge >= 2))
    throw std::invalid_argument(
        "tetrahedralise: need edge > 0, facet_distance >= 0, facet_angle in (0, 30], radius_edge >= 2");
  // Mesh in units of the bounding radius: CGAL's tolerances are tuned for unit-sized input.
  const double s = bounding_radius;
  auto f = [&](const Point& p) -> double { return sdf(Vec3{p.x() * s, p.y() * s, p.z() * s}) / s; };
  CGAL::Random rng(opt.seed);
  namespace params = CGAL::parameters;
  const double r = 1.05;  // domain sphere around the shape (unit radius after scaling)
  Domain domain = Domain::create_implicit_mesh_domain(
      std::function<double(const Point&)>(f), K::Sphere_3(CGAL::ORIGIN, r * r),
      params::relative_error_bound = 1e-6, params::p_rng = &rng);
  const double h = opt.edge / s;
  const double fd = (opt.facet_distance > 0 ? opt.facet_distance : opt.edge / 10) / s;
  Criteria criteria(params::facet_angle = opt.facet_angle, params::facet_size = h, params::facet_distance = fd,
                    params::cell_radius_edge_ratio = opt.radius_edge, params::cell_size = h);
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, params::no_perturb(), params::no_exude(), params::no_lloyd(),
                                      params::no_odt());

  TetMesh out;
  std::map<Tr::Vertex_handle, int> index;
  auto vid = [&](Tr::Vertex_handle v) {
    auto [it, fresh] = index.emplace(v, static_cast<int>(out.vertices.size()));
    if (fresh) {
      const auto& p = v->point().point();
      out.vertices.push_back({p.x() * s, p.y() * s, p.z() * s});
      out.on_boundary.push_back(0);
    }
    return it->second;
  };
  // Cells in the triangulation's order (deterministic for a given input).
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<int, 4> t{vid(c->vertex(0)), vid(c->vertex(1)), vid(c->vertex(2)), vid(c->vertex(3))};
    const Vec3 a = out.vertices[t[0]], b = out.vertices[t[1]], cc = out.vertices[t[2]], d = out.vertices[t[3]];
    if (dot(cross(b - a, cc - a), d - a) < 0) std::swap(t[2], t[3]);
    out.tets.push_back(t);
  }
  for (auto fct = c3t3.facets_in_complex_begin(); fct != c3t3.facets_in_complex_end(); ++fct) {
    const auto cell = fct->first;
    const int opposite = fct->second;
    for (int k = 0; k < 4; ++k)
      if (k != opposite) {
        auto it = index.find(cell->vertex(k));
        if (it != index.end()) out.on_boundary[it->second] = 1;
      }
  }
  if (out.tets.empty()) throw std::runtime_error("tetrahedralise: the mesher produced no cell (shape smaller than the edge?)");
  return out;
}

}  // namespace crumble
