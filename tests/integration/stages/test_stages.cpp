// `crumble stages DIR`: the per-MPa cost table of a run, its power-law fits and the
// extrapolation to a higher stress (tools/Stages.h), on a synthetic stages.csv whose
// answer is known in closed form, and its errors on bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <nlohmann/json.hpp>

#include "output/Writers.h"
#include "run/RunPipeline.h"
#include "output/Writers.h"
#include "tools/Stages.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using crumble::testing_support::run_cli;

namespace {
// Grains N(σ) = 720·(σ/MPa)^1.2 at each stage's end (stage 0–1 MPa without breakage), and a wall
// time per MPa of 0.002·N^1.5 at the stage's mean grain count.
double grains(double s) { return 720 * std::pow(s, 1.2); }
double cost(double n) { return 0.002 * std::pow(n, 1.5); }

fs::path write_table(const std::string& name, int stages, bool partial, bool strain = false) {
  const fs::path dir = fs::temp_directory_path() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream o(dir / "stages.csv");
  o << std::setprecision(17) << (strain ? "strain_from_percent,strain_to_percent" : "stress_from_MPa,stress_to_MPa")
    << ",complete,resumed,step,time_s,grains_start,grains,wall_s,wall_total_s,steps,"
       "engine_s,engine_ms_per_step,analyses,breaking_analyses,analysis_s,mean_analysis_ms,"
       "breaking_share_of_analysis_time,fragments_s,analyses_total,breakage_events_total\n";
  double total = 0, n0 = 720;
  for (int k = 0; k < stages; ++k) {
    const double n1 = k == 0 ? 720 : grains(k + 1);
    const double w = k == 0 ? 5.0 : cost(0.5 * (n0 + n1));
    total += w;
    o << k << ',' << k + 1 << ",1,0," << 100 * (k + 1) << ",0.1," << static_cast<long>(n0) << ','
      << static_cast<long>(n1) << ',' << w << ',' << total << ",100,1,10," << (k ? 50 : 0) << ',' << (k ? 20 : 0)
      << ",1," << (k ? "30" : "") << ',' << (k ? "0.7" : "") << ",0.1,0,0\n";
    n0 = n1;
  }
  if (partial) {
    const double n1 = grains(stages + 0.4), w = 0.4 * cost(0.5 * (n0 + n1));
    o << stages << ',' << stages + 0.4 << ",0,0,1,0.1," << static_cast<long>(n0) << ',' << static_cast<long>(n1) << ','
      << w << ',' << total + w << ",1,1,1,0,0,0,,,0,0,0\n";
  }
  return dir;
}
}  // namespace

TEST(Stages, FitsAndExtrapolatesAPowerLawRun) {
  // Grain counts are written as integers, so the fits recover the laws to rounding (< 0.1 %).
  const fs::path dir = write_table("crumble_stages_fit", 12, true);
  std::string md;
  const auto j = crumble::stage_report(dir.string(), 30, &md);
  ASSERT_TRUE(j.contains("cost_fit")) << j.dump(2);
  EXPECT_NEAR(j["cost_fit"]["b"].get<double>(), 1.5, 2e-3);
  EXPECT_NEAR(j["grains_fit"]["k"].get<double>(), 1.2, 2e-3);
  EXPECT_EQ(j["cost_fit"]["stages"].get<int>(), 12);  // the stages with breakage, the partial one too
  // The partial stage (12–12.4 MPa) is where the measurement ends; the extrapolation
  // continues its grain count (scaled) with the fitted law to 30 MPa.
  EXPECT_DOUBLE_EQ(j["measured_to_MPa"].get<double>(), 12.4);
  const double measured = j["measured_wall_s"].get<double>();
  double expect = measured, n = static_cast<double>(static_cast<long>(grains(12.4)));
  const double scale = n / grains(12.4);
  double s0 = 12.4;
  for (double s1 : {13.0, 14.0, 15.0, 16.0, 17.0, 18.0, 19.0, 20.0, 21.0, 22.0, 23.0, 24.0, 25.0, 26.0, 27.0, 28.0,
                    29.0, 30.0}) {
    const double n1 = scale * grains(s1);
    expect += cost(0.5 * (n + n1)) * (s1 - s0);
    n = n1;
    s0 = s1;
  }
  EXPECT_NEAR(j["predicted_wall_s"].get<double>(), expect, 0.01 * expect);
  EXPECT_NE(md.find("| 12–12.4 (partial) |"), std::string::npos) << md;
  EXPECT_NE(md.find("Extrapolated to 30 MPa"), std::string::npos) << md;
}

TEST(Stages, TooFewStagesSayToRunFurther) {
  const fs::path dir = write_table("crumble_stages_short", 3, false);
  const auto j = crumble::stage_report(dir.string(), 30);
  EXPECT_FALSE(j.contains("predicted_wall_s"));
  EXPECT_NE(j["note"].get<std::string>().find("run further"), std::string::npos);
}

// A run stopped cleanly inside a stage (SIGTERM, a time budget) writes it as a partial row and,
// resumed, the rest of it from there: the report joins the two into the row an uninterrupted
// run writes (wall, analyses and steps summed; mean analysis time, breaking share and engine
// time per step weighted), so the table, the fits and the extrapolation do not change.
TEST(Stages, AStageInterruptedAndResumedIsOneRow) {
  const fs::path whole = write_table("crumble_stages_whole", 12, false);
  const fs::path split = write_table("crumble_stages_split", 12, false);
  {
    std::ifstream in(split / "stages.csv");
    std::vector<std::string> lines;
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    // Stage 5–6 (line 7): wall w, 50 analyses, 20 breaking, 100 steps, 30 ms mean, share 0.7,
    // 10 ms/step. Interrupted at 5.4 MPa after 0.4 w, 20 analyses (8 breaking, 40 ms mean,
    // share 0.5), 40 steps at 12 ms; resumed for the rest: 30 analyses (12 breaking, 70/3 ms
    // mean, share 0.7·(50·30) − 0.5·(20·40) over 30·70/3), 60 steps at 26/3 ms.
    std::vector<std::string> c;
    std::stringstream ss(lines[6]);
    for (std::string cell; std::getline(ss, cell, ',');) c.push_back(cell);
    const double w = std::stod(c[8]), total = std::stod(c[9]);
    auto row = [&](const std::string& from, const std::string& to, int complete, double wall, double wall_total,
                   int steps, double eng, int an, int br, double mean, double share) {
      std::ostringstream o;
      o << std::setprecision(17) << from << ',' << to << ',' << complete << ",0," << c[4] << ',' << c[5] << ','
        << c[6] << ',' << c[7] << ',' << wall << ',' << wall_total << ',' << steps << ",1," << eng << ',' << an << ','
        << br << ",1," << mean << ',' << share << ",0.1,0,0";
      return o.str();
    };
    const double share2 = (0.7 * 50 * 30 - 0.5 * 20 * 40) / (30 * 70.0 / 3);
    lines[6] = row("5", "5.4", 0, 0.4 * w, total - 0.6 * w, 40, 12, 20, 8, 40, 0.5) + "\n" +
               row("5.4", "6", 1, 0.6 * w, total, 60, 26.0 / 3, 30, 12, 70.0 / 3, share2);
    std::ofstream out(split / "stages.csv");
    for (const auto& l : lines) out << l << '\n';
  }
  std::string md_whole, md_split;
  const auto a = crumble::stage_report(whole.string(), 30, &md_whole);
  const auto b = crumble::stage_report(split.string(), 30, &md_split);
  ASSERT_EQ(a["stages"].size(), b["stages"].size()) << md_split;
  EXPECT_EQ(a["stages"][5], b["stages"][5]);
  EXPECT_EQ(a["cost_fit"]["stages"], b["cost_fit"]["stages"]);
  EXPECT_NEAR(b["predicted_wall_s"].get<double>(), a["predicted_wall_s"].get<double>(),
              1e-9 * a["predicted_wall_s"].get<double>());
  EXPECT_EQ(md_whole, md_split);
}

TEST(Stages, CliNamesAMissingOrBrokenFile) {
  const fs::path dir = fs::temp_directory_path() / "crumble_stages_missing";
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto r = run_cli("stages " + dir.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("stages.csv"), std::string::npos) << r.output;
  const fs::path bad = write_table("crumble_stages_bad", 4, false);
  {
    std::ofstream o(bad / "stages.csv", std::ios::app);
    o << "4,5,1,0,500,0.1,9,9,abc,1,1,1,1,0,0,0,,,0,0,0\n";
  }
  r = run_cli("stages " + bad.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("line 6, column wall_s"), std::string::npos) << r.output;
  // A run still going: its rows so far are in stages.csv.part, which is read and said so.
  const fs::path going = write_table("crumble_stages_going", 12, false);
  fs::rename(going / "stages.csv", going / "stages.csv.part");
  r = run_cli("stages " + going.string());
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("from stages.csv.part"), std::string::npos) << r.output;
  r = run_cli("stages " + write_table("crumble_stages_ok", 12, false).string() + " --to 20 --json");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("\"predicted_hours\""), std::string::npos) << r.output;
}

// A strain-controlled run (loading.mode strain_rate) is staged per percent of axial strain:
// the same fits, the extrapolation to 15 % by default (Harmon et al. 2020 §5).
TEST(Stages, StrainTablesAreReadPerPercent) {
  const fs::path dir = write_table("crumble_stages_strain", 8, false, true);
  std::string md;
  const auto j = crumble::stage_report(dir.string(), std::nan(""), &md);
  EXPECT_EQ(j.at("axis"), "axial strain");
  EXPECT_DOUBLE_EQ(j.at("measured_to_percent").get<double>(), 8);
  EXPECT_DOUBLE_EQ(j.at("target_percent").get<double>(), 15);
  EXPECT_NEAR(j.at("cost_fit").at("b").get<double>(), 1.5, 2e-3);
  EXPECT_GT(j.at("predicted_wall_s").get<double>(), j.at("measured_wall_s").get<double>());
  EXPECT_NE(md.find("| % strain | grains |"), std::string::npos) << md;
  EXPECT_NE(md.find("Extrapolated to 15 % strain"), std::string::npos) << md;
  EXPECT_DOUBLE_EQ(crumble::stage_report(write_table("crumble_stages_stress_default", 12, false).string(), std::nan(""))
                       .at("target_MPa")
                       .get<double>(),
                   30);
}

// A run under loading.mode strain_rate writes its stages per percent of axial strain, one row
// each, in order; a stress ramp per MPa (the header says which).
TEST(Stages, AStrainRateRunIsStagedByStrain) {
  const fs::path dir = fs::temp_directory_path() / "crumble_stages_strain_run";
  fs::remove_all(dir);
  fs::create_directories(dir);
  // One sphere under a platen moving at a strain rate of 10 /s for 3.5 % (lsdem, no breakage).
  std::ofstream(dir / "s.json") << R"({
  "name": "stages_strain", "engine": {"type": "lsdem"}, "breakage": {"type": "none"},
  "container": {"lx": 0.01, "ly": 0.01, "height": 0.004},
  "packing": {"type": "grains", "grains": [
     {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.005, 0.005, 0.0011]}]},
  "loading": {"mode": "strain_rate", "strain_rate": 10.0, "stop_strain": 0.035},
  "time_step": 1e-5, "simulation": {"sample_every": 10}, "output": {"plots": false}
})";
  const auto r = run_cli("run " + (dir / "s.json").string() + " --out " + (dir / "out").string() + " --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto rows = crumble::read_csv((dir / "out" / "stages.csv").string());
  ASSERT_GE(rows.size(), 4u);
  EXPECT_EQ(rows[0][0], "strain_from_percent");
  EXPECT_EQ(rows[0][1], "strain_to_percent");
  for (std::size_t i = 1; i <= 3; ++i) {
    EXPECT_EQ(std::stod(rows[i][0]), static_cast<double>(i - 1));
    EXPECT_EQ(std::stod(rows[i][1]), static_cast<double>(i));
  }
  const auto s = run_cli("stages " + (dir / "out").string());
  EXPECT_EQ(s.status, 0) << s.output;
  EXPECT_NE(s.output.find("% strain"), std::string::npos) << s.output;
}
