// `crumble shape`: how well a representation resolves a shape.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace crumble {

// Volume, centroid, inertia, surface area (2D perimeter), grid, nodes and shape descriptors
// of a shape under one representation ("level_set", "mesh" or "hull").
nlohmann::json shape_report(const std::string& spec, const std::string& representation, double spacing,
                            long nodes);

}  // namespace crumble
