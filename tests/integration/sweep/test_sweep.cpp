// `crumble sweep` end to end on the shipped single-grain peridynamics scene (Zhu & Zhao 2019
// §4.2) at coarse lattice spacings (about 2 s in all): one run folder and one sweep.csv row per
// setting, metric values equal to each run's own summary.json, relative errors against the
// reference recomputed here, the front marked by Pareto dominance, cost and peak memory
// present; and bad input refused with exit 2 before anything runs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "output/Writers.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

namespace {

const std::string kScenario = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/single_grain_pd.json";

fs::path test_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path d = fs::temp_directory_path() / "crumble_sweep_test" / info->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

struct Table {
  std::vector<std::vector<std::string>> rows;
  std::size_t col(const std::string& name) const {
    for (std::size_t i = 0; i < rows[0].size(); ++i)
      if (rows[0][i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
  const std::string& at(std::size_t row, const std::string& name) const { return rows[row + 1][col(name)]; }
};

}  // namespace

TEST(Sweep, SpacingFractionAgainstTheFinest) {
  const fs::path out = test_dir() / "out";
  // 0.2: too few lattice points to break below the 10 MPa the scene stops at (no crushing force);
  // 0.15 and 0.13 break. Reference: the last value.
  const auto r = run_cli("sweep " + kScenario + " --out " + out.string() +
                         " --param breakage.spacing_fraction --values 0.2,0.15,0.13 --metric crushing_force"
                         " --metric grains_final --set output.vtk_final=false --threads 1 --jobs 2 --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  Table t{crumble::read_csv((out / "sweep.csv").string())};
  ASSERT_EQ(t.rows.size(), 4u) << slurp(out / "sweep.csv");
  EXPECT_EQ(t.rows[0][0], "breakage.spacing_fraction");
  const std::vector<std::string> values = {"0.2", "0.15", "0.13"};
  std::vector<Json> s;
  for (std::size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE(values[i]);
    EXPECT_EQ(t.rows[i + 1][0], values[i]);
    EXPECT_EQ(t.at(i, "status"), "ok");
    EXPECT_EQ(t.at(i, "reference"), i == 2 ? "1" : "0");
    const fs::path folder = out / ("breakage.spacing_fraction=" + values[i]);
    EXPECT_EQ(t.at(i, "folder"), folder.filename().string());
    s.push_back(Json::parse(slurp(folder / "summary.json")));
    // Cost: the run's own wall time, where it went, and its process's peak memory.
    EXPECT_NEAR(std::stod(t.at(i, "wall_seconds")), s[i].at("wall_seconds").get<double>(),
                1e-8 * s[i].at("wall_seconds").get<double>());
    EXPECT_NEAR(std::stod(t.at(i, "time_analyses_s")), s[i]["time_breakdown_s"]["analyses"].get<double>(), 1e-8);
    const double rss = std::stod(t.at(i, "peak_rss_bytes"));
    EXPECT_GT(rss, 4e6);   // a crumble process with Bullet and a lattice: megabytes,
    EXPECT_LT(rss, 2e9);   // not the kilobytes ru_maxrss counts in
    EXPECT_EQ(std::stod(t.at(i, "grains_final")), s[i].at("grains_final").get<double>());
  }
  // The coarsest never broke: no crushing force, error not finite, not on the front.
  EXPECT_FALSE(s[0].contains("crushing_force_N"));
  EXPECT_EQ(t.at(0, "crushing_force_N"), "");
  EXPECT_EQ(t.at(0, "error"), "inf");
  EXPECT_EQ(t.at(0, "on_front"), "0");
  // The others: the metric is the summary's figure, the error is |F - F_ref| / F_ref.
  const double f1 = s[1].at("crushing_force_N").get<double>(), fref = s[2].at("crushing_force_N").get<double>();
  EXPECT_GT(fref, 100.0);  // broke at a physical force (the paper's 2 mm grain: ~180 N)
  EXPECT_NEAR(std::stod(t.at(1, "crushing_force_N")), f1, 1e-8 * f1);
  const double e1 = std::abs(f1 - fref) / fref;
  EXPECT_GT(e1, 1e-4);  // a coarser lattice gives another force
  EXPECT_NEAR(std::stod(t.at(1, "crushing_force_rel_error")), e1, 1e-8);
  EXPECT_EQ(std::stod(t.at(2, "crushing_force_rel_error")), 0.0);
  // error = the largest over the chosen metrics.
  const double g1 = std::abs(s[1].at("grains_final").get<double>() - s[2].at("grains_final").get<double>()) /
                    s[2].at("grains_final").get<double>();
  EXPECT_NEAR(std::stod(t.at(1, "error")), std::max(e1, g1), 1e-8);
  // The reference has zero error: on the front. 0.15 is cheaper (fewer lattice points): on it too.
  EXPECT_EQ(t.at(2, "on_front"), "1");
  const bool cheaper = s[1].at("wall_seconds").get<double>() < s[2].at("wall_seconds").get<double>();
  EXPECT_EQ(t.at(1, "on_front"), cheaper ? "1" : "0");

  const std::string md = slurp(out / "pareto.md");
  EXPECT_NE(md.find("| 0.13 | ok (reference) | ✓ | 0 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 0.2 | ok | — | not reached |"), std::string::npos) << md;
  EXPECT_NE(md.find("`crushing_force` (N), `grains_final` (1)"), std::string::npos) << md;
  EXPECT_NE(md.find("Front, cheapest first:"), std::string::npos) << md;
  // compare's own tables are there too.
  EXPECT_TRUE(fs::exists(out / "comparison.csv"));

  // An explicit reference, and every metric the reference reports by default.
  const fs::path out2 = test_dir() / "out2";
  const auto r2 = run_cli("sweep " + kScenario + " --out " + out2.string() +
                          " --param breakage.spacing_fraction --values 0.15,0.13 --reference 0.15"
                          " --set output.vtk_final=false --threads 1 --quiet");
  ASSERT_EQ(r2.status, 0) << r2.output;
  Table t2{crumble::read_csv((out2 / "sweep.csv").string())};
  ASSERT_EQ(t2.rows.size(), 3u);
  EXPECT_EQ(t2.at(0, "reference"), "1");
  EXPECT_EQ(t2.at(1, "reference"), "0");
  for (const char* c : {"crushing_force_N", "first_breakage_stress_Pa", "psd_d50_m", "grains_final"}) t2.col(c);
  const double f13 = std::stod(t2.at(1, "crushing_force_N")), f15 = std::stod(t2.at(0, "crushing_force_N"));
  EXPECT_NEAR(std::stod(t2.at(1, "crushing_force_rel_error")), std::abs(f13 - f15) / f15, 1e-8);
  EXPECT_NE(slurp(out2 / "pareto.md").find("(--reference)"), std::string::npos);
}

TEST(Sweep, BadInputIsExit2BeforeAnythingRuns) {
  const fs::path out = test_dir() / "out";
  const std::string base = "sweep " + kScenario + " --out " + out.string() + " --quiet ";
  const struct {
    std::string args;
    std::vector<std::string> needles;
  } cases[] = {
      {"--param breakage.spacing_fraction --values 0.2,0.15 --metric crushing_forc",
       {"unknown metric 'crushing_forc'", "crushing_force (N)", "first_breakage_stress (Pa)", "psd_d50 (m)"}},
      {"--param breakage.spacing_fractio --values 0.2,0.15",
       {"--param", "/breakage/spacing_fractio", "unknown key", "spacing_fraction"}},
      {"--param breakage.spacing_fraction --values \"\"", {"empty value list"}},
      {"--param breakage.spacing_fraction --values 0.2,,0.1", {"value 2 of 3 is empty"}},
      {"--param breakage.spacing_fraction --values 0.2,0.9", {"/breakage/spacing_fraction", "0.5"}},
      {"--param breakage.spacing_fraction --values 0.2,0.15 --reference 0.1", {"--reference 0.1", "not among"}},
      {"--param breakage.spacing_fraction --param breakage.gc0 --values 0.2,0.15", {"2 --param but 1 --values"}},
      {"--param breakage.spacing_fraction=0.2 --values 0.2", {"expected a scenario path"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.args);
    const auto r = run_cli(base + c.args);
    EXPECT_EQ(r.status, 2) << r.output;
    for (const auto& n : c.needles) EXPECT_NE(r.output.find(n), std::string::npos) << "'" << n << "' not in:\n" << r.output;
    EXPECT_FALSE(fs::exists(out)) << "written before the check";
  }
}

// SIGTERM sent to `crumble sweep` alone while its packing stage settles reaches the packing
// child: the settling stops (no packing.json, its log says so) and the sweep ends interrupted
// (143) without starting any setting. The settling does not converge (tolerance 1e-12) and would
// run for packing.settle.max_time otherwise (about 20 s), and write packing.json at its end.
TEST(Sweep, SigtermDuringThePackingStageStopsIt) {
  const fs::path out = test_dir() / "out";
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json";
  const std::string cmd = std::string(CRUMBLE_BINARY) + " sweep " + scen + " --out " + out.string() +
                          " --param loading.max_stress --values 5e5,1e6 --threads 1 --quiet"
                          " --set packing.settle.tolerance=1e-12 --set packing.settle.max_time=2";
  // Signalled once the packing child has begun (its effective_scenario.json is written just
  // before its packing is built and settled), and a moment later, so that it is settling.
  const fs::path started = out / "packing" / "effective_scenario.json";
  const auto r = run_cli("--version >/dev/null; " + cmd + " >/dev/null 2>&1 & p=$!; for i in $(seq 1 6000); do [ -f " +
                         started.string() + " ] && break; kill -0 $p 2>/dev/null || break; sleep 0.01; done; sleep 1;"
                         " kill -TERM $p; wait $p; echo \"sweep status $?\"");
  EXPECT_NE(r.output.find("sweep status 143"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "packing" / "packing.json")) << "the packing stage ran to its end";
  const std::string log = slurp(out / "logs" / "packing.log");
  EXPECT_NE(log.find("interrupted while the packing settled"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out / "sweep.csv"));
}
