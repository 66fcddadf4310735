// Resume keeps its promise: every analysis of the run is one row of events.csv, also across
// an interruption (rows matched by step, not by a printed time), and a resumed run reports
// the settling of the run it continues.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "output/Writers.h"

#include "scenarios/Registry.h"
#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using crumble::testing_support::run_cli;
using crumble::testing_support::column;
using crumble::testing_support::slurp;

namespace {

long data_rows(const std::string& csv) {
  std::stringstream in(csv);
  std::string line;
  long n = -1;  // header
  while (std::getline(in, line))
    if (!line.empty()) ++n;
  return n;
}

// Starts `cmd` (a crumble run writing into `out`) in the background and kills it with SIGKILL
// once out/series.csv.part holds a row of step >= `kill_step` (the run is a few steps further
// by then: the kill lands wherever the run is).
crumble::testing_support::CliResult run_and_kill(const std::string& cmd, const fs::path& out, long kill_step) {
  const std::string part = (out / "series.csv.part").string();
  return run_cli("--version >/dev/null; " + cmd + " >/dev/null 2>&1 & p=$!; for i in $(seq 1 6000); do [ -f " + part +
                 " ] && awk -F, 'NR>1 && $2>=" + std::to_string(kill_step) + " {f=1} END{exit !f}' " + part +
                 " && break; kill -0 $p 2>/dev/null || break; sleep 0.01; done; kill -KILL $p; wait $p; "
                 "echo killed");
}

// Starts `cmd` (a crumble run writing into `out`) in the background and kills it with SIGKILL
// once out/checkpoint.json is a checkpoint of the settling at settling step >= `kill_step`
// (the settling may have gone on to its next checkpoint by then).
crumble::testing_support::CliResult run_and_kill_settling(const std::string& cmd, const fs::path& out, long kill_step) {
  const std::string cp = (out / "checkpoint.json").string();
  return run_cli("--version >/dev/null; " + cmd + " >/dev/null 2>&1 & p=$!; for i in $(seq 1 20000); do [ -f " + cp +
                 " ] && s=$(grep -o '\"settling\":{[^}]*\"steps\":[0-9]*' " + cp +
                 " | grep -o '[0-9]*$') && [ \"$s\" -ge " + std::to_string(kill_step) +
                 " ] && break; kill -0 $p 2>/dev/null || break; sleep 0.002; done; kill -KILL $p; wait $p; echo killed");
}

// The settling step of a checkpoint of the settling, -1 for another checkpoint.
long settling_step(const fs::path& checkpoint) {
  const auto cp = nlohmann::json::parse(slurp(checkpoint));
  return cp.contains("settling") ? cp["settling"]["steps"].get<long>() : -1;
}

// One settling resume: `scenario` (a file in scenarios/) run with `sets` to its end into
// NAME/whole; the same run killed with SIGKILL at a settling step drawn from `seed` in
// [first_kill, settling steps − kill_margin] into NAME/killed, then resumed there. The
// settling must take more than `min_settle` steps, and the kill must land inside it.
struct SettlingResume {
  fs::path whole, killed;
  nlohmann::json whole_summary, resumed_summary;
  long resumed_at = -1;  // the settling step of the checkpoint the run resumed from
};

void kill_while_settling_and_resume(const std::string& name, const std::string& scenario, const std::string& sets,
                                    long min_settle, long first_kill, long kill_margin, unsigned seed,
                                    SettlingResume& r) {
  const fs::path base = fs::temp_directory_path() / "crumble_resume_test" / name;
  r.whole = base / "whole";
  r.killed = base / "killed";
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/" + scenario;
  const auto a = run_cli("run " + scen + " --out " + r.whole.string() + sets);
  ASSERT_EQ(a.status, 0) << a.output;
  r.whole_summary = nlohmann::json::parse(slurp(r.whole / "summary.json"));
  const long settle = r.whole_summary["packing_settle_steps"].get<long>();
  ASSERT_GT(settle, min_settle);
  std::mt19937 rng(seed);
  const long kill_step = std::uniform_int_distribution<long>(first_kill, settle - kill_margin)(rng);
  run_and_kill_settling(std::string(CRUMBLE_BINARY) + " run " + scen + " --out " + r.killed.string() + sets, r.killed,
                        kill_step);
  ASSERT_TRUE(fs::exists(r.killed / "checkpoint.json")) << "kill step " << kill_step;
  r.resumed_at = settling_step(r.killed / "checkpoint.json");
  ASSERT_GE(r.resumed_at, kill_step) << "killed after the settling";
  ASSERT_FALSE(fs::exists(r.killed / "packing.json")) << "killed after the settling (kill step " << kill_step << ")";
  const auto b = run_cli("run " + scen + " --out " + r.killed.string() + sets + " --resume");
  ASSERT_EQ(b.status, 0) << b.output;
  r.resumed_summary = nlohmann::json::parse(slurp(r.killed / "summary.json"));
  EXPECT_EQ(r.resumed_summary["resumed_from_settle_step"].get<long>(), r.resumed_at);
}

// summary.json without its wall times, resume markers and representation counts.
std::string summary_but_process(const fs::path& file) {
  auto j = nlohmann::json::parse(slurp(file));
  for (const char* k : {"wall_seconds", "time_breakdown_s", "resumed_from_step", "resumed_from_settle_step",
                        "representations_built"})
    j.erase(k);
  return j.dump(1);
}

// Every regular file under `dir`, relative paths.
std::set<std::string> files_under(const fs::path& dir) {
  std::set<std::string> r;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) r.insert(fs::relative(e.path(), dir).string());
  return r;
}

// A CSV with the named columns blanked (wall-time columns).
std::string without_columns(const std::string& csv, const std::set<std::string>& names) {
  std::stringstream in(csv);
  std::string line, out;
  std::set<int> drop;
  bool header = true;
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::string cell;
    int k = 0;
    while (std::getline(ls, cell, ',')) {
      if (header && names.count(cell)) drop.insert(k);
      out += (k ? "," : "") + (drop.count(k) ? std::string("*") : cell);
      ++k;
    }
    out += "\n";
    header = false;
  }
  return out;
}

// The resumed run's folder holds the same files as the uninterrupted one, each byte for byte
// but summary.json, stages.csv and events.csv's wall_ms column (wall times of the process).
void expect_same_files_but_wall_times(const fs::path& whole, const fs::path& killed, long kill_step) {
  ASSERT_EQ(files_under(whole), files_under(killed)) << "kill step " << kill_step;  // no .part left
  for (const auto& f : files_under(whole)) {
    if (f == "summary.json" || f == "events.csv" || f == "stages.csv") continue;
    EXPECT_TRUE(slurp(whole / f) == slurp(killed / f)) << f << " differs (kill step " << kill_step << ")";
  }
  EXPECT_EQ(without_columns(slurp(whole / "events.csv"), {"wall_ms"}),
            without_columns(slurp(killed / "events.csv"), {"wall_ms"}))
      << "kill step " << kill_step;
}

}  // namespace

// stages.csv of a killed and resumed run against the uninterrupted one's.
static void expect_same_stages(const fs::path& whole, const fs::path& killed, const nlohmann::json& sa,
                               const nlohmann::json& sb, long kill_step) {
  // stages.csv: the same stages, steps, grains and analysis counts; wall times are the process's.
  const std::set<std::string> wall_columns{"resumed", "wall_s", "wall_total_s", "engine_s", "engine_ms_per_step",
                                           "analysis_s", "mean_analysis_ms", "breaking_share_of_analysis_time",
                                           "fragments_s"};
  EXPECT_EQ(without_columns(slurp(whole / "stages.csv"), wall_columns),
            without_columns(slurp(killed / "stages.csv"), wall_columns))
      << "kill step " << kill_step;
  {
    // Its stages add up to the run: every analysis and breakage event in exactly one stage.
    const auto rows = crumble::read_csv((whole / "stages.csv").string());
    ASSERT_GE(rows.size(), 2u);
    const std::size_t ca = column(rows, "analyses"), ce = column(rows, "breaking_analyses");
    long na = 0, ne = 0;
    for (std::size_t i = 1; i < rows.size(); ++i) na += std::stol(rows[i][ca]), ne += std::stol(rows[i][ce]);
    EXPECT_EQ(na, sa["analyses"].get<long>());
    EXPECT_EQ(ne, sa["breakage_events"].get<long>());
  }
  {
    // The stage the resume fell into: its engine time is this process's, so its time per step
    // is over the steps since the resume, not since the stage began.
    const auto rows = crumble::read_csv((killed / "stages.csv").string());
    ASSERT_GE(rows.size(), 2u);
    const std::size_t c_step = column(rows, "step"), c_steps = column(rows, "steps"),
                      c_engine = column(rows, "engine_s"), c_per = column(rows, "engine_ms_per_step");
    const long resumed_at = sb["resumed_from_step"].get<long>();
    bool seen = false;
    for (std::size_t i = 1; i < rows.size(); ++i) {
      const long end = std::stol(rows[i][c_step]), begin = end - std::stol(rows[i][c_steps]);
      if (!(begin < resumed_at && resumed_at < end)) continue;
      seen = true;
      EXPECT_NEAR(std::stod(rows[i][c_per]), 1e3 * std::stod(rows[i][c_engine]) / (end - resumed_at),
                  1e-6 * std::stod(rows[i][c_per]))
          << "stage ending at step " << end << ", resumed at " << resumed_at;
    }
    if (!seen) std::cerr << "(the resume fell on a stage boundary: no stage to check)\n";
  }
}

// The checkpoint holds the engine state and every grain's strength values.
static void expect_engine_state_and_strengths(const fs::path& killed) {
  const auto cp = nlohmann::json::parse(slurp(killed / "checkpoint.json"));
  ASSERT_TRUE(cp.contains("engine_state"));
  EXPECT_EQ(cp["engine_state"]["engine"], "lsdem");
  EXPECT_FALSE(cp["engine_state"]["pairs"].empty());
  int remembered = 0;
  for (const auto& g : cp["grains"]) {
    EXPECT_FALSE(g["strength"].empty());
    remembered += g.contains("intact_load");
  }
  EXPECT_GT(remembered, 0);
}

// lsdem saves its contact history, half-step velocities and platen motion in the checkpoint
// (Engine::save_state), and the checkpoint saves the shapes' mass properties as they were:
// a run killed with SIGKILL at a (seeded) random step after its first checkpoint and resumed
// writes every file as the uninterrupted run does, byte for byte, but for wall times. The
// final checkpoint.json (grains with their Weibull strengths, lineage, poses, and the engine
// state) is compared too, so the stress model's per-grain state is restored as it was.
// (The body is shared with LsdemSelectiveScalingResumedAfterSigkillIsBitIdentical: `extra`
// adds settings, `name` the folder; the uninterrupted run's summary is returned in `whole_summary`.)
static void lsdem_kill_and_resume(const std::string& name, const std::string& extra, nlohmann::json& whole_summary) {
  const fs::path base = fs::temp_directory_path() / "crumble_resume_test" / name;
  const fs::path whole = base / "whole", killed = base / "killed";
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json";
  // Crushable (stress model, von Mises, weak grains, level-set fragments); first breakage
  // at step 2150 of 2802; checkpoints every 500 steps and no wall-time checkpoint, so the
  // resume point is known.
  // The skip rule is on (Screening.h): each grain's memory of its last intact analysis is in
  // the checkpoint, or the resumed run would analyse grains the whole run skipped.
  const std::string sets =
      " --quiet --threads 1 --set breakage.type=stress --set breakage.criterion=von_mises --set breakage.strength=3e6"
      " --set schedule.every_steps=50 --set output.checkpoint_every=500 --set output.checkpoint_every_s=0"
      " --set screening.skip_intact_tolerance=0.1" + extra;
  const auto a = run_cli("run " + scen + " --out " + whole.string() + sets);
  ASSERT_EQ(a.status, 0) << a.output;
  const auto sa = nlohmann::json::parse(slurp(whole / "summary.json"));
  whole_summary = sa;
  const long steps = sa["steps"].get<long>();
  ASSERT_GT(sa["breakage_events"].get<long>(), 0);
  ASSERT_GT(sa["analyses_skipped"].get<long>(), 0);
  ASSERT_GT(steps, 1200);
  // Kill somewhere after the first checkpoint (step 500) and before the end.
  std::mt19937 rng(20261130);
  const long kill_step = std::uniform_int_distribution<long>(600, steps - 150)(rng);
  const std::string cmd = std::string(CRUMBLE_BINARY) + " run " + scen + " --out " + killed.string() + sets;
  run_and_kill(cmd, killed, kill_step);
  ASSERT_TRUE(fs::exists(killed / "checkpoint.json")) << "kill step " << kill_step;
  ASSERT_FALSE(fs::exists(killed / "summary.json")) << "the run ended before it was killed (kill step " << kill_step << ")";
  // A killed run leaves its rows in .part files, possibly past the checkpoint.
  EXPECT_TRUE(fs::exists(killed / "series.csv.part"));
  EXPECT_TRUE(fs::exists(killed / "events.csv.part"));
  const auto b = run_cli("run " + scen + " --out " + killed.string() + sets + " --resume");
  ASSERT_EQ(b.status, 0) << b.output;
  const auto sb = nlohmann::json::parse(slurp(killed / "summary.json"));
  EXPECT_EQ(sb["resumed_from_step"].get<long>() % 500, 0);
  EXPECT_GE(sb["resumed_from_step"].get<long>(), 500);
  EXPECT_LE(sb["resumed_from_step"].get<long>(), kill_step + 500);
  // The screening tally goes on from the checkpoint's (Simulation::saved_state).
  ASSERT_GT(sa["screening_selected"].get<double>(), 0);
  for (const char* k : {"screening_too_small", "screening_few_contacts", "screening_below_threshold",
                        "screening_unbalanced_force", "screening_unbalanced_moment", "screening_selected"})
    EXPECT_EQ(sa[k], sb[k]) << k;

  expect_same_files_but_wall_times(whole, killed, kill_step);
  expect_same_stages(whole, killed, sa, sb, kill_step);
  // summary.json: equal but for wall times, the resume marker and the representation counts
  // (a cost of the process: a resumed run counts what it rebuilt from the checkpoint).
  nlohmann::json ja = sa, jb = sb;
  for (auto* j : {&ja, &jb})
    for (const char* k : {"wall_seconds", "time_breakdown_s", "resumed_from_step", "representations_built"}) j->erase(k);
  EXPECT_EQ(ja.dump(1), jb.dump(1));
  expect_engine_state_and_strengths(killed);
}

TEST(Resume, LsdemRunResumedAfterSigkillIsBitIdentical) {
  nlohmann::json sa;
  lsdem_kill_and_resume("bit_identical", "", sa);
}

// Selective mass scaling (engine.selective_dt_fraction 1: every fragment below the
// initial packing's stable step is scaled up to it): the target and the factors are in the
// checkpoint's engine state, and the killed and resumed run is the uninterrupted one byte
// for byte, its added mass (summary.json) included.
TEST(Resume, LsdemSelectiveScalingResumedAfterSigkillIsBitIdentical) {
  nlohmann::json sa;
  lsdem_kill_and_resume("selective_scaling", " --set engine.selective_dt_fraction=1", sa);
  if (HasFatalFailure()) return;
  ASSERT_TRUE(sa.contains("engine_selective_scaling_grains_scaled")) << sa.dump(1);
  EXPECT_GT(sa["engine_selective_scaling_grains_scaled"].get<double>(), 0);
  EXPECT_GT(sa["engine_selective_scaling_added_mass_kg"].get<double>(), 0);
  EXPECT_GT(sa["engine_selective_scaling_max_factor"].get<double>(), 1);
}

// Bullet keeps state a checkpoint does not hold (persistent manifolds, solver warm starts, the
// platen's velocity: it restarts at rest where it was), so a resumed run is a new sample of
// the same loading, not a continuation bit for bit. Its statistics stay close: on this small
// crushable scenario (40 spheres, stress model, alpha-shape plane cuts, 3 MPa) resumes at
// steps 100 and 200 of 250 ended with the same 37 breakage events and 77 grains and a final
// void ratio 2.1 % above and 2.2 % below the uninterrupted run's (0.959). Tolerances: 5 % on
// the void ratio, 20 % on events and grains.
TEST(Resume, BulletRunResumedAfterSigkillStaysWithinTolerance) {
  bool bullet = false, alpha = false;
  for (const auto& e : crumble::engines().entries()) bullet |= e.name == "bullet";
  for (const auto& e : crumble::fragment_builders().entries()) alpha |= e.name == "alpha_shape";
  if (!bullet || !alpha) GTEST_SKIP() << "needs the bullet engine and the alpha_shape builder";
  const fs::path base = fs::temp_directory_path() / "crumble_resume_test" / "bullet";
  const fs::path whole = base / "whole", killed = base / "killed";
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_quick.json";
  const std::string sets =
      " --quiet --threads 1 --set packing.count=40 --set container.lx=5e-3 --set container.ly=5e-3"
      " --set breakage.type=stress --set breakage.criterion=von_mises --set breakage.strength=4e6"
      " --set fragments.type=alpha_shape --set loading.max_stress=3e6 --set loading.ramp_time=0.02"
      " --set engine.solver_iterations=100 --set simulation.sample_every=1"
      " --set output.checkpoint_every=100 --set output.checkpoint_every_s=0"
      // A time step by stress level (as Zhu & Zhao 2019 §5), 6e-5 s from 0.1 MPa on: reached
      // well before the first checkpoint.
      " --set 'time_step=[{\"below_stress\":1e5,\"dt\":8e-5},{\"below_stress\":1e300,\"dt\":6e-5}]'";
  const auto a = run_cli("run " + scen + " --out " + whole.string() + sets);
  ASSERT_EQ(a.status, 0) << a.output;
  const auto sa = nlohmann::json::parse(slurp(whole / "summary.json"));
  ASSERT_GT(sa["breakage_events"].get<long>(), 10);
  std::mt19937 rng(1130);
  const long kill_step = std::uniform_int_distribution<long>(110, sa["steps"].get<long>() - 40)(rng);
  run_and_kill(std::string(CRUMBLE_BINARY) + " run " + scen + " --out " + killed.string() + sets, killed, kill_step);
  ASSERT_TRUE(fs::exists(killed / "checkpoint.json"));
  ASSERT_FALSE(fs::exists(killed / "summary.json")) << "the run ended before it was killed";
  const auto b = run_cli("run " + scen + " --out " + killed.string() + sets + " --resume");
  ASSERT_EQ(b.status, 0) << b.output;
  const auto sb = nlohmann::json::parse(slurp(killed / "summary.json"));
  EXPECT_GE(sb["resumed_from_step"].get<long>(), 100);
  EXPECT_EQ(sb["steps"], sa["steps"]);
  const double ea = sa["void_ratio_final"].get<double>(), eb = sb["void_ratio_final"].get<double>();
  EXPECT_NEAR(eb, ea, 0.05 * ea) << "kill step " << kill_step;
  auto near = [](long x, long y) { return std::abs(x - y) <= std::max(1L, y / 5); };
  EXPECT_TRUE(near(sb["breakage_events"].get<long>(), sa["breakage_events"].get<long>())) << sb.dump(1);
  EXPECT_TRUE(near(sb["grains_final"].get<long>(), sa["grains_final"].get<long>())) << sb.dump(1);
  // Every analysis is one row of events.csv, every sample one row of series.csv.
  EXPECT_EQ(data_rows(slurp(killed / "events.csv")), sb["analyses"].get<long>());
  EXPECT_EQ(data_rows(slurp(killed / "series.csv")), data_rows(slurp(whole / "series.csv")));
  EXPECT_FALSE(nlohmann::json::parse(slurp(killed / "checkpoint.json")).contains("engine_state"));
  // Bullet keeps no contact forces in the checkpoint: the first step after the resume still
  // takes the time step of the checkpoint's stress, not that of zero stress.
  const auto rows = crumble::read_csv((killed / "series.csv").string());
  ASSERT_GE(rows.size(), 2u);
  const std::size_t c_step = column(rows, "step"), c_dt = column(rows, "dt_s");
  ASSERT_GT(c_dt, 0u);
  long after = 0;
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (std::stol(rows[i][c_step]) > sb["resumed_from_step"].get<long>()) {
      ++after;
      EXPECT_DOUBLE_EQ(std::stod(rows[i][c_dt]), 6e-5) << "step " << rows[i][c_step];
    }
  EXPECT_GT(after, 0);
}

// A checkpoint whose engine state does not fit the grains is refused with the JSON path.
TEST(Resume, MalformedEngineStateIsAConfigError) {
  const fs::path out = fs::temp_directory_path() / "crumble_resume_test" / "bad_state";
  fs::remove_all(out);
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json";
  const std::string sets = " --quiet --set simulation.max_steps=200 --set output.checkpoint_every=100";
  ASSERT_EQ(run_cli("run " + scen + " --out " + out.string() + sets).status, 0);
  auto cp = nlohmann::json::parse(slurp(out / "checkpoint.json"));
  ASSERT_TRUE(cp.contains("engine_state"));
  cp["engine_state"]["bodies"].erase(0);
  std::ofstream(out / "checkpoint.json") << cp.dump();
  const auto r = run_cli("run " + scen + " --out " + out.string() + sets + " --set simulation.max_steps=400 --resume");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("/engine_state"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bodies"), std::string::npos) << r.output;
}

// A grain's skip-rule memory (intact_load) that is not [partner, fx, fy, fz] rows in
// increasing partner order is refused with its JSON path.
TEST(Resume, MalformedIntactLoadIsAConfigError) {
  const fs::path out = fs::temp_directory_path() / "crumble_resume_test" / "bad_intact_load";
  fs::remove_all(out);
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json";
  const std::string sets = " --quiet --set simulation.max_steps=200 --set output.checkpoint_every=100";
  ASSERT_EQ(run_cli("run " + scen + " --out " + out.string() + sets).status, 0);
  const auto good = nlohmann::json::parse(slurp(out / "checkpoint.json"));
  for (const auto& bad : {nlohmann::json::parse(R"([[3, 1.0, 2.0, 3.0], [2, 1.0, 2.0, 3.0]])"),
                          nlohmann::json::parse(R"([[3, 1.0, "x", 3.0]])"), nlohmann::json::parse(R"([[3, 1.0]])"),
                          nlohmann::json::parse(R"({"3": 1})")}) {
    auto cp = good;
    cp["grains"][0]["intact_load"] = bad;
    std::ofstream(out / "checkpoint.json") << cp.dump();
    const auto r = run_cli("run " + scen + " --out " + out.string() + sets + " --set simulation.max_steps=400 --resume");
    EXPECT_EQ(r.status, 2) << bad.dump() << "\n" << r.output;
    EXPECT_NE(r.output.find("/grains/0/intact_load"), std::string::npos) << r.output;
  }
}

TEST(Resume, EventsRowsMatchAnalysesAcrossAnInterruption) {
  const fs::path out = fs::temp_directory_path() / "crumble_resume_test" / "events";
  fs::remove_all(out);
  // A small crushable 2D packing (stress criterion, weak grains, a check every 50 steps,
  // level-set fragments), checkpointed every 500 steps and killed, so analyses at and after
  // the checkpoint step meet the resume.
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json";
  const std::string sets =
      " --quiet --set breakage.type=stress --set breakage.criterion=von_mises --set breakage.strength=3e6"
      " --set schedule.every_steps=50 --set output.checkpoint_every=500";
  // SIGKILL past the first checkpoint (step 500): the .part files then hold rows past the
  // checkpoint, which the resume must drop, keeping every row up to the checkpoint step. (The
  // kill follows the run's own series, not a clock: a loaded machine once let the whole run
  // end between a poll for the checkpoint file and a fixed sleep.)
  const std::string cmd = std::string(CRUMBLE_BINARY) + " run " + scen + " --out " + out.string() + sets;
  const auto first = run_and_kill(cmd, out, 600);
  ASSERT_TRUE(fs::exists(out / "checkpoint.json")) << first.output;
  ASSERT_FALSE(fs::exists(out / "summary.json")) << "the run ended before it was killed: " << first.output;
  const auto second = run_cli("run " + scen + " --out " + out.string() + sets + " --resume");
  ASSERT_EQ(second.status, 0) << second.output;
  const auto s2 = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s2["resumed_from_step"].get<long>() % 500, 0);
  EXPECT_GT(s2["analyses"].get<long>(), 0);
  EXPECT_GT(s2["breakage_events"].get<long>(), 0);
  EXPECT_EQ(data_rows(slurp(out / "events.csv")), s2["analyses"].get<long>());
}

// A run killed while writing a row leaves it cut in the .part file: the resumed stream keeps
// only whole rows up to the resume step (a cut "0.0052" once passed as step 0, and a cut step
// "3" of 312 would pass as step 3).
TEST(Resume, CutRowsOfAKilledRunAreDropped) {
  const fs::path dir = fs::temp_directory_path() / "crumble_resume_test" / "cut_rows";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string header = "time_s,step,outcome,note";
  const std::string whole = "0.1,100,split,\n0.2,200,intact,x\n";
  for (const std::string cut : {"0.0052", "0.31,3", "0.31,312,spl", "0.31,"}) {
    std::ofstream(dir / "events.csv.part") << header << "\n" << whole << "0.3,300,split,y\n" << cut;
    crumble::CsvStream s((dir / "events.csv").string(), header, 250);
    s.finish();
    EXPECT_EQ(slurp(dir / "events.csv"), header + "\n" + whole) << "cut row: " << cut;
  }
  // Resumed from a finished file: until the run finishes, only the .part holds its rows.
  std::ofstream(dir / "events.csv") << header << "\n" << whole << "0.3,300,split,y\n";
  {
    crumble::CsvStream s((dir / "events.csv").string(), header, 250);
    EXPECT_FALSE(fs::exists(dir / "events.csv"));
    EXPECT_EQ(slurp(dir / "events.csv.part"), header + "\n" + whole);
  }
  EXPECT_FALSE(fs::exists(dir / "events.csv"));
}

// The settling is checkpointed like the loading (output.checkpoint_every settling steps): an
// lsdem run killed with SIGKILL at a (seeded) random step of its settling and resumed
// settles on from the checkpoint and writes every file as the uninterrupted run does, byte for
// byte, but for wall times (the packing, the series, the summary).
TEST(Resume, LsdemSettlingResumedAfterSigkillIsBitIdentical) {
  // 80 disks and polygons settling for 20000 steps; a short loading after it.
  const std::string sets =
      " --quiet --threads 1 --set simulation.max_steps=300 --set output.checkpoint_every=2000"
      " --set output.checkpoint_every_s=0 --set output.plots=false";
  SettlingResume r;
  kill_while_settling_and_resume("settling_lsdem", "oedometer_rigid_2d_quick.json", sets, 8000, 2000, 4000, 20260521,
                                 r);
  if (HasFatalFailure()) return;
  EXPECT_FALSE(r.resumed_summary.contains("resumed_from_step"));
  EXPECT_EQ(summary_but_process(r.whole / "summary.json"), summary_but_process(r.killed / "summary.json"));
  ASSERT_EQ(files_under(r.whole), files_under(r.killed));
  for (const auto& f : files_under(r.whole)) {
    if (f == "summary.json" || f == "stages.csv") continue;
    EXPECT_TRUE(slurp(r.whole / f) == slurp(r.killed / f))
        << f << " differs (resumed at settling step " << r.resumed_at << ")";
  }
}

// Bullet rebuilt from a checkpoint of the settling restarts its contacts and the platen at
// rest (docs/scenarios.md, output): the packing settles on to a new sample of the same
// settling, and the run stays within the resume tolerance of the loading's resume (5 % on the
// final void ratio). Killed at a seeded random step after the first checkpoint.
TEST(Resume, BulletSettlingResumedAfterSigkillStaysWithinTolerance) {
  bool bullet = false;
  for (const auto& e : crumble::engines().entries()) bullet |= e.name == "bullet";
  if (!bullet) GTEST_SKIP() << "needs the bullet engine";
  // 40 spheres settling in about 1100 steps, then a ramp to 3 MPa in 250 steps.
  const std::string sets =
      " --quiet --threads 1 --set packing.count=40 --set container.lx=5e-3 --set container.ly=5e-3"
      " --set loading.max_stress=3e6 --set engine.solver_iterations=100 --set output.checkpoint_every=100"
      " --set output.checkpoint_every_s=0 --set output.plots=false";
  SettlingResume r;
  kill_while_settling_and_resume("settling_bullet", "oedometer_rigid_quick.json", sets, 500, 100, 200, 521, r);
  if (HasFatalFailure()) return;
  const nlohmann::json &sa = r.whole_summary, &sb = r.resumed_summary;
  EXPECT_EQ(sb["steps"], sa["steps"]);
  EXPECT_EQ(sb["packing_settled"], 1.0);
  const double ea = sa["void_ratio_final"].get<double>(), eb = sb["void_ratio_final"].get<double>();
  EXPECT_NEAR(eb, ea, 0.05 * ea) << "resumed at settling step " << r.resumed_at;
  EXPECT_EQ(data_rows(slurp(r.killed / "series.csv")), data_rows(slurp(r.whole / "series.csv")));
}

// A run killed while its packing settles, before the settling's first checkpoint, leaves
// nothing to resume: --resume says so and what to do, instead of blaming the settings.
TEST(Resume, KilledBeforeTheFirstCheckpointSaysSo) {
  const fs::path out = fs::temp_directory_path() / "crumble_resume_test" / "before_first";
  fs::remove_all(out);
  fs::create_directories(out);
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json";
  const std::string sets = " --quiet --set output.checkpoint_every=1000000 --set output.checkpoint_every_s=0";
  const std::string cmd = std::string(CRUMBLE_BINARY) + " run " + scen + " --out " + out.string() + sets;
  run_cli("--version >/dev/null; " + cmd + " >/dev/null 2>&1 & p=$!; for i in $(seq 1 5000); do [ -f " +
          (out / "effective_scenario.json").string() + " ] && break; sleep 0.002; done; kill -KILL $p; wait $p; echo k");
  ASSERT_FALSE(fs::exists(out / "checkpoint.json"));
  ASSERT_FALSE(fs::exists(out / "packing.json")) << "the settling ended before the kill";
  const auto r = run_cli("run " + scen + " --out " + out.string() + sets + " --resume");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("stopped while its packing settled, before the settling's first checkpoint (every 1000000 steps"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--force"), std::string::npos) << r.output;
  // A folder without a run says that instead.
  const fs::path empty = out / "empty";
  fs::create_directories(empty);
  const auto e = run_cli("run " + scen + " --out " + empty.string() + sets + " --resume");
  EXPECT_EQ(e.status, 2) << e.output;
  EXPECT_NE(e.output.find("the folder holds no run"), std::string::npos) << e.output;
}

// The jaw crusher (an open scene: rocks fed one after another, a swing jaw on its eccentric,
// product leaving through the discharge) is checkpointed like a closed packing: the feed count,
// the product collected so far, the lsdem engine state with the walls' poses, motion and
// forces. A shortened run (6 cycles, 4 rocks wider than the closed side setting, so that some
// break) killed with SIGKILL at a seeded random step after its first product grain and
// resumed writes the same product_psd.csv and product.csv, byte for byte, and every other file
// but for wall times.
TEST(Resume, JawCrusherResumedAfterSigkillGivesTheSameProduct) {
  const fs::path base = fs::temp_directory_path() / "crumble_resume_test" / "jaw";
  const fs::path whole = base / "whole", killed = base / "killed";
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/jaw_crusher_2d_quick.json";
  // About 710000 steps; the first product grain leaves at step ≈ 412500, and the time step
  // is reduced to the engine's stable step from step ≈ 522000 on.
  const std::string sets =
      " --quiet --threads 1 --set scene.cycles=6 --set scene.rocks.count=4 --set 'scene.rocks.diameter=[0.06,0.1]'"
      " --set output.checkpoint_every=20000 --set output.checkpoint_every_s=0 --set output.plots=false";
  const auto a = run_cli("run " + scen + " --out " + whole.string() + sets);
  ASSERT_EQ(a.status, 0) << a.output;
  const auto sa = nlohmann::json::parse(slurp(whole / "summary.json"));
  ASSERT_EQ(sa["rocks_fed"].get<double>(), 4);
  ASSERT_GE(sa["product_grains"].get<double>(), 3);
  ASSERT_GT(sa["breakage_events"].get<long>(), 0);
  ASSERT_GT(sa["steps"].get<long>(), 680000);
  std::mt19937 rng(20261204);
  const long kill_step = std::uniform_int_distribution<long>(480000, 660000)(rng);
  run_and_kill(std::string(CRUMBLE_BINARY) + " run " + scen + " --out " + killed.string() + sets, killed, kill_step);
  ASSERT_TRUE(fs::exists(killed / "checkpoint.json")) << "kill step " << kill_step;
  ASSERT_FALSE(fs::exists(killed / "summary.json")) << "the run ended before it was killed (kill step " << kill_step << ")";
  {
    // What the run is resumed from: rocks fed, product collected, the walls in the engine state.
    const auto cp = nlohmann::json::parse(slurp(killed / "checkpoint.json"));
    ASSERT_TRUE(cp["state"].contains("open_scene")) << "kill step " << kill_step;
    EXPECT_GE(cp["state"]["open_scene"]["rocks_fed"].get<long>(), 1);
    EXPECT_FALSE(cp["state"]["open_scene"]["product"].empty()) << "kill step " << kill_step;
    ASSERT_TRUE(cp.contains("engine_state"));
    EXPECT_EQ(cp["engine_state"]["walls"].size(), 4u);  // the fixed and the swing jaw, the hopper's two sides
  }
  const auto b = run_cli("run " + scen + " --out " + killed.string() + sets + " --resume");
  ASSERT_EQ(b.status, 0) << b.output;
  const auto sb = nlohmann::json::parse(slurp(killed / "summary.json"));
  EXPECT_GE(sb["resumed_from_step"].get<long>(), 460000);
  EXPECT_TRUE(slurp(whole / "product_psd.csv") == slurp(killed / "product_psd.csv")) << "kill step " << kill_step;
  EXPECT_TRUE(slurp(whole / "product.csv") == slurp(killed / "product.csv")) << "kill step " << kill_step;
  expect_same_files_but_wall_times(whole, killed, kill_step);
  EXPECT_EQ(summary_but_process(whole / "summary.json"), summary_but_process(killed / "summary.json"));
}

// An open scene's part of a checkpoint that does not fit the scene is refused with its JSON
// path: more rocks fed than the scene feeds, a product grain that is not eight numbers.
TEST(Resume, MalformedOpenSceneIsAConfigError) {
  const fs::path out = fs::temp_directory_path() / "crumble_resume_test" / "bad_open_scene";
  fs::remove_all(out);
  const std::string scen = std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/jaw_crusher_2d_quick.json";
  const std::string sets = " --quiet --set scene.cycles=1 --set scene.rocks.count=2 --set output.checkpoint_every=20000"
                           " --set output.plots=false";
  ASSERT_EQ(run_cli("run " + scen + " --out " + out.string() + sets).status, 0);
  const auto good = nlohmann::json::parse(slurp(out / "checkpoint.json"));
  ASSERT_TRUE(good["state"].contains("open_scene"));
  const std::vector<std::pair<std::string, nlohmann::json>> bad = {
      {"rocks_fed", 3}, {"product", nlohmann::json::parse(R"([[1, 0, 0, 0.1, 1e-3, 2.6]])")},
      {"product", nlohmann::json::parse(R"([[1, 0, 0, 0.1, 1e-3, 2.6, 0.05, "x"]])")}, {"mass_fed", -1}};
  for (const auto& [key, value] : bad) {
    auto cp = good;
    cp["state"]["open_scene"][key] = value;
    std::ofstream(out / "checkpoint.json") << cp.dump();
    const auto r = run_cli("run " + scen + " --out " + out.string() + sets + " --resume");
    EXPECT_EQ(r.status, 2) << key << " = " << value.dump() << "\n" << r.output;
    EXPECT_NE(r.output.find(key == "rocks_fed" ? "rocks fed" : "/state/open_scene/" + key), std::string::npos)
        << r.output;
  }
}
