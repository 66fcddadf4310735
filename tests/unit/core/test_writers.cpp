// Output writers agree with each other and with summary.json.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <fstream>
#include <string>

#include "scenarios/ScenarioFactory.h"
#include "output/Writers.h"
#include "tests/support/CliRunner.h"

using namespace crumble;
namespace fs = std::filesystem;

namespace {
const char* kTwoGrains = R"({"name": "w", "engine": {"type": "lsdem"},
  "container": {"lx": 0.01, "ly": 0.01, "height": 0.006},
  "packing": {"type": "grains", "grains": [
    {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.003, 0.005, 0.0011]},
    {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.007, 0.005, 0.0011]}]},
  "loading": {"mode": "stress_ramp", "max_stress": 5e6}, "time_step": 1e-8})";

struct Fixture {
  Scenario sc;
  fs::path dir;
  explicit Fixture(const std::string& name) {
    sc = build_scenario(parse_json_text(kTwoGrains, "w.json"), BuildOptions{});
    build_packing(*sc.sim, sc.packing);
    dir = fs::temp_directory_path() / "crumble_writer_test" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
};

BreakageEvent event(double stress, std::size_t children, double removed) {
  BreakageEvent e;
  e.platen_stress = stress;
  e.parent = 1;
  e.parent_diameter = 2e-3;
  e.parent_volume = 4.19e-9;
  for (std::size_t i = 0; i < children; ++i) {
    e.children.push_back(static_cast<GrainId>(10 + i));
    e.child_volumes.push_back(1e-9);
    e.child_diameters.push_back(1e-3);
  }
  e.removed_volume = removed;
  e.analysis.outcome = "split";
  return e;
}
}  // namespace

TEST(EventsWriter, BreakagePerMpaCountsEventsWhoseChildrenAllBecameFines) {
  Fixture f("per_mpa");
  EventsWriter w(f.dir.string(), {});
  RunState s;
  s.platen_stress = 2.5e6;
  // Two splits with children, one whose pieces were all removed as fines, one analysis
  // that did not break the grain: 3 events (what summary.json counts), in MPa bins 0, 1, 2.
  w.on_breakage(*f.sc.sim, event(0.5e6, 2, 0));
  w.on_breakage(*f.sc.sim, event(1.5e6, 0, 4.19e-9));
  AnalysisRecord intact;
  intact.platen_stress = 1.7e6;
  intact.analysis.outcome = "intact";
  w.on_analysis(*f.sc.sim, intact);
  w.on_breakage(*f.sc.sim, event(2.2e6, 3, 1e-10));
  RunSummary sum;
  w.on_finish(*f.sc.sim, s, sum);
  const auto rows = read_csv((f.dir / "breakage_per_mpa.csv").string());
  ASSERT_EQ(rows.size(), 4u);  // header + 0–1, 1–2, 2–3 MPa
  long total = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i][2], "1") << "bin " << rows[i][0];
    total += std::stol(rows[i][2]);
  }
  EXPECT_EQ(total, 3);
  // read_breakage_rows (what the metrics use): the header and the three breakage rows, in order.
  {
    // An intact analysis row (as written by the loop: its analysis, no breakage after it).
    std::ofstream o(f.dir / "events.csv", std::ios::app);
    o << "0,0,1700000,2,0.002,0,0,intact,0,0,,,0,\n";
  }
  ASSERT_EQ(read_csv((f.dir / "events.csv").string()).size(), 5u);
  const auto br = read_breakage_rows((f.dir / "events.csv").string());
  ASSERT_EQ(br.size(), 4u);
  EXPECT_EQ(br[0][0], "time_s");
  EXPECT_EQ(std::stod(br[1][2]), 0.5e6);
  EXPECT_EQ(std::stod(br[2][2]), 1.5e6);  // no children, only removed fines: still a breakage
  EXPECT_EQ(std::stod(br[3][2]), 2.2e6);
  EXPECT_TRUE(read_breakage_rows((f.dir / "nosuch.csv").string()).empty());
}

// output.intact_analyses false: only the analyses that broke their grain get a row.
TEST(EventsWriter, IntactAnalysesCanBeLeftOut) {
  Fixture f("no_intact");
  EventsWriter w(f.dir.string(), {}, -1, false);
  AnalysisRecord intact;
  intact.platen_stress = 1.7e6;
  intact.analysis.outcome = "intact";
  w.on_analysis(*f.sc.sim, intact);
  AnalysisRecord breaking = intact;
  breaking.analysis.outcome = "split";
  w.on_analysis(*f.sc.sim, breaking);
  w.on_breakage(*f.sc.sim, event(2.2e6, 2, 0));
  w.on_analysis(*f.sc.sim, intact);
  RunState s;
  s.platen_stress = 2.5e6;
  RunSummary sum;
  w.on_finish(*f.sc.sim, s, sum);
  const auto rows = read_csv((f.dir / "events.csv").string());
  ASSERT_EQ(rows.size(), 2u);  // header + the breakage
  EXPECT_EQ(rows[1][7], "split");
}

TEST(PsdWriter, LevelNotReachedIsWrittenWithTheFinalState) {
  Fixture f("psd");
  PsdWriter w(f.dir.string(), {1e6, 5e6});
  RunState s;
  w.on_start(*f.sc.sim, s);
  s.platen_stress = s.target_stress = 1.2e6;
  w.on_sample(*f.sc.sim, s);
  // The ramp ends a hair below loading.max_stress.
  s.platen_stress = s.target_stress = 5e6 * (1 - 1e-9);
  w.on_sample(*f.sc.sim, s);
  RunSummary sum;
  w.on_finish(*f.sc.sim, s, sum);
  const std::string psd = crumble::testing_support::slurp(f.dir / "psd.csv");
  EXPECT_NE(psd.find("\nlevel_1e+06,1200000,"), std::string::npos) << psd;
  EXPECT_NE(psd.find("\nlevel_5e+06_not_reached_final_at_4999999.995_Pa,4999999.995,"), std::string::npos) << psd;
  EXPECT_NE(psd.find("\nfinal,"), std::string::npos) << psd;
  // Every table has the same 25 sieves: initial, two levels, final.
  EXPECT_EQ(read_csv((f.dir / "psd.csv").string()).size(), 1u + 4 * 25);
}

TEST(PsdWriter, StrainLevelsGetTablesAndAResumeKeepsThem) {
  Fixture f("psd_strain");
  {
    PsdWriter w(f.dir.string(), {}, -1, {0.10, 0.05});
    RunState s;
    w.on_start(*f.sc.sim, s);
    s.axial_strain = 0.051;
    s.platen_stress = 2e6;
    w.on_sample(*f.sc.sim, s);
    RunSummary sum;
    w.on_finish(*f.sc.sim, s, sum);  // 0.10 never reached
  }
  std::string psd = crumble::testing_support::slurp(f.dir / "psd.csv");
  EXPECT_EQ(psd.rfind("label,platen_stress_Pa,sieve_diameter_m,percent_passing_by_mass,axial_strain,step\n", 0), 0u);
  EXPECT_NE(psd.find("\nstrain_0.05,2000000,"), std::string::npos) << psd;
  EXPECT_NE(psd.find(",0.051,0\n"), std::string::npos);
  EXPECT_NE(psd.find("\nstrain_0.1_not_reached_final_at_0.051,"), std::string::npos);
  // Resumed at strain 0.06: the 5 % table is kept (not written twice), the 10 % one follows.
  PsdWriter r(f.dir.string(), {}, 2e6, {0.05, 0.10}, 0.06);
  RunState s;
  s.axial_strain = 0.06;
  r.on_start(*f.sc.sim, s);
  s.axial_strain = 0.12;
  r.on_sample(*f.sc.sim, s);
  RunSummary sum;
  r.on_finish(*f.sc.sim, s, sum);
  const auto rows = read_csv((f.dir / "psd.csv").string());
  std::map<std::string, int> n;
  for (std::size_t i = 1; i < rows.size(); ++i) ++n[rows[i][0]];
  EXPECT_EQ(n["initial"], 25);
  EXPECT_EQ(n["strain_0.05"], 25);
  EXPECT_EQ(n["strain_0.1"], 25);
  EXPECT_EQ(n["final"], 25);
  EXPECT_EQ(n.count("strain_0.1_not_reached_final_at_0.051"), 0u);
}

TEST(ShapeWriter, MeansOfTheGrainsDescriptorsPerSample) {
  // Two spheres of the 3D fixture: icosphere meshes (42 vertices) have sphericity < 1 and
  // isotropic inertia; their extents along the principal axes (Zhu & Zhao 2019 §5) are the
  // diameter within the facets' chord error, ≈ 2 % for 42 vertices, so EI, FI = 1 within 3 %.
  Fixture f("shape");
  {
    ShapeWriter w(f.dir.string(), 3);
    RunState s;
    w.on_start(*f.sc.sim, s);
    s.step = 10;
    s.axial_strain = 0.01;
    w.on_sample(*f.sc.sim, s);
    w.on_sample(*f.sc.sim, s);  // same step: no second row
    RunSummary sum;
    w.on_finish(*f.sc.sim, s, sum);
    EXPECT_NEAR(sum.extra["mean_zingg_ei_final"], 1.0, 0.03);
  }
  const auto rows = read_csv((f.dir / "shape.csv").string());
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0][5], "mean_sphericity");
  const double sph = std::stod(rows[2][5]);
  EXPECT_GT(sph, 0.95);
  EXPECT_LT(sph, 1.0);
  EXPECT_NEAR(std::stod(rows[2][6]), 1.0, 0.03);
  EXPECT_NEAR(std::stod(rows[2][7]), 1.0, 0.03);
}

TEST(SeriesWriter, K0IsTheLastColumnAndEmptyWithoutVerticalStress) {
  // Two spheres on the floor, clear of the side walls: the walls carry nothing, so K0 = 0 once
  // the platen carries a stress, and an empty cell (never NaN) while it carries none.
  Fixture f("series_k0");
  RunSummary sum;
  {
    SeriesWriter w(f.dir.string());
    RunState s;
    s.step = 1;
    s.platen_height = 0.006;
    w.on_sample(*f.sc.sim, s);
    s.step = 2;
    s.platen_stress = 1e6;
    w.on_sample(*f.sc.sim, s);
    w.on_finish(*f.sc.sim, s, sum);
  }
  const auto rows = read_csv((f.dir / "series.csv").string());
  ASSERT_EQ(rows.size(), 3u);
  ASSERT_EQ(rows[0].size(), 14u);
  EXPECT_EQ(rows[0][12], "floor_force_N");  // the earlier columns keep their order
  EXPECT_EQ(rows[0][13], "k0");
  EXPECT_EQ(rows[1][13], "");
  EXPECT_EQ(rows[2][13], "0");
  EXPECT_EQ(sum.extra["k0_final"], 0.0);
}
