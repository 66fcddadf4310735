// `crumble bench WHAT`: engine (the adapter against the raw library, --engine), lsdem,
// pd-kernel, pd-analysis. One JSON object per benchmark.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace crumble {

nlohmann::json run_benchmark(const std::string& what, long steps, int threads, const std::string& scenario,
                             const std::string& engine = "", long settle_steps = -1);

}  // namespace crumble
