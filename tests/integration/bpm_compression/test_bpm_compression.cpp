// The densely arrayed bonded-particle model (DA-BPM) end to end through the CLI: the quick 2D
// one-dimensional compression (lsdem + bonded_particles + level_set) reduced to a few
// seconds — grains break, the mass budget is exact, series.csv carries void ratio and K0,
// events.csv the model's figures, and scripts/bpm_stages.py marks the stages.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "output/Writers.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::read_csv;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

namespace {

// 10 grains in a 3.5 mm cell (the quick scenario's grains per width), to 6 % axial strain.
const char* kReduce =
    " --quiet --threads 1 --set packing.count=10 --set container.lx=3.5e-3 --set loading.stop_strain=0.06"
    " --set output.psd_at_stress=[1e6]";

int column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

}  // namespace

TEST(BpmCompression, QuickRunBreaksGrainsKeepsMassAndWritesVoidRatioAndK0) {
  const fs::path out = fs::temp_directory_path() / "crumble_bpm_quick";
  fs::remove_all(out);
  const std::string args = std::string("run ") + CRUMBLE_SOURCE_DIR + "/scenarios/compression_bpm_2d_quick.json --out " +
                           out.string() + kReduce;
  const auto r = run_cli(args);
  ASSERT_EQ(r.status, 0) << args << "\n" << r.output;
  const Json s = Json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["breakage"], "bonded_particles");
  EXPECT_GT(s["breakage_events"].get<long>(), 0) << s.dump(2);
  const double m0 = s["mass_initial_kg"], m1 = s["mass_final_kg"], mr = s["mass_removed_kg"];
  EXPECT_NEAR(m1 + mr, m0, 1e-12 * m0);

  // series.csv: void ratio falls with the strain; K0 is written (finite, in (0, 3)) for most rows.
  const auto series = read_csv((out / "series.csv").string());
  ASSERT_GT(series.size(), 10u);
  const int ie = column(series[0], "void_ratio"), ik = column(series[0], "k0");
  ASSERT_GE(ie, 0);
  ASSERT_GE(ik, 0);
  const double e_first = std::stod(series[1][ie]), e_last = std::stod(series.back()[ie]);
  EXPECT_GT(e_first, 0);
  EXPECT_LT(e_last, e_first);
  int k0_rows = 0;
  for (std::size_t i = 1; i < series.size(); ++i)
    if (static_cast<int>(series[i].size()) > ik && !series[i][ik].empty()) {
      const double k0 = std::stod(series[i][ik]);
      EXPECT_TRUE(std::isfinite(k0));
      k0_rows += k0 > 0 && k0 < 3;
    }
  EXPECT_GT(k0_rows, static_cast<int>(series.size()) / 2);

  // events.csv: the model's figures as columns; a split reports its elements and pieces.
  const auto events = read_csv((out / "events.csv").string());
  ASSERT_GT(events.size(), 1u);
  for (const char* name : {"elements", "bonds", "steps", "broken_bonds", "force_at_split_N", "pieces",
                           "largest_piece_deca_m", "inner_pore_volume_m3"})
    EXPECT_GE(column(events[0], name), 0) << name;
  const int io = column(events[0], "outcome"), iel = column(events[0], "elements"), ip = column(events[0], "pieces");
  int splits = 0;
  for (std::size_t i = 1; i < events.size(); ++i)
    if (events[i][io] == "split") {
      ++splits;
      EXPECT_GE(std::stod(events[i][iel]), 12) << i;  // min_elements 12: a grain of 12 may split
      EXPECT_GE(std::stod(events[i][ip]), 2) << i;
    }
  EXPECT_GT(splits, 0);

  // The stage script reads the run (skipped where python3 is missing).
  if (std::system("python3 --version > /dev/null 2>&1") == 0) {
    // Runs the script on a run folder and returns its bpm_stages.json ("" on failure).
    auto stages_of = [](const fs::path& dir) -> std::string {
      const std::string cmd =
          std::string("python3 ") + CRUMBLE_SOURCE_DIR + "/scripts/bpm_stages.py " + dir.string() + " > /dev/null";
      return std::system(cmd.c_str()) == 0 ? slurp(dir / "bpm_stages.json") : "";
    };
    const std::string full = stages_of(out);
    ASSERT_FALSE(full.empty()) << out;
    const Json st = Json::parse(full);
    EXPECT_NEAR(st["stages"]["e0"].get<double>(), e_first, 0.05 * e_first);
    EXPECT_TRUE(st["stages"]["I_to_II_Pa"].is_number()) << st["stages"].dump();
    // A run that did not finish leaves series.csv.part: the script reads that, with the same stages.
    const fs::path part = out.string() + "_unfinished";
    fs::remove_all(part);
    fs::create_directories(part);
    fs::copy_file(out / "series.csv", part / "series.csv.part");
    const std::string unfinished = stages_of(part);
    ASSERT_FALSE(unfinished.empty()) << part;
    EXPECT_EQ(Json::parse(unfinished)["stages"], st["stages"]);
  }
}
