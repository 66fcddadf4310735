// Shapes from scenario JSON ("shape" objects) and mesh files.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "geometry/LevelSetGrid.h"
#include "geometry/Shape.h"

namespace crumble {

// {"type": "sphere", "radius": r} | {"type": "ellipsoid", "radii": [a,b,c]} |
// {"type": "superellipsoid", "radii": [..], "eps1": e1, "eps2": e2} |
// {"type": "box", "half_extents": [..]} |
// {"type": "polyhedron", "vertices": [[x,y,z],..], "triangles": [[i,j,k],..]} or {"file": "m.obj"} |
// {"type": "disk", "radius": r} | {"type": "ellipse", "radii": [a,b]} |
// {"type": "superellipse", "radii": [a,b], "eps": e} | {"type": "polygon", "vertices": [[x,y],..]} |
// {"type": "level_set", "dimension", "origin", "spacing", "counts", "values", ["node_spacing", "nodes",
// "node_weights"]} (2D or 3D: a grain saved by an earlier run, see level_set_to_json)
// plus optional "scale" (uniform factor, default 1) and "resolution": {"mesh_subdivisions", "level_set_spacing", "surface_nodes"}.
// With `unit_size` the size keys are optional and default to an equivalent diameter of 1 m
// (packing templates, scaled per grain).
Shape::Ptr shape_from_config(const Config& c, int dimension, bool unit_size = false);

// Wavefront OBJ (v / f lines; polygons fan-triangulated). Errors name file and line.
TriMesh read_obj(const std::string& path);

// A level-set grid as SHAPE JSON ({"type": "level_set", ...}: dimension, origin, spacing,
// counts, values in x-fastest order, node_spacing, nodes, node_weights), read back
// exactly by shape_from_config.
nlohmann::json level_set_to_json(const LevelSetGrid& grid);

}  // namespace crumble
