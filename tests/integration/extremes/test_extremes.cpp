// Stability at the extremes: runs at the edges a user will reach, each a few
// seconds, through the CLI for every registered engine in every dimension it declares
// (tests/support/Registered.h), on the cross product's tiny packings (tests/integration/cross)
// or on small scenarios written here. Every run must
//   - write no NaN or infinity into any file of its output folder (CSV, JSON, VTK, .part);
//   - when it wrote summary.json: keep the mass budget, |m_final + m_removed − m_initial| ≤
//     1e-9·m_initial, and bounded energy, the guards' largest kinetic energy at most the
//     energy that entered (guard_max_energy_ratio ≤ 1, finite);
//   - end with the outcome decided for its case: exit 0 with what it counts (breakage events,
//     analysis outcomes, time-step reductions), or exit 1 / 2 with a message naming the cause.
// Each run prints one row of the table `extremes | case | engine | outcome` (ctest -L extremes -V).
// The energy of a free, undamped system is checked on the engines themselves (public factory).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/Config.h"
#include "scenarios/Registry.h"
#include "tests/support/CliRunner.h"
#include "tests/support/Registered.h"
#include "tests/support/VtkArrays.h"

namespace fs = std::filesystem;
using namespace crumble;
using namespace crumble::testing_support;
using nlohmann::json;

namespace {

std::string src(const std::string& rel) { return std::string(CRUMBLE_SOURCE_DIR) + "/" + rel; }

// The fragment builder of every run: level sets in 2D (alpha shapes are 3D), alpha shapes in
// 3D — also on lsdem, where a 3D level-set split costs ≈ 0.4 s against ≈ 0.1 s for an alpha-
// shape cut and a child's grid (the cross product runs every pairing).
std::string builder_for(const std::string& /*engine*/, int dim) { return dim == 2 ? "level_set" : "alpha_shape"; }

std::string cross_scenario(int dim) {
  return src("tests/integration/cross/cross_" + std::to_string(dim) + "d.json");
}

// The crushable packing of the cross product with the stress model (Harmon et al. 2020),
// 5 MPa strength: every engine breaks grains within a few hundred steps.
std::string crushable(const std::string& engine, int dim) {
  return cross_scenario(dim) + " --set engine.type=" + engine + " --set breakage.type=stress" +
         " --set breakage.strength=5e6 --set fragments.type=" + builder_for(engine, dim);
}

struct Outcome {
  int status = -1;
  std::string output;
  fs::path out;
  json summary;  // null without summary.json
  bool has_summary() const { return !summary.is_null(); }
  long events() const { return summary.value("breakage_events", -1L); }
};

// Files under `dir` holding a NaN or an infinity as a token ("nan", "-inf", "inf",
// "infinity", any case), with the first offending line. The PNG figures are binary (their
// compressed bytes can spell "INF") and hold no number: skipped. A binary VTK array (its
// base64 text can spell "+inf/" too) is decoded and its values checked instead.
std::vector<std::string> non_finite_in(const fs::path& dir) {
  static const std::regex token(R"((^|[^A-Za-z_])[-+]?(nan|inf|infinity)([^A-Za-z_]|$))", std::regex::icase);
  std::vector<std::string> bad;
  if (!fs::exists(dir)) return bad;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file() || e.path().extension() == ".png") continue;
    std::ifstream in(e.path());
    std::string line, body;
    while (std::getline(in, line)) {
      if (line.find("format=\"binary\"") != std::string::npos && std::getline(in, body)) {
        for (double v : crumble::test::data_array_values(line, body))
          if (!std::isfinite(v)) line += " [decoded: " + std::to_string(v) + "]";
        if (line.find("[decoded:") == std::string::npos) continue;
      } else if (!std::regex_search(line, token)) {
        continue;
      }
      bad.push_back(e.path().string() + ": " + line.substr(0, 200));
      break;
    }
  }
  return bad;
}

std::string out_name(const std::string& tag) {
  return sanitized(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" + sanitized(tag);
}

// Runs `crumble run ARGS` into a fresh folder and checks the invariants every case shares.
// `energy_limit`: the largest guard_max_energy_ratio accepted (1: no more kinetic energy than
// entered).
Outcome run_case(const std::string& args, const std::string& tag, double energy_limit = 1.0) {
  Outcome r;
  r.out = fs::temp_directory_path() / "crumble_extremes" / out_name(tag);
  fs::remove_all(r.out);
  const CliResult c = run_cli(plugin_args() + " run " + args + " --quiet --threads 1 --out " + r.out.string());
  r.status = c.status;
  r.output = c.output;
  for (const auto& b : non_finite_in(r.out)) ADD_FAILURE() << "non-finite value written: " << b << "\n" << args;
  if (fs::exists(r.out / "summary.json")) {
    r.summary = json::parse(slurp(r.out / "summary.json"));
    const double m0 = r.summary["mass_initial_kg"], m1 = r.summary["mass_final_kg"],
                 mr = r.summary["mass_removed_kg"];
    EXPECT_GT(m0, 0) << args;
    EXPECT_LE(std::abs(m1 + mr - m0), 1e-9 * m0) << "mass budget: initial " << m0 << ", final " << m1
                                                  << ", removed " << mr << "\n" << args;
    const double e = r.summary.value("guard_max_energy_ratio", 0.0);
    EXPECT_TRUE(std::isfinite(e) && e <= energy_limit)
        << "kinetic energy " << e << " × the energy that entered\n" << args << "\n" << r.output;
  }
  return r;
}

// One row of the case × engine table.
void report(const std::string& c, const std::string& engine, int dim, const Outcome& r, const std::string& extra = "") {
  std::ostringstream o;
  o << "extremes | " << c << " | " << engine << " " << dim << "D | exit " << r.status;
  if (r.has_summary())
    o << ", " << r.events() << " events, grains " << r.summary["grains_initial"] << " -> " << r.summary["grains_final"]
      << ", E/budget " << r.summary.value("guard_max_energy_ratio", 0.0);
  if (!extra.empty()) o << ", " << extra;
  std::cout << o.str() << "\n";
}

// Exit 1 (a physical guard or an engine failure) or 2 (input): the message names the cause.
void expect_named_failure(const Outcome& r, int status, const std::vector<std::string>& any_of) {
  EXPECT_EQ(r.status, status) << r.output;
  bool named = false;
  for (const auto& n : any_of) named = named || r.output.find(n) != std::string::npos;
  std::string list;
  for (const auto& n : any_of) list += " '" + n + "'";
  EXPECT_TRUE(named) << "expected one of" << list << " in\n" << r.output;
  if (status != 0) EXPECT_FALSE(r.has_summary()) << "a failed run left summary.json";
}

// Column `name` of a CSV file, as strings.
std::vector<std::string> column(const fs::path& csv, const std::string& name) {
  std::stringstream in(slurp(csv));
  std::string line, cell;
  std::getline(in, line);
  std::stringstream h(line);
  int k = -1, i = 0;
  while (std::getline(h, cell, ',')) {
    if (cell == name) k = i;
    ++i;
  }
  std::vector<std::string> out;
  if (k < 0) return out;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    for (int j = 0; j <= k && std::getline(ss, cell, ','); ++j) {
    }
    out.push_back(cell);
  }
  return out;
}

long count_of(const std::vector<std::string>& v, const std::string& x) {
  return static_cast<long>(std::count(v.begin(), v.end(), x));
}

// Writes a scenario for this test into the temporary folder.
std::string write_scenario(const json& s, const std::string& tag) {
  const fs::path p = fs::temp_directory_path() / "crumble_extremes" / (out_name(tag) + ".json");
  fs::create_directories(p.parent_path());
  std::ofstream(p) << s.dump(1);
  return p.string();
}

std::vector<Registered> engines_of(int dim) {
  std::vector<Registered> out;
  for (const auto& e : registered_engines())
    if (e.dimension == dim) out.push_back(e);
  return out;
}
std::vector<Registered> all_engines() {
  std::vector<Registered> out = engines_of(3);
  for (const auto& e : engines_of(2)) out.push_back(e);
  return out;
}
bool has_model(const std::string& name, int dim) {
  for (const auto& m : registered_models())
    if (m.name == name && m.dimension == dim) return true;
  return false;
}

class Extremes : public ::testing::TestWithParam<Registered> {
 protected:
  const std::string& engine() const { return GetParam().name; }
  int dim() const { return GetParam().dimension; }
};
// Cases whose scene exists in 3D only (the single_grain scene).
class Extremes3D : public Extremes {};

// ---------------------------------------------------------------- time step
// An explicit engine (a finite stable bound) runs at its bound without reduction; twice past
// it, the step is reduced with a warning (auto_reduce_dt, the default) or refused with exit 2
// naming /time_step and the bound. An engine without a bound (Bullet, ODE: implicit contact
// solves) runs at Zhu & Zhao 2019 §5's largest step, 8e-5 s, and twice past it either runs or
// stops on a guard that names time_step; never NaN.
TEST_P(Extremes, TimeStepAtTheStableBoundAndTwicePastIt) {
  const std::string base = cross_scenario(dim()) + " --set engine.type=" + engine() +
                           " --set simulation.stop_after_breakage_events=0 --set simulation.max_steps=3000";
  // The bound, from the refusal of a step of 1 s without reduction.
  const CliResult probe = run_cli(plugin_args() + " validate " + base + " --set time_step=1 --set simulation.auto_reduce_dt=false");
  const std::regex bound_re(R"(stable step ([0-9.eE+-]+) s)");
  std::smatch m;
  if (probe.status == 0) {
    const Outcome at = run_case(base + " --set time_step=8e-5", "at");
    EXPECT_EQ(at.status, 0) << at.output;
    report("dt 8e-5 s (Zhu & Zhao §5)", engine(), dim(), at);
    const Outcome past = run_case(base + " --set time_step=1.6e-4", "past");
    if (past.status != 0) expect_named_failure(past, 1, {"time_step"});
    report("dt 1.6e-4 s (2x)", engine(), dim(), past);
    return;
  }
  ASSERT_EQ(probe.status, 2) << probe.output;
  ASSERT_TRUE(std::regex_search(probe.output, m, bound_re)) << probe.output;
  EXPECT_NE(probe.output.find("/time_step"), std::string::npos) << probe.output;
  const double bound = std::stod(m[1]);
  ASSERT_TRUE(bound > 0 && std::isfinite(bound));
  const auto dt = [](double v) {
    std::ostringstream o;
    o.precision(17);
    o << v;
    return o.str();
  };
  // The bound is printed to 6 digits: stay 1e-5 below it.
  const Outcome at = run_case(base + " --set simulation.auto_reduce_dt=false --set time_step=" + dt(bound * (1 - 1e-5)), "at");
  EXPECT_EQ(at.status, 0) << at.output;
  if (at.has_summary()) EXPECT_EQ(at.summary["dt_reductions"], 0);
  report("dt at the bound " + dt(bound) + " s", engine(), dim(), at);
  const Outcome refused = run_case(base + " --set simulation.auto_reduce_dt=false --set time_step=" + dt(2 * bound), "refused");
  expect_named_failure(refused, 2, {"/time_step"});
  report("dt 2x the bound, auto_reduce_dt false", engine(), dim(), refused);
  const Outcome reduced = run_case(base + " --set time_step=" + dt(2 * bound), "reduced");
  EXPECT_EQ(reduced.status, 0) << reduced.output;
  EXPECT_NE(reduced.output.find("reduced to the engine's stable step"), std::string::npos) << reduced.output;
  if (reduced.has_summary()) EXPECT_GT(reduced.summary["dt_reductions"].get<double>(), 0);
  report("dt 2x the bound, reduced", engine(), dim(), reduced);
}

// ---------------------------------------------------------------- mass scaling
// ×1 (no scaling: the smallest explicit step, the liveliest grains) and ×1000 on the crushable
// packing: both run and break grains.
TEST_P(Extremes, MassScalingOneAndAThousand) {
  if (!has_model("stress", dim())) GTEST_SKIP() << "needs the stress model";
  for (const char* s : {"1", "1000"}) {
    const Outcome r = run_case(crushable(engine(), dim()) + " --set engine.mass_scale=" + s, std::string("ms") + s);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_GT(r.events(), 0) << r.output;
    report(std::string("mass scaling x") + s, engine(), dim(), r);
  }
}

// ---------------------------------------------------------------- materials
TEST_P(Extremes, FrictionZeroAndOne) {
  if (!has_model("stress", dim())) GTEST_SKIP() << "needs the stress model";
  for (const char* f : {"0", "1"}) {
    const Outcome r = run_case(crushable(engine(), dim()) + " --set materials.0.friction=" + f +
                               " --set materials.0.wall_friction=" + f,
                           std::string("mu") + f);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_GT(r.events(), 0) << r.output;
    report(std::string("friction ") + f, engine(), dim(), r);
  }
}

// No engine models restitution: 0 runs; 1 is refused at its path instead of being ignored.
TEST_P(Extremes, RestitutionZeroAndOne) {
  const std::string base = cross_scenario(dim()) + " --set engine.type=" + engine();
  const Outcome zero = run_case(base + " --set materials.0.restitution=0", "e0");
  EXPECT_EQ(zero.status, 0) << zero.output;
  report("restitution 0", engine(), dim(), zero);
  const Outcome one = run_case(base + " --set materials.0.restitution=1", "e1");
  expect_named_failure(one, 2, {"/materials/0/restitution"});
  report("restitution 1", engine(), dim(), one);
}

// Weibull modulus 1 and 20 (Harmon et al. 2020, eqs. 11–13): both run; the strengths the
// analyses record scatter as the modulus says (coefficient of variation 1 for m = 1,
// ≈ 0.06 for m = 20, widened a little by the size effect of eq. 13 over 1.6–2 mm grains).
TEST_P(Extremes, WeibullModulusOneAndTwenty) {
  if (!has_model("stress", dim())) GTEST_SKIP() << "needs the stress model";
  std::map<std::string, double> cv;
  for (const char* m : {"1", "20"}) {
    const Outcome r = run_case(crushable(engine(), dim()) + " --set breakage.weibull_modulus=" + m, std::string("m") + m);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_GT(r.events(), 0) << r.output;
    // First analysis of each initial grain (generation 0).
    const auto grain = column(r.out / "events.csv", "grain");
    const auto gen = column(r.out / "events.csv", "generation");
    const auto strength = column(r.out / "events.csv", "strength_Pa");
    std::set<std::string> seen;
    std::vector<double> s;
    for (std::size_t i = 0; i < strength.size() && i < grain.size() && i < gen.size(); ++i)
      if (gen[i] == "0" && seen.insert(grain[i]).second) s.push_back(std::stod(strength[i]));
    double mean = 0, var = 0;
    for (double x : s) mean += x / s.size();
    for (double x : s) var += (x - mean) * (x - mean) / std::max<std::size_t>(1, s.size() - 1);
    cv[m] = mean > 0 ? std::sqrt(var) / mean : 0;
    EXPECT_GE(s.size(), 4u) << "too few grains analysed to see the scatter\n" << r.output;
    report(std::string("Weibull modulus ") + m, engine(), dim(), r,
           "strength CV " + std::to_string(cv[m]) + " over " + std::to_string(s.size()) + " grains");
  }
  EXPECT_GT(cv["1"], 0.3);
  EXPECT_LT(cv["20"], 0.15);
}

// ---------------------------------------------------------------- loading
// 1000 MPa on a crushable packing is beyond what any contact law here carries: the run stops
// with exit 1 on a guard (or an engine failure) whose message says what to change; it never
// crashes (ODE aborts on a non-finite quaternion) or writes NaN.
TEST_P(Extremes, ThousandMegapascalsOnACrushablePacking) {
  if (!has_model("stress", dim())) GTEST_SKIP() << "needs the stress model";
  json s = json::parse(slurp(cross_scenario(dim())));
  // A ramp to 1000 MPa in 0.2 ms, grains of 50 MPa breaking at every 200 MPa of platen stress,
  // pieces below 1.2 mm leaving as fines: a few checks before the packing gives way.
  s["loading"] = {{"mode", "stress_ramp"}, {"max_stress", 1e9}, {"ramp_time", 0.0002}};
  s["schedule"] = {{"every_stress", 2e8}, {"every_steps", 0}};
  s["simulation"]["stop_after_breakage_events"] = 0;
  s["simulation"]["fines_diameter"] = 1.2e-3;
  const Outcome r = run_case(write_scenario(s, "1GPa") + " --set engine.type=" + engine() +
                                 " --set breakage.type=stress --set breakage.strength=5e7 --set fragments.type=" +
                                 builder_for(engine(), dim()),
                             "1GPa");
  if (r.status == 0) {
    // Reaching 1000 MPa is fine if the grains carried it.
    EXPECT_GT(r.summary["max_platen_stress_Pa"].get<double>(), 0.99e9) << r.output;
  } else {
    expect_named_failure(r, 1, {"time_step", "loading.max_stress", "engine.kn"});
  }
  report("1000 MPa platen stress", engine(), dim(), r);
}

// One grain resting on the floor: one contact. 3D: Harmon et al. 2020 §3.3 hold breakage off
// (outcome single_contact, counted in events.csv, no breakage). 2D: the contact and the
// centroid fix the splitting line, so a grain weaker than its weight's stress splits.
TEST_P(Extremes, GrainLoadedByASingleContact) {
  if (!has_model("stress", dim())) GTEST_SKIP() << "needs the stress model";
  const double r0 = 1e-3;
  json grain = dim() == 3 ? json{{"shape", {{"type", "sphere"}, {"radius", r0}}}, {"position", {2e-3, 2e-3, r0}}}
                          : json{{"shape", {{"type", "disk"}, {"radius", r0}}}, {"position", {2e-3, r0, 0}}};
  json s = json::parse(slurp(cross_scenario(dim())));
  s["engine"]["type"] = engine();
  s["packing"] = {{"type", "grains"}, {"settle", false}, {"grains", {grain}}};
  s["container"] = dim() == 3 ? json{{"lx", 4e-3}, {"ly", 4e-3}, {"height", 4e-3}} : json{{"lx", 4e-3}, {"height", 4e-3}};
  s["loading"] = {{"mode", "none"}, {"duration", 0.01}};
  s["simulation"] = {{"sample_every", 10}, {"max_steps", 4000}};
  s["breakage"] = {{"type", "stress"}, {"strength", 1.0}, {"weibull", false}};
  s["fragments"] = {{"type", builder_for(engine(), dim())}};
  s["screening"] = {{"min_contacts", 1}};
  s["schedule"] = {{"every_steps", 10}};
  const Outcome r = run_case(write_scenario(s, "one"), "one");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto outcomes = column(r.out / "events.csv", "outcome");
  const long single = count_of(outcomes, "single_contact");
  if (dim() == 3) {
    EXPECT_GT(single, 0) << r.output;
    EXPECT_EQ(r.events(), 0);
  } else {
    EXPECT_EQ(single, 0);
    EXPECT_GT(r.events(), 0) << "the contact and the centroid fix the line in 2D";
  }
  report("single contact", engine(), dim(), r, std::to_string(single) + " single_contact analyses");
}

// A grain between two plates: both contacts and the centroid on one line. The plane holds
// the line (a meridian split, as a Brazilian test): one event, two pieces.
TEST_P(Extremes3D, CollinearContacts) {
  if (!has_model("stress", 3)) GTEST_SKIP() << "needs the stress model";
  const Outcome r = run_case(src("scenarios/single_grain_pd.json") + " --set engine.type=" + engine() +
                             " --set fragments.type=" + builder_for(engine(), 3) +
                             " --set breakage.type=stress --set breakage.strength=5e6 --set breakage.weibull=false",
                         "collinear");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.events(), 1);
  EXPECT_EQ(r.summary["fragment_count"], 2);
  EXPECT_EQ(count_of(column(r.out / "events.csv", "outcome"), "split"), 1);
  report("collinear contacts (grain between plates)", engine(), 3, r);
}

// Grains spawned overlapping: beyond 1 % of the smaller diameter the packing is refused
// at the grain's path (exit 2); within it the run starts, the engine pushes them apart and
// the energy stays bounded.
TEST_P(Extremes, GrainsSpawnedOverlapping) {
  const double r0 = 1e-3;
  const auto make = [&](double gap) {
    json s = json::parse(slurp(cross_scenario(dim())));
    s["engine"]["type"] = engine();
    const auto at = [&](double x) {
      return dim() == 3 ? json{{"shape", {{"type", "sphere"}, {"radius", r0}}}, {"position", {x, 2e-3, r0}}}
                        : json{{"shape", {{"type", "disk"}, {"radius", r0}}}, {"position", {x, r0, 0}}};
    };
    s["packing"] = {{"type", "grains"}, {"settle", false}, {"grains", {at(1.1e-3), at(1.1e-3 + 2 * r0 + gap)}}};
    s["container"] = dim() == 3 ? json{{"lx", 4.5e-3}, {"ly", 4e-3}, {"height", 4e-3}} : json{{"lx", 4.5e-3}, {"height", 4e-3}};
    s["loading"] = {{"mode", "none"}, {"duration", 0.002}};
    s["simulation"] = {{"sample_every", 10}, {"max_steps", 4000}};
    return s;
  };
  const Outcome refused = run_case(write_scenario(make(-0.5e-3), "deep"), "deep");
  expect_named_failure(refused, 2, {"/packing/grains/1/position"});
  report("spawned overlapping by 25 % of d", engine(), dim(), refused);
  // The elastic energy stored in the accepted overlap is energy present at the start
  // (Engine::elastic_energy, counted after the first step): the kinetic energy the engine
  // releases by pushing the grains apart stays within the guards' budget.
  const Outcome ok = run_case(write_scenario(make(-0.019e-3), "shallow"), "shallow");
  report("spawned overlapping by 0.95 % of d", engine(), dim(), ok);
  EXPECT_EQ(ok.status, 0) << ok.output;
}

// A lattice of grains (3 × 3, in 3D two layers) of radius 1 mm whose neighbours overlap by a
// fraction of the diameter, 2 mm: spacing 2 mm × (1 − fraction), the first row touching the
// walls and the floor, positions as a user writes them (decimals not exact in binary).
json overlapping_lattice(const std::string& engine, int dim, double fraction) {
  json s = json::parse(slurp(cross_scenario(dim)));
  s["engine"]["type"] = engine;
  const double r = 1e-3, sp = 2 * r * (1 - fraction);
  json grains = json::array();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < (dim == 3 ? 2 : 1); ++k)
        grains.push_back(dim == 3 ? json{{"shape", {{"type", "sphere"}, {"radius", r}}},
                                         {"position", {r + i * sp, r + j * sp, r + k * sp}}}
                                  : json{{"shape", {{"type", "disk"}, {"radius", r}}}, {"position", {r + i * sp, r + j * sp, 0}}});
  const double side = 2 * r + 2 * sp;
  s["packing"] = {{"type", "grains"}, {"settle", false}, {"grains", grains}};
  s["container"] = dim == 3 ? json{{"lx", side}, {"ly", side}, {"height", 7e-3}} : json{{"lx", side}, {"height", 7e-3}};
  s["loading"] = {{"mode", "none"}, {"duration", 0.002}};
  s["simulation"] = {{"sample_every", 10}, {"max_steps", 4000}};
  return s;
}

// At the overlap tolerance (1 % of the diameter) the lattice is accepted: an overlap equal to
// the tolerance up to rounding is not more than it. Past it (1.01 %, and by 1e-7 of it) the
// refusal prints both numbers with the digits that tell them apart.
TEST_P(Extremes, LatticeAtTheOverlapToleranceIsAccepted) {
  const CliResult at = run_cli("validate " + write_scenario(overlapping_lattice(engine(), dim(), 0.01), "lattice_at"));
  EXPECT_EQ(at.status, 0) << at.output;
  const CliResult past = run_cli("validate " + write_scenario(overlapping_lattice(engine(), dim(), 0.0101), "lattice_past"));
  EXPECT_EQ(past.status, 2) << past.output;
  EXPECT_NE(past.output.find("by 2.02e-05 m, more than the tolerance 2e-05 m"), std::string::npos) << past.output;
  // 1e-7 past it: %g would print both as 2e-05.
  const CliResult hair = run_cli("validate " + write_scenario(overlapping_lattice(engine(), dim(), 0.01000001), "lattice_hair"));
  EXPECT_EQ(hair.status, 2) << hair.output;
  EXPECT_NE(hair.output.find("by 2.000002e-05 m, more than the tolerance 2e-05 m"), std::string::npos) << hair.output;
}

// A lattice overlapping by 0.99 % of the diameter runs with the guards on: the elastic energy
// stored in its overlaps is counted as energy present at the start.
TEST_P(Extremes, LatticeOverlappingWithinTheToleranceRuns) {
  const Outcome r = run_case(write_scenario(overlapping_lattice(engine(), dim(), 0.0099), "lattice_in"), "lattice_in");
  report("lattice overlapping by 0.99 % of d", engine(), dim(), r);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(r.has_summary());
}

// ---------------------------------------------------------------- sizes
// Four 0.1 mm grains on the floor beside a 50 mm grain in one box (a ratio of 500): the
// engine takes both (Bullet's and ODE's length scale comes from the first, small grain;
// lsdem's step from the smallest mass).
TEST_P(Extremes, TenthOfAMillimetreAndFiftyMillimetresInOnePacking) {
  json grains = json::array();
  for (int i = 0; i < 4; ++i)
    grains.push_back(dim() == 3 ? json{{"shape", {{"type", "sphere"}, {"radius", 0.05e-3}}},
                                       {"position", {0.005 + 0.001 * i, 0.005, 0.05e-3}}}
                                : json{{"shape", {{"type", "disk"}, {"radius", 0.05e-3}}},
                                       {"position", {0.005 + 0.001 * i, 0.05e-3, 0}}});
  grains.push_back(dim() == 3 ? json{{"shape", {{"type", "sphere"}, {"radius", 25e-3}}}, {"position", {0.03, 0.03, 0.0251}}}
                              : json{{"shape", {{"type", "disk"}, {"radius", 25e-3}}}, {"position", {0.03, 0.0251, 0}}});
  json s = json::parse(slurp(cross_scenario(dim())));
  s["engine"]["type"] = engine();
  s["packing"] = {{"type", "grains"}, {"settle", false}, {"grains", grains}};
  s["container"] = dim() == 3 ? json{{"lx", 0.06}, {"ly", 0.06}, {"height", 0.06}} : json{{"lx", 0.06}, {"height", 0.06}};
  s["loading"] = {{"mode", "none"}, {"duration", 0.002}};
  s["simulation"] = {{"sample_every", 10}, {"max_steps", 400}};
  const Outcome r = run_case(write_scenario(s, "mixed"), "mixed");
  EXPECT_EQ(r.status, 0) << r.output;
  if (r.has_summary()) EXPECT_EQ(r.summary["grains_final"], 5);
  report("0.1 mm and 50 mm grains", engine(), dim(), r);
}

// The unbalanced-force and -moment screening (Zhu & Zhao 2019 §3.1) is off in the two
// single-grain peridynamics cases: an explicit engine's grain between plates still rings at
// the few checks these fast ramps make, and the cases are about size and point count.
const std::string kNoBalanceScreening =
    " --set screening.max_unbalanced_force_ratio=0 --set screening.max_unbalanced_moment_ratio=0";

// Zhu & Zhao 2019 §5's crushing limit: a grain of exactly 0.3 mm is analysed (round-off must
// not screen it out) and crushed by peridynamics before the ramp ends.
TEST_P(Extremes3D, PeridynamicsGrainAtTheCrushingLimit) {
  if (!has_model("peridynamics", 3)) GTEST_SKIP() << "needs the peridynamics model";
  const Outcome r = run_case(src("scenarios/single_grain_pd.json") + " --set engine.type=" + engine() +
                             " --set fragments.type=" + builder_for(engine(), 3) +
                             " --set scene.diameter=0.3e-3 --set breakage.spacing_fraction=0.15"
                             " --set loading.max_stress=60e6 --set loading.ramp_time=0.02"
                             " --set engine.mass_scale=1000 --set schedule.every_stress=3e6" + kNoBalanceScreening,
                         "limit");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto outcomes = column(r.out / "events.csv", "outcome");
  EXPECT_GT(outcomes.size(), 0u) << "the 0.3 mm grain was never analysed";
  EXPECT_EQ(r.events(), 1) << r.output;
  report("PD grain at the 0.3 mm crushing limit", engine(), 3, r, std::to_string(outcomes.size()) + " analyses");
}

// A lattice far below peridynamics' minimum point count (spacing 0.4 d: 7 points against
// min_points 100): every analysis reports too_few_points, the grain stays whole, exit 0.
TEST_P(Extremes3D, PeridynamicsFarBelowTheMinimumPointCount) {
  if (!has_model("peridynamics", 3)) GTEST_SKIP() << "needs the peridynamics model";
  const Outcome r = run_case(src("scenarios/single_grain_pd.json") + " --set engine.type=" + engine() +
                             " --set fragments.type=" + builder_for(engine(), 3) +
                             " --set breakage.spacing_fraction=0.4 --set loading.max_stress=4e6"
                             " --set schedule.every_stress=1e6 --set engine.mass_scale=1000" + kNoBalanceScreening,
                         "few");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto outcomes = column(r.out / "events.csv", "outcome");
  const long few = count_of(outcomes, "too_few_points");
  EXPECT_GT(few, 0) << r.output;
  EXPECT_EQ(few, static_cast<long>(outcomes.size()));
  EXPECT_EQ(r.events(), 0);
  report("PD far below the minimum point count", engine(), 3, r, std::to_string(few) + " too_few_points");
}

INSTANTIATE_TEST_SUITE_P(Registry, Extremes, ::testing::ValuesIn(all_engines()),
                         [](const auto& info) { return param_name(info.param); });
INSTANTIATE_TEST_SUITE_P(Registry, Extremes3D, ::testing::ValuesIn(engines_of(3)),
                         [](const auto& info) { return param_name(info.param); });

}  // namespace
