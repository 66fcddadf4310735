// Shapes from scenario JSON ("shape" objects) and mesh files.
#pragma once
#include <string>

#include "core/Config.h"
#include "geometry/Shape.h"

namespace crumble {

// {"type": "sphere", "radius": r} | {"type": "ellipsoid", "radii": [a,b,c]} |
// {"type": "superellipsoid", "radii": [..], "eps1": e1, "eps2": e2} |
// {"type": "box", "half_extents": [..]} |
// {"type": "polyhedron", "vertices": [[x,y,z],..], "triangles": [[i,j,k],..]} or {"file": "m.obj"} |
// {"type": "disk", "radius": r} | {"type": "ellipse", "radii": [a,b]} |
// {"type": "superellipse", "radii": [a,b], "eps": e} | {"type": "polygon", "vertices": [[x,y],..]}
// plus optional "scale" (uniform factor, default 1) and "resolution": {"mesh_subdivisions", "level_set_spacing", "surface_nodes"}.
// With `unit_size` the size keys are optional and default to an equivalent diameter of 1 m
// (packing templates, scaled per grain).
Shape::Ptr shape_from_config(const Config& c, int dimension, bool unit_size = false);

// Wavefront OBJ (v / f lines; polygons fan-triangulated). Errors name file and line.
TriMesh read_obj(const std::string& path);

}  // namespace crumble
