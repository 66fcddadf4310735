// Study files (studies/*.json, `crumble sweep --study`, docs/speed-accuracy.md): every shipped
// study parses into the sweep it describes and names only known metrics; a tiny study runs end
// to end and its table equals the one the same sweep on the command line gives; the shipped
// lsdem study (the smallest, ≈ 5 s of CPU) runs from the checkout; malformed studies and
// command lines that mix a study with --param are refused with exit 2, naming the JSON path.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "tools/Compare.h"
#include "run/RunPipeline.h"
#include "tools/Sweep.h"
#include "output/Writers.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::testing_support::run_cli;
using crumble::testing_support::scenario_file;
using crumble::testing_support::slurp;

namespace {

const fs::path kSource(CRUMBLE_SOURCE_DIR);

fs::path out_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path d = fs::temp_directory_path() / "crumble_studies_test" / info->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::vector<fs::path> shipped_studies() {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(kSource / "studies")) {
    if (e.path().extension() != ".json") continue;
    const Json j = Json::parse(slurp(e.path()));
    if (j.contains("study")) out.push_back(e.path());  // the folder also holds the scenarios studies use
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(Studies, EveryShippedStudyParsesIntoItsSweep) {
  const auto studies = shipped_studies();
  ASSERT_GE(studies.size(), 8u);
  for (const auto& f : studies) {
    SCOPED_TRACE(f.string());
    const Json j = Json::parse(slurp(f));
    crumble::SweepRequest req;
    ASSERT_NO_THROW(req = crumble::load_study(f.string(), crumble::SweepRequest{}, false, false));
    EXPECT_TRUE(req.scenario.is_object());
    ASSERT_EQ(req.params.size(), j["params"].size());
    ASSERT_EQ(req.values.size(), req.params.size());
    for (std::size_t i = 0; i < req.params.size(); ++i) {
      EXPECT_EQ(req.params[i], j["params"][i]["path"].get<std::string>());
      // One value per entry of the study's list (objects keep their commas inside braces).
      EXPECT_EQ(crumble::parse_vary(req.params[i] + "=" + req.values[i]).values.size(), j["params"][i]["values"].size());
    }
    EXPECT_EQ(req.metrics.size(), j.value("metrics", Json::array()).size());
    EXPECT_EQ(req.threads.value_or(0), j.value("threads", 0));
    // The scenario with every fixed value builds (the sweep checks every setting again).
    crumble::RunRequest rr;
    rr.scenario = req.scenario;
    rr.source_name = req.source_name;
    rr.sets = req.sets;
    EXPECT_NO_THROW(crumble::build_request(rr));
  }
}

TEST(Studies, ValuesReferencesAndCommandLineAdditions) {
  const std::string f = scenario_file("crumble_studies", "s.json", R"({
    "study": "s", "scenario": ")" + (kSource / "scenarios/single_grain_pd.json").string() + R"(",
    "set": ["output.vtk_final=false"],
    "params": [{"path": "breakage.spacing_fraction", "values": [0.2, 0.15], "reference": 0.2},
               {"path": "fragments", "values": [{"type": "level_set"}, {"type": "alpha_shape"}]},
               {"path": "breakage.weibull", "values": [false]}],
    "metrics": ["crushing_force"], "threads": 1, "jobs": 2, "seed": 5})");
  crumble::SweepRequest cli;
  cli.sets = {"breakage.gc0=20"};
  cli.threads = 2;
  const auto r = crumble::load_study(f, cli, false, false);
  EXPECT_EQ(r.source_name, (kSource / "scenarios/single_grain_pd.json").lexically_normal().string());
  EXPECT_EQ(r.values, (std::vector<std::string>{"0.2,0.15", R"({"type":"level_set"},{"type":"alpha_shape"})", "false"}));
  // A reference on one param: the others take their last value.
  EXPECT_EQ(r.reference, (std::vector<std::string>{"0.2", R"({"type":"alpha_shape"})", "false"}));
  // The study's --set first, the command line's after (it wins); the command line's threads win.
  EXPECT_EQ(r.sets, (std::vector<std::string>{"output.vtk_final=false", "breakage.gc0=20"}));
  EXPECT_EQ(r.threads.value_or(0), 2);
  EXPECT_EQ(r.jobs, 2);
  EXPECT_EQ(r.seed.value_or(0), 5u);
  // --jobs on the command line wins over the study's.
  crumble::SweepRequest cli_jobs;
  cli_jobs.jobs = 1;
  EXPECT_EQ(crumble::load_study(f, cli_jobs, false, true).jobs, 1);
}

TEST(Studies, MalformedStudiesNameTheFileAndPath) {
  const std::string sg = (kSource / "scenarios/single_grain_pd.json").string();
  struct Case {
    std::string text, path, words;
  };
  const std::vector<Case> cases = {
      {R"([1])", "/", "JSON object"},
      {R"({"scenario": ")" + sg + R"(", "params": [{"path": "a", "values": [1]}]})", "/study", ""},
      {R"({"study": "x", "params": [{"path": "a", "values": [1]}]})", "/scenario", "missing"},
      {R"({"study": "x", "scenario": "no_such.json", "params": [{"path": "a", "values": [1]}]})", "/scenario",
       "no scenario file"},
      {R"({"study": "x", "scenario": 3, "params": [{"path": "a", "values": [1]}]})", "/scenario", "file name"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "params": []})", "/params", "at least one"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "params": [{"path": "a", "values": []}]})", "/params/0/values",
       "non-empty"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "params": [{"path": "a=1", "values": [1]}]})", "/params/0/path",
       "scenario path"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "params": [{"path": "a", "values": ["b,c"]}]})",
       "/params/0/values/0", "commas"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "params": [{"path": "a", "values": [null]}]})",
       "/params/0/values/0", "not null"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "params": [{"path": "a", "values": [1], "refrence": 1}]})",
       "/params/0/refrence", "unknown key"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "set": "a=1", "params": [{"path": "a", "values": [1]}]})", "/set",
       "array"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "set": ["a"], "params": [{"path": "a", "values": [1]}]})",
       "/set/0", "path=value"},
      {R"({"study": "x", "scenario": ")" + sg + R"(", "threads": 0, "params": [{"path": "a", "values": [1]}]})",
       "/threads", ""},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].text);
    const std::string f = scenario_file("crumble_studies", "bad" + std::to_string(i) + ".json", cases[i].text);
    try {
      crumble::load_study(f, crumble::SweepRequest{}, false, false);
      ADD_FAILURE() << "accepted";
    } catch (const crumble::ConfigError& e) {
      EXPECT_EQ(e.path(), cases[i].path) << e.what();
      EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(cases[i].words), std::string::npos) << e.what();
    }
  }
  // An unknown metric: exit 2 naming the entry.
  const std::string m = scenario_file("crumble_studies", "m.json", R"({"study": "x", "scenario": ")" + sg +
                                                                       R"(", "params": [{"path": "a", "values": [1]}], "metrics": ["crush"]})");
  EXPECT_THROW(crumble::load_study(m, crumble::SweepRequest{}, false, false), crumble::InputError);
  // The CLI: a study with --param or a scenario is exit 2 before anything runs; so is a
  // malformed study and a sweep with neither a scenario nor a study.
  const fs::path out = out_dir();
  const std::string study = (kSource / "studies/pd_spacing.json").string();
  for (const std::string& args :
       {"sweep --study " + study + " --out " + (out / "a").string() + " --param x --values 1",
        "sweep " + sg + " --study " + study + " --out " + (out / "b").string(),
        "sweep --study " + m + " --out " + (out / "c").string(), "sweep --out " + (out / "d").string(),
        "sweep " + sg + " --out " + (out / "e").string()}) {
    SCOPED_TRACE(args);
    const auto r = run_cli(args);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(out / "a"));
  EXPECT_FALSE(fs::exists(out / "b" / "sweep.csv"));
}

TEST(Studies, TinyStudyRunsAsTheSameSweepOnTheCommandLine) {
  const fs::path out = out_dir();
  const std::string sg = (kSource / "scenarios/single_grain_pd.json").string();
  // Coarse lattices of the single grain (Zhu & Zhao 2019 §4.2): about a second each.
  const std::string f = scenario_file("crumble_studies", "tiny.json", R"({
    "study": "tiny", "scenario": ")" + sg + R"(", "set": ["output.vtk_final=false"],
    "params": [{"path": "breakage.spacing_fraction", "values": [0.2, 0.15]}],
    "metrics": ["crushing_force", "largest_fragment_volume"], "threads": 1})");
  const auto a = run_cli("sweep --study " + f + " --out " + (out / "study").string() + " --quiet");
  ASSERT_EQ(a.status, 0) << a.output;
  const auto b = run_cli("sweep " + sg + " --out " + (out / "cli").string() +
                         " --param breakage.spacing_fraction --values 0.2,0.15 --metric crushing_force"
                         " --metric largest_fragment_volume --set output.vtk_final=false --threads 1 --quiet");
  ASSERT_EQ(b.status, 0) << b.output;
  const auto ta = crumble::read_csv((out / "study" / "sweep.csv").string());
  const auto tb = crumble::read_csv((out / "cli" / "sweep.csv").string());
  ASSERT_EQ(ta.size(), 3u);
  ASSERT_EQ(ta[0], tb[0]);
  for (std::size_t i = 0; i < ta[0].size(); ++i) {
    const std::string& col = ta[0][i];
    if (col.rfind("time_", 0) == 0 || col == "wall_seconds" || col == "peak_rss_bytes" || col == "on_front") continue;
    for (std::size_t r = 1; r < ta.size(); ++r) EXPECT_EQ(ta[r][i], tb[r][i]) << col << " row " << r;
  }
  // 0.15 breaks (a crushing force and its largest child); 0.2 has too few points to break.
  const std::size_t v = [&] {
    for (std::size_t i = 0; i < ta[0].size(); ++i)
      if (ta[0][i] == "largest_fragment_volume_m3") return i;
    return ta[0].size();
  }();
  ASSERT_LT(v, ta[0].size());
  EXPECT_EQ(ta[1][v], "");
  const double vol = std::stod(ta[2][v]);
  // The largest child of a 2 mm grain: below the grain's volume, above a tenth of it.
  const double grain = 3.14159265358979 / 6 * 8e-9;
  EXPECT_LT(vol, grain);
  EXPECT_GT(vol, 0.1 * grain);
}

TEST(Studies, ShippedLsdemStudyRunsFromTheCheckout) {
  const fs::path out = out_dir();
  const auto r = run_cli("sweep --study " + (kSource / "studies/lsdem_dt_safety.json").string() + " --out " +
                         out.string() + " --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto t = crumble::read_csv((out / "sweep.csv").string());
  ASSERT_EQ(t.size(), 6u);
  std::size_t err = t[0].size(), ref = t[0].size(), front = t[0].size();
  for (std::size_t i = 0; i < t[0].size(); ++i) {
    if (t[0][i] == "error") err = i;
    if (t[0][i] == "reference") ref = i;
    if (t[0][i] == "on_front") front = i;
  }
  ASSERT_LT(err, t[0].size());
  ASSERT_LT(front, t[0].size());
  EXPECT_EQ(t[5][ref], "1");
  EXPECT_EQ(std::stod(t[5][err]), 0.0);
  EXPECT_EQ(t[5][front], "1");  // the reference has error 0: nothing dominates it
  for (std::size_t r2 = 1; r2 < 5; ++r2) {
    // Every coarser step has a finite error, and the void ratios of a rigid 2D cell differ by
    // at most a few per cent (measured: ≤ 8 %, docs/speed-accuracy.md).
    const double e = std::stod(t[r2][err]);
    EXPECT_GE(e, 0.0);
    EXPECT_LT(e, 0.2);
  }
  EXPECT_TRUE(fs::exists(out / "pareto.md"));
}

TEST(Studies, ListAndValidateShowTheFidelityPresets) {
  const auto l = run_cli("list");
  ASSERT_EQ(l.status, 0) << l.output;
  EXPECT_NE(l.output.find("fidelity presets"), std::string::npos) << l.output;
  for (const char* k : {"breakage.spacing_fraction", "engine.solver_iterations", "engine.dt_safety"})
    EXPECT_NE(l.output.find(k), std::string::npos) << k;
  const std::string sg = (kSource / "scenarios/single_grain_pd.json").string();
  const auto ok = run_cli("validate " + sg + " --set fidelity=fast --print");
  ASSERT_EQ(ok.status, 0) << ok.output;
  EXPECT_NE(ok.output.find("note: fidelity 'fast' sets breakage.spacing_fraction="), std::string::npos) << ok.output;
  const auto bad = run_cli("validate " + sg + " --set fidelity=fastest");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("/fidelity: unknown preset 'fastest'; expected one of: fast, balanced, accurate"),
            std::string::npos)
      << bad.output;
}
