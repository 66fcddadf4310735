// Breakage analyses over MPI ranks (parallel/MpiAnalyses.h): `mpirun -np 2 crumble run` gives
// the same results as the 1-thread run of the same scenario and seed, bit for bit (wall
// times aside), and a rank-0 error ends every rank. Needs a build with -DCRUMBLE_MPI=ON;
// in the default build every test here is skipped (GTEST_SKIP) and says so.
#include <sys/wait.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support/CliRunner.h"

namespace {

using crumble::testing_support::scenario_file;
using crumble::testing_support::slurp;
using Json = nlohmann::json;
namespace fs = std::filesystem;

// A small Zhu & Zhao oedometer (30 spheres, coarse peridynamic lattice, low G_c): 60 analyses
// and 47 breakage events to 6 MPa, so rank 1 analyses spheres and fragments (alpha-shape
// polyhedra) alike. The contacts' rolling couples count in the moment balance
// (screening.moment_couples): with Zhu & Zhao's default the filter lets through 19 analyses
// here since concave fragments collide as convex pieces, too few to share. About 15 s on one core.
const char* kScenario = R"({
  "name": "mpi_small_oedometer",
  "dimension": 3,
  "seed": 3,
  "materials": [{"density": 2650, "young": 1e11, "poisson": 0.15, "friction": 0.5, "wall_friction": 0.0,
                 "rolling_friction": 0.05, "restitution": 0.0}],
  "engine": {"type": "bullet", "mass_scale": 70, "solver_iterations": 1000, "kn": 5e6},
  "breakage": {"type": "peridynamics", "gc0": 10, "d0": 0.002, "spacing_fraction": 0.12, "min_points": 50},
  "container": {"lx": 0.006, "ly": 0.006},
  "packing": {"type": "cloud", "count": 30, "psd": [[0.0014, 0.0], [0.002, 1.0]], "shape": {"type": "sphere"},
              "settle": {"stress": 10000.0}},
  "loading": {"mode": "stress_ramp", "max_stress": 6e6, "ramp_time": 0.03},
  "time_step": 8e-5,
  "fragments": {"type": "alpha_shape"},
  "schedule": {"every_stress": 2e5},
  "screening": {"min_diameter": 0.0003, "force_threshold": true, "max_unbalanced_force_ratio": 0.02,
                "max_unbalanced_moment_ratio": 0.2, "moment_couples": true},
  "output": {"plots": false, "vtk_final": false, "psd_at_stress": [3e6]}
})";

struct Result {
  int status;
  std::string output;
};

Result shell(const std::string& cmd) {
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  std::string out;
  char buf[4096];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  const int st = p ? pclose(p) : -1;
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

// Two ranks on this machine whatever its core count; as root mpirun needs the two
// OMPI_ALLOW_* variables. `timeout`: a rank left waiting must fail the test, not hang it.
std::string mpirun(int ranks) {
  return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 timeout 300 " + std::string(CRUMBLE_MPIEXEC) +
         " --oversubscribe -np " + std::to_string(ranks) + " " + CRUMBLE_BINARY;
}

// events.csv without its wall-time column.
std::string events_without_wall(const fs::path& f) {
  std::istringstream in(slurp(f));
  std::string line, out;
  int wall = -1;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ls(line);
    for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
    if (wall < 0)
      for (std::size_t i = 0; i < cells.size(); ++i)
        if (cells[i] == "wall_ms") wall = static_cast<int>(i);
    for (std::size_t i = 0; i < cells.size(); ++i)
      if (static_cast<int>(i) != wall) out += cells[i] + ",";
    out += "\n";
  }
  EXPECT_GE(wall, 0) << "events.csv has no wall_ms column";
  return out;
}

#define SKIP_WITHOUT_MPI() \
  if (std::string(CRUMBLE_MPIEXEC).empty()) GTEST_SKIP() << "crumble is built without MPI (configure with -DCRUMBLE_MPI=ON)"

TEST(Mpi, TwoRanksGiveTheOneThreadResults) {
  SKIP_WITHOUT_MPI();
  const std::string file = scenario_file("mpi", "small.json", kScenario);
  const fs::path dir = fs::path(file).parent_path();
  const fs::path a = dir / "threads1", b = dir / "ranks2";
  fs::remove_all(a);
  fs::remove_all(b);
  const Result ra = shell(std::string(CRUMBLE_BINARY) + " run " + file + " --out " + a.string() + " --threads 1 --quiet");
  ASSERT_EQ(ra.status, 0) << ra.output;
  const Result rb = shell(mpirun(2) + " run " + file + " --out " + b.string() + " --threads 1 --quiet");
  ASSERT_EQ(rb.status, 0) << rb.output;

  Json sa = Json::parse(slurp(a / "summary.json")), sb = Json::parse(slurp(b / "summary.json"));
  EXPECT_FALSE(sa.contains("analysis_ranks"));
  EXPECT_EQ(sb.value("analysis_ranks", 0), 2);
  // The run must have something to compare: analyses and breakage events.
  EXPECT_GE(sa.value("analyses", 0), 20);
  EXPECT_GE(sa.value("breakage_events", 0), 5);
  // Rank 1 ran analyses: the lattices it built are not counted by rank 0.
  EXPECT_LT(sb["representations_built"].value("pd_lattices", 0), sa["representations_built"].value("pd_lattices", 0));
  // Both ranks ran analyses, and every analysis ran once.
  ASSERT_EQ(sb["analyses_per_rank"].size(), 2u);
  EXPECT_GE(sb["analyses_per_rank"][0].get<long>(), 1);
  EXPECT_GE(sb["analyses_per_rank"][1].get<long>(), 1);
  EXPECT_EQ(sb["analyses_per_rank"][0].get<long>() + sb["analyses_per_rank"][1].get<long>(), sa.value("analyses", 0L));
  for (const char* k : {"wall_seconds", "time_breakdown_s", "representations_built", "analysis_ranks",
                        "analyses_per_rank", "analysis_seconds_per_rank"}) {
    sa.erase(k);
    sb.erase(k);
  }
  EXPECT_EQ(sa.dump(), sb.dump());
  EXPECT_EQ(events_without_wall(a / "events.csv"), events_without_wall(b / "events.csv"));
  // Time series, PSD tables and the final grains (shapes, poses, strength values) bit for bit.
  for (const char* f : {"series.csv", "psd.csv", "checkpoint.json"}) {
    ASSERT_TRUE(fs::exists(a / f)) << f;
    EXPECT_TRUE(slurp(a / f) == slurp(b / f)) << f << " differs between the 1-thread and the 2-rank run";
  }
}

// The other method: Harmon et al. 2020's 2D oedometer (LS-DEM, average-stress criterion, planar
// level-set splitting), so cutting planes travel back and level-set grids travel out.
TEST(Mpi, TwoRanksGiveTheOneThreadResultsForTheStressCriterionIn2D) {
  SKIP_WITHOUT_MPI();
  const std::string file = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_harmon_2d_quick.json";
  const fs::path dir = fs::path(scenario_file("mpi", "unused", "")).parent_path();
  const fs::path a = dir / "threads1", b = dir / "ranks2";
  fs::remove_all(a);
  fs::remove_all(b);
  const std::string args = " --threads 1 --quiet --set output.plots=false --set simulation.max_steps=6000";
  const Result ra = shell(std::string(CRUMBLE_BINARY) + " run " + file + " --out " + a.string() + args);
  ASSERT_EQ(ra.status, 0) << ra.output;
  const Result rb = shell(mpirun(2) + " run " + file + " --out " + b.string() + args);
  ASSERT_EQ(rb.status, 0) << rb.output;
  const Json sa = Json::parse(slurp(a / "summary.json")), sb = Json::parse(slurp(b / "summary.json"));
  EXPECT_GE(sa.value("breakage_events", 0), 1);
  ASSERT_EQ(sb["analyses_per_rank"].size(), 2u);
  EXPECT_GE(sb["analyses_per_rank"][1].get<long>(), 1);
  EXPECT_EQ(sa.value("breakage_events", -1), sb.value("breakage_events", -2));
  EXPECT_EQ(events_without_wall(a / "events.csv"), events_without_wall(b / "events.csv"));
  for (const char* f : {"series.csv", "checkpoint.json"})
    EXPECT_TRUE(slurp(a / f) == slurp(b / f)) << f << " differs between the 1-thread and the 2-rank run";
}

TEST(Mpi, BadInputOnRankZeroEndsEveryRank) {
  SKIP_WITHOUT_MPI();
  const std::string file = scenario_file("mpi", "small.json", kScenario);
  const fs::path out = fs::path(file).parent_path() / "bad";
  fs::remove_all(out);
  const Result r = shell(mpirun(2) + " run " + file + " --out " + out.string() + " --set breakage.gc0=-1 --quiet");
  EXPECT_EQ(r.status, 2) << r.output;  // not 124 (timeout): the worker was told to stop
  EXPECT_NE(r.output.find("/breakage/gc0"), std::string::npos) << r.output;
}

TEST(Mpi, VersionSaysHowManyRanks) {
  SKIP_WITHOUT_MPI();
  const Result r = shell(mpirun(2) + " --version");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("2 ranks"), std::string::npos) << r.output;
}

}  // namespace
