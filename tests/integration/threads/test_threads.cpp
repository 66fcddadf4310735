// Threads change the time of a run, never its results. A breakage check that selects one
// grain gives that grain's analysis every thread of the run (events.csv `threads`); the
// peridynamic passes add in the same order on any thread count, so the events are the same.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "output/Writers.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using crumble::testing_support::column;
using crumble::testing_support::run_cli;


// Zhu & Zhao 2019 §4.2: the 2 mm grain between two plates, checked every 0.5 MPa until it
// splits (a few analyses, each the only one of its check).
TEST(Threads, AOneGrainCheckRunsOnEveryThreadWithTheSameEvents) {
  const fs::path dir = fs::temp_directory_path() / "crumble_threads_test";
  fs::remove_all(dir);
  std::vector<std::vector<std::vector<std::string>>> events;
  for (int threads : {1, 2}) {
    const fs::path out = dir / ("t" + std::to_string(threads));
    const auto r = run_cli("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/single_grain_pd.json --quiet --out " +
                           out.string() + " --threads " + std::to_string(threads) +
                           " --set schedule.every_stress=0.5e6 --set output.plots=false --set output.vtk_final=false");
    ASSERT_EQ(r.status, 0) << r.output;
    events.push_back(crumble::read_csv((out / "events.csv").string()));
  }
  const auto& a = events[0];
  const auto& b = events[1];
  ASSERT_GE(a.size(), 3u);  // header and at least two analyses
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a[0], b[0]);
  const std::size_t wall = column(a, "wall_ms"), threads = column(a, "threads"), outcome = column(a, "outcome");
  EXPECT_EQ(a.back()[outcome], "split");
  for (std::size_t i = 1; i < a.size(); ++i) {
    EXPECT_EQ(a[i][threads], "1") << "row " << i;
    EXPECT_EQ(b[i][threads], "2") << "row " << i;
    for (std::size_t k = 0; k < a[i].size(); ++k) {
      if (k != wall && k != threads) {
        EXPECT_EQ(a[i][k], b[i][k]) << a[0][k] << " of row " << i;
      }
    }
  }
}
