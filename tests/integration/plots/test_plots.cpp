// The figures of an output folder (output/Plots.h, scripts/crumble_plot.py): `crumble plot`
// on a checked-in crushable run (data/zhu_zhao_quick_8MPa: the CSVs and JSON files of
// oedometer_zhu_zhao_quick.json stopped with SIGINT at 8.56 MPa, 100 -> 235 grains, 105 breakage
// events; no VTK files, so shape.png draws the means of shape.csv), the figures at the end of a tiny `crumble run`, a sweep
// folder, and the messages when a CSV is missing or garbled or no matplotlib is there.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

namespace {

// What the binary tries (output/Plots.cpp): python3 on PATH, then /usr/bin/python3.
bool have_matplotlib() {
  for (const char* py : {"python3", "/usr/bin/python3"}) {
    const std::string cmd = std::string(py) + " -c 'import matplotlib' >/dev/null 2>&1";
    if (std::system(cmd.c_str()) == 0) return true;
  }
  return false;
}

#define SKIP_WITHOUT_MATPLOTLIB()                                                                            \
  if (!have_matplotlib())                                                                                    \
  GTEST_SKIP() << "no python3 that imports matplotlib (Debian: apt-get install python3-matplotlib); the "    \
                  "figures cannot be drawn here"

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / "crumble_plots" / name;
  fs::remove_all(d);
  fs::create_directories(d.parent_path());
  return d;
}

fs::path copy_fixture(const std::string& name) {
  const fs::path d = fresh_dir(name);
  fs::copy(fs::path(CRUMBLE_SOURCE_DIR) / "tests/integration/plots/data/zhu_zhao_quick_8MPa", d,
           fs::copy_options::recursive);
  return d;
}

// A PNG: the 8-byte signature, an IHDR chunk first, a plausible size in pixels, and more than
// `min_bytes` (an empty figure at 110 dpi is ≈ 5 kB; one with curves, labels and a legend is more).
void expect_png(const fs::path& p, std::uintmax_t min_bytes = 15000) {
  ASSERT_TRUE(fs::exists(p)) << p;
  const std::string s = slurp(p);
  ASSERT_GT(s.size(), 33u) << p;
  EXPECT_EQ(s.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << p;
  EXPECT_EQ(s.substr(12, 4), "IHDR") << p;
  auto be32 = [&](std::size_t i) {
    return (static_cast<std::uint32_t>(static_cast<unsigned char>(s[i])) << 24) |
           (static_cast<std::uint32_t>(static_cast<unsigned char>(s[i + 1])) << 16) |
           (static_cast<std::uint32_t>(static_cast<unsigned char>(s[i + 2])) << 8) |
           static_cast<std::uint32_t>(static_cast<unsigned char>(s[i + 3]));
  };
  EXPECT_GE(be32(16), 400u) << p << ": width";
  EXPECT_GE(be32(20), 300u) << p << ": height";
  EXPECT_GT(fs::file_size(p), min_bytes) << p;
}

}  // namespace

TEST(Plots, PlotOfACrushableRunFolderDrawsItsFigures) {
  SKIP_WITHOUT_MATPLOTLIB();
  const fs::path d = copy_fixture("crushable");
  const auto r = run_cli("plot " + d.string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* f : {"ncl.png", "psd.png", "breakage.png", "shape.png"}) {
    expect_png(d / f);
    EXPECT_NE(r.output.find(f), std::string::npos) << f << " not reported: " << r.output;
  }
  // A stress-controlled oedometer: no stress–strain or load–displacement figure.
  EXPECT_FALSE(fs::exists(d / "stress_strain.png"));
  EXPECT_FALSE(fs::exists(d / "load_displacement.png"));
  for (const auto& e : fs::directory_iterator(d)) EXPECT_NE(e.path().extension(), ".tmp") << e.path();
}

TEST(Plots, MissingOrGarbledCsvIsAnErrorNamingTheFile) {
  SKIP_WITHOUT_MATPLOTLIB();
  {
    const fs::path d = copy_fixture("no_series");
    fs::remove(d / "series.csv");
    const auto r = run_cli("plot " + d.string());
    EXPECT_NE(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("series.csv"), std::string::npos) << r.output;
  }
  {
    const fs::path d = copy_fixture("garbled_psd");
    // Line 2's percent_passing_by_mass (the fourth field) becomes "12 %".
    std::string psd = slurp(d / "psd.csv");
    std::size_t at = psd.find('\n') + 1;
    for (int k = 0; k < 3; ++k) at = psd.find(',', at) + 1;
    psd.replace(at, psd.find(',', at) - at, "12 %");
    std::ofstream(d / "psd.csv") << psd;
    const auto r = run_cli("plot " + d.string());
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("psd.csv: line 2: column 'percent_passing_by_mass': '12 %' is not a number"),
              std::string::npos)
        << r.output;
  }
  {
    const fs::path d = copy_fixture("short_header");
    std::ofstream(d / "series.csv") << "time_s,step\n0,1\n";
    const auto r = run_cli("plot " + d.string());
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("series.csv: no column 'platen_stress_Pa'"), std::string::npos) << r.output;
  }
  {
    const fs::path d = fresh_dir("empty");
    fs::create_directories(d);
    const auto r = run_cli("plot " + d.string());
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("no crumble output"), std::string::npos) << r.output;
    const auto n = run_cli("plot " + (d / "absent").string());
    EXPECT_EQ(n.status, 2) << n.output;
    EXPECT_NE(n.output.find("not a folder"), std::string::npos) << n.output;
  }
}

// The tiny rigid run of Cli.SameSeedSameSummary: 25 spheres to 0.2 MPa.
const char* kTinyRun =
    " --threads 1 --set packing.count=25 --set container.lx=6e-3 --set container.ly=6e-3"
    " --set loading.max_stress=2e5 --set loading.ramp_time=0.01 --set engine.solver_iterations=200";

TEST(Plots, ARunEndsWithItsFiguresUnlessOutputPlotsIsFalse) {
  SKIP_WITHOUT_MATPLOTLIB();
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json";
  const fs::path d = fresh_dir("run");
  const auto r = run_cli("run " + scen + " --out " + d.string() + kTinyRun);
  ASSERT_EQ(r.status, 0) << r.output;
  expect_png(d / "ncl.png");
  expect_png(d / "psd.png");
  EXPECT_NE(r.output.find("crumble: plots: ncl.png, psd.png"), std::string::npos) << r.output;
  // 25 identical rigid spheres: one sphericity, no breakage; a shape figure would show one dot
  // and flat lines, so none is drawn.
  EXPECT_FALSE(fs::exists(d / "shape.png"));
  EXPECT_NE(r.output.find("crumble: plots: ncl.png, psd.png in"), std::string::npos) << r.output;
  // --force removes the earlier figures with the earlier run's files.
  const auto off = run_cli("run " + scen + " --force --out " + d.string() + kTinyRun + " --set output.plots=false");
  ASSERT_EQ(off.status, 0) << off.output;
  EXPECT_FALSE(fs::exists(d / "ncl.png"));
  EXPECT_FALSE(fs::exists(d / "psd.png"));
  EXPECT_EQ(off.output.find("crumble: plots"), std::string::npos) << off.output;
  const auto bad = run_cli("validate " + scen + " --set output.plots=3");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("/output/plots"), std::string::npos) << bad.output;
}

TEST(Plots, WithoutMatplotlibTheRunWritesEveryCsvAndSaysSoInOneLine) {
  // No matplotlib needed: the interpreter named does not exist.
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json";
  const fs::path d = fresh_dir("no_python");
  const std::string env = "CRUMBLE_PYTHON=/nonexistent/python3 ";
  const std::string cmd = env + CRUMBLE_BINARY + " run " + scen + " --quiet --out " + d.string() + kTinyRun;
  const auto r = run_cli("--version >/dev/null; " + cmd);
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* f : {"summary.json", "series.csv", "psd.csv", "ncl.csv", "events.csv"}) EXPECT_TRUE(fs::exists(d / f)) << f;
  EXPECT_FALSE(fs::exists(d / "ncl.png"));
  std::size_t lines = 0, at = 0;
  while ((at = r.output.find("plots skipped", at)) != std::string::npos) ++lines, ++at;
  EXPECT_EQ(lines, 1u) << r.output;
  EXPECT_NE(r.output.find("python3-matplotlib"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("crumble plot " + d.string()), std::string::npos) << r.output;
  const auto p = run_cli("--version >/dev/null; " + env + CRUMBLE_BINARY + " plot " + d.string());
  EXPECT_EQ(p.status, 1) << p.output;
  EXPECT_NE(p.output.find("no python3 with matplotlib"), std::string::npos) << p.output;
  // A script that cannot be found: skipped the same way, naming the variable that points to it.
  const auto s = run_cli("--version >/dev/null; CRUMBLE_PLOT_SCRIPT=/nonexistent/crumble_plot.py " +
                         std::string(CRUMBLE_BINARY) + " plot " + d.string());
  EXPECT_EQ(s.status, 1) << s.output;
  EXPECT_NE(s.output.find("CRUMBLE_PLOT_SCRIPT"), std::string::npos) << s.output;
}

TEST(Plots, SweepFolderGetsTheErrorCostFront) {
  SKIP_WITHOUT_MATPLOTLIB();
  const fs::path d = fresh_dir("sweep");
  const auto r = run_cli("sweep " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/single_grain_pd.json --out " +
                         d.string() + " --param breakage.spacing_fraction --values 0.2,0.17,0.15 --threads 1");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_png(d / "pareto.png");
  EXPECT_NE(r.output.find("pareto.png"), std::string::npos) << r.output;
  // Its runs are a compare folder's: their curves overlaid; no figures inside the run folders.
  expect_png(d / "compare_psd.png");
  for (const auto& e : fs::directory_iterator(d)) {
    if (e.is_directory()) {
      EXPECT_FALSE(fs::exists(e.path() / "psd.png")) << e.path();
    }
  }
}

// A compare of jaw-crusher runs overlays their products (Harmon et al. 2020 Fig. 8): a tiny
// crusher (unbreakable 30-40 mm rocks, 6 cycles) at two closed side settings.
TEST(Plots, JawCompareOverlaysTheProducts) {
  SKIP_WITHOUT_MATPLOTLIB();
  const fs::path d = fresh_dir("jaw_compare");
  const auto r = run_cli("compare " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/jaw_crusher_2d_quick.json --out " +
                         d.string() + " --vary scene.css=0.05,0.08 --threads 1 --set breakage.type=none"
                         " --set scene.cycles=6 --set scene.rocks.count=6 --set 'scene.rocks.diameter=[0.03,0.04]'");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_png(d / "compare_product_psd.png");
  EXPECT_NE(r.output.find("compare_product_psd.png"), std::string::npos) << r.output;
}

// A level the loading did not reach is never shown as reached. lsdem's measured stress rings
// above the ramp: in this 2D run (sampled every 10 steps, stopped at step 700 while the ramp
// commands 280 kPa) it passes 300 kPa from step 640 on. The 300 kPa table is then the final
// state, and psd.csv, summary.json and the psd.png legend name the stress it shows.
TEST(Plots, ALevelNotReachedIsLabelledWithTheStressReached) {
  const fs::path d = fresh_dir("not_reached");
  const auto r = run_cli("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json --quiet --out " +
                         d.string() + " --set output.plots=false --set simulation.sample_every=10"
                         " --set simulation.max_steps=700 --set output.psd_at_stress=[3e5]");
  ASSERT_EQ(r.status, 0) << r.output;
  // The case: a measured sample above the level, the commanded stress always below it.
  bool measured_above = false;
  {
    std::istringstream in(slurp(d / "series.csv"));
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::vector<std::string> c;
      std::istringstream ls(line);
      for (std::string x; std::getline(ls, x, ',');) c.push_back(x);
      ASSERT_GE(c.size(), 5u);
      measured_above |= std::stod(c[3]) >= 3e5;
      ASSERT_LT(std::stod(c[4]), 3e5) << line;
    }
  }
  ASSERT_TRUE(measured_above) << "the measured stress no longer passes the level: the test needs another case";
  // psd.csv: no table labelled as the level reached; the one standing for it names the final stress.
  const std::string psd = slurp(d / "psd.csv");
  EXPECT_EQ(psd.find("\nlevel_300000,"), std::string::npos) << psd;
  std::string final_stress;
  {
    const auto at = psd.find("\nfinal,");
    ASSERT_NE(at, std::string::npos);
    final_stress = psd.substr(at + 7, psd.find(',', at + 7) - at - 7);
  }
  char label[96];
  std::snprintf(label, sizeof label, "\nlevel_300000_not_reached_final_at_%.10g_Pa,", std::stod(final_stress));
  EXPECT_NE(psd.find(label), std::string::npos) << label << " not in\n" << psd;
  // summary.json (compare and sweep tables): no void ratio at a level not reached.
  EXPECT_EQ(slurp(d / "summary.json").find("void_ratio_at_stress_300000_Pa"), std::string::npos);
  // The figure's legend (scripts/crumble_plot.py; its labels need no matplotlib).
  const auto py = run_cli("--version >/dev/null; python3 -c \"import sys; sys.path.insert(0, '" +
                          std::string(CRUMBLE_SOURCE_DIR) + "/scripts'); import crumble_plot as p; t = p.fold_not_reached("
                          "p.read_psd('" + (d / "psd.csv").string() + "')); print('|'.join(p.psd_label(k, v) for k, v in t.items()))\"");
  char legend[96];
  std::snprintf(legend, sizeof legend, "final (%.3g MPa; 0.3 MPa not reached)", std::stod(final_stress) / 1e6);
  EXPECT_NE(py.output.find(legend), std::string::npos) << legend << " not in " << py.output;
  EXPECT_EQ(py.output.find("at 0.3 MPa"), std::string::npos) << py.output;
}

namespace {

// A run folder of a strain-controlled 2D oedometer, written by hand: five samples, the size
// distribution at 5 % strain and (when `reached_10`) at 10 %, the mean shapes.
void write_strain_run(const fs::path& d, double scale, bool reached_10) {
  fs::create_directories(d);
  std::ofstream(d / "effective_scenario.json") << R"({"name": "synthetic", "dimension": 2, "loading": {"mode": "strain_rate"}})";
  std::ofstream s(d / "series.csv");
  s << "time_s,platen_stress_Pa,axial_strain,void_ratio,grains,breakage_events\n";
  std::ofstream sh(d / "shape.csv");
  sh << "time_s,step,axial_strain,platen_stress_Pa,grains,mean_circularity,mean_aspect_ratio,mean_sieve_size_m\n";
  for (int i = 0; i < 5; ++i) {
    const double e = 0.025 * i;
    s << 0.01 * i << "," << scale * 1e7 * i << "," << e << "," << 0.2 - e << "," << 10 + 5 * i << "," << 5 * i << "\n";
    sh << 0.01 * i << "," << 100 * i << "," << e << "," << scale * 1e7 * i << "," << 10 + 5 * i << ","
       << 0.9 - 0.05 * i * scale << "," << 0.8 - 0.04 * i << "," << 1e-3 << "\n";
  }
  std::ofstream p(d / "psd.csv");
  p << "label,platen_stress_Pa,sieve_diameter_m,percent_passing_by_mass,axial_strain,step\n";
  const std::vector<std::string> labels = {"initial", "strain_0.05",
                                           reached_10 ? "strain_0.1" : "strain_0.1_not_reached_final_at_0.08", "final"};
  for (std::size_t k = 0; k < labels.size(); ++k)
    for (int j = 0; j < 6; ++j)
      p << labels[k] << "," << 1e7 * k << "," << 2e-4 * (j + 1) << "," << std::min(100.0, (j + 1) * (10.0 + 15 * k * scale))
        << "," << 0.05 * k << "," << 100 * k << "\n";
}

}  // namespace

// A compare of strain-controlled runs: stress and void ratio against strain, the size
// distributions at each psd level a run reached (10 %: only the run that reached it; the one
// that stopped at 8 % is named as not reaching it), and the mean shapes against strain.
TEST(Plots, StrainCompareDrawsLevelsShapesAndVoidRatio) {
  SKIP_WITHOUT_MATPLOTLIB();
  const fs::path d = fresh_dir("strain_compare");
  fs::create_directories(d);
  std::ofstream(d / "comparison.csv") << "breakage.criterion,folder,status\nvon_mises,a,ok\ntresca,b,ok\n";
  write_strain_run(d / "a", 1.0, true);
  write_strain_run(d / "b", 1.3, false);
  const auto r = run_cli("plot " + d.string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* f : {"compare_stress_strain.png", "compare_psd_levels.png", "compare_shape.png"}) expect_png(d / f);
  const auto py = run_cli("--version >/dev/null; python3 -c \"import sys; sys.path.insert(0, '" +
                          std::string(CRUMBLE_SOURCE_DIR) + "/scripts'); import crumble_plot as p; print(p.reached_levels(["
                          "p.read_psd('" + (d / "a/psd.csv").string() + "'), p.read_psd('" + (d / "b/psd.csv").string() +
                          "')]))\"");
  ASSERT_EQ(py.status, 0) << py.output;
  EXPECT_NE(py.output.find("['strain_0.05', 'strain_0.1']"), std::string::npos) << py.output;
}
