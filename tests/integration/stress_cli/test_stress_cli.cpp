// Harmon et al. 2020 §3 end to end through the CLI: the stress model on the single-grain
// scene (Bullet moves the grain, the average stress breaks it, alpha_shape cuts the plane).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "crumble_config.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

TEST(StressCli, SingleGrainBreaksAtTheVonMisesStrength) {
#if !CRUMBLE_WITH_BULLET || !CRUMBLE_WITH_CGAL
  GTEST_SKIP() << "needs Bullet and CGAL";
#endif
  const fs::path out = fs::temp_directory_path() / "crumble_stress_single_grain";
  fs::remove_all(out);
  const std::string args = std::string("run ") + CRUMBLE_SOURCE_DIR +
                           "/scenarios/single_grain_pd.json --quiet --out " + out.string() +
                           " --set breakage.type=stress --set breakage.criterion=von_mises"
                           " --set breakage.weibull=false";
  const auto r = run_cli(args);
  ASSERT_EQ(r.status, 0) << args << "\n" << r.output;
  const Json s = Json::parse(slurp(out / "summary.json"));
  ASSERT_TRUE(s.contains("crushing_force_N")) << s.dump(2);
  ASSERT_TRUE(s.contains("crushing_stress_Pa")) << s.dump(2);
  // A 2 mm sphere between plates: σ_V = 3P/(2πR²) (eq. 5) reaches 35 MPa (Table 2) at
  // P = 73.3 N. Checks every 0.1 MPa of platen stress (3.6 N) or 100 steps: allow 8 N.
  const double pi = 3.14159265358979323846, P = 35e6 * 2 * pi * 1e-6 / 3;
  EXPECT_GE(s["crushing_stress_Pa"].get<double>(), 35e6);
  EXPECT_NEAR(s["crushing_force_N"].get<double>(), P + 4, 4.5);
  EXPECT_EQ(s["breakage_events"], 1);
  EXPECT_EQ(s["fragment_count"], 2);
  double v = 0;
  for (double d : s["fragment_diameters_m"]) v += std::pow(d, 3);
  EXPECT_NEAR(v, 8e-9, 8e-9 * 1e-9);  // volume conserved by the plane cut
  const std::string events = slurp(out / "events.csv");
  EXPECT_NE(events.find("sigma_1_Pa,sigma_2_Pa,sigma_3_Pa,equivalent_stress_Pa,strength_Pa"), std::string::npos)
      << events;
  // output.intact_analyses false: the same run, events.csv has the breakage row alone while
  // summary.json still counts every analysis.
  const auto lines = [](const std::string& t) { return std::count(t.begin(), t.end(), '\n'); };
  ASSERT_GT(s["analyses"].get<long>(), 1);
  EXPECT_EQ(lines(events), 1 + s["analyses"].get<long>());
  const auto r2 = run_cli(args + " --force --set output.intact_analyses=false");
  ASSERT_EQ(r2.status, 0) << r2.output;
  EXPECT_EQ(lines(slurp(out / "events.csv")), 2);
  EXPECT_EQ(Json::parse(slurp(out / "summary.json"))["analyses"], s["analyses"]);
}

TEST(StressCli, UnknownCriterionIsAConfigError) {
  const auto r = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR +
                         "/scenarios/single_grain_pd.json --set breakage.type=stress --set breakage.criterion=bogus");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("/breakage/criterion"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("max_principal, von_mises, tresca"), std::string::npos) << r.output;
}

TEST(StressCli, ListShowsTheCriteria) {
  const auto r = run_cli("list");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("stress"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("max_principal von_mises tresca"), std::string::npos) << r.output;
}
