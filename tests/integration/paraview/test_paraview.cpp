// ParaView output read back with VTK's own readers (python3-vtk9, read_vtk.py beside this
// file): every file of grains.pvd, scene.pvd and analyses.pvd opens, counts agree, the
// documented fields are there and hold no NaN (docs/output.md "ParaView"). Skipped with the
// reason when python3-vtk9 is not installed (scripts/setup.sh installs it).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;
using Json = nlohmann::json;

namespace {

const std::string kReader = std::string(CRUMBLE_SOURCE_DIR) + "/tests/integration/paraview/read_vtk.py";

// Debian's python3-vtk9 belongs to /usr/bin/python3; a `python3` earlier on PATH (pyenv,
// a venv) may not see it. "" when neither has VTK.
std::string vtk_python() {
  for (const char* py : {"/usr/bin/python3", "python3"})
    if (std::system((std::string(py) + " -c 'import vtkmodules.vtkIOXML' >/dev/null 2>&1").c_str()) == 0) return py;
  return "";
}

bool have_vtk() { return !vtk_python().empty(); }

struct Read {
  int status = -1;
  std::string output;
  Json report;
};

Read read_vtk(const fs::path& dir, const std::string& args) {
  Read r;
  const std::string cmd = vtk_python() + " " + kReader + " " + dir.string() + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  while (p && fgets(buf, sizeof buf, p)) r.output += buf;
  const int st = p ? pclose(p) : -1;
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  if (r.status == 0) r.report = Json::parse(r.output.substr(r.output.find('{')));
  return r;
}

fs::path fresh(const std::string& name) {
  const fs::path out = fs::temp_directory_path() / "crumble_paraview_test" / name;
  fs::remove_all(out);
  return out;
}

const std::string kGrainFields =
    "grain,parent,origin,generation,crush_count,diameter,velocity,angular_velocity";

}  // namespace

// 3D crushable: one 2 mm sphere crushed by peridynamics (Zhu & Zhao 2019 §4.2), every block,
// contact lines and the analysis lattice with damage.
TEST(ParaView, SingleGrainPeridynamicsEveryFileReads) {
  if (!have_vtk()) GTEST_SKIP() << "python3-vtk9 is not installed (apt-get install python3-vtk9)";
  const fs::path out = fresh("single_grain_pd");
  const auto run = run_cli("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/single_grain_pd.json --out " +
                           out.string() +
                           " --quiet --threads 1 --set breakage.spacing_fraction=0.1 --set output.vtk_every=200"
                           " --set output.vtk_contacts=true --set output.vtk_analyses=true");
  ASSERT_EQ(run.status, 0) << run.output;
  const Json sum = Json::parse(slurp(out / "summary.json"));
  ASSERT_EQ(sum["breakage_events"].get<long>(), 1) << "the grain must break for the test to mean anything";

  const Read r = read_vtk(out, "--cell-fields " + kGrainFields +
                                   ",max_contact_force_N,gc_J_m2,threshold_force_N,sphericity --contacts --analyses"
                                   " --point-fields damage,piece,displacement_m,grain");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto& grains = r.report["grains"];
  ASSERT_GE(grains.size(), 2u);
  // First snapshot: the one grain; last: its children, each crushed once.
  EXPECT_EQ(grains.front()["grains"].get<long>(), 1);
  EXPECT_EQ(grains.back()["grains"].get<long>(), sum["grains_final"].get<long>());
  EXPECT_EQ(grains.back()["max_crush_count"].get<int>(), 1);
  // Every snapshot has the walls (floor + 4 sides) and the platen as blocks of its scene.
  const auto& scene = r.report["scene"];
  ASSERT_EQ(scene.size(), grains.size());
  for (const auto& s : scene) {
    EXPECT_EQ(s["blocks"]["walls"]["cells"].get<long>(), 5);
    EXPECT_EQ(s["blocks"]["platen"]["cells"].get<long>(), 1);
    EXPECT_EQ(s["blocks"]["contacts"]["cells"].get<long>() * 2, s["blocks"]["contacts"]["points"].get<long>());
  }
  // The loaded grain touches the floor and the platen at the snapshot before it broke.
  long max_contacts = 0;
  for (const auto& s : scene) max_contacts = std::max(max_contacts, s["blocks"]["contacts"]["cells"].get<long>());
  EXPECT_GE(max_contacts, 2);
  // One analysis file for the one breakage, its lattice damaged somewhere (a crack).
  const auto& an = r.report["analyses"];
  ASSERT_EQ(an.size(), 1u);
  EXPECT_GT(an[0]["points"].get<long>(), 100);
  EXPECT_GT(an[0]["max_damage"].get<double>(), 0.0);
  EXPECT_LE(an[0]["max_damage"].get<double>(), 1.0);
}

// 2D crushable: level-set DEM with the average-stress criterion (Harmon et al. 2020): walls
// and platen as polylines, the criterion's equivalent stress and the Weibull strength per grain.
TEST(ParaView, TwoDimensionalStressRunEveryFileReads) {
  if (!have_vtk()) GTEST_SKIP() << "python3-vtk9 is not installed (apt-get install python3-vtk9)";
  const fs::path out = fresh("cross_2d_stress");
  const auto run = run_cli("run " + std::string(CRUMBLE_SOURCE_DIR) + "/tests/integration/cross/cross_2d.json --out " +
                           out.string() +
                           " --quiet --threads 1 --set breakage.type=stress --set breakage.strength=5e6"
                           " --set output.vtk_every=2000 --set output.vtk_contacts=true --set output.vtk_analyses=true");
  ASSERT_EQ(run.status, 0) << run.output;
  const Json sum = Json::parse(slurp(out / "summary.json"));
  ASSERT_GT(sum["breakage_events"].get<long>(), 0) << "the run must break grains for the test to mean anything";

  const Read r = read_vtk(out, "--cell-fields " + kGrainFields +
                                   ",equivalent_stress_Pa,strength_Pa,circularity --contacts --analyses");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto& grains = r.report["grains"];
  ASSERT_GE(grains.size(), 2u);
  // 2D: one polygon cell per grain.
  for (const auto& g : grains) EXPECT_EQ(g["cells"].get<long>(), g["grains"].get<long>());
  EXPECT_EQ(grains.back()["grains"].get<long>(), sum["grains_final"].get<long>());
  EXPECT_GE(grains.back()["max_crush_count"].get<int>(), 1);
  for (const auto& s : r.report["scene"]) {
    EXPECT_EQ(s["blocks"]["walls"]["cells"].get<long>(), 3);  // floor and two side walls, as lines
    EXPECT_EQ(s["blocks"]["walls"]["points"].get<long>(), 6);
    EXPECT_EQ(s["blocks"]["platen"]["cells"].get<long>(), 1);
  }
  // The stress model returns no per-point data: analyses.pvd lists nothing.
  EXPECT_EQ(r.report["analyses"].size(), 0u);
}

namespace {
// The grains snapshots a run of the 2D rigid oedometer (lsdem, a 0.02 s stress ramp) writes
// with a snapshot wanted at every sample and `max_frames` as output.vtk_max_frames.
long rigid_2d_snapshots(long max_frames) {
  const fs::path out = fresh("frames_" + std::to_string(max_frames));
  const auto run = run_cli("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json --out " +
                           out.string() + " --quiet --threads 1 --set output.vtk_every=1 --set output.vtk_final=false" +
                           " --set output.plots=false --set output.vtk_max_frames=" + std::to_string(max_frames));
  EXPECT_EQ(run.status, 0) << run.output;
  long n = 0;
  for (const auto& e : fs::directory_iterator(out / "vtk")) n += e.path().filename().string().rfind("grains_", 0) == 0;
  return n;
}
}  // namespace

// output.vtk_max_frames reaches the writer: 4 frames over the ramp give the first state and
// the first sample in each quarter of it (and its end); 0 gives a snapshot at every sample.
// A negative count is refused with its JSON path.
TEST(ParaView, MaxFramesLimitsTheSnapshotsOverTheLoading) {
  const long all = rigid_2d_snapshots(0), four = rigid_2d_snapshots(4);
  EXPECT_GE(all, 20);
  EXPECT_GE(four, 4);
  EXPECT_LE(four, 6);
  const fs::path out = fresh("frames_negative");
  const auto bad = run_cli("run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/oedometer_rigid_2d_quick.json --out " +
                           out.string() + " --quiet --set output.vtk_max_frames=-1");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("/output/vtk_max_frames"), std::string::npos) << bad.output;
}
