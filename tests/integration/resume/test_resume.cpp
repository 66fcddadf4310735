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
  // A small crushable 2D packing (stress criterion, weak grains, a check every 50 steps,
  // level-set fragments), checkpointed every 500 steps and killed, so analyses at and after
  // the checkpoint step meet the resume.
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json";
  const std::string sets =
      " --quiet --set breakage.type=stress --set breakage.criterion=von_mises --set breakage.strength=3e6"
      " --set schedule.every_steps=50 --set output.checkpoint_every=500";
  // SIGKILL once the first checkpoint exists: the .part files then hold rows past the
  // checkpoint, which the resume must drop, keeping every row up to the checkpoint step.
  const std::string cmd = std::string(CRUMBLE_BINARY) + " run " + scen + " --out " + out.string() + sets;
  const auto first = run_cli("--version >/dev/null; " + cmd + " 2>&1 & p=$!; for i in $(seq 1 1500); do [ -f " +
                             (out / "checkpoint.json").string() + " ] && break; sleep 0.1; done; sleep 0.1; kill -KILL $p");
  ASSERT_TRUE(fs::exists(out / "checkpoint.json")) << first.output;
  ASSERT_FALSE(fs::exists(out / "summary.json")) << "the run ended before it was killed: " << first.output;
  const auto second = run_cli("run " + scen + " --out " + out.string() + sets + " --resume");
  ASSERT_EQ(second.status, 0) << second.output;
  const auto s2 = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s2["resumed_from_step"].get<long>() % 500, 0);
  EXPECT_GT(s2["analyses"].get<long>(), 0);
  EXPECT_GT(s2["breakage_events"].get<long>(), 0);
  EXPECT_EQ(data_rows(slurp(out / "events.csv")), s2["analyses"].get<long>());
}
