// `crumble stages DIR`: reads a run's stages.csv (output/StagesWriter.h) back, fits the cost per
// stage against the grain count and the grain count against the level (power laws,
// core/Measures.h fit_power_law) and extrapolates the wall time to a target level.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace crumble {

// The table of DIR/stages.csv with the fits and the extrapolation to `target` in the table's
// unit (MPa or percent of strain; NaN: 30 MPa, Zhu & Zhao 2019 §5, or 15 %, Harmon et al. 2020
// §5), as JSON; `markdown` gets the same as a Markdown table and text. Throws InputError when
// the file is missing or malformed (naming the file, line and column).
nlohmann::json stage_report(const std::string& dir, double target, std::string* markdown = nullptr);

}  // namespace crumble
