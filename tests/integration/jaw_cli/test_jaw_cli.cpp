// A tiny jaw crusher through the CLI: rocks pass the gap, product_psd.csv is written and the
// mass budget of the open scene closes exactly (product + in the engine + removed = fed).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "../../support/CliRunner.h"

using namespace crumble::testing_support;
namespace fs = std::filesystem;

namespace {
fs::path tmp_dir(const std::string& name) {
  const char* t = std::getenv("TMPDIR");
  fs::path p = fs::path(t ? t : "/tmp") / name;
  fs::remove_all(p);
  return p;
}
}  // namespace

TEST(JawCli, TinyCrusherPassesRocksAndBalancesMass) {
  const fs::path out = tmp_dir("crumble_jaw_cli_tiny");
  // Rocks of 30-40 mm pass a 50 mm closed-side setting without breaking (breakage none);
  // 1.2 s (6 cycles at 300 rpm) lets them fall through.
  const std::string args = std::string("run ") + CRUMBLE_SOURCE_DIR + "/scenarios/jaw_crusher_2d_quick.json --out " +
                           out.string() +
                           " --quiet --set breakage.type=none --set scene.cycles=6 --set scene.rocks.count=6"
                           " --set 'scene.rocks.diameter=[0.03,0.04]'";
  const CliResult r = run_cli(args);
  ASSERT_EQ(r.status, 0) << r.output;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["rocks_fed"].get<double>(), 6);
  EXPECT_GE(s["product_grains"].get<double>(), 3) << "rocks should pass the 50 mm gap";
  const double fed = s["mass_fed_kg"].get<double>() + s["mass_initial_kg"].get<double>();
  const double left = s["product_mass_kg"].get<double>() + s["mass_final_kg"].get<double>() + s["mass_removed_kg"].get<double>();
  EXPECT_GT(fed, 0);
  EXPECT_NEAR(left, fed, 1e-12 * fed);
  EXPECT_EQ(s["mass_budget_error_kg"].get<double>(), left - fed);
  // Every rock that left is smaller than the open side setting: d50 between the rocks' sizes.
  const double d50 = s["product_d50_m"].get<double>();
  EXPECT_GT(d50, 0.02);
  EXPECT_LT(d50, 0.045);
  ASSERT_TRUE(fs::exists(out / "product_psd.csv"));
  std::istringstream csv(slurp(out / "product_psd.csv"));
  std::string line, last;
  std::getline(csv, line);
  EXPECT_EQ(line, "sieve_m,passing_percent,passing_mass_kg");
  int rows = 0;
  double prev = -1;
  while (std::getline(csv, line)) {
    ++rows;
    const double pass = std::stod(line.substr(line.find(',') + 1));
    EXPECT_GE(pass, prev);  // cumulative
    prev = pass;
    last = line;
  }
  EXPECT_GE(rows, 3);
  EXPECT_NEAR(prev, 100.0, 1e-9) << last;
  EXPECT_TRUE(fs::exists(out / "product.csv"));
}

// The crushing mechanism (Harmon et al. 2020 §4): rocks wider than the open side setting
// (0.12–0.13 m against OSS = 0.1 m) leave only as fragments. With the shipped physics (k_n
// per 1 mm of thickness, stress/von Mises, level-set splitting) the chamber must not jam:
// fragments pass the gap within 8 cycles, every product grain is a fragment (generation >= 1)
// narrower than the OSS, and the mass budget closes. Before the fixes of the chamber jam
// (plane along a face, unresolved slabs) the first rocks left after > 1.5 s or not at all.
TEST(JawCli, RocksWiderThanTheGapLeaveOnlyAsFragments) {
  const fs::path out = tmp_dir("crumble_jaw_cli_crush");
  const std::string args = std::string("run ") + CRUMBLE_SOURCE_DIR + "/scenarios/jaw_crusher_2d_quick.json --out " +
                           out.string() +
                           " --quiet --set scene.cycles=8 --set scene.rocks.count=2"
                           " --set 'scene.rocks.diameter=[0.12,0.13]'";
  const CliResult r = run_cli(args);
  ASSERT_EQ(r.status, 0) << r.output;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_GE(s["breakage_events"].get<double>(), 1);
  EXPECT_GE(s["product_grains"].get<double>(), 2) << "fragments should pass the gap";
  const double fed = s["mass_fed_kg"].get<double>();
  const double left = s["product_mass_kg"].get<double>() + s["mass_final_kg"].get<double>() + s["mass_removed_kg"].get<double>();
  EXPECT_NEAR(left, fed, 1e-12 * fed);
  // Fines removed inside the crusher stay below the product that left as grains.
  EXPECT_LT(s["mass_removed_kg"].get<double>(), s["product_mass_kg"].get<double>());
  // No fragment pressed deep into a neighbour or a plate (stiff contacts, checks every 50 steps).
  EXPECT_LT(s["guard_max_overlap_fraction"].get<double>(), 0.05);
  std::istringstream csv(slurp(out / "product.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "time,grain,origin,generation,equivalent_diameter_m,sieve_m,mass_kg");
  int rows = 0;
  while (std::getline(csv, line)) {
    std::vector<double> v;
    std::istringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 7u) << line;
    EXPECT_GE(v[3], 1) << "an unbroken rock wider than the OSS left: " << line;
    EXPECT_LT(v[5], 0.1) << line;  // sieve size below the OSS
    ++rows;
  }
  EXPECT_EQ(rows, s["product_grains"].get<double>());
}

namespace {

// Removed mass over the rock fed of the quick jaw file at CSS 50 mm, shortened to `cycles`
// revolutions, with `extra` settings; the summary in *s.
double jaw_removed_fraction(const std::string& name, int cycles, const std::string& extra, nlohmann::json* s) {
  const fs::path out = tmp_dir(name);
  const std::string args = std::string("run ") + CRUMBLE_SOURCE_DIR + "/scenarios/jaw_crusher_2d_quick.json --out " +
                           out.string() + " --quiet --threads 1 --set scene.css=0.05 --set scene.cycles=" +
                           std::to_string(cycles) + extra;
  const CliResult r = run_cli(args);
  EXPECT_EQ(r.status, 0) << args << "\n" << r.output;  // no guard stop
  *s = nlohmann::json::parse(slurp(out / "summary.json"));
  const double fed = (*s)["mass_fed_kg"].get<double>() + (*s)["mass_initial_kg"].get<double>();
  EXPECT_GT(fed, 0);
  EXPECT_LT(std::abs((*s)["mass_budget_error_kg"].get<double>()), 1e-9 * fed);
  return (*s)["mass_removed_kg"].get<double>() / fed;
}

}  // namespace

// Harmon et al. 2020, §4: "the total mass of the filtered particles was < 1 % of the total mass
// of the specimen". The quick jaw file keeps it so with its fragment and breakage settings
// (the second of §3.4's three ways, children resampled at their own size, with a minimum
// piece size and thickness; docs/validation.md, "Jaw crusher fines"). Shortened to 4 cycles
// (0.8 s, 4 rocks fed, crushed from 0.5 s on: 12 breakage events, none removed). Without
// those settings (Table 1's 7 mm grid for every child, no minimum piece) the same run removes
// 4.9 % of the rock fed as slivers and grains the grid cannot resolve (the file's earlier
// settings fail this test), so the test can fail.
TEST(JawCli, QuickFileRemovesLessThanOnePercentOfTheRockFed) {
  nlohmann::json s;
  const double kept = jaw_removed_fraction("crumble_jaw_fines", 4, "", &s);
  EXPECT_GE(s["breakage_events"].get<double>(), 10) << s.dump(2);
  EXPECT_GT(s["fragment_refinements"].get<double>(), 0) << s.dump(2);
  EXPECT_LT(kept, 0.01) << s.dump(2);
  const double before = jaw_removed_fraction("crumble_jaw_fines_off", 4,
                                             " --set fragments.cells_across=0 --set breakage.min_piece_diameter=0"
                                             " --set breakage.min_piece_thickness=0",
                                             &s);
  EXPECT_GT(before, 0.02) << "the shortened run no longer crushes rocks down to the grid: the test cannot fail";
}

TEST(JawCli, ValidateShippedJawScenarios) {
  for (const char* f : {"jaw_crusher_2d.json", "jaw_crusher_2d_quick.json"}) {
    const CliResult r = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR + "/scenarios/" + f);
    EXPECT_EQ(r.status, 0) << f << ": " << r.output;
  }
  // Bad wall JSON from the command line: exit 2 with the path.
  const CliResult r = run_cli(std::string("validate ") + CRUMBLE_SOURCE_DIR +
                              "/scenarios/jaw_crusher_2d_quick.json --set scene.throw=-1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("/scene/throw"), std::string::npos) << r.output;
}
