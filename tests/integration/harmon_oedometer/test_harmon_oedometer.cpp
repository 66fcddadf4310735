// Harmon et al. 2020 §5 end to end through the CLI: the quick 2D oedometer (lsdem + stress +
// level_set, a pool of generated outlines), reduced to a few seconds: grains break, the mass
// budget is exact, shape.csv and the PSD tables at strain levels are written, and the run is
// the same with one or two threads.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "crumble_config.h"
#include "output/Writers.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::read_csv;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

namespace {

// 12 grains in a 4.2 mm cell (the quick scenario's grains per width), 12000 steps of loading
// (≈ 1 % axial strain, well past the first breakage at Table 2 strengths).
const char* kReduce =
    " --quiet --set packing.count=12 --set container.lx=4.2e-3 --set simulation.max_steps=12000"
    " --set packing.settle.window=0.0005 --set packing.settle.max_time=0.012"
    " --set output.psd_at_strain=[0.001,0.003,0.5] --set output.vtk_final=true";

Json run_quick(const fs::path& out, const std::string& extra) {
  fs::remove_all(out);
  const std::string args = std::string("run ") + CRUMBLE_SOURCE_DIR + "/scenarios/oedometer_harmon_2d_quick.json --out " +
                           out.string() + kReduce + extra;
  const auto r = run_cli(args);
  EXPECT_EQ(r.status, 0) << args << "\n" << r.output;
  return Json::parse(slurp(out / "summary.json"));
}

}  // namespace

TEST(HarmonOedometer, QuickRunBreaksGrainsKeepsMassAndWritesShapeAndStrainPsd) {
  const fs::path out = fs::temp_directory_path() / "crumble_harmon_quick";
  const Json s = run_quick(out, " --threads 1");
  EXPECT_GT(s["breakage_events"].get<long>(), 0) << s.dump(2);
  EXPECT_GT(s["grains_final"].get<long>(), 12);
  // Children + removed pieces = parent, exactly (the loop checks 1e-9 per event).
  const double m0 = s["mass_initial_kg"], m1 = s["mass_final_kg"], mr = s["mass_removed_kg"];
  EXPECT_NEAR(m1 + mr, m0, 1e-12 * m0);
  // Frictionless settling (settle.friction_scale 0) gives a dense 2D packing (0.33 here,
  // three grains across a narrow cell; 0.24 in the quick scenario, 0.22 in the full one).
  EXPECT_LT(s["void_ratio_initial"].get<double>(), 0.36);

  // shape.csv: a row at the start of loading and one per sample, means in (0, 1].
  const auto shape = read_csv((out / "shape.csv").string());
  ASSERT_GE(shape.size(), 3u);
  EXPECT_EQ(shape[0][5], "mean_circularity");
  EXPECT_EQ(shape[0][6], "mean_aspect_ratio");
  EXPECT_EQ(shape[1][2], "0");  // axial strain of the first row
  for (std::size_t i = 1; i < shape.size(); ++i)
    for (int k : {5, 6}) {
      const double v = std::stod(shape[i][k]);
      EXPECT_GT(v, 0.5) << i;
      EXPECT_LE(v, 1.0) << i;
    }
  // The pool's grains: the mean circularity the docs quote for the 25 outlines, within what
  // a 12-grain draw scatters.
  EXPECT_NEAR(std::stod(shape[1][5]), 0.927, 0.03);
  EXPECT_TRUE(s.contains("mean_circularity_final"));

  // psd.csv: tables at 0.1 % and 0.3 % strain, one never reached, and the final one.
  const std::string psd = slurp(out / "psd.csv");
  EXPECT_NE(psd.find("\nstrain_0.001,"), std::string::npos) << psd.substr(0, 400);
  EXPECT_NE(psd.find("\nstrain_0.003,"), std::string::npos);
  EXPECT_NE(psd.find("\nstrain_0.5_not_reached_final_at_"), std::string::npos);
  EXPECT_NE(psd.find("\nfinal,"), std::string::npos);
  const auto rows = read_csv((out / "psd.csv").string());
  ASSERT_GT(rows.size(), 1u);
  ASSERT_GE(rows[0].size(), 6u);
  EXPECT_EQ(rows[0][4], "axial_strain");
  EXPECT_EQ(rows[0][5], "step");
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (rows[i][0] == "strain_0.001") EXPECT_GE(std::stod(rows[i][4]), 0.001);

  // The VTK snapshot carries the descriptors per grain.
  bool found = false;
  for (const auto& e : fs::directory_iterator(out / "vtk")) {
    const std::string v = slurp(e.path());
    found = found || (v.find("Name=\"circularity\"") != std::string::npos &&
                      v.find("Name=\"sieve_size\"") != std::string::npos);
  }
  EXPECT_TRUE(found);

  // Regression of the physics on one core against two: results do not depend on threads.
  const Json s2 = run_quick(fs::temp_directory_path() / "crumble_harmon_quick_t2", " --threads 2");
  for (const char* k : {"breakage_events", "grains_final", "mass_final_kg", "void_ratio_final", "max_platen_stress_Pa"})
    EXPECT_EQ(s[k], s2[k]) << k;
}

// Table 2's global damping acts in the loading only: the files scale it by 0 while settling.
// An engine without global damping refuses a scale, naming the option, before anything runs.
TEST(HarmonOedometer, GlobalDampingScaleIsCheckedUpFront) {
  const auto ok = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR + "/scenarios/oedometer_harmon_2d_quick.json");
  EXPECT_EQ(ok.status, 0) << ok.output;
#if CRUMBLE_WITH_BULLET
  const auto bad = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR +
                           "/scenarios/oedometer_rigid_quick.json --set packing.settle.global_damping_scale=0");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("/packing/settle/global_damping_scale"), std::string::npos) << bad.output;
#endif
  const auto range = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR +
                             "/scenarios/oedometer_harmon_2d_quick.json --set packing.settle.global_damping_scale=2");
  EXPECT_EQ(range.status, 2) << range.output;
  EXPECT_NE(range.output.find("/packing/settle/global_damping_scale"), std::string::npos) << range.output;
}

TEST(HarmonOedometer, FrictionScaleIsCheckedUpFront) {
#if CRUMBLE_WITH_BULLET
  // Bullet scales friction while settling too (Zhu & Zhao packing densified that way).
  const auto v = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR +
                         "/scenarios/oedometer_rigid_quick.json --set packing.settle.friction_scale=0");
  EXPECT_EQ(v.status, 0) << v.output;
#endif
  const auto bad = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR +
                           "/scenarios/oedometer_harmon_2d_quick.json --set packing.settle.friction_scale=2");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("/packing/settle/friction_scale"), std::string::npos) << bad.output;
  const auto strain = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR +
                              "/scenarios/oedometer_harmon_2d_quick.json --set output.psd_at_strain=[0.05,1.5]");
  EXPECT_EQ(strain.status, 2) << strain.output;
  EXPECT_NE(strain.output.find("/output/psd_at_strain/1"), std::string::npos) << strain.output;
}

namespace {

// Mass removed as fines over the initial mass of the reduced quick run (12 grains) to 5 %
// axial strain, with `extra` settings.
double removed_fraction(const fs::path& out, const std::string& extra, Json* summary = nullptr) {
  fs::remove_all(out);
  const std::string args = std::string("run ") + CRUMBLE_SOURCE_DIR + "/scenarios/oedometer_harmon_2d_quick.json --out " +
                           out.string() +
                           " --quiet --threads 1 --set packing.count=12 --set container.lx=4.2e-3"
                           " --set packing.settle.window=0.0005 --set packing.settle.max_time=0.012"
                           " --set loading.stop_strain=0.05" + extra;
  const auto r = run_cli(args);
  EXPECT_EQ(r.status, 0) << args << "\n" << r.output;
  const Json s = Json::parse(slurp(out / "summary.json"));
  if (summary) *summary = s;
  const double m0 = s["mass_initial_kg"], m1 = s["mass_final_kg"], mr = s["mass_removed_kg"];
  EXPECT_NEAR(m1 + mr, m0, 1e-9 * m0);
  return mr / m0;
}

}  // namespace

// Harmon et al. 2020 §3.4: "the total mass of the filtered particles was < 1 % of the total
// mass of the specimen". The quick file's fragments.fines_policy halt and
// breakage.min_piece_diameter (first method: breakage halted short of pieces the run would
// remove) and fragments.absorb_cells (unresolved slivers stay with their child) keep it so;
// with the builder's defaults (fines removed) the same run removes more than 2 %.
TEST(HarmonOedometer, QuickFileRemovesLessThanOnePercentOfTheMass) {
  Json s;
  const double kept = removed_fraction(fs::temp_directory_path() / "crumble_harmon_fines", "", &s);
  EXPECT_GT(s["breakage_events"].get<long>(), 20) << s.dump(2);
  EXPECT_LT(kept, 0.01) << s.dump(2);
  const double before = removed_fraction(fs::temp_directory_path() / "crumble_harmon_fines_off",
                                         " --set breakage.min_piece_diameter=0 --set fragments.absorb_cells=0"
                                         " --set fragments.fines_policy=remove");
  EXPECT_GT(before, 0.02) << "the reduced run no longer breaks grains down to the fines: the test cannot fail";
}

// The same bound with the other two criteria of Harmon et al. 2020 (eqs. 7–10), each at its
// Table 2 strength (the von Mises case is the test above).
TEST(HarmonOedometer, QuickFileRemovesLessThanOnePercentWithEachCriterion) {
  for (const std::string c : {"max_principal", "tresca"}) {
    Json s;
    const double removed =
        removed_fraction(fs::temp_directory_path() / ("crumble_harmon_fines_" + c), " --set breakage.criterion=" + c, &s);
    EXPECT_GT(s["breakage_events"].get<long>(), 20) << c << "\n" << s.dump(2);
    EXPECT_LT(removed, 0.01) << c << "\n" << s.dump(2);
  }
}
