// The fuzz targets: one input in, a classified outcome out. Used by the seeded mutation
// loop that runs in the suite (test_fuzz.cpp) and by the libFuzzer entry points
// (fuzz_main.cpp, built with -DCRUMBLE_FUZZ=ON and clang).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace crumble::fuzz {

enum class Outcome {
  Accepted,    // a valid input, fully built
  InputError,  // rejected as the CLI would with exit 2 (ConfigError or std::invalid_argument)
  OtherError,  // any other exception: the CLI exits 1 "failed" — a finding for input checks
};

// A scenario document: parse (duplicate keys, overflow) + build_scenario (every option,
// shape, packing spec) — what `crumble validate` does.
Outcome scenario(const std::string& text, std::string* what = nullptr);
// A SHAPE object: shape_from_config + mass properties, mesh or outline, level set at a
// bounded resolution, shape metrics — what `crumble shape` does.
Outcome shape(const std::string& text, std::string* what = nullptr);
// A Wavefront OBJ file's text: read_obj + the polyhedron checks a mesh grain gets.
Outcome obj(const std::string& text, std::string* what = nullptr);

}  // namespace crumble::fuzz
