// Bad-input classes of the scenario reader: each names the JSON path and what was expected.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "scenarios/ScenarioFactory.h"

using namespace crumble;
using Json = nlohmann::json;

namespace {
std::string error_of(const std::string& text, std::vector<std::string> sets = {}) {
  try {
    BuildOptions o;
    o.overrides = std::move(sets);
    build_scenario(parse_json_text(text, "test.json"), o);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
const char* kMinimal = R"({"engine": {"type": "none_such"},
  "container": {"lx": 0.01, "ly": 0.01, "height": 0.01},
  "packing": {"type": "grains", "grains": [{"shape": {"type": "sphere", "radius": 0.001}, "position": [0.005, 0.005, 0.001]}]}})";
}  // namespace

TEST(Config, DefaultsAreRecordedAndRangesChecked) {
  Json d = {{"a", 1.5}, {"sub", {{"k", true}}}};
  Config c(d);
  EXPECT_EQ(c.number("a", 0), 1.5);
  EXPECT_EQ(c.number("b", 2.0), 2.0);
  EXPECT_EQ(d["b"], 2.0);  // default written back
  EXPECT_TRUE(c.child("sub").boolean("k", false));
  EXPECT_NO_THROW(c.check_unknown());
  EXPECT_THROW(c.number("a", 0, 2.0, 3.0), ConfigError);
}

TEST(Config, UnknownKeyNamesPathAndKnownKeys) {
  Json d = {{"sub", {{"solver_iterations", 5}, {"solver_iteratons", 7}}}};
  Config c(d);
  c.child("sub").integer("solver_iterations", 10);
  try {
    c.check_unknown();
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.path(), "/sub/solver_iteratons");
    EXPECT_NE(std::string(e.what()).find("solver_iterations"), std::string::npos);
  }
}

TEST(Config, MalformedJson) {
  EXPECT_THROW(parse_json_text("{\"a\": 1,,}", "x.json"), ConfigError);
  try {
    parse_json_text("{\"a\": ", "x.json");
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("x.json"), std::string::npos);
  }
}

TEST(Config, WrongTypeNaNNegativeZero) {
  Json d = {{"n", "12"}, {"neg", -1.0}, {"zero", 0.0}, {"i", 1.5}};
  Config c(d);
  EXPECT_THROW(c.number("n", 0), ConfigError);
  EXPECT_THROW(c.positive("neg", 1), ConfigError);
  EXPECT_THROW(c.positive("zero", 1), ConfigError);
  EXPECT_THROW(c.integer("i", 1), ConfigError);
  Json e = {{"x", std::nan("")}};
  EXPECT_THROW(
      {
        Config ce(e);  // non-finite numbers are refused when the document is wrapped
        ce.number("x", 0);
      },
      ConfigError);
}

TEST(Config, OverridesCreatePathsAndParseJson) {
  Json d = {{"engine", {{"type", "bullet"}}}};
  apply_override(d, "engine.type=lsdem");
  apply_override(d, "loading.max_stress=2e6");
  apply_override(d, "output.psd_at_stress=[1e6,2e6]");
  EXPECT_EQ(d["engine"]["type"], "lsdem");
  EXPECT_EQ(d["loading"]["max_stress"], 2e6);
  EXPECT_EQ(d["output"]["psd_at_stress"].size(), 2u);
  EXPECT_THROW(apply_override(d, "novalue"), ConfigError);
}

TEST(ScenarioErrors, UnknownEngineListsKnownNames) {
  const std::string e = error_of(kMinimal);
  EXPECT_NE(e.find("/engine/type"), std::string::npos) << e;
  EXPECT_NE(e.find("known:"), std::string::npos) << e;
}

TEST(ScenarioErrors, UnknownBreakageModel) {
  const std::string e = error_of(kMinimal, {"engine.type=" + std::string("none_such"), "breakage.type=crushy"});
  // engine is checked first; fix it to a registered one if any exists
  EXPECT_FALSE(e.empty());
}

TEST(ScenarioErrors, NegativeAndZeroSizes) {
  EXPECT_NE(error_of(kMinimal, {"container.lx=-0.01"}).find("/container/lx"), std::string::npos);
  EXPECT_NE(error_of(kMinimal, {"packing.grains.0.shape.radius=0"}).find("/packing/grains/0/shape/radius"),
            std::string::npos);
  EXPECT_NE(error_of(kMinimal, {"packing.grains.0.shape.radius=\"big\""}).find("expected a number"),
            std::string::npos);
}

// ---- "Never a wrong answer with exit 0": what validate must catch before anything runs ----

namespace {
// A valid lsdem scenario (every engine-independent check applies to it).
const char* kLsdem = R"({"name": "t", "engine": {"type": "lsdem"},
  "container": {"lx": 0.01, "ly": 0.01, "height": 0.006},
  "packing": {"type": "grains", "grains": [
    {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.003, 0.005, 0.0011]},
    {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.007, 0.005, 0.0011]}]},
  "loading": {"mode": "strain_rate", "strain_rate": 1.0, "stop_strain": 0.001}, "time_step": 1e-8})";

ConfigError config_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e;
  }
  return ConfigError("", "no error");
}
bool has(const std::string& text, const std::string& needle) { return text.find(needle) != std::string::npos; }
}  // namespace

TEST(ScenarioErrors, ValidLsdemScenarioBuilds) { EXPECT_EQ(error_of(kLsdem), ""); }

TEST(ScenarioErrors, MaterialIndexOutOfRangeNamesPathAndCount) {
  const std::string e = error_of(kLsdem, {"packing.grains.1.material=5"});
  EXPECT_TRUE(has(e, "/packing/grains/1/material")) << e;
  EXPECT_TRUE(has(e, "defines 1 material")) << e;
  const std::string two = error_of(kLsdem, {"materials=[{},{}]", "packing.grains.0.material=2"});
  EXPECT_TRUE(has(two, "/packing/grains/0/material")) << two;
  EXPECT_TRUE(has(two, "defines 2 materials")) << two;
  EXPECT_EQ(error_of(kLsdem, {"materials=[{},{}]", "packing.grains.0.material=1"}), "");
  // A generated cloud names its one material key.
  const std::string cloud =
      error_of(R"({"engine": {"type": "lsdem"}, "container": {"lx": 0.01, "ly": 0.01},
                   "packing": {"count": 3, "diameter": 0.002, "material": 5}})");
  EXPECT_TRUE(has(cloud, "/packing/material")) << cloud;
}

TEST(ScenarioErrors, EmptyMaterialsIsAnError) {
  const std::string e = error_of(kLsdem, {"materials=[]"});
  EXPECT_TRUE(has(e, "/materials")) << e;
  EXPECT_TRUE(has(e, "at least one material")) << e;
}

TEST(ScenarioErrors, TimeStepAboveTheStableStepIsCaughtAtBuildTime) {
  // lsdem: dt_stable = dt_safety·√(m_min/k_n) (Harmon et al. 2020, Appendix) = 0.1·√(m/4e7)
  // for a 2 mm sphere of 2650 kg/m³, m = 1.110e-5 kg → 5.268e-8 s.
  const double m = 2650 * 4.0 / 3.0 * 3.14159265358979 * 1e-9;
  const double bound = 0.1 * std::sqrt(m / 4e7);
  char expect[64];
  std::snprintf(expect, sizeof expect, "stable step %g s", bound);
  const std::string e = error_of(kLsdem, {"time_step=1e-6", "simulation.auto_reduce_dt=false"});
  EXPECT_TRUE(has(e, "/time_step:")) << e;
  EXPECT_TRUE(has(e, "/simulation/auto_reduce_dt")) << e;
  EXPECT_TRUE(has(e, expect)) << e << "\nexpected: " << expect;
  EXPECT_TRUE(has(e, "time step 1e-06 s")) << e;
  // Rules name the rule.
  const std::string r = error_of(kLsdem, {"time_step=[{\"below_stress\": 1e6, \"dt\": 1e-8}, {\"dt\": 1e-6}]",
                                          "simulation.auto_reduce_dt=false"});
  EXPECT_TRUE(has(r, "/time_step/1/dt")) << r;
  // Below the bound, or reduced automatically: fine.
  EXPECT_EQ(error_of(kLsdem, {"time_step=5e-8", "simulation.auto_reduce_dt=false"}), "");
  EXPECT_EQ(error_of(kLsdem, {"time_step=1e-6"}), "");
}

TEST(ScenarioErrors, ExplicitGrainsOutsideTheContainer) {
  const std::string floor = error_of(kLsdem, {"packing.grains.1.position=[0.007, 0.005, 0.0005]"});
  EXPECT_TRUE(has(floor, "/packing/grains/1/position")) << floor;
  EXPECT_TRUE(has(floor, "below the floor")) << floor;
  const std::string wall = error_of(kLsdem, {"packing.grains.1.position=[0.0095, 0.005, 0.0011]"});
  EXPECT_TRUE(has(wall, "/packing/grains/1/position")) << wall;
  const std::string top = error_of(kLsdem, {"packing.grains.0.position=[0.003, 0.005, 0.0055]"});
  EXPECT_TRUE(has(top, "/packing/grains/0/position")) << top;
  // Touching a wall within 1 % of the diameter is fine (1e-6 m inside the floor of a 2 mm grain).
  EXPECT_EQ(error_of(kLsdem, {"packing.grains.0.position=[0.003, 0.005, 0.000999]"}), "");
}

TEST(ScenarioErrors, ExplicitGrainsOverlapping) {
  // Spheres 1.9 mm apart overlap by 0.1 mm, above 1 % of 2 mm.
  const std::string e = error_of(kLsdem, {"packing.grains.1.position=[0.0049, 0.005, 0.0011]"});
  EXPECT_TRUE(has(e, "/packing/grains/1/position")) << e;
  EXPECT_TRUE(has(e, "overlaps grain 0")) << e;
  EXPECT_TRUE(has(e, "by 0.0001 m")) << e;
  // 1.99 mm apart: 0.01 mm, within the tolerance.
  EXPECT_EQ(error_of(kLsdem, {"packing.grains.1.position=[0.00499, 0.005, 0.0011]"}), "");
  // Boxes (signed distance): 2 mm cubes whose centres are 1.8 mm apart overlap by 0.2 mm.
  const std::vector<std::string> boxes = {"packing.grains.0.shape={\"type\":\"box\",\"half_extents\":[0.001,0.001,0.001]}",
                                          "packing.grains.1.shape={\"type\":\"box\",\"half_extents\":[0.001,0.001,0.001]}"};
  auto with = [&](std::vector<std::string> v, const std::string& s) {
    v.push_back(s);
    return v;
  };
  const std::string b = error_of(kLsdem, with(boxes, "packing.grains.1.position=[0.0048, 0.005, 0.0011]"));
  EXPECT_TRUE(has(b, "/packing/grains/1/position")) << b;
  EXPECT_EQ(error_of(kLsdem, with(boxes, "packing.grains.1.position=[0.00501, 0.005, 0.0011]")), "");
}

TEST(ScenarioErrors, NumbersInMessagesKeepTheirSize) {
  // std::to_string printed 1e-12 m as "0.000000 m".
  const std::string e = error_of(R"({"container": {"lx": 1e-14, "ly": 0.01},
     "packing": {"count": 2, "diameter": 1e-12}})");
  EXPECT_TRUE(has(e, "1e-12 m")) << e;
  EXPECT_TRUE(has(e, "container.lx = 1e-14")) << e;
}

TEST(ScenarioErrors, OneGrainThatFitsIsAccepted) {
  // A cloud of one grain: the cloud height was volume / (fill · area), thinner than the grain.
  EXPECT_EQ(error_of(R"({"engine": {"type": "lsdem"}, "container": {"lx": 0.009, "ly": 0.009},
                         "packing": {"count": 1, "diameter": 0.002}})"),
            "");
}

TEST(ScenarioErrors, SeedTakesTheFullUnsignedRange) {
  Json doc = parse_json_text(kLsdem, "t.json");
  BuildOptions o;
  o.seed = 18446744073709551615ull;
  Scenario sc = build_scenario(doc, o);
  EXPECT_EQ(sc.seed, 18446744073709551615ull);
  EXPECT_EQ(sc.effective["seed"].get<std::uint64_t>(), 18446744073709551615ull);
  const std::string neg = error_of(kLsdem, {"seed=-1"});
  EXPECT_TRUE(has(neg, "/seed")) << neg;
  EXPECT_TRUE(has(neg, "18446744073709551615")) << neg;
  // Above 2^53 a seed written as a double has been rounded already: refused.
  EXPECT_TRUE(has(error_of(kLsdem, {"seed=1e19"}), "/seed")) << error_of(kLsdem, {"seed=1e19"});
}

TEST(Config, IntegersAboveLongMaxDoNotWrap) {
  Json d = {{"n", 9223372036854775808ull}};
  Config c(d);
  const ConfigError e = config_error_of([&] { c.integer("n", 0, 0); });
  EXPECT_TRUE(has(e.what(), "got 9223372036854775808")) << e.what();
}

TEST(Config, NumberOverflowNamesFileLineAndPath) {
  const ConfigError e = config_error_of([] { parse_json_text("{\"a\": 1,\n \"b\": {\"c\": [1, 1e999]}}", "s.json"); });
  EXPECT_EQ(e.path(), "/b/c/1");
  EXPECT_TRUE(has(e.what(), "s.json line 2")) << e.what();
  EXPECT_TRUE(has(e.what(), "1e999")) << e.what();
  Json d = {{"x", 1}};
  const ConfigError o = config_error_of([&] { apply_override(d, "loading.max_stress=1e999"); });
  EXPECT_EQ(o.path(), "/loading/max_stress");
  EXPECT_TRUE(has(o.what(), "--set loading.max_stress=1e999")) << o.what();
  // Infinity placed in a document by code is refused wherever it is.
  Json inf = {{"deep", {{"list", {1.0, std::numeric_limits<double>::infinity()}}}}};
  const ConfigError ci = config_error_of([&] { Config c(inf); });
  EXPECT_EQ(ci.path(), "/deep/list/1");
}

TEST(Config, DuplicateKeysAreErrors) {
  const ConfigError e =
      config_error_of([] { parse_json_text(R"({"loading": {"mode": "none", "duration": 1, "mode": "x"}})", "d.json"); });
  EXPECT_EQ(e.path(), "/loading/mode");
  EXPECT_TRUE(has(e.what(), "duplicate key 'mode'")) << e.what();
  EXPECT_TRUE(has(e.what(), "d.json")) << e.what();
  const ConfigError a = config_error_of([] { parse_json_text(R"({"g": [{"x": 1}, {"y": 1, "y": 2}]})", "d.json"); });
  EXPECT_EQ(a.path(), "/g/1/y");
  // Through --set as well, with the path from the target.
  Json d = {{"x", 1}};
  const ConfigError s = config_error_of([&] { apply_override(d, R"(loading={"mode": "none", "mode": "x"})"); });
  EXPECT_EQ(s.path(), "/loading/mode");
  EXPECT_TRUE(has(s.what(), "duplicate key 'mode'")) << s.what();
  // The same key in different objects is fine.
  EXPECT_NO_THROW(parse_json_text(R"({"a": {"k": 1}, "b": {"k": 1}, "k": [ {"k": 2} ]})", "d.json"));
}
