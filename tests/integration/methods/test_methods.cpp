// Named methods (scenarios/Methods.h) and what the fidelity presets report: a method fills the
// keys it governs that the scenario leaves out, a value in the file or a --set wins, a bad name
// is an error at /method listing the methods, validate --print and summary.json say what it
// set; `compare --vary method=...` runs both methods from one packing; a preset that changes
// nothing says so and why, on stderr and in summary.json.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "crumble_config.h"
#include "output/Writers.h"
#include "run/RunPipeline.h"
#include "scenarios/Methods.h"
#include "scenarios/ScenarioFactory.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using namespace crumble;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

namespace {

const std::string kSource(CRUMBLE_SOURCE_DIR);

// A 3D cell with no implementation named: the method chooses them.
Json bare(const std::string& method) {
  return Json{{"method", method},
              {"container", {{"lx", 0.004}, {"ly", 0.004}}},
              {"packing", {{"type", "cloud"}, {"count", 4}, {"diameter", 0.0015}, {"settle", {{"enabled", false}}}}}};
}

bool has_note(const Scenario& sc, const std::string& text) {
  for (const auto& n : sc.notes)
    if (n == text) return true;
  return false;
}

// A fresh folder for the current test (under $TMPDIR, one per test: ctest runs them in parallel).
fs::path test_dir(const Json& scenario, const std::string& name) {
  const fs::path f = testing_support::scenario_file("crumble_methods_test", name, scenario.dump(2));
  fs::remove_all(f.parent_path() / "out");
  return f.parent_path();
}

}  // namespace

TEST(Methods, EachMethodSetsTheKeysItGoverns) {
  for (const auto& m : methods().entries()) {
    SCOPED_TRACE(m.name);
#if !CRUMBLE_WITH_BULLET || !CRUMBLE_WITH_CGAL
    if (m.name == "zhu_zhao_2019") continue;
#endif
    const Scenario sc = build_scenario(bare(m.name), BuildOptions{});
    ASSERT_FALSE(m.settings.empty());
    for (const auto& s : m.settings) {
      std::string ptr = "/";
      for (char c : s.path) ptr.push_back(c == '.' ? '/' : c);
      EXPECT_EQ(sc.effective.at(Json::json_pointer(ptr)), s.value) << s.path;
      EXPECT_TRUE(has_note(sc, "method '" + m.name + "' sets " + s.path + "=" + s.value.dump())) << s.path;
    }
    EXPECT_EQ(sc.presets.at("method").at("name"), m.name);
    EXPECT_EQ(sc.presets.at("method").at("sets").size(), m.settings.size());
  }
  const Scenario z = build_scenario(bare("harmon_2020"), BuildOptions{});
  EXPECT_EQ(z.engine_name, "lsdem");
  EXPECT_EQ(z.breakage_name, "stress");
  EXPECT_EQ(z.fragments_name, "level_set");
#if CRUMBLE_WITH_BULLET && CRUMBLE_WITH_CGAL
  const Scenario h = build_scenario(bare("zhu_zhao_2019"), BuildOptions{});
  EXPECT_EQ(h.engine_name, "bullet");
  EXPECT_EQ(h.breakage_name, "peridynamics");
  EXPECT_EQ(h.fragments_name, "alpha_shape");
  EXPECT_EQ(h.effective["time_step"].size(), 3u);
  EXPECT_EQ(h.effective["engine"]["mass_scale"].get<double>(), 70.0);
#endif
}

TEST(Methods, FileAndSetValuesWinOverTheMethod) {
  Json doc = bare("harmon_2020");
  doc["schedule"] = {{"every_steps", 7}};         // in the file
  doc["breakage"] = {{"criterion", "tresca"}};    // a key the method does not govern: kept
  BuildOptions opt;
  opt.overrides = {"screening.min_diameter=1e-4"};  // on the command line
  const Scenario sc = build_scenario(doc, opt);
  EXPECT_EQ(sc.effective["schedule"]["every_steps"].get<int>(), 7);
  EXPECT_EQ(sc.effective["screening"]["min_diameter"].get<double>(), 1e-4);
  EXPECT_EQ(sc.effective["breakage"]["criterion"], "tresca");
  EXPECT_EQ(sc.breakage_name, "stress");
  EXPECT_TRUE(has_note(sc, "method 'harmon_2020' leaves schedule.every_steps, screening.min_diameter as the scenario "
                           "or --set gives them"));
  const Json left = sc.presets.at("method").at("left_as_given");
  EXPECT_EQ(left, Json::array({"schedule.every_steps", "screening.min_diameter"}));
  // --set method=... chooses the method over the file's; --set engine.type over the method's.
  BuildOptions other;
  other.overrides = {"method=harmon_2020", "engine.type=lsdem", "breakage.type=none"};
  Json z = bare("zhu_zhao_2019");
  const Scenario b = build_scenario(z, other);
  EXPECT_EQ(b.effective["method"], "harmon_2020");
  EXPECT_EQ(b.breakage_name, "none");
}

TEST(Methods, ABadMethodIsAnErrorAtMethodListingTheMethods) {
  for (const Json& bad : {Json("zhu_zhao"), Json(""), Json(2019), Json::array({"harmon_2020"})}) {
    SCOPED_TRACE(bad.dump());
    Json doc = bare("harmon_2020");
    doc["method"] = bad;
    try {
      build_scenario(doc, BuildOptions{});
      ADD_FAILURE() << "accepted";
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.path(), "/method");
      EXPECT_NE(std::string(e.what()).find("zhu_zhao_2019, harmon_2020"), std::string::npos) << e.what();
    }
  }
  const auto r = run_cli("validate " + kSource + "/scenarios/oedometer_harmon_2d_quick.json --set method=harmon");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("/method: unknown method 'harmon'; expected one of: zhu_zhao_2019, harmon_2020"),
            std::string::npos)
      << r.output;
}

TEST(Methods, AMethodCanBeRegistered) {
  MethodTable t;
  t.add({"mine", "a test method", {{"engine.type", "lsdem", "test"}}});
  EXPECT_THROW(t.add({"mine", "twice", {}}), std::invalid_argument);
  EXPECT_THROW(t.add({"", "no name", {}}), std::invalid_argument);
  EXPECT_THROW(t.add({"bad_path", "", {{"engine..type", "lsdem", "test"}}}), std::invalid_argument);
  EXPECT_NE(t.find("mine"), nullptr);
  EXPECT_EQ(t.find("yours"), nullptr);
}

TEST(Methods, ValidatePrintShowsWhatTheMethodSet) {
#if !CRUMBLE_WITH_BULLET || !CRUMBLE_WITH_CGAL
  GTEST_SKIP() << "needs Bullet and CGAL";
#endif
  const auto r = run_cli("validate " + kSource + "/scenarios/oedometer_zhu_zhao_quick.json --print");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* n : {"note: method 'zhu_zhao_2019' sets engine.type=\"bullet\"",
                        "note: method 'zhu_zhao_2019' sets schedule.every_stress=80000.0",
                        "note: method 'zhu_zhao_2019' leaves engine.mass_scale, engine.solver_iterations, "
                        "engine.solver_tolerance as the scenario or --set gives them",
                        "\"mass_scale\": 70", "\"every_stress\": 80000.0", "\"min_diameter\": 0.0003"})
    EXPECT_NE(r.output.find(n), std::string::npos) << n << "\n" << r.output;
}

// The shipped Zhu & Zhao files name the method instead of the keys it governs; their
// effective values are the ones they spelled out before (Zhu & Zhao 2019 §2.2, §5).
TEST(Methods, ShippedZhuZhaoFilesKeepTheirValues) {
#if !CRUMBLE_WITH_BULLET || !CRUMBLE_WITH_CGAL
  GTEST_SKIP() << "needs Bullet and CGAL";
#endif
  for (const char* f : {"oedometer_zhu_zhao.json", "oedometer_zhu_zhao_quick.json"}) {
    SCOPED_TRACE(f);
    const Json doc = load_scenario_file(kSource + "/scenarios/" + f);
    EXPECT_EQ(doc["method"], "zhu_zhao_2019");
    EXPECT_FALSE(doc.contains("time_step"));
    const Json e = build_scenario(doc, BuildOptions{}).effective;
    const bool quick = std::string(f).find("quick") != std::string::npos;
    EXPECT_EQ(e["engine"]["type"], "bullet");
    EXPECT_EQ(e["engine"]["mass_scale"].get<double>(), 70);
    EXPECT_EQ(e["engine"]["solver_iterations"].get<int>(), quick ? 1000 : 2000);
    EXPECT_EQ(e["engine"]["solver_tolerance"].get<double>(), quick ? 2e-4 : 0.0);
    EXPECT_EQ(e["breakage"]["type"], "peridynamics");
    EXPECT_EQ(e["breakage"]["gc0"].get<double>(), 30);
    EXPECT_EQ(e["breakage"]["weibull_modulus"].get<double>(), 3.1);
    EXPECT_EQ(e["fragments"]["type"], "alpha_shape");
    EXPECT_EQ(e["schedule"]["every_stress"].get<double>(), 0.08e6);
    EXPECT_EQ(e["screening"]["min_diameter"].get<double>(), 0.3e-3);
    EXPECT_EQ(e["screening"]["max_unbalanced_force_ratio"].get<double>(), 0.02);
    EXPECT_EQ(e["screening"]["max_unbalanced_moment_ratio"].get<double>(), 0.2);
    EXPECT_EQ(e["time_step"], Json::parse(R"([{"below_stress": 1e7, "dt": 8e-5}, {"below_stress": 2.4e7, "dt": 6e-5},
                                             {"below_stress": 1e300, "dt": 5e-5}])"));
  }
}

// The two methods from one packing: the Zhu & Zhao file reduced to 8 grains and 1 MPa (soft
// lsdem contacts and mass scaling keep the lsdem run to a few thousand steps).
TEST(Methods, CompareVaryMethodRunsBothFromOnePacking) {
#if !CRUMBLE_WITH_BULLET || !CRUMBLE_WITH_CGAL
  GTEST_SKIP() << "needs Bullet and CGAL";
#endif
  Json doc = load_scenario_file(kSource + "/scenarios/oedometer_zhu_zhao_quick.json");
  doc["container"] = {{"lx", 0.004}, {"ly", 0.004}};
  doc["packing"]["count"] = 8;
  doc["engine"]["kn"] = 2e5;
  doc["engine"]["mass_scale"] = 100;
  doc["loading"] = {{"mode", "stress_ramp"}, {"max_stress", 1e6}, {"ramp_time", 0.005}};
  doc["output"] = {{"psd_at_stress", {1e6}}, {"vtk_final", false}, {"shape_metrics", false}, {"plots", false}};
  doc["threads"] = 1;
  const fs::path dir = test_dir(doc, "zz_tiny.json");
  const fs::path f = dir / "zz_tiny.json";
  const fs::path out = dir / "out";
  const auto r = run_cli("compare " + f.string() + " --out " + out.string() +
                         " --vary method=zhu_zhao_2019,harmon_2020 --threads 1 --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto rows = read_csv((out / "comparison.csv").string());
  ASSERT_EQ(rows.size(), 3u) << slurp(out / "comparison.csv");
  const std::string hash = file_sha256((out / "packing.json").string());
  const auto col = [&](const std::string& n) { return testing_support::column(rows, n); };
  const char* expect[2][4] = {{"zhu_zhao_2019", "bullet", "peridynamics", "alpha_shape"},
                              {"harmon_2020", "lsdem", "stress", "level_set"}};
  for (int i = 0; i < 2; ++i) {
    const auto& row = rows[i + 1];
    EXPECT_EQ(row[0], expect[i][0]);
    EXPECT_EQ(row[col("status")], "ok");
    EXPECT_EQ(row[col("engine")], expect[i][1]);
    EXPECT_EQ(row[col("breakage")], expect[i][2]);
    EXPECT_EQ(row[col("fragments")], expect[i][3]);
    EXPECT_EQ(row[col("packing_hash")], hash);
    const Json s = Json::parse(slurp(out / ("method=" + std::string(expect[i][0])) / "summary.json"));
    EXPECT_EQ(s.at("method").at("name"), expect[i][0]);
    EXPECT_FALSE(s.at("method").at("sets").empty());
  }
  EXPECT_TRUE(fs::exists(out / "comparison.md"));
}

// Done-when of the presets: on the rigid quick oedometer (Bullet, its solver iterations given)
// the fast preset changes nothing and says so, and why.
TEST(Methods, APresetThatChangesNothingSaysSo) {
#if !CRUMBLE_WITH_BULLET
  GTEST_SKIP() << "needs Bullet";
#endif
  const std::string rigid = kSource + "/scenarios/oedometer_rigid_quick.json";
  Json doc = load_scenario_file(rigid);
  doc["engine"].erase("solver_iterations");
  const fs::path dir = test_dir(doc, "rigid_no_iterations.json");
  const std::string why =
      "note: fidelity 'fast' changes nothing: every key it governs here is already set (engine.solver_iterations "
      "given by the scenario or --set)";
  const auto v = run_cli("validate " + rigid + " --set fidelity=fast");
  ASSERT_EQ(v.status, 0) << v.output;
  EXPECT_NE(v.output.find(why), std::string::npos) << v.output;
  // A run (8 grains, 20 steps) says it on stderr and records it in summary.json.
  const fs::path out = dir / "out";
  const auto r = run_cli("run " + rigid + " --set fidelity=fast --set packing.count=8 --set simulation.max_steps=20 " +
                         "--set output.plots=false --set output.vtk_final=false --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(why), std::string::npos) << r.output;
  const Json s = Json::parse(slurp(out / "summary.json"));
  const Json& f = s.at("fidelity");
  EXPECT_EQ(f.at("preset"), "fast");
  EXPECT_EQ(f.at("changes_nothing"), true);
  EXPECT_EQ(f.at("left_as_given"), Json::array({"engine.solver_iterations"}));
  EXPECT_TRUE(f.at("sets").empty());
  EXPECT_NE(f.at("note").get<std::string>().find("already set"), std::string::npos);
  // With the key left out the same preset acts, and says what it set.
  const fs::path f2 = dir / "rigid_no_iterations.json";
  const auto acts = run_cli("validate " + f2.string() + " --set fidelity=fast");
  EXPECT_NE(acts.output.find("fidelity 'fast' sets engine.solver_iterations=300"), std::string::npos) << acts.output;
}

// A preset on a method file: it sets what neither gives, and names what it left to each.
TEST(Methods, APresetNamesWhatItLeftToTheFileAndToTheMethod) {
#if !CRUMBLE_WITH_BULLET || !CRUMBLE_WITH_CGAL
  GTEST_SKIP() << "needs Bullet and CGAL";
#endif
  BuildOptions opt;
  opt.overrides = {"fidelity=fast"};
  const Scenario sc = build_scenario(load_scenario_file(kSource + "/scenarios/oedometer_zhu_zhao_quick.json"), opt);
  EXPECT_TRUE(has_note(sc, "fidelity 'fast' sets breakage.spacing_fraction=0.1"));
  EXPECT_TRUE(has_note(sc, "fidelity 'fast' sets breakage.density_scale=64"));
  EXPECT_TRUE(has_note(sc, "fidelity 'fast' leaves engine.solver_iterations given by the scenario or --set; "
                           "schedule.every_stress set by method 'zhu_zhao_2019'"));
  const Json& f = sc.presets.at("fidelity");
  EXPECT_EQ(f.at("changes_nothing"), false);
  EXPECT_EQ(f.at("left_as_method_set"), Json::array({"schedule.every_stress"}));
}

// On an lsdem method file whose dt_safety is given, the preset says it changes nothing.
TEST(Methods, APresetOnAnLsdemFileWithItsKnobGivenSaysSo) {
  Json doc = bare("harmon_2020");
  doc["engine"] = {{"dt_safety", 0.3}};
  doc["fidelity"] = "accurate";
  const Scenario sc = build_scenario(doc, BuildOptions{});
  EXPECT_TRUE(has_note(sc, "fidelity 'accurate' changes nothing: every key it governs here is already set "
                           "(engine.dt_safety given by the scenario or --set)"));
  EXPECT_EQ(sc.presets.at("fidelity").at("changes_nothing"), true);
  EXPECT_EQ(sc.effective["engine"]["dt_safety"].get<double>(), 0.3);
}
