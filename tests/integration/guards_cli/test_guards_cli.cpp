// Runs that go physically wrong stop with exit 1 and a message naming the broken invariant
// (never a wrong answer with exit 0). Each case would otherwise end with an impossible void
// ratio; none may leave a summary.json, and
// no row of series.csv(.part) may hold a void ratio <= 0.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

namespace {

std::string scen(const std::string& name) { return std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/" + name; }

fs::path out_dir() {
  const fs::path d = fs::temp_directory_path() / "crumble_guards_test" /
                     ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(d);
  return d;
}

// Every void ratio written to the series (finished or partial) is > 0.
void expect_positive_void_ratios(const fs::path& dir) {
  const fs::path f = fs::exists(dir / "series.csv") ? dir / "series.csv" : dir / "series.csv.part";
  std::stringstream in(slurp(f));
  std::string line;
  std::getline(in, line);  // header; void_ratio is column 6
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    for (int k = 0; k <= 6; ++k) std::getline(ss, cell, ',');
    EXPECT_GT(std::stod(cell), 0.0) << f << ": " << line;
  }
}

void expect_guard_failure(const std::string& args, const std::string& needle) {
  const fs::path out = out_dir();
  const auto r = run_cli("run " + args + " --quiet --out " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("physical guard failed at step"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(needle), std::string::npos) << "expected '" << needle << "' in\n" << r.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  expect_positive_void_ratios(out);
}

}  // namespace

TEST(GuardsCli, BulletTimeStepTooLargeStops) {
  // Was: void_ratio_final -2.05 with exit 0.
  expect_guard_failure(scen("oedometer_rigid_quick.json") + " --set packing.count=30 --set time_step=2e-4",
                       "time_step");
}

TEST(GuardsCli, BulletStressBeyondWhatTheContactsCarryStops) {
  // Was: e -0.20 with exit 0.
  expect_guard_failure(scen("oedometer_rigid_quick.json") +
                           " --set packing.count=30 --set loading.max_stress=1e9 --set container.lx=6e-3"
                           " --set container.ly=6e-3 --set engine.solver_iterations=200",
                       "loading.max_stress");
}

TEST(GuardsCli, LsdemPlatenThroughTheFloorStops2D) {
  // Was: e -2.42 with the platen 11 mm below the floor, exit 0.
  expect_guard_failure(scen("oedometer_rigid_2d_quick.json") + " --set loading.max_stress=1e9", "engine.kn");
}

TEST(GuardsCli, GrainBelowTheScreeningSizeIsNotCrushedThrough) {
  // Was: strain 97 %, e -0.58, exit 0 (the 0.2 mm grain is never analysed).
  expect_guard_failure(scen("single_grain_pd.json") + " --set scene.diameter=0.2e-3", "wall");
}

TEST(GuardsCli, HealthyRunReportsItsMargins) {
  const fs::path out = out_dir();
  const auto r = run_cli("run " + scen("oedometer_rigid_2d_quick.json") + " --quiet --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string s = slurp(out / "summary.json");
  EXPECT_NE(s.find("guard_max_overlap_fraction"), std::string::npos);
  EXPECT_NE(s.find("guard_max_energy_ratio"), std::string::npos);
  expect_positive_void_ratios(out);
}

TEST(GuardsCli, InterruptedSettlingIsCheckpointedAndResumed) {
  // SIGTERM while the packing settles: no packing.json of an unsettled packing, an exit
  // status that is not 0, and a checkpoint of the settling that --resume settles on from
  // (interrupted again here: the settling's tolerance is never met).
  const fs::path out = out_dir();
  const std::string sets = " --set packing.count=30 --set container.lx=6e-3 --set container.ly=6e-3"
                           " --set packing.settle.tolerance=1e-12 --set packing.settle.max_time=100"
                           " --set output.checkpoint_every=10 --set engine.solver_iterations=50";
  const std::string run = "--version >/dev/null; timeout -s TERM 3 " + std::string(CRUMBLE_BINARY) + " run " +
                          scen("oedometer_rigid_quick.json") + sets + " --quiet --out " + out.string();
  const auto r = run_cli(run + " 2>&1; echo status=$?");
  EXPECT_NE(r.output.find("interrupted while the packing settled"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("continue the settling with --resume"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("status=0"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "packing.json"));
  ASSERT_TRUE(fs::exists(out / "checkpoint.json"));
  const auto first = nlohmann::json::parse(slurp(out / "checkpoint.json"));
  ASSERT_TRUE(first.contains("settling")) << "not a checkpoint of the settling";
  const long at = first["settling"]["steps"].get<long>();
  EXPECT_GT(at, 0);
  const auto again = run_cli(run + " --resume 2>&1; echo status=$?");
  EXPECT_NE(again.output.find("interrupted while the packing settled"), std::string::npos) << again.output;
  const auto second = nlohmann::json::parse(slurp(out / "checkpoint.json"));
  ASSERT_TRUE(second.contains("settling"));
  EXPECT_GT(second["settling"]["steps"].get<long>(), at) << "the resumed settling did not go on from its checkpoint";
}

TEST(GuardsCli, InterruptedSettlingWithoutCheckpointsLeavesNothingToResume) {
  // Checkpoints off: SIGTERM while the packing settles leaves neither packing.json nor a
  // checkpoint, and --resume refuses, saying the run writes none.
  const fs::path out = out_dir();
  const std::string sets = " --set packing.count=30 --set container.lx=6e-3 --set container.ly=6e-3"
                           " --set packing.settle.tolerance=1e-12 --set packing.settle.max_time=100"
                           " --set output.checkpoint_every=0 --set output.checkpoint_every_s=0"
                           " --set engine.solver_iterations=50";
  const auto r = run_cli("--version >/dev/null; timeout -s TERM 2 " + std::string(CRUMBLE_BINARY) + " run " +
                         scen("oedometer_rigid_quick.json") + sets + " --quiet --out " + out.string() + " 2>&1; echo status=$?");
  EXPECT_NE(r.output.find("interrupted while the packing settled"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("status=0"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "packing.json"));
  EXPECT_FALSE(fs::exists(out / "checkpoint.json"));
  const auto again = run_cli("run " + scen("oedometer_rigid_quick.json") + sets + " --quiet --resume --out " + out.string());
  EXPECT_EQ(again.status, 2) << again.output;
  EXPECT_NE(again.output.find("the run writes none"), std::string::npos) << again.output;
}
