// `crumble compare` end to end: one packing for every combination (same SHA-256 in every
// summary.json, same initial grains and void ratio), one folder and one table row per
// combination, a guard failure as a row (exit 1), bad --vary input refused (exit 2) before
// anything runs; and the pieces it is made of (--vary parsing, SHA-256).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "crumble_config.h"
#include "tools/Compare.h"
#include "run/RunPipeline.h"
#include "run/ThreadCheck.h"
#include "output/Writers.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

namespace {

// 10 spheres settled under 10 kPa, loaded to 2 MPa; soft lsdem contacts and mass scaling
// keep it to a few seconds per run.
const char* kTiny = R"({
  "name": "compare_tiny", "dimension": 3, "seed": 3,
  "engine": {"type": "lsdem", "mass_scale": 100, "kn": 2e5},
  "breakage": {"type": "stress", "criterion": "von_mises", "weibull": false, "strength": 15e6},
  "fragments": {"type": "level_set"},
  "container": {"lx": 0.005, "ly": 0.005},
  "packing": {"type": "cloud", "count": 10, "psd": [[0.0015, 0], [0.002, 1]], "shape": {"type": "sphere"},
              "settle": {"stress": 1e4, "max_time": 0.02}},
  "loading": {"mode": "stress_ramp", "max_stress": 2e6, "ramp_time": 0.01},
  "time_step": 5e-5,
  "output": {"psd_at_stress": [1e6, 2e6], "vtk_final": false, "shape_metrics": false}
})";

fs::path test_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path d = fs::temp_directory_path() / "crumble_compare_test" / info->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string scenario(const fs::path& dir) {
  const fs::path f = dir / "tiny.json";
  std::ofstream(f) << kTiny;
  return f.string();
}

void expect_bad(const std::string& args, const fs::path& out, const std::vector<std::string>& needles) {
  const auto r = run_cli(args + " --out " + out.string());
  EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
  for (const auto& n : needles) EXPECT_NE(r.output.find(n), std::string::npos) << "'" << n << "' not in:\n" << r.output;
  // Checked before anything runs: no folder, no packing.
  EXPECT_FALSE(fs::exists(out / "packing.json")) << args;
  EXPECT_FALSE(fs::exists(out / "logs")) << args;
}

}  // namespace

TEST(Compare, TwoEnginesTimesTwoModelsFromOnePacking) {
#if CRUMBLE_WITH_BULLET
  const std::string engines = "lsdem,bullet";
#else
  const std::string engines = "lsdem";
#endif
  const fs::path dir = test_dir();
  const fs::path out = dir / "out";
  const auto r = run_cli("compare " + scenario(dir) + " --out " + out.string() + " --vary engine.type=" + engines +
                         " --vary breakage.type=none,stress --threads 1 --quiet");
  ASSERT_EQ(r.status, 0) << r.output;

  const std::string hash = crumble::file_sha256((out / "packing.json").string());
  ASSERT_EQ(hash.size(), 64u);
  std::vector<std::string> folders;
  for (const auto& e : {std::string("lsdem"), std::string("bullet")}) {
    if (engines.find(e) == std::string::npos) continue;
    for (const char* m : {"none", "stress"}) folders.push_back("engine.type=" + e + "__breakage.type=" + m);
  }
  double e0 = -1, e_relaxed_from = -1;
  for (const auto& f : folders) {
    SCOPED_TRACE(f);
    ASSERT_TRUE(fs::exists(out / f / "summary.json"));
    const Json s = Json::parse(slurp(out / f / "summary.json"));
    // The identical packing: the same bytes and grains.
    EXPECT_EQ(s.at("packing_hash").get<std::string>(), hash);
    EXPECT_EQ(s.at("grains_initial").get<int>(), 10);
    if (f.find("engine.type=lsdem") != std::string::npos) {
      // The packing's own engine (lsdem) loads it as it is: not settled again, not relaxed,
      // the same (container height, solid volume) e0 in every such row.
      if (e0 < 0) e0 = s.at("void_ratio_initial").get<double>();
      EXPECT_NEAR(s.at("void_ratio_initial").get<double>(), e0, 1e-9 * e0);
      EXPECT_EQ(s.at("packing_settle_steps").get<double>(), 0.0);
      EXPECT_EQ(s.at("packing_relaxed").get<double>(), 0.0);
    } else {
      // Another engine relaxes it first (packing.relax auto), from the file's void ratio.
      EXPECT_EQ(s.at("packing_relaxed").get<double>(), 1.0);
      EXPECT_GT(s.at("packing_settle_steps").get<double>(), 0.0);
      EXPECT_EQ(s.at("relax_steps").get<double>(), s.at("packing_settle_steps").get<double>());
      EXPECT_NEAR(s.at("relax_void_ratio_after").get<double>(), s.at("void_ratio_initial").get<double>(), 1e-9);
      EXPECT_GE(s.at("relax_platen_stress_max_Pa").get<double>(), s.at("relax_platen_stress_first_Pa").get<double>());
      e_relaxed_from = s.at("relax_void_ratio_before").get<double>();
    }
    const Json eff = Json::parse(slurp(out / f / "effective_scenario.json"));
    EXPECT_EQ(eff["packing"]["type"], "file");
    // Fragment building has its own entry in where the time went.
    EXPECT_TRUE(s.at("time_breakdown_s").contains("fragments"));
    // Per breakage event: a time, so with the times (not among the figures that must not
    // depend on threads).
    EXPECT_GE(s.at("time_breakdown_s").at("fragments_per_event").get<double>(), 0.0);
    EXPECT_FALSE(s.contains("fragments_s_per_event"));
    EXPECT_TRUE(s.contains("psd_d50_final_m"));
    EXPECT_TRUE(s.contains("void_ratio_at_stress_1e+06_Pa"));
    // No breakage with breakage.type none; the mass budget holds either way.
    if (f.find("none") != std::string::npos) {
      EXPECT_EQ(s.at("breakage_events").get<int>(), 0);
    }
    EXPECT_NEAR(s.at("mass_final_kg").get<double>() + s.at("mass_removed_kg").get<double>(),
                s.at("mass_initial_kg").get<double>(), 1e-12 * s.at("mass_initial_kg").get<double>());
  }
  if (e_relaxed_from >= 0) {
    EXPECT_NEAR(e_relaxed_from, e0, 1e-9 * e0);  // relaxed from the shared file
  }
  // The packing stage ran once and its packing.json is the one shared.
  EXPECT_EQ(crumble::file_sha256((out / "packing" / "packing.json").string()), hash);

  // comparison.csv: a header and one row per combination, in order, status ok, the hash.
  const auto rows = crumble::read_csv((out / "comparison.csv").string());
  ASSERT_EQ(rows.size(), folders.size() + 1);
  const auto& h = rows[0];
  auto col = [&](const std::string& name) {
    for (std::size_t i = 0; i < h.size(); ++i)
      if (h[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return std::size_t(0);
  };
  EXPECT_EQ(h[0], "engine.type");
  EXPECT_EQ(h[1], "breakage.type");
  for (std::size_t i = 0; i < folders.size(); ++i) {
    const auto& row = rows[i + 1];
    ASSERT_EQ(row.size(), h.size());
    EXPECT_EQ(row[col("folder")], folders[i]);
    EXPECT_EQ(row[col("status")], "ok");
    EXPECT_EQ(row[col("packing_hash")], hash);
    EXPECT_EQ(row[col("grains_initial")], "10");
    EXPECT_FALSE(row[col("wall_seconds")].empty());
    EXPECT_FALSE(row[col("time_fragments_s")].empty());
    EXPECT_FALSE(row[col("void_ratio_at_stress_1e+06_Pa")].empty());
  }
  col("void_ratio_at_stress_2e+06_Pa");  // a column for every reported level
  // comparison.md: one table line per combination.
  const std::string md = slurp(out / "comparison.md");
  EXPECT_NE(md.find(hash), std::string::npos);
  for (const auto& f : folders) {
    const std::string e = f.substr(12, f.find("__") - 12), m = f.substr(f.rfind('=') + 1);
    EXPECT_NE(md.find("| " + e + " | " + m + " | ok |"), std::string::npos) << md;
  }
  // The table is rebuilt from the summaries alone (resumed or other runs too): the same rows.
  std::vector<crumble::ComparisonRow> again;
  std::vector<crumble::VaryAxis> axes = {crumble::parse_vary("engine.type=" + engines),
                                         crumble::parse_vary("breakage.type=none,stress")};
  for (const auto& c : crumble::combinations(axes)) {
    crumble::ComparisonRow row;
    row.combination = c;
    row.status = "ok";
    row.exit_status = 0;
    row.summary = Json::parse(slurp(out / c.name / "summary.json"));
    again.push_back(row);
  }
  const fs::path copy = dir / "again";
  fs::create_directories(copy);
  crumble::write_comparison(copy.string(), axes, again, {"void_ratio_at_stress_2e+06_Pa"}, {});
  EXPECT_EQ(slurp(copy / "comparison.csv"), slurp(out / "comparison.csv"));

  // A second compare into the same folder is refused (exit 2) unless --force.
  const auto again_r = run_cli("compare " + scenario(dir) + " --out " + out.string() +
                               " --vary engine.type=lsdem --threads 1 --quiet");
  EXPECT_EQ(again_r.status, 2) << again_r.output;
  EXPECT_NE(again_r.output.find("not empty"), std::string::npos) << again_r.output;
}

// --jobs N without --threads: each run gets the usable CPUs / N threads (at least one); a
// given --threads and a single job are left as they are.
TEST(Compare, JobsShareTheCpusWhenThreadsAreNotGiven) {
  crumble::CompareRequest req;
  req.jobs = 2;
  ASSERT_TRUE(crumble::with_threads_per_job(req).threads.has_value());
  EXPECT_EQ(*crumble::with_threads_per_job(req).threads, std::max(1, crumble::usable_cpus() / 2));
  req.jobs = 1000;
  EXPECT_EQ(*crumble::with_threads_per_job(req).threads, 1);
  req.threads = 3;
  EXPECT_EQ(*crumble::with_threads_per_job(req).threads, 3);
  req.threads.reset();
  req.jobs = 1;
  EXPECT_FALSE(crumble::with_threads_per_job(req).threads.has_value());
}

TEST(Compare, AGuardFailureIsARowNotAnAbort) {
  const fs::path dir = test_dir();
  const fs::path out = dir / "out";
  // The second value stops its run at the overlap guard (exit 1); the first still runs.
  const auto r = run_cli("compare " + scenario(dir) + " --out " + out.string() +
                         " --vary simulation.guards.max_overlap_fraction=0.5,0.001 --set breakage.type=none"
                         " --threads 1 --quiet --jobs 2");
  EXPECT_EQ(r.status, 1) << r.output;
  const auto rows = crumble::read_csv((out / "comparison.csv").string());
  ASSERT_EQ(rows.size(), 3u) << slurp(out / "comparison.csv");
  EXPECT_EQ(rows[1][0], "0.5");
  EXPECT_EQ(rows[1][2], "ok");
  EXPECT_EQ(rows[2][0], "0.001");
  EXPECT_EQ(rows[2][2], "failed");
  EXPECT_EQ(rows[2][3], "1");
  const std::string csv = slurp(out / "comparison.csv");
  EXPECT_NE(csv.find("max_overlap_fraction"), std::string::npos);
  EXPECT_NE(slurp(out / "comparison.md").find("physical guard"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "simulation.guards.max_overlap_fraction=0.5" / "summary.json"));
  EXPECT_FALSE(fs::exists(out / "simulation.guards.max_overlap_fraction=0.001" / "summary.json"));
}

TEST(Compare, BadVaryIsExit2BeforeAnythingRuns) {
  const fs::path dir = test_dir();
  const std::string sc = scenario(dir);
  const fs::path out = dir / "out";
  expect_bad("compare " + sc + " --vary engine.type=lsdem,warp", out,
             {"engine.type=warp", "/engine/type", "unknown engine 'warp'", "lsdem"});
  expect_bad("compare " + sc + " --vary breakage.criterion=von_mises,bogus", out,
             {"/breakage/criterion", "max_principal, von_mises, tresca"});
  expect_bad("compare " + sc + " --vary engine.type=", out, {"--vary engine.type=", "empty value list"});
  expect_bad("compare " + sc + " --vary engine.type=lsdem,,lsdem", out, {"value 2 of 3 is empty"});
  expect_bad("compare " + sc + " --vary engine.type=lsdem,lsdem", out, {"'lsdem' is given twice"});
  expect_bad("compare " + sc + " --vary engine.type=lsdem --vary engine.type=bullet", out,
             {"'engine.type' is varied twice"});
  expect_bad("compare " + sc + " --vary engine.type", out, {"--vary engine.type", "expected path=value1,value2"});
  expect_bad("compare " + sc + " --vary =lsdem", out, {"empty path"});
  expect_bad("compare " + sc + " --vary engine..type=lsdem", out, {"empty component"});
  expect_bad("compare " + sc + " --vary packing.count=5,10", out, {"'packing.count' cannot vary"});
  expect_bad("compare " + sc + " --vary engine.type=lsdem --set engine.type=lsdem", out,
             {"also given by --set engine.type=lsdem"});
  expect_bad("compare " + sc + " --vary loading.max_stress=1e6,-1", out,
             {"loading.max_stress=-1", "/loading/max_stress"});
  // Without --vary: a usage error.
  EXPECT_EQ(run_cli("compare " + sc + " --out " + out.string()).status, 2);
  EXPECT_FALSE(fs::exists(out));
}

TEST(Compare, VaryParsing) {
  const auto a = crumble::parse_vary("output.psd_at_stress=[1e6,2e6], [3e6]");
  ASSERT_EQ(a.values.size(), 2u);
  EXPECT_EQ(a.values[0], "[1e6,2e6]");
  EXPECT_EQ(a.values[1], "[3e6]");
  EXPECT_EQ(a.path, "output.psd_at_stress");
  const auto b = crumble::parse_vary("name=\"a,b\",c");
  ASSERT_EQ(b.values.size(), 2u);
  EXPECT_EQ(b.values[0], "\"a,b\"");
  const auto combos = crumble::combinations({crumble::parse_vary("engine.type=lsdem,bullet"),
                                             crumble::parse_vary("breakage.criterion=tresca,von_mises")});
  ASSERT_EQ(combos.size(), 4u);
  EXPECT_EQ(combos[0].name, "engine.type=lsdem__breakage.criterion=tresca");
  EXPECT_EQ(combos[1].name, "engine.type=lsdem__breakage.criterion=von_mises");
  EXPECT_EQ(combos[3].name, "engine.type=bullet__breakage.criterion=von_mises");
  EXPECT_EQ(crumble::sanitise_folder_name("a.b=[1 ,2]/x"), "a.b=_1__2__x");
  // Two values that sanitise to the same folder are refused.
  EXPECT_THROW(crumble::combinations({crumble::parse_vary("name=a/b,a:b")}), crumble::InputError);
}

TEST(Compare, Sha256KnownVectors) {
  // FIPS 180-4 examples.
  EXPECT_EQ(crumble::sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(crumble::sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(crumble::sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");  // two blocks (sha256sum)
  EXPECT_EQ(crumble::sha256_hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// A packing Bullet settled, loaded by lsdem: lsdem meets Bullet's overlaps as stored energy.
// Loaded as it is (packing.relax off) the platen's first sample reads megapascals while the
// ramp commands kilopascals; relaxed (auto: packing.json says Bullet built it) the grains
// give that energy up first and the loading starts at the settling stress.
TEST(Compare, APackingFromAnotherEngineRelaxesBeforeLoading) {
#if CRUMBLE_WITH_BULLET
  const fs::path dir = test_dir();
  const std::string scen = (dir / "small.json").string();
  std::ofstream(scen) << R"({
    "name": "relax_small", "dimension": 3, "seed": 1,
    "materials": [{"density": 2650, "young": 1e11, "poisson": 0.15, "friction": 0.5, "restitution": 0}],
    "engine": {"type": "bullet", "mass_scale": 70, "solver_iterations": 1000, "kn": 5e6},
    "breakage": {"type": "none"},
    "container": {"lx": 0.0055, "ly": 0.0055},
    "packing": {"type": "cloud", "count": 20, "psd": [[0.0014, 0], [0.002, 1]], "shape": {"type": "sphere"},
                "settle": {"stress": 1e4}},
    "loading": {"mode": "stress_ramp", "max_stress": 1e5, "ramp_time": 0.0005},
    "time_step": 8e-5,
    "output": {"vtk_final": false, "plots": false, "series_every": 1}
  })";
  const fs::path bullet = dir / "bullet";
  ASSERT_EQ(run_cli("run " + scen + " --out " + bullet.string() + " --threads 1 --quiet").status, 0);
  EXPECT_EQ(Json::parse(slurp(bullet / "packing.json")).at("engine"), "bullet");
  const std::string lsdem = " --set engine.type=lsdem --set loading.ramp_time=0.01 --set loading.max_stress=2e6 --threads 1 --quiet"
                            " --set packing='{\"type\": \"file\", \"path\": \"" + (bullet / "packing.json").string() + "\"}'";
  auto first_stress = [](const fs::path& out) {
    const auto rows = crumble::read_csv((out / "series.csv").string());
    std::size_t c = 0;
    while (c < rows[0].size() && rows[0][c] != "platen_stress_Pa") ++c;
    return std::stod(rows.at(1).at(c));
  };
  const fs::path off = dir / "off", relaxed = dir / "relaxed";
  ASSERT_EQ(run_cli("run " + scen + " --out " + off.string() + lsdem + " --set packing.relax=off").status, 0);
  const auto r = run_cli("run " + scen + " --out " + relaxed.string() + lsdem);
  ASSERT_EQ(r.status, 0) << r.output;
  const Json s_off = Json::parse(slurp(off / "summary.json")), s = Json::parse(slurp(relaxed / "summary.json"));
  EXPECT_EQ(s_off.at("packing_relaxed").get<double>(), 0.0);
  EXPECT_EQ(s.at("packing_relaxed").get<double>(), 1.0);
  EXPECT_EQ(s.at("relax_converged").get<double>(), 1.0);
  // The transient: Bullet's overlaps push at > 1 MPa on lsdem; relaxed, the settling stress
  // (10 kPa) within 50 %, and the relaxation saw and reported the push it removed.
  EXPECT_GT(first_stress(off), 1e6);
  EXPECT_NEAR(first_stress(relaxed), 1e4, 5e3);
  EXPECT_GT(s.at("relax_platen_stress_max_Pa").get<double>(), 1e6);
  EXPECT_NEAR(s.at("relax_platen_stress_final_Pa").get<double>(), 1e4, 5e3);
  EXPECT_GT(s.at("relax_grain_displacement_max_m").get<double>(), 0.0);
  // The push launches the platen; it stops rising once no grain pushes it, so the packing is
  // at rest within a few settling windows (26 448 steps, two windows; a platen left to fly
  // took 330 600 steps to fall back).
  EXPECT_LT(s.at("relax_steps").get<double>(), 100000.0);
  // A file packing that names no other engine, or the loading engine, is loaded as it is.
  EXPECT_EQ(s_off.at("packing_settle_steps").get<double>(), 0.0);
  // The run's effective scenario runs again as it is (a file packing's settle keys that do
  // not apply are not written back).
  const auto again = run_cli("validate " + (relaxed / "effective_scenario.json").string());
  EXPECT_EQ(again.status, 0) << again.output;
  // lsdem colliding the facets Bullet collided (sphere_representation polyhedron): a tenth of
  // the push at most (what is left is Bullet's own penetration), and the grains stay where
  // Bullet left them (under 2 % of the smallest diameter, 1.4 mm, on average; the overlaps
  // of exact spheres are ≈ 4 % of a diameter).
  const fs::path facets = dir / "facets";
  ASSERT_EQ(run_cli("run " + scen + " --out " + facets.string() + lsdem + " --set engine.sphere_representation=polyhedron")
                .status, 0);
  const Json f = Json::parse(slurp(facets / "summary.json"));
  EXPECT_EQ(f.at("relax_converged").get<double>(), 1.0);
  EXPECT_LT(f.at("relax_platen_stress_max_Pa").get<double>(), 0.1 * s.at("relax_platen_stress_max_Pa").get<double>());
  EXPECT_LT(f.at("relax_grain_displacement_mean_m").get<double>(), 0.02 * 1.4e-3);
  EXPECT_NEAR(first_stress(facets), 1e4, 5e3);
#else
  GTEST_SKIP() << "needs Bullet";
#endif
}

TEST(Compare, AFilePackingIsNotSettledAgain) {
  const fs::path dir = test_dir();
  const auto r = run_cli("validate " + scenario(dir) +
                         " --set packing='{\"type\": \"file\", \"path\": \"x.json\", \"settle\": {\"enabled\": true}}'");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("/packing/settle/enabled"), std::string::npos) << r.output;
}

// `compare --resume` after the whole comparison was killed (SIGKILL to its process group, as
// when a machine goes away) while its second run was loaded: the finished run is kept as it
// was (its summary.json byte for byte), the killed one continues from its checkpoint, and
// both end as in the uninterrupted comparison (lsdem: bit-identical series.csv); a resume that
// does not match the folder is refused before anything runs.
TEST(Compare, ResumeKeepsFinishedRunsAndContinuesTheOthers) {
  const fs::path dir = test_dir();
  const std::string sc = scenario(dir);
  const std::string common = " --vary breakage.criterion=von_mises,tresca --threads 1 --jobs 1"
                             " --set loading.ramp_time=0.05 --set output.checkpoint_every=100"
                             " --set output.checkpoint_every_s=0";
  const std::string args = common + " --quiet";
  const fs::path whole = dir / "whole", cut = dir / "cut";
  const auto a = run_cli("compare " + sc + " --out " + whole.string() + args);
  ASSERT_EQ(a.status, 0) << a.output;
  const fs::path tresca = cut / "breakage.criterion=tresca", vm = cut / "breakage.criterion=von_mises";
  const std::string part = (tresca / "series.csv.part").string();
  run_cli("--version >/dev/null; setsid " + std::string(CRUMBLE_BINARY) + " compare " + sc + " --out " + cut.string() +
          args + " >/dev/null 2>&1 & p=$!; for i in $(seq 1 6000); do [ -f " + part +
          " ] && awk -F, 'NR>1 && $2>=700 {f=1} END{exit !f}' " + part +
          " && break; kill -0 $p 2>/dev/null || break; sleep 0.01; done; /usr/bin/kill -KILL -- -$p; wait $p; echo killed");
  ASSERT_TRUE(fs::exists(vm / "summary.json"));
  ASSERT_FALSE(fs::exists(tresca / "summary.json")) << "the run ended before it was killed";
  ASSERT_TRUE(fs::exists(tresca / "checkpoint.json"));
  ASSERT_FALSE(fs::exists(cut / "comparison.csv"));
  const std::string kept = slurp(vm / "summary.json");

  expect_bad("compare " + sc + args + " --resume --force", cut / "x", {"--resume and --force exclude each other"});
  const auto none = run_cli("compare " + sc + " --out " + (dir / "none").string() + args + " --resume");
  EXPECT_EQ(none.status, 2) << none.output;
  EXPECT_NE(none.output.find("nothing to resume"), std::string::npos) << none.output;
  const auto other = run_cli("compare " + sc + " --out " + cut.string() +
                             " --vary breakage.criterion=max_principal --threads 1 --quiet --resume");
  EXPECT_EQ(other.status, 2) << other.output;
  EXPECT_NE(other.output.find("none of this comparison's combinations"), std::string::npos) << other.output;
  const auto changed = run_cli("compare " + sc + " --out " + cut.string() + args + " --set breakage.strength=16e6 --resume");
  EXPECT_EQ(changed.status, 2) << changed.output;
  EXPECT_NE(changed.output.find("/breakage/strength"), std::string::npos) << changed.output;
  EXPECT_FALSE(fs::exists(tresca / "summary.json"));

  // An edited description is not a different scenario.
  const auto b = run_cli("compare " + sc + " --out " + cut.string() + common + " --set description=edited --resume");
  ASSERT_EQ(b.status, 0) << b.output;
  EXPECT_NE(b.output.find("breakage.criterion=von_mises finished before: kept"), std::string::npos) << b.output;
  EXPECT_NE(b.output.find("breakage.criterion=tresca continued from its checkpoint"), std::string::npos) << b.output;
  EXPECT_EQ(slurp(vm / "summary.json"), kept);
  EXPECT_EQ(slurp(tresca / "series.csv"), slurp(whole / "breakage.criterion=tresca" / "series.csv"));
  const auto sb = Json::parse(slurp(tresca / "summary.json"));
  EXPECT_GT(sb["resumed_from_step"].get<long>(), 0);
  const auto ra = crumble::read_csv((whole / "comparison.csv").string());
  const auto rb = crumble::read_csv((cut / "comparison.csv").string());
  ASSERT_EQ(ra.size(), 3u);
  ASSERT_EQ(rb.size(), ra.size());
  for (const char* col : {"status", "grains_final", "breakage_events", "void_ratio_final", "psd_d50_final_m", "steps",
                          "packing_hash"}) {
    const auto c = std::find(ra[0].begin(), ra[0].end(), col) - ra[0].begin();
    ASSERT_LT(c, static_cast<long>(ra[0].size())) << col;
    for (std::size_t i = 1; i < ra.size(); ++i) EXPECT_EQ(rb[i][c], ra[i][c]) << col << " row " << i;
  }
  EXPECT_NE(slurp(cut / "comparison.md").find("1 run(s) that had finished kept as they were, 1 continued"),
            std::string::npos);
}
