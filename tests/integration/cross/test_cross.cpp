// The cross product (DESIGN.md "The three seams": any engine × any breakage model × any
// fragment builder must run): every registered engine × model × builder that supports the
// dimension runs one tiny crushable packing through the CLI (cross_3d.json, cross_2d.json).
// Each run must exit 0 with summary.json, break grains when the model can break (the model
// is active), and keep the mass budget: initial = final + removed within 1e-9 relative.
//
// The triples come from the registration tables, filtered by each entry's `dimensions`; a
// new registration, or a plugin named in CRUMBLE_TEST_PLUGINS (tests/support/Registered.h),
// is run without editing this file. Each run prints one row of the table
//   cross | dim | engine | model | builder | events | grains | mass error
// (ctest -L cross -V, or the test binary itself).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scenarios/Registry.h"
#include "tests/support/CliRunner.h"
#include "tests/support/Registered.h"

namespace fs = std::filesystem;
using namespace crumble;
using namespace crumble::testing_support;

namespace {

struct Triple {
  std::string engine, model, builder;
  int dimension = 3;
};

std::vector<Triple> triples() {
  std::vector<Triple> out;
  for (int dim : {3, 2})
    for (const auto& e : registered_engines())
      if (e.dimension == dim)
        for (const auto& m : registered_models())
          if (m.dimension == dim)
            for (const auto& b : registered_builders())
              if (b.dimension == dim) out.push_back({e.name, m.name, b.name, dim});
  return out;
}

// How each model is made to break in the tiny packing within a few milliseconds of loading:
// a strength well below what the full-size scenarios use. A model without an entry (e.g. a
// plugin) runs with its defaults and must still break if it is active.
const std::map<std::string, std::string>& break_profile() {
  static const std::map<std::string, std::string> p = {
      // Zhu & Zhao 2019 eq. 16 makes the crushing force ∝ √G_c: G_c 3 J/m² crushes a 2 mm
      // grain at ≈ 57 N instead of 180 N; a coarse lattice (≈ 500 points) keeps it fast.
      {"peridynamics", " --set breakage.gc0=3 --set breakage.weibull=false --set breakage.spacing_fraction=0.1"},
      // Harmon et al. 2020 Table 2's 35 MPa (von Mises) lowered to 5 MPa.
      {"stress", " --set breakage.strength=5e6"},
  };
  return p;
}

bool model_is_active(const std::string& name, int dim) {
  nlohmann::json doc = {{"type", name}};
  Config cfg(doc);
  EngineContext ctx;
  ctx.dimension = dim;
  return breakage_models().find(name, "/breakage/type").make(cfg, ctx)->active();
}

class Cross : public ::testing::TestWithParam<Triple> {};

TEST_P(Cross, RunsBreaksAndKeepsTheMassBudget) {
  const Triple& t = GetParam();
  const std::string tag = std::to_string(t.dimension) + "d_" + t.engine + "_" + t.model + "_" + t.builder;
  const fs::path out = fs::temp_directory_path() / "crumble_cross" / sanitized(tag);
  fs::remove_all(out);
  const std::string scenario = std::string(CRUMBLE_SOURCE_DIR) + "/tests/integration/cross/cross_" +
                               std::to_string(t.dimension) + "d.json";
  const auto prof = break_profile().find(t.model);
  const std::string args = plugin_args() + " run " + scenario + " --out " + out.string() +
                           " --quiet --threads 1 --set engine.type=" + t.engine + " --set breakage.type=" + t.model +
                           " --set fragments.type=" + t.builder + (prof == break_profile().end() ? "" : prof->second);
  const CliResult r = run_cli(args);
  ASSERT_EQ(r.status, 0) << args << "\n" << r.output;
  ASSERT_TRUE(fs::exists(out / "summary.json")) << r.output;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["engine"], t.engine);
  EXPECT_EQ(s["breakage"], t.model);
  const long events = s["breakage_events"].get<long>();
  const double m0 = s["mass_initial_kg"], m1 = s["mass_final_kg"], mr = s["mass_removed_kg"];
  const double error = std::abs(m1 + mr - m0) / m0;
  std::cout << "cross | " << t.dimension << "D | " << t.engine << " | " << t.model << " | " << t.builder << " | "
            << events << " events | " << s["grains_initial"] << " -> " << s["grains_final"] << " grains | mass error "
            << error << "\n";
  EXPECT_GT(m0, 0);
  EXPECT_LE(error, 1e-9) << "initial " << m0 << ", final " << m1 << ", removed " << mr;
  if (model_is_active(t.model, t.dimension)) {
    EXPECT_GT(events, 0) << "an active model breaks no grain of the crushable packing\n" << r.output;
    EXPECT_GT(s["grains_final"].get<long>() + (mr > 0 ? 1 : 0), s["grains_initial"].get<long>());
  } else {
    EXPECT_EQ(events, 0);
    EXPECT_EQ(s["grains_final"], s["grains_initial"]);
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, Cross, ::testing::ValuesIn(triples()), [](const auto& info) {
  const Triple& t = info.param;
  return sanitized(std::to_string(t.dimension) + "d_" + t.engine + "_" + t.model + "_" + t.builder);
});

}  // namespace
