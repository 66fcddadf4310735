#include "tools/ShapeCommand.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "base/Format.h"
#include "core/Config.h"
#include "core/ShapeSpec.h"
#include "geometry/ConvexHull.h"
#include "geometry/LevelSetGrid.h"
#include "geometry/ShapeMetrics.h"
#include "output/Writers.h"

namespace crumble {

using Json = nlohmann::json;

namespace {

Json mass_json(const MassProperties& mp) {
  Json I = Json::array();
  for (int i = 0; i < 3; ++i) I.push_back({mp.inertia(i, 0), mp.inertia(i, 1), mp.inertia(i, 2)});
  return {{"volume", mp.volume}, {"centroid", {mp.centroid.x, mp.centroid.y, mp.centroid.z}}, {"inertia", I}};
}

double perimeter(const std::vector<Vec3>& poly) {
  double p = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) p += norm(poly[(i + 1) % poly.size()] - poly[i]);
  return p;
}

}  // namespace

Json shape_report(const std::string& spec, const std::string& repr, double spacing, long nodes) {
  std::string text = spec;
  if (!spec.empty() && spec.front() != '{') {
    std::ifstream in(spec);
    if (!in) throw ConfigError("--json", "neither inline JSON nor a readable file: '" + spec + "'");
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  Json doc = parse_json_text(text, "--json");
  if (!doc.is_object()) throw ConfigError("--json", "expected a shape object");
  // NaN compares false with everything: without the isfinite test it fell through to the
  // automatic spacing silently.
  if (!std::isfinite(spacing) || spacing < 0)
    throw ConfigError("--spacing", "expected a finite grid spacing > 0 (m), got " + fmt_num(spacing));
  if (nodes < 0) throw ConfigError("--nodes", "must be > 0");
  if (spacing > 0 || nodes > 0) {
    Json& r = doc["resolution"];
    if (spacing > 0) r["level_set_spacing"] = spacing;
    if (nodes > 0) r["surface_nodes"] = nodes;
  }
  Config c(doc);
  const int dim = static_cast<int>(c.integer("dimension", 3, 2, 3));
  Shape::Ptr s = shape_from_config(c, dim);
  c.check_unknown();
  Json j;
  j["shape"] = s->describe();
  j["representation"] = repr;
  j["exact"] = mass_json(s->mass_properties());
  j["equivalent_diameter"] = s->equivalent_diameter();
  if (repr == "level_set") {
    const LevelSetGrid& g = s->level_set();
    Json m = mass_json(g.mass_properties());
    j.update(m);
    const auto n = g.counts();
    j["grid"] = {n[0], n[1], n[2]};
    j["spacing"] = g.spacing();
    j["nodes"] = g.nodes().size();
    double area = 0;
    for (double w : g.node_weights()) area += w;
    j[dim == 2 ? "perimeter" : "surface_area"] = area;
  } else if (dim == 2) {
    const auto& o = s->outline();
    j["volume"] = s->volume();
    j["perimeter"] = perimeter(o);
    j["nodes"] = o.size();
  } else {
    const TriMesh& m = repr == "mesh" ? s->mesh() : s->convex_hull();
    j.update(mass_json(polyhedron_mass_properties(m)));
    j["surface_area"] = surface_area(m);
    j["nodes"] = m.vertices.size();
    j["triangles"] = m.triangles.size();
  }
  // Shape descriptors of the outline (2D) or surface mesh (3D), as shape.csv reports them.
  const GrainShapeMetrics gm = grain_shape_metrics(*s);
  for (const auto& [k, v] : {std::pair<const char*, double>{"circularity", gm.circularity},
                             {"aspect_ratio", gm.aspect_ratio}, {"sieve_size", gm.sieve_size},
                             {"sphericity", gm.sphericity}, {"zingg_ei", gm.elongation}, {"zingg_fi", gm.flatness}})
    if (std::isfinite(v)) j[k] = v;
  return j;
}

}  // namespace crumble

#include <iostream>

#include "tools/Subcommand.h"

namespace crumble {
namespace {

class ShapeCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c = app.add_subcommand("shape", "report how well a shape is resolved by a representation");
    c->add_option("--json", spec_, "shape JSON (inline text, or a file name)")->required();
    c->add_option("--representation", repr_, "level_set | mesh | hull")
        ->check(CLI::IsMember({"level_set", "mesh", "hull"}));
    c->add_option("--spacing", spacing_, "level-set grid spacing (m)");
    c->add_option("--nodes", nodes_, "level-set surface nodes");
    return c;
  }

  int run(const CommandContext&) override {
    std::cout << shape_report(spec_, repr_, spacing_, nodes_).dump() << "\n";
    return 0;
  }

 private:
  std::string spec_, repr_ = "level_set";
  double spacing_ = 0;
  long nodes_ = 0;
};

}  // namespace

std::unique_ptr<Subcommand> make_shape_command() { return std::make_unique<ShapeCommand>(); }

}  // namespace crumble
