// The options each implementation declares (core/Options.h, RegistryEntry::options) are the
// one source of truth: docs/scenarios.md must hold exactly the generated table of every
// registered implementation, the CLI must print the same, and bad input is refused naming
// the JSON path and the declared range or values.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/Options.h"
#include "tools/OptionDocs.h"
#include "scenarios/Registry.h"
#include "scenarios/ScenarioFactory.h"
#include "tests/support/CliRunner.h"
#include "tests/support/DocBlocks.h"

namespace fs = std::filesystem;
using crumble::testing_support::run_cli;
using crumble::testing_support::first_difference;
using crumble::testing_support::slurp;

namespace {

const std::string kDocs = std::string(CRUMBLE_SOURCE_DIR) + "/docs/scenarios.md";
const std::string kRefresh =
    "refresh the generated tables with scripts/update-option-docs.sh (after building build/crumble)";

bool compiled_out(const std::string& name) {
  return !crumble::not_compiled_reason("engine", name).empty() ||
         !crumble::not_compiled_reason("fragment builder", name).empty();
}

std::string scenario_file(const std::string& name, const std::string& text) {
  return crumble::testing_support::scenario_file("crumble_option_docs_test", name, text);
}

// A valid rigid 3D scenario on the in-house engine, with Bullet's option in the engine section.
const std::string kLsdem = R"({
  "name": "options_test", "engine": {"type": "lsdem", "solver_iterations": 1000}, "breakage": {"type": "none"},
  "container": {"lx": 0.01, "ly": 0.01, "height": 0.004},
  "packing": {"type": "grains", "grains": [
     {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.005, 0.005, 0.0011]}]},
  "loading": {"mode": "strain_rate", "strain_rate": 1.0, "stop_strain": 0.001},
  "time_step": 1e-6, "simulation": {"max_steps": 50}
})";

}  // namespace

TEST(OptionDocs, EveryDeclaredTableIsInTheDocsAsGenerated) {
  const auto blocks = crumble::option_doc_blocks(slurp(kDocs));
  std::map<std::string, std::string> docs;
  for (const auto& b : blocks) {
    EXPECT_TRUE(docs.emplace(b.name, b.content).second)
        << kDocs << ":" << b.line << ": a second options block for '" << b.name << "'";
  }
  int checked = 0;
  for (const auto& n : crumble::registered_options()) {
    if (n.options->empty()) continue;
    const auto it = docs.find(n.name);
    if (it == docs.end()) {
      ADD_FAILURE() << kDocs << " has no block <!-- options:" << n.name << " --> for the " << n.seam << " '" << n.name
                    << "' (" << n.options->size() << " declared options); add the markers and " << kRefresh;
      continue;
    }
    const std::string want = crumble::option_table_markdown(*n.options);
    EXPECT_EQ(it->second, want) << kDocs << ": the options of '" << n.name << "' disagree with the code, first at "
                                << first_difference(want, it->second) << "\n" << kRefresh;
    ++checked;
  }
  // lsdem, stress and level_set are always compiled in.
  EXPECT_GE(checked, 3);
  // No block for an implementation that does not exist (a renamed or removed one).
  for (const auto& b : blocks) {
    bool known = compiled_out(b.name);
    for (const auto& n : crumble::registered_options()) known = known || n.name == b.name;
    EXPECT_TRUE(known) << kDocs << ":" << b.line << ": options block for '" << b.name
                       << "', which is not a registered implementation";
  }
}

TEST(OptionDocs, TheCliPrintsTheSameTable) {
  const auto r = run_cli("list --options lsdem --markdown");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output, crumble::option_table_markdown(crumble::engines().find("lsdem", "").options));
}

TEST(OptionDocs, DocBlocksWithoutTheirEndAreRefused) {
  EXPECT_THROW(crumble::option_doc_blocks("<!-- options:lsdem -->\n| a |\n"), std::invalid_argument);
  EXPECT_THROW(crumble::option_doc_blocks("<!-- /options -->\n"), std::invalid_argument);
  const auto b = crumble::option_doc_blocks("x\n<!-- options:kn -->\n| a |\n<!-- /options -->\n");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].name, "kn");
  EXPECT_EQ(b[0].content, "| a |\n");
  EXPECT_EQ(b[0].line, 2);
}

TEST(Options, ListShowsEveryEngineWithItsOptions) {
  const auto r = run_cli("list");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const auto& e : crumble::engines().entries()) {
    EXPECT_NE(r.output.find("  " + e.name + " — "), std::string::npos) << r.output;
    for (const auto& s : e.options) EXPECT_NE(r.output.find(s.key), std::string::npos) << s.key;
  }
  const auto o = run_cli("list --options lsdem");
  ASSERT_EQ(o.status, 0) << o.output;
  EXPECT_NE(o.output.find("kn                       number  4e7 N/m   > 0"), std::string::npos) << o.output;
}

TEST(Options, ListOptionsOfAnUnknownNameListsTheKnownOnes) {
  const auto r = run_cli("list --options nosuch");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("unknown implementation 'nosuch'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("lsdem"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("level_set"), std::string::npos) << r.output;
}

TEST(Options, WrongTypeNamesThePath) {
  const std::string f = scenario_file("lsdem.json", kLsdem);
  const auto r = run_cli("validate " + f + " --set 'engine.kn=\"abc\"'");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("/engine/kn: expected a number, got a string"), std::string::npos) << r.output;
}

TEST(Options, OutOfRangeNamesThePathAndTheRange) {
  const std::string f = scenario_file("lsdem.json", kLsdem);
  const auto r = run_cli("validate " + f + " --set engine.kn=-1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("/engine/kn: expected a number > 0, got -1"), std::string::npos) << r.output;
  const auto d = run_cli("validate " + f + " --set engine.dt_safety=3");
  EXPECT_EQ(d.status, 2) << d.output;
  EXPECT_NE(d.output.find("/engine/dt_safety: expected a number in [1e-06, 2], got 3"), std::string::npos) << d.output;
  const auto c = run_cli("validate " + f + " --set engine.contact_law=spring");
  EXPECT_EQ(c.status, 2) << c.output;
  EXPECT_NE(c.output.find("/engine/contact_law: unknown value 'spring'; expected one of: linear, hertz"),
            std::string::npos)
      << c.output;
}

TEST(Options, AnUnknownEngineListsTheKnownOnes) {
  const std::string f = scenario_file("lsdem.json", kLsdem);
  const auto r = run_cli("validate " + f + " --set engine.type=chrono");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("/engine/type: unknown engine 'chrono'; known: lsdem"), std::string::npos) << r.output;
}

TEST(Options, ASiblingOptionIsAcceptedFromItsTableAndChecked) {
  const std::string f = scenario_file("lsdem.json", kLsdem);
  if (crumble::engines().entries().size() < 2) GTEST_SKIP() << "only lsdem compiled in";
  const auto ok = run_cli("validate " + f);
  EXPECT_EQ(ok.status, 0) << ok.output;
  EXPECT_NE(ok.output.find("/engine/solver_iterations is an option of '"), std::string::npos) << ok.output;
  EXPECT_NE(ok.output.find("ignored by 'lsdem'"), std::string::npos) << ok.output;
  // The value is still checked against the sibling's declaration.
  const auto bad = run_cli("validate " + f + " --set engine.solver_iterations=0.5");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("/engine/solver_iterations: expected an integer"), std::string::npos) << bad.output;
  // A key no implementation declares stays an error.
  const auto typo = run_cli("validate " + f + " --set engine.solver_iteration=10");
  EXPECT_EQ(typo.status, 2) << typo.output;
  EXPECT_NE(typo.output.find("/engine/solver_iteration: unknown key"), std::string::npos) << typo.output;
}

// Validating an lsdem scenario constructs no sibling: the factories of the other engines,
// models and builders are swapped for ones that fail the test if called.
TEST(Options, SiblingOptionsNeedNoSiblingFactory) {
  auto& table = crumble::engines();
  if (table.entries().size() < 2) GTEST_SKIP() << "only lsdem compiled in";
  int sibling_calls = 0;
  std::vector<crumble::EngineFactory> saved;
  auto& entries = const_cast<std::vector<crumble::RegistryEntry<crumble::EngineFactory>>&>(table.entries());
  for (auto& e : entries) {
    saved.push_back(e.make);
    if (e.name != "lsdem")
      e.make = [&sibling_calls](const crumble::Config&, const crumble::EngineContext&)
          -> std::unique_ptr<crumble::Engine> {
        ++sibling_calls;
        throw std::runtime_error("a sibling engine was constructed");
      };
  }
  std::string error;
  std::vector<std::string> notes;
  try {
    crumble::BuildOptions opt;
    auto sc = crumble::build_scenario(nlohmann::json::parse(kLsdem), opt);
    notes = sc.notes;
  } catch (const std::exception& e) {
    error = e.what();
  }
  for (std::size_t i = 0; i < entries.size(); ++i) entries[i].make = saved[i];
  EXPECT_EQ(error, "");
  EXPECT_EQ(sibling_calls, 0);
  ASSERT_FALSE(notes.empty());
  EXPECT_NE(notes.front().find("/engine/solver_iterations is an option of"), std::string::npos) << notes.front();
}

// Reading a key that is not in the table is a programming error, not a silent default.
TEST(Options, UndeclaredKeyIsAProgrammingError) {
  nlohmann::json doc = {{"kn", 1.0}};
  crumble::Config cfg(doc);
  const crumble::OptionTable table{crumble::opt::positive("kn", 4e7, "N/m", "stiffness")};
  const crumble::Options o(cfg, table);
  EXPECT_DOUBLE_EQ(o.number("kn"), 1.0);
  EXPECT_THROW(o.number("ks"), std::logic_error);
  EXPECT_THROW(o.integer("kn"), std::logic_error);
  EXPECT_THROW(o.number("kn", 2.0), std::logic_error);  // kn has a declared default
}

// The default written back into the effective scenario is the table's, with its JSON type.
TEST(Options, DefaultsComeFromTheTable) {
  nlohmann::json doc = nlohmann::json::object();
  crumble::Config cfg(doc);
  const crumble::OptionTable table{
      crumble::opt::number("a", 0.5, 0, 1, "", "a"), crumble::opt::integer("n", 7, 1, 10, "n"),
      crumble::opt::boolean("b", true, "b"), crumble::opt::choice("c", "x", {"x", "y"}, "c"),
      crumble::opt::positive_below("w", 1.0, 2.0, true, "", "w")};
  const crumble::Options o(cfg, table);
  EXPECT_EQ(o.number("a"), 0.5);
  EXPECT_EQ(o.integer("n"), 7);
  EXPECT_TRUE(o.boolean("b"));
  EXPECT_EQ(o.string("c"), "x");
  EXPECT_EQ(o.number("w"), 1.0);
  EXPECT_EQ(doc.dump(), R"({"a":0.5,"b":true,"c":"x","n":7,"w":1.0})");
  nlohmann::json bad = {{"w", 2.0}};
  crumble::Config cb(bad);
  try {
    crumble::Options(cb, table).number("w");
    ADD_FAILURE() << "w = 2 accepted";
  } catch (const crumble::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "/w: expected a number in (0, 2), got 2");
  }
  EXPECT_EQ(crumble::option_range_text(table[4]), "(0, 2)");
  EXPECT_EQ(crumble::option_range_text(table[1]), "[1, 10]");
  EXPECT_EQ(crumble::option_number_text(4e5), "4e5");
  EXPECT_EQ(crumble::option_number_text(0.002), "0.002");
  EXPECT_EQ(crumble::option_number_text(1e-4), "1e-4");
}

// Every scenario-level section has its generated block: a default changed in the code (or in
// the docs) fails EveryDeclaredTableIsInTheDocsAsGenerated.
TEST(OptionDocs, TheScenarioSectionsAreDocumented) {
  std::map<std::string, std::string> docs;
  for (const auto& b : crumble::option_doc_blocks(slurp(kDocs))) docs[b.name] = b.content;
  for (const char* name : {"scenario", "materials", "container", "packing", "settle", "loading", "simulation",
                           "guards", "schedule", "screening", "output", "scene", "jaw_crusher", "rocks", "walls",
                           "motion"}) {
    const auto found = crumble::find_options(name, "test");
    ASSERT_EQ(found.size(), 1u) << name;
    EXPECT_EQ(docs[name], crumble::option_table_markdown(*found.front().options)) << name;
  }
}

namespace {
struct Inner {
  int steps = 4;
};
struct Bound {
  double kn = 4e7;
  std::string mode = "a";
  double rate = 2;  // read only in mode "b"
  bool aligned = true;
  double strength = 0;  // default follows the mode
  Inner inner;
};
const crumble::OptionTable& bound_table() {
  namespace opt = crumble::opt;
  static const crumble::OptionTable t = {
      opt::positive("kn", &Bound::kn, "N/m", "stiffness"),
      opt::choice("mode", &Bound::mode, {"a", "b"}, "mode"),
      opt::positive("rate", &Bound::rate, "", "rate").when<Bound>([](const Bound& b) { return b.mode == "b"; }),
      opt::mapped_choice("alignment", &Bound::aligned, {{"load", true}, {"body", false}}, "alignment"),
      opt::positive("strength", &Bound::strength, "Pa", "strength")
          .depends<Bound>("per mode", [](const Bound& b) { return b.mode == "a" ? 1.0 : 2.0; }),
      opt::integer("steps", opt::nested(&Bound::inner, &Inner::steps), 1, 10, "steps"),
  };
  return t;
}
}  // namespace

// A table bound to its struct fills it: defaults from the struct's initialisers (written back),
// conditions and computed defaults in table order, ranges checked for read and built settings.
TEST(Options, ABoundTableFillsItsStruct) {
  nlohmann::json doc = {{"mode", "b"}, {"alignment", "body"}};
  crumble::Config cfg(doc);
  Bound b;
  crumble::read_options(cfg, bound_table(), b);
  EXPECT_EQ(b.kn, 4e7);
  EXPECT_EQ(b.rate, 2.0);
  EXPECT_FALSE(b.aligned);
  EXPECT_EQ(b.strength, 2.0);
  EXPECT_EQ(b.inner.steps, 4);
  EXPECT_EQ(doc.dump(), R"({"alignment":"body","kn":40000000.0,"mode":"b","rate":2.0,"steps":4,"strength":2.0})");
  EXPECT_EQ(crumble::option_default_text(bound_table()[3]), "\"load\"");
  EXPECT_EQ(crumble::option_default_text(bound_table()[4]), "per mode");
  // Mode "a" does not read "rate": the key is left unread (check_unknown reports it).
  nlohmann::json other = {{"rate", 3}};
  crumble::Config co(other);
  Bound a;
  crumble::read_options(co, bound_table(), a);
  EXPECT_EQ(a.rate, 2.0);
  EXPECT_EQ(a.strength, 1.0);
  EXPECT_THROW(co.check_unknown(), crumble::ConfigError);
  // Out of range: the read names the path, check_options the key.
  nlohmann::json bad = {{"steps", 11}};
  crumble::Config cb(bad);
  Bound c;
  EXPECT_THROW(crumble::read_options(cb, bound_table(), c), crumble::ConfigError);
  c.inner.steps = 0;
  try {
    crumble::check_options(bound_table(), c, "test");
    ADD_FAILURE() << "steps = 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "test: steps must lie in [1, 10], got 0");
  }
  // A table read into another struct is a programming error.
  int wrong = 0;
  EXPECT_THROW(crumble::read_options(cb, bound_table(), wrong), std::logic_error);
}
