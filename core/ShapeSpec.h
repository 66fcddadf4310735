// Shapes from scenario JSON ("shape" objects) and mesh files.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "core/Options.h"
#include "geometry/LevelSetGrid.h"
#include "geometry/Shape.h"

namespace crumble {

// {"type": "sphere", "radius": r} | {"type": "ellipsoid", "radii": [a,b,c]} |
// {"type": "superellipsoid", "radii": [..], "eps1": e1, "eps2": e2} |
// {"type": "box", "half_extents": [..]} |
// {"type": "polyhedron", "vertices": [[x,y,z],..], "triangles": [[i,j,k],..]} or {"file": "m.obj"} |
// {"type": "disk", "radius": r} | {"type": "ellipse", "radii": [a,b]} |
// {"type": "superellipse", "radii": [a,b], "eps": e} | {"type": "polygon", "vertices": [[x,y],..]} |
// {"type": "random_polygon", "vertices", "irregularity", "modes", "decay", "seed", "radius"} (see random_outline) |
// {"type": "level_set", "dimension", "origin", "spacing", "counts", "values", ["node_spacing", "nodes",
// "node_weights"]} (2D or 3D: a grain saved by an earlier run, see level_set_to_json)
// plus optional "scale" (uniform factor, default 1) and "resolution": {"mesh_subdivisions", "level_set_spacing", "surface_nodes"}.
// With `unit_size` the size keys are optional and default to an equivalent diameter of 1 m
// (packing templates, scaled per grain).
Shape::Ptr shape_from_config(const Config& c, int dimension, bool unit_size = false);

// Irregular 2D grain outlines (the XRCT outlines of Harmon et al. 2020 are not available):
// a star-shaped polygon r(θ) = radius·(1 + Σ_{k=2..modes} a_k cos(kθ + φ_k)) at `vertices`
// equally spaced angles, a_k = irregularity·u_k·k^-decay / Σ_j j^-decay (u_k uniform in
// [0, 1]), φ_k uniform: smooth random radii in [radius·(1 − irregularity), radius·(1 +
// irregularity)]. Deterministic for a seed. std::invalid_argument on bad values.
struct RandomOutlineSpec {
  int vertices = 32;
  double irregularity = 0.5;
  int modes = 8;
  double decay = 1.0;
  std::uint64_t seed = 1;
  double radius = 0.5;  // m
};
std::vector<Vec3> random_outline(const RandomOutlineSpec& spec);

// {"type": "pool", "count": 25, + the random_polygon keys but radius}: `count`
// random_polygon SHAPE specs with seeds seed, seed + 1, … (a packing's templates).
std::vector<nlohmann::json> shape_pool(const Config& c);

// The keys of SHAPE objects, each table bound to the struct it fills (the size keys,
// "vertices", "triangles", "file" and the level_set keys are read by hand: their form
// depends on the type and dimension). Generated into docs/scenarios.md.
struct ShapeSettings {
  double scale = 1;  // every SHAPE: uniform factor
};
const OptionTable& shape_options();
const OptionTable& shape_resolution_options();  // SHAPE.resolution, bound to ShapeResolution
struct SuperellipsoidSettings {
  double eps1 = 1, eps2 = 1;
};
const OptionTable& superellipsoid_options();
struct SuperellipseSettings {
  double eps = 1;
};
const OptionTable& superellipse_options();
// Bound to RandomOutlineSpec; "radius" is required for a grain and defaults for a template.
const OptionTable& random_polygon_options();
struct PoolSettings {
  long count = 25;
};
const OptionTable& pool_options();  // besides the random_polygon keys

// Wavefront OBJ (v / f lines; polygons fan-triangulated). Errors name file and line.
TriMesh read_obj(const std::string& path);

// A level-set grid as SHAPE JSON ({"type": "level_set", ...}: dimension, origin, spacing,
// counts, values in x-fastest order, node_spacing, nodes, node_weights), read back
// exactly by shape_from_config.
nlohmann::json level_set_to_json(const LevelSetGrid& grid);

}  // namespace crumble
