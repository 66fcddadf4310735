// Resume keeps its promise: every analysis of the run is one row of events.csv, also across
// an interruption (rows matched by step, not by a printed time), and a resumed run reports
// the settling of the run it continues.
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

long data_rows(const std::string& csv) {
  std::stringstream in(csv);
  std::string line;
  long n = -1;  // header
  while (std::getline(in, line))
    if (!line.empty()) ++n;
  return n;
}

}  // namespace

TEST(Resume, EventsRowsMatchAnalysesAcrossAnInterruption) {
  const fs::path out = fs::temp_directory_path() / "crumble_resume_test" / "events";
  fs::remove_all(out);
  // A small crushable packing whose grains are analysed often (stress criterion, weak
  // grains, a check every 5 steps), checkpointed every 20 steps and stopped at step 50, so
  // analyses at the checkpoint step itself must survive the resume.
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json";
  const std::string sets =
      " --quiet --set packing.count=30 --set container.lx=6e-3 --set container.ly=6e-3"
      " --set engine.solver_iterations=100 --set loading.max_stress=2e6 --set loading.ramp_time=0.02"
      " --set breakage.type=stress --set breakage.criterion=von_mises --set breakage.strength=3e6"
      " --set simulation.fines_diameter=0.7e-3"
      " --set schedule.every_steps=5 --set output.checkpoint_every=20";
  const auto first = run_cli("run " + scen + " --out " + out.string() + sets + " --set simulation.max_steps=50");
  ASSERT_EQ(first.status, 0) << first.output;
  const auto s1 = nlohmann::json::parse(slurp(out / "summary.json"));
  ASSERT_GT(s1["analyses"].get<long>(), 0) << "the test needs analyses before the checkpoint";
  const auto second = run_cli("run " + scen + " --out " + out.string() + sets + " --set simulation.max_steps=90 --resume");
  ASSERT_EQ(second.status, 0) << second.output;
  const auto s2 = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s2["resumed_from_step"], 40);
  EXPECT_EQ(s2["steps"], 90);
  EXPECT_EQ(data_rows(slurp(out / "events.csv")), s2["analyses"].get<long>());
  EXPECT_EQ(s2["packing_settle_steps"], s1["packing_settle_steps"]);
}
