// The cross product (any engine × any breakage model × any
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
//
// Each run also checks that it built only what its scene needs (summary.json
// `representations_built`, base/BuildCounters.h): no level set on a Bullet/ODE run unless
// the level_set builder cuts a broken grain, no alpha shape or mesh clip on an lsdem run unless
// the alpha_shape builder is chosen, and a peridynamics lattice only for a grain that passed
// screening (never more lattices than analyses).
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
      // DA-BPM bonds of 1 MPa instead of 30 MPa (a 1.5 mm disc then crushes at ≈ 2.4 kN/m),
      // 8 elements across.
      {"bonded_particles", " --set breakage.normal_strength=1e6 --set breakage.shear_strength=1e6"
                           " --set breakage.elements_across=8"},
      // Liu et al. 2019 block–beam with its default 3 MPa tensile strength breaks a 2 mm
      // grain at a few newtons; coarser blocks and a shorter ramp keep each analysis short.
      {"block_beam", " --set breakage.blocks_per_diameter=4 --set breakage.ramp_steps=3000"},
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

// The representations a run of `t` may build, against what summary.json says it built.
void expect_only_needed_representations(const Triple& t, const nlohmann::json& s) {
  ASSERT_TRUE(s.contains("representations_built") && s["representations_built"].is_object()) << s.dump(1);
  const auto& b = s["representations_built"];
  auto built = [&](const char* kind) {
    EXPECT_TRUE(b.contains(kind) && b[kind].is_number_integer()) << kind << " missing in " << b.dump();
    return b.value(kind, -1L);
  };
  const long analyses = s["analyses"].get<long>();
  const std::string what = t.engine + " + " + t.model + " + " + t.builder + ": " + b.dump();
  // A lattice per analysed grain at most; none for a grain that never passed screening.
  EXPECT_LE(built("pd_lattices"), t.model == "peridynamics" ? analyses : 0L) << what;
  EXPECT_GE(built("pd_lattices"), 0) << what;
  // Rigid-body engines collide hulls/spheres: a level set only for a grain the level_set
  // builder cuts (its children carry their own grids).
  const bool rigid_engine = t.engine == "bullet" || t.engine == "ode";
  if (rigid_engine) {
    EXPECT_LE(built("level_set_grids"), t.builder == "level_set" ? analyses : 0L) << what;
  }
  // Alpha shapes and mesh clipping belong to the alpha_shape builder, and to broken grains.
  if (t.builder != "alpha_shape") {
    EXPECT_EQ(built("alpha_shapes"), 0) << what;
    EXPECT_EQ(built("meshes_clipped"), 0) << what;
  }
  if (t.builder != "level_set") {
    EXPECT_EQ(built("level_set_splits"), 0) << what;
  }
  if (analyses == 0) {
    EXPECT_EQ(built("alpha_shapes") + built("meshes_clipped") + built("level_set_splits"), 0) << what;
  }
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
  expect_only_needed_representations(t, s);
  if (model_is_active(t.model, t.dimension)) {
    EXPECT_GT(events, 0) << "an active model breaks no grain of the crushable packing\n" << r.output;
    EXPECT_GT(s["grains_final"].get<long>() + (mr > 0 ? 1 : 0), s["grains_initial"].get<long>());
  } else {
    EXPECT_EQ(events, 0);
    EXPECT_EQ(s["grains_final"], s["grains_initial"]);
  }
}

// Zhu & Zhao 2019 §3.1 analyse only grains whose largest contact force passes the screening
// threshold: a grain below it is never discretised. The same tiny packing on Bullet, once as
// the cross product runs it (lattices built, at most one per analysis) and once with a
// threshold no contact reaches (no analysis, no lattice).
TEST(CrossRepresentations, AGrainBelowTheScreeningThresholdIsNeverDiscretised) {
  const std::string scenario = std::string(CRUMBLE_SOURCE_DIR) + "/tests/integration/cross/cross_3d.json";
  auto run = [&](const std::string& tag, const std::string& extra) {
    const fs::path out = fs::temp_directory_path() / "crumble_cross" / tag;
    fs::remove_all(out);
    const std::string args = plugin_args() + " run " + scenario + " --out " + out.string() +
                             " --quiet --threads 1 --set engine.type=bullet --set breakage.type=peridynamics"
                             " --set fragments.type=alpha_shape" +
                             break_profile().at("peridynamics") + extra;
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.status, 0) << args << "\n" << r.output;
    return nlohmann::json::parse(slurp(out / "summary.json"));
  };
  // No stop after the first breakages: the screened run must load as long as the other one.
  const nlohmann::json screened =
      run("screened_out", " --set breakage.threshold_force_ref=1e9 --set simulation.stop_after_breakage_events=0");
  EXPECT_EQ(screened["analyses"].get<long>(), 0) << screened.dump(1);
  EXPECT_EQ(screened["representations_built"]["pd_lattices"].get<long>(), 0) << screened.dump(1);
  EXPECT_GT(screened["max_platen_stress_Pa"].get<double>(), 1e6) << "the packing was not loaded";
  const nlohmann::json analysed = run("analysed", "");
  const long lattices = analysed["representations_built"]["pd_lattices"].get<long>();
  EXPECT_GT(lattices, 0) << analysed.dump(1);
  EXPECT_LE(lattices, analysed["analyses"].get<long>()) << analysed.dump(1);
}

// A shape builds only the representations its engine asks for: an LS-DEM run never builds a convex hull. With no output
// that draws the grains (shape.csv's sphericity and the VTK files need a surface mesh), a 3D
// lsdem run builds one level set per distinct shape and nothing else.
TEST(CrossRepresentations, AnLsdemRunBuildsOnlyLevelSets) {
  const std::string scenario = std::string(CRUMBLE_SOURCE_DIR) + "/tests/integration/cross/cross_3d.json";
  const fs::path out = fs::temp_directory_path() / "crumble_cross" / "lsdem_level_sets_only";
  fs::remove_all(out);
  const std::string args = plugin_args() + " run " + scenario + " --out " + out.string() +
                           " --quiet --threads 1 --set engine.type=lsdem --set breakage.type=none"
                           " --set output.shape_metrics=false --set output.vtk_final=false";
  const CliResult r = run_cli(args);
  ASSERT_EQ(r.status, 0) << args << "\n" << r.output;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  const auto& b = s["representations_built"];
  const long grains = s["grains_initial"].get<long>();
  EXPECT_GE(b["level_set_grids"].get<long>(), 1) << b.dump();
  EXPECT_LE(b["level_set_grids"].get<long>(), grains) << b.dump();
  long others = 0;
  for (auto it = b.begin(); it != b.end(); ++it)
    if (it.key() != "level_set_grids") others += it.value().get<long>();
  EXPECT_EQ(others, 0) << b.dump();
}

INSTANTIATE_TEST_SUITE_P(Registry, Cross, ::testing::ValuesIn(triples()), [](const auto& info) {
  const Triple& t = info.param;
  return sanitized(std::to_string(t.dimension) + "d_" + t.engine + "_" + t.model + "_" + t.builder);
});

}  // namespace
