// Fidelity presets (scenarios/Fidelity.h, docs/speed-accuracy.md): a preset writes the knobs of
// the implementations the scenario selects and no others; a value in the scenario or a --set
// wins over it; an unknown or mistyped preset is a ConfigError at /fidelity listing the presets;
// every preset value is one its option accepts.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "scenarios/Fidelity.h"
#include "scenarios/ScenarioFactory.h"

using Json = nlohmann::json;
using namespace crumble;

namespace {

const std::string kSource(CRUMBLE_SOURCE_DIR);

Json single_grain() { return load_scenario_file(kSource + "/scenarios/single_grain_pd.json"); }

// "engine.solver_iterations" -> /engine/solver_iterations
Json::json_pointer pointer(const std::string& dotted) {
  std::string s(1, '/');
  for (char c : dotted) s.push_back(c == '.' ? '/' : c);
  return Json::json_pointer(s);
}

}  // namespace

TEST(Fidelity, PresetSetsTheSelectedImplementationsKnobsOnly) {
  for (const auto& preset : fidelity_presets()) {
    SCOPED_TRACE(preset);
    Json doc = single_grain();  // bullet + peridynamics + alpha_shape
    doc["fidelity"] = preset;
    doc["engine"].erase("solver_iterations");
    doc.erase("schedule");
    const auto written = apply_fidelity(doc);
    std::set<std::string> expected;
    for (const auto& k : fidelity_knobs()) {
      if (k.implementation != "bullet" && k.implementation != "peridynamics" && k.implementation != "alpha_shape") continue;
      expected.insert(k.path + "=" + fidelity_value(k, preset).dump());
      // The value is in the document at the knob's path.
      EXPECT_EQ(doc.at(pointer(k.path)), fidelity_value(k, preset)) << k.path;
    }
    ASSERT_FALSE(expected.empty());
    EXPECT_EQ(std::set<std::string>(written.begin(), written.end()), expected);
    // Knobs of engines the scenario does not use are not written (lsdem's dt_safety, ode's
    // iterations would land on the same path: only bullet's value is there).
    EXPECT_FALSE(doc["engine"].contains("dt_safety"));
  }
}

TEST(Fidelity, ExplicitValuesAndSetOverridesWin) {
  Json doc = single_grain();
  doc["fidelity"] = "fast";
  doc["breakage"]["spacing_fraction"] = 0.07;  // in the file
  BuildOptions opt;
  opt.overrides = {"breakage.density_scale=2"};  // on the command line
  const Scenario sc = build_scenario(doc, opt);
  EXPECT_EQ(sc.effective["breakage"]["spacing_fraction"].get<double>(), 0.07);
  EXPECT_EQ(sc.effective["breakage"]["density_scale"].get<double>(), 2.0);
  // single_grain_pd gives solver_iterations and its breakage check interval itself: the preset
  // leaves them.
  EXPECT_EQ(sc.effective["engine"]["solver_iterations"].get<int>(), 1000);
  EXPECT_EQ(sc.effective["schedule"]["every_stress"].get<double>(), 0.1e6);
  // What the preset did is said: a note per value it wrote, none here (every knob was given),
  // and one note naming the knobs it left and why.
  std::string leaves;
  for (const auto& n : sc.notes) {
    EXPECT_EQ(n.rfind("fidelity 'fast' sets ", 0), std::string::npos) << n;
    if (n.rfind("fidelity 'fast' changes nothing: ", 0) == 0) leaves = n;
  }
  for (const char* k : {"breakage.spacing_fraction", "breakage.density_scale", "engine.solver_iterations",
                        "schedule.every_stress", "given by the scenario or --set"})
    EXPECT_NE(leaves.find(k), std::string::npos) << k << " not in '" << leaves << "'";
  EXPECT_EQ(sc.presets.at("fidelity").at("changes_nothing"), true);
  // --set fidelity=... chooses the preset too; the preset fills what nothing else gives.
  Json plain = single_grain();
  plain["engine"].erase("solver_iterations");
  plain.erase("schedule");
  BuildOptions set_preset;
  set_preset.overrides = {"fidelity=accurate"};
  const Scenario acc = build_scenario(plain, set_preset);
  for (const auto& k : fidelity_knobs()) {
    if (k.implementation != "peridynamics" && k.implementation != "bullet") continue;
    EXPECT_EQ(acc.effective.at(pointer(k.path)), k.accurate) << k.path;
  }
  EXPECT_EQ(acc.effective["fidelity"], "accurate");
  std::size_t notes = 0;
  for (const auto& n : acc.notes) notes += n.rfind("fidelity 'accurate' sets ", 0) == 0;
  EXPECT_GE(notes, 4u);  // spacing, density scaling, check interval, iterations
}

TEST(Fidelity, NoPresetChangesNothing) {
  Json doc = single_grain();
  const Json before = doc;
  EXPECT_TRUE(apply_fidelity(doc).empty());
  EXPECT_EQ(doc, before);
}

TEST(Fidelity, UnknownOrMistypedPresetIsAnErrorAtItsPath) {
  for (const Json& bad : {Json("quick"), Json("Fast"), Json(""), Json(2), Json::array({"fast"})}) {
    SCOPED_TRACE(bad.dump());
    Json doc = single_grain();
    doc["fidelity"] = bad;
    try {
      build_scenario(doc, BuildOptions{});
      ADD_FAILURE() << "accepted";
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.path(), "/fidelity");
      const std::string w = e.what();
      for (const char* p : {"fast", "balanced", "accurate"}) EXPECT_NE(w.find(p), std::string::npos) << w;
    }
  }
}

TEST(Fidelity, EveryPresetValueIsAcceptedByItsImplementation) {
  // One scenario per implementation a knob names, built with each preset: the option tables
  // check type and range, so a preset value out of range would be a ConfigError here.
  for (const auto& preset : fidelity_presets()) {
    for (const auto& k : fidelity_knobs()) {
      SCOPED_TRACE(preset + " " + k.implementation + " " + k.path);
      Json doc = k.implementation == "lsdem" ? load_scenario_file(kSource + "/scenarios/oedometer_rigid_2d_quick.json")
                                             : single_grain();
      if (k.seam == "engine") {
        doc["engine"] = Json{{"type", k.implementation}};
        if (k.implementation != "lsdem") doc["engine"]["mass_scale"] = 70;
      }
      doc["fidelity"] = preset;
      doc.erase("schedule");
      Scenario sc;
      ASSERT_NO_THROW(sc = build_scenario(doc, BuildOptions{}));
      EXPECT_EQ(sc.effective.at(pointer(k.path)), fidelity_value(k, preset));
    }
  }
}

TEST(Fidelity, OdeIterationsAreWrittenOnlyWhereTheScenarioLeavesThemOut) {
  // The ODE row (studies/ode_iterations.json): engine.solver_iterations, the same path as
  // Bullet's knob, so it must go to ODE scenarios only, and never over a value the scenario or
  // a --set gives.
  const FidelityKnob* ode = nullptr;
  const FidelityKnob* bullet = nullptr;
  for (const auto& k : fidelity_knobs()) {
    if (k.implementation == "ode" && k.path == "engine.solver_iterations") ode = &k;
    if (k.implementation == "bullet" && k.path == "engine.solver_iterations") bullet = &k;
  }
  ASSERT_NE(ode, nullptr);
  ASSERT_NE(bullet, nullptr);
  const Json rigid = load_scenario_file(kSource + "/scenarios/oedometer_rigid_quick.json");
  ASSERT_TRUE(rigid["engine"].contains("solver_iterations"));
  for (const auto& preset : fidelity_presets()) {
    SCOPED_TRACE(preset);
    // ODE without its own iterations: the preset's ODE value, as a note.
    Json doc = rigid;
    doc["engine"]["type"] = "ode";
    doc["engine"].erase("solver_iterations");
    doc["fidelity"] = preset;
    const Scenario sc = build_scenario(doc, BuildOptions{});
    EXPECT_EQ(sc.effective["engine"]["solver_iterations"], fidelity_value(*ode, preset));
    std::size_t notes = 0;
    for (const auto& n : sc.notes)
      notes += n.find("engine.solver_iterations=" + fidelity_value(*ode, preset).dump()) != std::string::npos;
    EXPECT_EQ(notes, 1u);
    // The scenario's own value (300 in oedometer_rigid_quick) wins; the one note says the preset
    // changed nothing, and why.
    Json fixed = rigid;
    fixed["engine"]["type"] = "ode";
    fixed["fidelity"] = preset;
    const Scenario kept = build_scenario(fixed, BuildOptions{});
    EXPECT_EQ(kept.effective["engine"]["solver_iterations"].get<int>(), 300);
    for (const auto& n : kept.notes)
      if (n.find("solver_iterations") != std::string::npos)
        EXPECT_EQ(n, "fidelity '" + preset + "' changes nothing: every key it governs here is already set "
                                             "(engine.solver_iterations given by the scenario or --set)");
    // A --set wins too, also when it is what selects ODE.
    BuildOptions set;
    set.overrides = {"engine.type=ode", "engine.solver_iterations=77"};
    Json bare = rigid;
    bare["engine"].erase("solver_iterations");
    bare["fidelity"] = preset;
    EXPECT_EQ(build_scenario(bare, set).effective["engine"]["solver_iterations"].get<int>(), 77);
    BuildOptions only_type;
    only_type.overrides = {"engine.type=ode"};
    EXPECT_EQ(build_scenario(bare, only_type).effective["engine"]["solver_iterations"], fidelity_value(*ode, preset));
    // The same file on Bullet gets Bullet's value, not ODE's.
    EXPECT_EQ(build_scenario(bare, BuildOptions{}).effective["engine"]["solver_iterations"],
              fidelity_value(*bullet, preset));
  }
}
