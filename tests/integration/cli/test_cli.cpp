// The command line end to end: exit statuses and error messages for every bad-input class.
#include <gtest/gtest.h>


#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "crumble_config.h"
#include "scenarios/Registry.h"
#include "run/ThreadCheck.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;

namespace {

using Result = crumble::testing_support::CliResult;
Result run(const std::string& args) { return crumble::testing_support::run_cli(args); }

std::string scenario_file(const std::string& name, const std::string& text) {
  return crumble::testing_support::scenario_file("crumble_cli_test", name, text);
}

// A valid rigid scenario on the in-house engine (no external dependency).
const std::string kGood = R"({
  "name": "cli_test", "engine": {"type": "lsdem"}, "breakage": {"type": "none"},
  "container": {"lx": 0.01, "ly": 0.01, "height": 0.004},
  "packing": {"type": "grains", "grains": [
     {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.005, 0.005, 0.0011]}]},
  "loading": {"mode": "strain_rate", "strain_rate": 1.0, "stop_strain": 0.001},
  "time_step": 1e-6, "simulation": {"max_steps": 50}
})";

void expect_input_error(const std::string& args, const std::string& needle) {
  const Result r = run(args);
  EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
  EXPECT_NE(r.output.find(needle), std::string::npos) << "expected '" << needle << "' in:\n" << r.output;
}

}  // namespace

TEST(Cli, VersionHelpList) {
  EXPECT_EQ(run("--version").status, 0);
  const Result h = run("--help");
  EXPECT_EQ(h.status, 0);
  EXPECT_NE(h.output.find("validate"), std::string::npos);
  const Result l = run("list");
  EXPECT_EQ(l.status, 0);
  EXPECT_NE(l.output.find("lsdem"), std::string::npos);
  EXPECT_NE(l.output.find("none"), std::string::npos);
}

TEST(Cli, ValidScenarioValidates) {
  const Result r = run("validate " + scenario_file("good.json", kGood));
  EXPECT_EQ(r.status, 0) << r.output;
}

TEST(Cli, MalformedJson) {
  expect_input_error("validate " + scenario_file("bad.json", "{\"engine\": {\"type\": \"lsdem\",}"), "malformed JSON");
}

TEST(Cli, MissingFile) { expect_input_error("validate /nonexistent/x.json", "cannot open"); }

// A folder given as the scenario is named as a folder (reading it once gave "malformed JSON …
// unexpected end of input").
TEST(Cli, FolderAsScenarioSaysItIsAFolder) {
  const std::string dir = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios";
  expect_input_error("validate " + dir, "is a folder, not a scenario file");
  const Result r = run("run " + dir + " --out " + (fs::temp_directory_path() / "crumble_cli_test" / "folder").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output.find("malformed JSON"), std::string::npos) << r.output;
}

// --seed takes 0 … 2^64 - 1; a negative seed is refused (it once wrapped to 2^64 - 1 silently).
TEST(Cli, NegativeSeedIsRefused) {
  const std::string f = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json";
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "negative_seed";
  fs::remove_all(out);
  expect_input_error("run " + f + " --seed -1 --out " + out.string(), "-1: expected a whole number from 0 to");
  EXPECT_FALSE(fs::exists(out));
  expect_input_error("compare " + f + " --seed -5 --out " + out.string() + " --vary engine.type=lsdem", "-5: expected");
}

TEST(Cli, UnknownKeyNamesPath) {
  const std::string f = scenario_file("good.json", kGood);
  expect_input_error("validate " + f + " --set loading.strain_rte=2", "/loading/strain_rte");
}

TEST(Cli, WrongType) {
  const std::string f = scenario_file("good.json", kGood);
  expect_input_error("validate " + f + " --set container.lx=wide", "/container/lx: expected a number");
}

TEST(Cli, UnknownNamesListKnownOnes) {
  const std::string f = scenario_file("good.json", kGood);
  expect_input_error("validate " + f + " --set engine.type=havok", "known:");
  expect_input_error("validate " + f + " --set breakage.type=magic", "/breakage/type");
  expect_input_error("validate " + f + " --set fragments.type=origami", "/fragments/type");
}

TEST(Cli, NegativeZeroAndNaNSizes) {
  const std::string f = scenario_file("good.json", kGood);
  expect_input_error("validate " + f + " --set packing.grains.0.shape.radius=-0.001", "/packing/grains/0/shape/radius");
  expect_input_error("validate " + f + " --set packing.grains.0.shape.radius=0", "/packing/grains/0/shape/radius");
  expect_input_error("validate " + f + " --set packing.grains.0.shape.radius=NaN", "/packing/grains/0/shape/radius");
  expect_input_error("validate " + f + " --set container.height=0", "/container/height");
}

TEST(Cli, BadCommandLine) {
  EXPECT_EQ(run("run").status, 2);
  EXPECT_EQ(run("frobnicate").status, 2);
  const std::string f = scenario_file("good.json", kGood);
  expect_input_error("run " + f + " --out /tmp/x --set nodot", "path=value");
}

TEST(Cli, RunWritesEveryOutput) {
  const std::string f = scenario_file("good.json", kGood);
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "run_out";
  fs::remove_all(out);
  const Result r = run("run " + f + " --out " + out.string() + " --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* name : {"summary.json", "series.csv", "events.csv", "psd.csv", "effective_scenario.json",
                           "packing.json", "breakage_per_mpa.csv", "grains.pvd", "ncl.csv"})
    EXPECT_TRUE(fs::exists(out / name)) << name;
  std::ifstream in(out / "summary.json");
  std::string s((std::istreambuf_iterator<char>(in)), {});
  for (const char* key : {"scenario", "engine", "breakage", "fragments", "seed", "threads", "wall_seconds", "steps",
                          "grains_initial", "grains_final", "breakage_events", "mass_initial_kg", "mass_final_kg",
                          "mass_removed_kg", "void_ratio_initial", "void_ratio_final", "max_platen_stress_Pa"})
    EXPECT_NE(s.find(std::string("\"") + key + "\""), std::string::npos) << key;
  // time_breakdown_s.output by writer: every standard writer has its entry, and they sum to output.
  const auto t = nlohmann::json::parse(s).at("time_breakdown_s");
  ASSERT_TRUE(t.contains("output_by_writer")) << t.dump();
  double sum = 0;
  for (const auto& [name, seconds] : t.at("output_by_writer").items()) sum += seconds.get<double>();
  for (const char* name : {"series", "events", "psd", "shape", "vtk", "stages", "compression", "report"})
    EXPECT_TRUE(t.at("output_by_writer").contains(name)) << name << " in " << t.dump();
  EXPECT_NEAR(sum, t.at("output").get<double>(), 1e-9 + 1e-9 * sum);
}

using crumble::testing_support::slurp;

TEST(Cli, SameSeedSameSummary) {
  // Two runs of a small rigid Bullet oedometer with one thread: summary.json identical but
  // for the wall-clock figures; series.csv identical.
  const fs::path base = fs::temp_directory_path() / "crumble_cli_test";
  const std::string sets =
      " --quiet --threads 1 --set packing.count=25 --set container.lx=6e-3 --set container.ly=6e-3"
      " --set loading.max_stress=2e5 --set loading.ramp_time=0.01 --set engine.solver_iterations=200";
  std::string sums[2], series[2];
  for (int k = 0; k < 2; ++k) {
    const fs::path out = base / ("det" + std::to_string(k));
    fs::remove_all(out);
    const Result r = run("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json --out " +
                         out.string() + sets);
    ASSERT_EQ(r.status, 0) << r.output;
    auto j = nlohmann::json::parse(slurp(out / "summary.json"));
    j.erase("wall_seconds");
    j.erase("time_breakdown_s");
    sums[k] = j.dump();
    series[k] = slurp(out / "series.csv");
  }
  EXPECT_EQ(sums[0], sums[1]);
  EXPECT_EQ(series[0], series[1]);
  EXPECT_GT(series[0].size(), 100u);
}

TEST(Cli, ShapeReportsResolution) {
  const Result r = run("shape --json '{\"type\":\"sphere\",\"radius\":1}' --representation level_set --spacing 0.05");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_NEAR(j["volume"].get<double>(), 4.18879, 0.004 * 4.18879);
  EXPECT_GT(j["nodes"].get<long>(), 100);
  EXPECT_EQ(j["grid"].size(), 3u);
  EXPECT_NEAR(j["surface_area"].get<double>(), 4 * 3.14159265, 0.01 * 4 * 3.14159265);
  const Result m = run("shape --json '{\"type\":\"box\",\"half_extents\":[1,2,3]}' --representation hull");
  ASSERT_EQ(m.status, 0) << m.output;
  const auto h = nlohmann::json::parse(m.output);
  EXPECT_NEAR(h["volume"].get<double>(), 48.0, 1e-9);
  EXPECT_EQ(h["nodes"].get<long>(), 8);
  const Result d = run("shape --json '{\"type\":\"disk\",\"radius\":1,\"dimension\":2}' --representation level_set");
  EXPECT_EQ(d.status, 0) << d.output;
  expect_input_error("shape --json '{\"type\":\"sphere\",\"radius\":-1}'", "/radius");
  expect_input_error("shape --json '{\"type\":\"sphere\",\"radius\":1}' --spacing 3", "thinner");
  expect_input_error("shape --json '{\"type\":\"polyhedron\",\"vertices\":[[0,0,0],[1,0,0],[0,1,0]],\"triangles\":[[0,1,2]]}'",
                     "not closed");
}

TEST(Cli, RigidOedometerRunsOnLsdem) {
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "rigid_lsdem";
  fs::remove_all(out);
  const Result r = run("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json --out " +
                       out.string() +
                       " --quiet --set engine.type=lsdem --set packing.count=20 --set container.lx=5e-3"
                       " --set container.ly=5e-3 --set loading.max_stress=2e5 --set loading.ramp_time=0.005"
                       " --set packing.settle.max_time=0.05");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("ignored by 'lsdem'"), std::string::npos) << r.output;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["engine"], "lsdem");
  // A fast ramp on a barely settled packing: the platen reaches the load and overshoots
  // dynamically, but stays bounded. The overshoot is a sample of a chaotic settling: 1.5×
  // and 2.8× on two builds whose force sums differ in order only (bitwise equal for the
  // first 26 000 settling steps, 1e-16 m apart after 28 000).
  EXPECT_GT(s["max_platen_stress_Pa"].get<double>(), 0.9 * 2e5);
  EXPECT_LT(s["max_platen_stress_Pa"].get<double>(), 4.0 * 2e5);
}

TEST(Cli, CheckpointAndResumeContinueTheRun) {
  // A run stopped at step 125 (after a checkpoint) and resumed ends where an uninterrupted
  // run ends, up to the contact history the resume rebuilds (measured: 0.05 % in e).
  const fs::path base = fs::temp_directory_path() / "crumble_cli_test";
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json";
  const std::string sets =
      " --quiet --set packing.count=40 --set container.lx=6e-3 --set container.ly=6e-3 --set loading.max_stress=1e6"
      " --set loading.ramp_time=0.02 --set engine.solver_iterations=300";
  const fs::path a = base / "ck_whole", b = base / "ck_resumed";
  fs::remove_all(a);
  fs::remove_all(b);
  const Result whole = run("run " + scen + " --out " + a.string() + sets);
  ASSERT_EQ(whole.status, 0) << whole.output;
  {
    // 300 sweeps of Bullet's solver do not reach its tolerance (2e-4) in this packing: the
    // run says so, and summary.json counts it. The file declares its 300 iterations
    // deliberate; the --set of engine.solver_iterations lapses that, so the note prints.
    const auto s = nlohmann::json::parse(slurp(a / "summary.json"));
    EXPECT_EQ(s["engine_solver_iterations_max"], 300);
    EXPECT_GE(s["engine_solver_limited_fraction"].get<double>(), 0.1);  // the note's threshold
    EXPECT_GT(s["engine_solver_limited_change_max"].get<double>(), 2e-4);
    EXPECT_NE(whole.output.find("the contact solver stopped at its iteration limit (300)"), std::string::npos)
        << whole.output;
  }
  ASSERT_EQ(run("run " + scen + " --out " + b.string() + sets +
                " --set output.checkpoint_every=50 --set simulation.max_steps=125")
                .status,
            0);
  ASSERT_TRUE(fs::exists(b / "checkpoint.json"));
  // A resume with another effective scenario is refused, naming the first differing path,
  // and leaves the folder as it was.
  expect_input_error("run " + scen + " --out " + b.string() + sets +
                         " --set output.checkpoint_every=50 --set packing.count=41 --resume",
                     "at /packing/count (was 40, now 41)");
  // A run written before an option existed lacks it in effective_scenario.json: the resume
  // fills it with its default and goes on, but still refuses a non-default value.
  {
    auto e = nlohmann::json::parse(slurp(b / "effective_scenario.json"));
    ASSERT_TRUE(e["output"].contains("intact_analyses"));
    e["output"].erase("intact_analyses");
    std::ofstream(b / "effective_scenario.json") << e.dump(2);
  }
  expect_input_error("run " + scen + " --out " + b.string() + sets +
                         " --set output.checkpoint_every=50 --set output.intact_analyses=false --resume",
                     "at /output/intact_analyses (was true, now false)");
  const fs::path c = base / "ck_resumed_smaller_dt";
  fs::remove_all(c);
  fs::copy(b, c, fs::copy_options::recursive);
  const Result r = run("run " + scen + " --out " + b.string() + sets + " --set output.checkpoint_every=50 --resume");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto sa = nlohmann::json::parse(slurp(a / "summary.json"));
  const auto sb = nlohmann::json::parse(slurp(b / "summary.json"));
  EXPECT_EQ(sb["resumed_from_step"], 125);
  // The resumed summary reports the settling of the run it continues, not 0.
  EXPECT_GT(sa["packing_settle_steps"].get<double>(), 0);
  EXPECT_EQ(sa["packing_settle_steps"], sb["packing_settle_steps"]);
  EXPECT_EQ(sa["steps"], sb["steps"]);
  EXPECT_EQ(sa["grains_initial"], sb["grains_initial"]);
  EXPECT_DOUBLE_EQ(sa["void_ratio_initial"].get<double>(), sb["void_ratio_initial"].get<double>());
  EXPECT_NEAR(sb["void_ratio_final"].get<double>(), sa["void_ratio_final"].get<double>(),
              0.01 * sa["void_ratio_final"].get<double>());
  // The series carries the rows before the checkpoint and continues without duplicates.
  const std::string series = slurp(b / "series.csv");
  EXPECT_NE(series.find("\n0.008,100,"), std::string::npos);
  EXPECT_NE(series.find("\n0.02,250,"), std::string::npos);
  EXPECT_EQ(series.find(",100,", series.find(",100,") + 1), std::string::npos);
  // What a guard's message advises — a smaller time step, more solver iterations, other guard
  // limits — may change on a resume; the run goes on from its checkpoint (at step 125,
  // t = 0.01 s), at 4e-5 s per step to the end of the 0.02 s ramp: 125 + 250 steps.
  const Result g = run("run " + scen + " --out " + c.string() + sets +
                       " --set output.checkpoint_every=50 --set time_step=4e-5 --set engine.solver_iterations=600"
                       " --set simulation.guards.max_overlap_fraction=0.6 --resume");
  ASSERT_EQ(g.status, 0) << g.output;
  EXPECT_NEAR(nlohmann::json::parse(slurp(c / "summary.json"))["steps"].get<double>(), 375, 2);
  // The folder's effective scenario now holds what the run went on with, and summary.json
  // what changed at the resume.
  EXPECT_EQ(nlohmann::json::parse(slurp(c / "effective_scenario.json"))["engine"]["solver_iterations"], 600);
  const auto changes = nlohmann::json::parse(slurp(c / "summary.json"))["resume_changes"];
  ASSERT_TRUE(changes.is_array()) << changes;
  bool iterations_named = false, guard_named = false;
  for (const auto& ch : changes) {
    if (ch["path"] == "/engine/solver_iterations") {
      iterations_named = true;
      EXPECT_EQ(ch["was"], 300);
      EXPECT_EQ(ch["now"], 600);
    }
    if (ch["path"] == "/simulation/guards/max_overlap_fraction") {  // the leaf, not the whole object
      guard_named = true;
      EXPECT_EQ(ch["was"], 0.5);
      EXPECT_EQ(ch["now"], 0.6);
    }
  }
  EXPECT_TRUE(iterations_named) << changes;
  EXPECT_TRUE(guard_named) << changes;
  EXPECT_NE(g.output.find("resuming with /engine/solver_iterations 600 (was 300)"), std::string::npos) << g.output;
  // The first resume only lifted the step limit that stopped the run.
  EXPECT_EQ(sb["resume_changes"], nlohmann::json::parse(R"([{"path": "/simulation/max_steps", "was": 125, "now": 0}])"));
  // Resuming a scenario that never wrote a checkpoint is an input error.
  expect_input_error("run " + scen + " --out " + (base / "nothing_here").string() + sets + " --resume",
                     "the folder holds no run");
}

TEST(Cli, SignalStopsTheRunWithEveryOutput) {
  // SIGTERM ends the loop after the current step: exit 143 (128 + SIGTERM), all files, a
  // checkpoint to resume.
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "interrupted";
  fs::remove_all(out);
  // The signal is sent once packing.json exists (the loading has begun), however slowly a
  // loaded machine settles the packing (the settling writes checkpoints of its own).
  const std::string cmd = std::string(CRUMBLE_BINARY) + " run " + CRUMBLE_SOURCE_DIR +
                          "/scenarios/oedometer_rigid_quick.json --quiet --out " + out.string() +
                          " --set loading.ramp_time=100 --set output.checkpoint_every=20 --set packing.count=30"
                          " --set container.lx=6e-3 --set container.ly=6e-3 --set engine.solver_iterations=200";
  const Result r = run("--version >/dev/null; " + cmd + " 2>&1 & p=$!; for i in $(seq 1 1500); do [ -f " +
                       (out / "packing.json").string() + " ] && break; sleep 0.2; done; kill -TERM $p; wait $p; echo status=$?");
  ASSERT_NE(r.output.find("status=143"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("interrupted at step"), std::string::npos) << r.output;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["interrupted"], true);
  EXPECT_TRUE(fs::exists(out / "series.csv"));
  ASSERT_TRUE(fs::exists(out / "checkpoint.json"));
  EXPECT_FALSE(nlohmann::json::parse(slurp(out / "checkpoint.json")).contains("settling"));
}

// More threads than CPUs: the run says so on stderr, even with --quiet, and still runs
// (docs/performance.md, "Threads on a busy machine").
TEST(Cli, MoreThreadsThanCpusWarns) {
  const int cpus = crumble::current_cpu_load().cpus;
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "too_many_threads";
  fs::remove_all(out);
  const Result r = run("run " + scenario_file("good.json", kGood) + " --quiet --out " + out.string() +
                       " --set simulation.max_steps=5 --threads " + std::to_string(cpus + 1));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("warning: --threads " + std::to_string(cpus + 1) + " on " + std::to_string(cpus) + " CPUs"),
            std::string::npos)
      << r.output;
}

TEST(Cli, CrushableRunDoesNotDependOnThreads) {
  // Breakage analyses run one grain per thread; the run must not depend on how many.
  const fs::path base = fs::temp_directory_path() / "crumble_cli_test";
  const std::string sets =
      " --quiet --set packing.count=40 --set container.lx=6e-3 --set container.ly=6e-3 --set loading.max_stress=5e6"
      " --set loading.ramp_time=0.025 --set breakage.spacing_fraction=0.1 --set output.vtk_every=0";
  std::string sums[2];
  for (int t = 1; t <= 2; ++t) {
    const fs::path out = base / ("threads" + std::to_string(t));
    fs::remove_all(out);
    const Result r = run("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_zhu_zhao_quick.json --out " +
                         out.string() + sets + " --threads " + std::to_string(t));
    ASSERT_EQ(r.status, 0) << r.output;
    auto j = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_GT(j["breakage_events"].get<long>(), 0);
    for (const char* k : {"wall_seconds", "time_breakdown_s", "threads"}) j.erase(k);
    sums[t - 1] = j.dump();
  }
  EXPECT_EQ(sums[0], sums[1]);
}

TEST(Cli, EveryShippedScenarioValidates) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(CRUMBLE_SOURCE_DIR) / "scenarios")) {
    if (e.path().extension() != ".json") continue;
    const Result r = run("validate " + e.path().string());
    EXPECT_EQ(r.status, 0) << e.path() << "\n" << r.output;
    ++n;
  }
  EXPECT_GE(n, 10);
}

// ---- "Never a wrong answer with exit 0" ----

TEST(Cli, NumberOverflowIsAnInputError) {
  const std::string f = scenario_file("good.json", kGood);
  expect_input_error("validate " + f + " --set time_step=1e999", "/time_step: number '1e999' is outside");
  const std::string inf = scenario_file("inf.json", "{\"name\": \"x\",\n \"time_step\": 1e999}");
  expect_input_error("validate " + inf, inf + " line 2, column 20: /time_step");
}

TEST(Cli, DuplicateKeyIsAnInputError) {
  const std::string f = scenario_file("dup.json", R"({"name": "a", "seed": 1, "name": "b"})");
  expect_input_error("validate " + f, "/name: duplicate key 'name'");
}

TEST(Cli, ValidateCatchesWhatRunRejects) {
  const std::string q = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json";
  expect_input_error("validate " + q + " --set packing.material=5", "/packing/material: material index 5");
  const std::string f = scenario_file("good.json", kGood);
  expect_input_error("validate " + f + " --set simulation.auto_reduce_dt=false", "/simulation/auto_reduce_dt");
  expect_input_error("validate " + f + " --set packing.grains.0.position=[0.0095,0.005,0.0011]",
                     "/packing/grains/0/position");
  expect_input_error("validate " + f + " --set materials=[]", "/materials: expected at least one material");
  // One grain that fits is a valid cloud.
  const Result one = run("validate " + q + " --set packing.count=1");
  EXPECT_EQ(one.status, 0) << one.output;
}

TEST(Cli, SeedTakesTheFullUnsignedRange) {
  const std::string f = scenario_file("good.json", kGood);
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "seed_max";
  fs::remove_all(out);
  const Result r = run("run " + f + " --quiet --out " + out.string() + " --seed 18446744073709551615");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["seed"].get<std::uint64_t>(), 18446744073709551615ull);
}

TEST(Cli, ShapeSpacingMustBeANumber) {
  expect_input_error("shape --json '{\"type\":\"sphere\",\"radius\":1}' --spacing nan", "--spacing");
  expect_input_error("shape --json '{\"type\":\"sphere\",\"radius\":1}' --spacing inf", "--spacing");
}

TEST(Cli, OutFolderNeverMixesTwoRuns) {
  const std::string f = scenario_file("good.json", kGood);
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "reuse";
  fs::remove_all(out);
  ASSERT_EQ(run("run " + f + " --quiet --out " + out.string()).status, 0);
  // Again into the same folder: refused, nothing touched.
  const auto before = slurp(out / "summary.json");
  expect_input_error("run " + f + " --quiet --out " + out.string(), "not empty");
  EXPECT_EQ(slurp(out / "summary.json"), before);
  // --force removes the earlier run's files (only crumble's) before running.
  std::ofstream(out / "my_notes.txt") << "keep me";
  fs::create_directories(out / "mine");
  const Result r = run("run " + f + " --quiet --out " + out.string() + " --force --set simulation.max_steps=20");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(slurp(out / "my_notes.txt"), "keep me");
  EXPECT_TRUE(fs::exists(out / "mine"));
  EXPECT_EQ(nlohmann::json::parse(slurp(out / "summary.json"))["steps"], 20);
  EXPECT_EQ(nlohmann::json::parse(slurp(out / "effective_scenario.json"))["simulation"]["max_steps"], 20);
  // A folder holding only someone else's files is refused too.
  const fs::path other = fs::temp_directory_path() / "crumble_cli_test" / "reuse_other";
  fs::remove_all(other);
  fs::create_directories(other);
  std::ofstream(other / "data.txt") << "x";
  expect_input_error("run " + f + " --quiet --out " + other.string(), "data.txt");
  // --resume needs a checkpoint (every run writes one at its end by default,
  // output.checkpoint_every_s: take it away).
  ASSERT_TRUE(fs::exists(out / "checkpoint.json"));
  fs::remove(out / "checkpoint.json");
  expect_input_error("run " + f + " --quiet --out " + out.string() + " --resume", "no checkpoint.json");
}

TEST(Cli, HelpDocumentsExitStatus) {
  const Result h = run("run --help");
  EXPECT_EQ(h.status, 0);
  EXPECT_NE(h.output.find("143"), std::string::npos) << h.output;
  EXPECT_NE(h.output.find("--force"), std::string::npos) << h.output;
}

namespace {

using Json = nlohmann::json;

// The stderr lines of a run, each without its "crumble: " prefix.
std::vector<std::string> stderr_lines(const std::string& output) {
  std::vector<std::string> lines;
  std::istringstream in(output);
  for (std::string l; std::getline(in, l);) lines.push_back(l.rfind("crumble: ", 0) == 0 ? l.substr(9) : l);
  return lines;
}

// The entry of summary.json's notes about `setting`, or null.
Json note_about(const Json& summary, const std::string& setting) {
  for (const auto& n : summary.at("notes"))
    if (n.value("setting", "") == setting) return n;
  return nullptr;
}

std::string project_version() {
  const std::string cmake = slurp(fs::path(CRUMBLE_SOURCE_DIR) / "CMakeLists.txt");
  std::smatch m;
  if (!std::regex_search(cmake, m, std::regex(R"(project\(crumble VERSION ([0-9]+\.[0-9]+\.[0-9]+))"))) return "";
  return m[1];
}

}  // namespace

// The README's first command, made smaller (40 grains to 1 MPa; the engine as the file has it):
// no note and no warning on stderr, only progress, where the results are and what to open
// first. The file declares its 300 solver iterations and lsdem's kn deliberate; the notes
// about them are in summary.json with the file's reasons.
TEST(Cli, FirstRunPrintsOnlyWhatANewcomerCanActOn) {
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "first_run";
  fs::remove_all(out);
  const Result r = run("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json --out " +
                       out.string() +
                       " --set packing.count=40 --set container.lx=6e-3 --set container.ly=6e-3"
                       " --set loading.max_stress=1e6 --set loading.ramp_time=0.02");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const std::string& l : stderr_lines(r.output)) {
    bool known = false;
    for (const char* start : {"building packing (", "packing settled in ", "[", "done in ", "plots", "open "})
      known = known || l.rfind(start, 0) == 0;
    EXPECT_TRUE(known) << "a line a newcomer cannot act on: '" << l << "' in\n" << r.output;
  }
  EXPECT_NE(r.output.find("results in " + out.string()), std::string::npos) << r.output;
  const std::string main_figure = fs::exists(out / "ncl.png") ? (out / "ncl.png").string() + " first, then " : "";
  EXPECT_NE(r.output.find("open " + main_figure + (out / "scene.pvd").string() + " in ParaView"), std::string::npos)
      << r.output;
  const Json s = Json::parse(slurp(out / "summary.json"));
  ASSERT_GE(s["engine_solver_limited_fraction"].get<double>(), 0.1) << "the solver note's condition holds";
  const Json solver = note_about(s, "/engine/solver_iterations");
  ASSERT_TRUE(solver.is_object()) << s["notes"].dump();
  EXPECT_NE(solver["note"].get<std::string>().find("iteration limit (300)"), std::string::npos) << solver.dump();
  const Json file = Json::parse(slurp(fs::path(CRUMBLE_SOURCE_DIR) / "scenarios/oedometer_rigid_quick.json"));
  ASSERT_TRUE(file.contains("deliberate"));
  EXPECT_EQ(solver.value("deliberate", ""), file["deliberate"].value("/engine/solver_iterations", "?"));
  for (const auto& n : s["notes"]) EXPECT_TRUE(n.contains("deliberate")) << "printed, yet: " << n.dump();
}

// An ignored option the file does not declare is still noted on stderr and in summary.json;
// a declared one is only in summary.json, with its reason; a --set of the declared setting
// lapses the declaration.
TEST(Cli, OnlyDeclaredSettingsAreNotNoted) {
  Json doc = Json::parse(kGood);
  doc["engine"]["solver_iterations"] = 300;    // Bullet's and ODE's: ignored by lsdem
  doc["engine"]["solver_tolerance"] = 1e-4;    // Bullet's: ignored by lsdem, not declared
  doc["deliberate"] = {{"/engine/solver_iterations", "kept for --set engine.type=bullet"}};
  const std::string f = scenario_file("deliberate.json", doc.dump());
  const fs::path out = fs::temp_directory_path() / "crumble_cli_test" / "deliberate";
  fs::remove_all(out);
  const Result r = run("run " + f + " --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.find("/engine/solver_iterations is an option of"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("note: /engine/solver_tolerance is an option of 'bullet', ignored by 'lsdem'"),
            std::string::npos)
      << r.output;
  const Json s = Json::parse(slurp(out / "summary.json"));
  const Json declared = note_about(s, "/engine/solver_iterations");
  ASSERT_TRUE(declared.is_object()) << s["notes"].dump();
  EXPECT_EQ(declared.value("deliberate", ""), "kept for --set engine.type=bullet");
  const Json undeclared = note_about(s, "/engine/solver_tolerance");
  ASSERT_TRUE(undeclared.is_object()) << s["notes"].dump();
  EXPECT_FALSE(undeclared.contains("deliberate")) << undeclared.dump();
  // The file's reason was about its own value: a --set of it prints the note again.
  fs::remove_all(out);
  const Result set = run("run " + f + " --out " + out.string() + " --set engine.solver_iterations=500");
  ASSERT_EQ(set.status, 0) << set.output;
  EXPECT_NE(set.output.find("note: /engine/solver_iterations is an option of"), std::string::npos) << set.output;
  const Json lapsed = note_about(Json::parse(slurp(out / "summary.json")), "/engine/solver_iterations");
  ASSERT_TRUE(lapsed.is_object());
  EXPECT_FALSE(lapsed.contains("deliberate")) << lapsed.dump();
  EXPECT_FALSE(Json::parse(slurp(out / "effective_scenario.json")).contains("deliberate"));
  // validate prints the undeclared note and not the declared one.
  const Result v = run("validate " + f);
  EXPECT_EQ(v.status, 0) << v.output;
  EXPECT_EQ(v.output.find("/engine/solver_iterations is an option of"), std::string::npos) << v.output;
  EXPECT_NE(v.output.find("/engine/solver_tolerance is an option of"), std::string::npos) << v.output;
}

// A declaration names a value the scenario sets and gives a reason; anything else is an error
// at /deliberate, never a declaration that silently matches nothing.
TEST(Cli, BadDeliberateDeclarationsAreErrors) {
  const auto with = [](const Json& d) {
    Json doc = Json::parse(kGood);
    doc["deliberate"] = d;
    return scenario_file("bad_deliberate.json", doc.dump());
  };
  expect_input_error("validate " + with({{"/engine/solver_iteration", "typo"}}),
                     "/deliberate: '/engine/solver_iteration' is not the JSON path of a setting");
  expect_input_error("validate " + with({{"engine.kn", "not a path"}}), "/deliberate: 'engine.kn' is not the JSON path");
  expect_input_error("validate " + with({{"/engine/type", ""}}), "/deliberate: '/engine/type': expected the reason");
  expect_input_error("validate " + with({{"/engine/type", 3}}), "/deliberate: '/engine/type': expected the reason");
  expect_input_error("validate " + with(Json::array({"/engine/type"})), "/deliberate: expected an object");
}

// One version: CMake's project version is what --version prints, the SDK's CRUMBLE_VERSION
// and CITATION.cff's version.
TEST(Cli, VersionIsTheProjectVersionEverywhere) {
  const std::string v = project_version();
  ASSERT_FALSE(v.empty()) << "no project(crumble VERSION x.y.z) in CMakeLists.txt";
  EXPECT_EQ(std::string(CRUMBLE_VERSION), v);
  EXPECT_EQ(std::to_string(CRUMBLE_VERSION_MAJOR) + "." + std::to_string(CRUMBLE_VERSION_MINOR) + "." +
                std::to_string(CRUMBLE_VERSION_PATCH),
            v);
  const Result r = run("--version");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.output.rfind("crumble " + v, 0), 0u) << r.output;
  const std::string cff = slurp(fs::path(CRUMBLE_SOURCE_DIR) / "CITATION.cff");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(cff, m, std::regex(R"((^|\n)version: ([^\n]+))"))) << cff;
  EXPECT_EQ(m[2].str(), v);
  EXPECT_TRUE(std::regex_search(cff, std::regex(R"((^|\n)license: GPL-3\.0-or-later\n)"))) << cff;
  EXPECT_NE(slurp(fs::path(CRUMBLE_SOURCE_DIR) / "LICENSE").find("GNU GENERAL PUBLIC LICENSE\n                       Version 3"),
            std::string::npos);
}
