// Every shipped crushable quick scenario (scenarios/*_quick.json with a breakage model, and
// single_grain_pd.json) with every breakage model and fragment builder registered for its
// dimension, on a shortened loading (each file's own settings otherwise): each run must exit
// 0 and keep the mass budget, initial (+ fed) = final + removed (+ product) within 1e-9
// relative. A geometry failure inside one analysis must not stop a run (core/Simulation:
// the grain stays intact and summary.json counts it in analyses_failed).
// ctest -L crushable_matrix; each run prints
//   matrix | scenario | model | builder | steps | analyses | failed | events | mass error
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support/CliRunner.h"
#include "tests/support/Registered.h"

namespace fs = std::filesystem;
using namespace crumble::testing_support;

namespace {

struct Scenario {
  std::string file;
  int dimension;
  std::string shorten;  // --set arguments that cut the loading short
};

// The loading of each file cut short, every run stopped at its third breakage event (the
// single grain at its first): a few seconds of one core per run.
const std::vector<Scenario>& scenarios() {
  const std::string stop = "--set simulation.stop_after_breakage_events=3 ";
  static const std::vector<Scenario> s = {
      // 40 of the 100 grains, the fast fidelity preset, the ramp's first 3 MPa at its rate.
      {"oedometer_zhu_zhao_quick.json", 3,
       stop + "--set packing.count=40 --set fidelity=fast --set loading.max_stress=3e6 --set loading.ramp_time=0.015"
              " --set simulation.max_steps=100"},
      {"plate_12_spheres_quick.json", 3, stop + "--set simulation.max_steps=30"},
      {"oedometer_lsdem_3d_quick.json", 3, stop + "--set loading.stop_strain=0.02"},
      // One grain between plates: stopped at its first split, as the file's crushing force
      // is (its pieces left under the ramp are pushed through the platen by Bullet).
      {"single_grain_pd.json", 3, "--set simulation.stop_after_breakage_events=1"},
      {"compression_bpm_2d_quick.json", 2, stop + "--set loading.stop_strain=0.02"},
      {"oedometer_harmon_2d_quick.json", 2, stop + "--set loading.stop_strain=0.02"},
      {"jaw_crusher_2d_quick.json", 2, stop + "--set simulation.max_steps=3000"},
  };
  return s;
}

// Coarser discretisations of the models whose analyses dominate a run (each option is
// ignored, with a note, by a file that sets the discretisation itself).
std::string model_profile(const std::string& model) {
  if (model == "peridynamics") return " --set breakage.spacing_fraction=0.1";
  if (model == "bonded_particles") return " --set breakage.elements_across=6";
  if (model == "block_beam") return " --set breakage.blocks_per_diameter=4 --set breakage.ramp_steps=3000";
  return "";
}

struct Case {
  Scenario scenario;
  std::string model, builder;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const auto& s : scenarios())
    for (const auto& m : registered_models())
      if (m.dimension == s.dimension && m.name != "none")
        for (const auto& b : registered_builders())
          if (b.dimension == s.dimension) out.push_back({s, m.name, b.name});
  return out;
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  const Case& c = info.param;
  return sanitized(c.scenario.file.substr(0, c.scenario.file.find('.')) + "_" + c.model + "_" + c.builder);
}

void PrintTo(const Case& c, std::ostream* os) { *os << c.scenario.file << " " << c.model << " " << c.builder; }

class CrushableMatrix : public ::testing::TestWithParam<Case> {};

TEST_P(CrushableMatrix, RunsAndKeepsTheMassBudget) {
  const Case& c = GetParam();
  const fs::path out = fs::temp_directory_path() / "crumble_crushable_matrix" / case_name({c, 0});
  fs::remove_all(out);
  const std::string args = plugin_args() + " run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/" + c.scenario.file +
                           " --out " + out.string() + " --quiet --threads 1 --set breakage.type=" + c.model +
                           " --set fragments.type=" + c.builder + " " + c.scenario.shorten + model_profile(c.model);
  const CliResult r = run_cli(args);
  ASSERT_EQ(r.status, 0) << args << "\n" << r.output;
  ASSERT_TRUE(fs::exists(out / "summary.json")) << r.output;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  // An open scene (the jaw crusher) also feeds rocks in and discharges product.
  const double m0 = s["mass_initial_kg"].get<double>() + s.value("mass_fed_kg", 0.0);
  const double m1 = s["mass_final_kg"].get<double>() + s.value("product_mass_kg", 0.0), mr = s["mass_removed_kg"];
  const double error = m0 > 0 ? std::abs(m1 + mr - m0) / m0 : std::abs(m1 + mr);
  std::cout << "matrix | " << c.scenario.file << " | " << c.model << " | " << c.builder << " | " << s["steps"]
            << " steps | " << s["analyses"] << " analyses | " << s.value("analyses_failed", -1.0) << " failed | "
            << s["breakage_events"] << " events | mass error " << error << "\n";
  EXPECT_LE(error, 1e-9) << "initial " << m0 << ", final " << m1 << ", removed " << mr;
}

INSTANTIATE_TEST_SUITE_P(Shipped, CrushableMatrix, ::testing::ValuesIn(cases()), case_name);

}  // namespace
