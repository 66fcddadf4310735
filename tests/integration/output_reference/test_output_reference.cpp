// The declarations of output/OutputReference.h are the one source of every CSV header and
// summary.json key: docs/output.md must hold exactly their generated reference (`crumble list
// --outputs --markdown`), and a real run must write exactly the declared columns and keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "crumble_config.h"
#include "output/OutputReference.h"
#include "tools/OptionDocs.h"
#include "output/Writers.h"
#include "tests/support/CliRunner.h"
#include "tests/support/DocBlocks.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::testing_support::run_cli;
using crumble::testing_support::first_difference;
using crumble::testing_support::slurp;

namespace {

const std::string kDocs = std::string(CRUMBLE_SOURCE_DIR) + "/docs/output.md";

// The lines between <!-- outputs --> and <!-- /outputs --> of docs/output.md.
std::string docs_block() {
  std::istringstream in(slurp(kDocs));
  std::string line, block;
  bool inside = false, found = false;
  while (std::getline(in, line)) {
    if (line == "<!-- outputs -->") {
      inside = found = true;
    } else if (line == "<!-- /outputs -->") {
      inside = false;
    } else if (inside) {
      block += line + "\n";
    }
  }
  EXPECT_TRUE(found) << kDocs << " has no <!-- outputs --> block";
  return block;
}

// Every leaf of summary.json by its dotted path (objects are descended into, arrays are leaves).
void leaves(const Json& j, const std::string& prefix, std::set<std::string>& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object()) leaves(*it, key, out);
    else out.insert(key);
  }
}

// A declared key, or the object of declared nested keys (`time_breakdown_s`).
bool declared_or_parent(const std::string& key) {
  const auto& k = crumble::summary_keys();
  return crumble::summary_key_declared(key) ||
         std::any_of(k.begin(), k.end(), [&](const crumble::SummaryKey& d) { return d.name.rfind(key + ".", 0) == 0; });
}

struct RunCase {
  std::string args;                                 // after `run SCENARIO --out DIR`
  std::map<std::string, std::string> csv_variants;  // file → variant: the CSV files it must write
  std::vector<std::string> figures;                 // events.csv's model figures
  std::set<std::string> conditional;                // summary keys whose condition holds
};

// Runs the case, then checks its files against the declarations: each expected CSV has
// exactly its declared header, every summary key is declared, and every key declared for
// every run (and each conditional key the case meets) is written.
void check_run(const std::string& name, const RunCase& c) {
  const fs::path out = fs::temp_directory_path() / ("crumble_output_reference_" + name);
  fs::remove_all(out);
  const std::string args = "run " + c.args + " --quiet --out " + out.string() + " --set output.plots=false";
  const auto r = run_cli(args);
  ASSERT_EQ(r.status, 0) << args << "\n" << r.output;
  for (const auto& [file, variant] : c.csv_variants) {
    const auto rows = crumble::read_csv((out / file).string());
    ASSERT_FALSE(rows.empty()) << file << " missing";
    const auto figures = c.figures;
    const std::string want = crumble::csv_header(file, variant, [&](const std::string& family) {
      return family == "<figure>" ? figures : std::vector<std::string>{};
    });
    std::string got;
    for (const auto& cell : rows[0]) got += (got.empty() ? "" : ",") + cell;
    EXPECT_EQ(got, want) << file << ": the header written is not the declared one";
    for (const auto& col : rows[0]) {
      bool declared = false;
      for (const auto& d : crumble::output_csv(file).columns) declared = declared || d.name == col;
      EXPECT_TRUE(declared) << file << ": column " << col << " is not declared in output/OutputReference.cpp";
    }
  }
  std::set<std::string> keys;
  leaves(Json::parse(slurp(out / "summary.json")), "", keys);
  for (const auto& k : keys)
    EXPECT_TRUE(crumble::summary_key_declared(k)) << "summary.json key " << k << " is not declared";
  for (const auto& d : crumble::summary_keys()) {
    if (!d.when.empty() && !c.conditional.count(d.name)) continue;
    const bool written =
        std::any_of(keys.begin(), keys.end(), [&](const std::string& k) { return crumble::matches_declared_name(d.name, k); });
    EXPECT_TRUE(written) << "summary.json lacks " << d.name << (d.when.empty() ? " (declared for every run)" : "");
  }
}

}  // namespace

TEST(OutputReference, DocsHoldTheGeneratedReference) {
  const std::string want = crumble::output_reference_markdown();
  // (EXPECT_TRUE: the whole block in the message would hide the line that differs.)
  EXPECT_TRUE(docs_block() == want) << kDocs << ", " << first_difference(want, docs_block())
                                << "\nrefresh it with scripts/update-option-docs.sh (after building build/crumble)";
  const auto r = run_cli("list --outputs --markdown");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(r.output == want) << "crumble list --outputs --markdown, " << first_difference(want, r.output);
}

TEST(OutputReference, EveryNameIsDeclaredOnceWithAUnitAndAMeaning) {
  std::set<std::string> keys;
  for (const auto& k : crumble::summary_keys()) {
    EXPECT_TRUE(keys.insert(k.name).second) << "summary key " << k.name << " declared twice";
    EXPECT_FALSE(k.meaning.empty()) << k.name;
  }
  for (const auto& f : crumble::output_csv_files()) {
    std::set<std::string> cols;
    for (const auto& c : f.columns) {
      EXPECT_TRUE(cols.insert(c.name).second) << f.file << ": column " << c.name << " declared twice";
      EXPECT_FALSE(c.meaning.empty()) << f.file << " " << c.name;
    }
  }
  EXPECT_THROW(crumble::output_csv("no_such.csv"), std::logic_error);
}

TEST(OutputReference, FamiliesMatchTheirMembersOnly) {
  EXPECT_TRUE(crumble::matches_declared_name("analyses_failed_<reason>", "analyses_failed_convex_hull"));
  EXPECT_FALSE(crumble::matches_declared_name("analyses_failed_<reason>", "analyses_failed_"));
  EXPECT_TRUE(crumble::matches_declared_name("void_ratio_at_stress_<Pa>_Pa", "void_ratio_at_stress_1e+06_Pa"));
  EXPECT_FALSE(crumble::matches_declared_name("void_ratio_at_stress_<Pa>_Pa", "void_ratio_at_stress_1e+06"));
  EXPECT_TRUE(crumble::summary_key_declared("time_breakdown_s.output_by_writer.series"));
  EXPECT_FALSE(crumble::summary_key_declared("no_such_key"));
  // A family the writer does not expand is left out; one it expands takes its place.
  EXPECT_EQ(crumble::csv_header("breakage_per_mpa.csv"), "stress_from_MPa,stress_to_MPa,breakage_events");
  const std::string events = crumble::csv_header("events.csv", "", [](const std::string&) {
    return std::vector<std::string>{"a_N", "b"};
  });
  EXPECT_EQ(events.substr(events.size() - 21), "fragment_method,a_N,b");
}

// Every summary key the sources write by name (`sum.extra["k"]`, `extra_arrays["k"]`, a prefix
// `extra["p" + …]`, and `j["k"]` of the run's summary) is declared: the runs below cover some
// paths, this covers the rest (open scenes, resumes, MPI).
TEST(OutputReference, EveryKeyTheSourcesWriteIsDeclared) {
  const std::regex literal(R"re(extra(?:_arrays)?\["([^"]+)"\])re");
  const std::regex prefix(R"re(extra\[(?:std::string\()?"([^"]+)"\)? \+)re");
  const std::regex json_key(R"re(\bj\["([^"]+)"\])re");
  int found = 0;
  for (const char* dir : {"core", "output", "run", "backends", "breakage", "scenarios", "tools"}) {
    for (const auto& e : fs::recursive_directory_iterator(fs::path(CRUMBLE_SOURCE_DIR) / dir)) {
      if (e.path().extension() != ".cpp") continue;
      const std::string text = slurp(e.path()), name = e.path().filename().string();
      auto check = [&](const std::regex& re, const std::string& suffix) {
        for (std::sregex_iterator it(text.begin(), text.end(), re), end; it != end; ++it, ++found)
          EXPECT_TRUE(declared_or_parent((*it)[1].str() + suffix))
              << e.path() << " writes summary key " << (*it)[1].str() << suffix << ", not declared";
      };
      check(literal, "");
      check(prefix, "x");
      if (name == "RunPipeline.cpp" || name == "Writers.cpp") check(json_key, "");
    }
  }
  EXPECT_GT(found, 50);
}

// A single grain under a stress model (Harmon et al. 2020, von Mises): series, events with the
// stress figures, psd, the stage table and the single-grain keys.
TEST(OutputReference, SingleGrainStressRunWritesTheDeclaredColumnsAndKeys) {
#if !CRUMBLE_WITH_BULLET || !CRUMBLE_WITH_CGAL
  GTEST_SKIP() << "needs Bullet and CGAL";
#endif
  RunCase c;
  c.args = std::string(CRUMBLE_SOURCE_DIR) +
           "/scenarios/single_grain_pd.json --set breakage.type=stress --set breakage.criterion=von_mises "
           "--set breakage.weibull=false";
  c.csv_variants = {{"series.csv", ""},  {"events.csv", ""},     {"psd.csv", ""},
                    {"stages.csv", "stress"}, {"ncl.csv", ""}, {"psd_summary.csv", ""},
                    {"breakage_per_mpa.csv", ""}, {"load_displacement.csv", ""}};
  c.figures = {"sigma_1_Pa", "sigma_2_Pa", "sigma_3_Pa", "equivalent_stress_Pa", "strength_Pa",
               "plane_through_centroid"};
  c.conditional = {"packing_settle_steps", "packing_settled", "diameter_m", "max_platen_force_N",
                   "displacement_at_max_force_m", "crushing_force_N", "crushing_stress_Pa",
                   "characteristic_strength_Pa", "fragment_count", "fragment_diameters_m", "psd_d50_final_m",
                   "psd_d10_final_m", "psd_d60_final_m", "fines_fraction_final"};
  check_run("single_grain_stress", c);
}

// A 2D oedometer of 80 grains without breakage, shortened: the closed-container keys, the
// void ratio at the reported stress, shape.csv's 2D columns and the layer PSD.
TEST(OutputReference, OedometerRunWritesTheDeclaredColumnsAndKeys) {
  RunCase c;
  c.args = std::string(CRUMBLE_SOURCE_DIR) +
           "/scenarios/oedometer_rigid_2d_quick.json --set output.shape_metrics=true --set output.psd_layers=2 "
           "--set output.psd_at_stress=[1e4] --set loading.max_stress=2e4 --set loading.ramp_time=0.002";
  c.csv_variants = {{"series.csv", ""},     {"events.csv", ""},      {"psd.csv", ""},
                    {"stages.csv", "stress"}, {"ncl.csv", ""},       {"psd_summary.csv", ""},
                    {"shape.csv", "2D"},    {"psd_layers.csv", ""},  {"load_displacement.csv", ""},
                    {"breakage_per_mpa.csv", ""}};
  c.conditional = {"packing_settle_steps", "packing_settled", "k0_final", "mean_circularity_final",
                   "mean_aspect_ratio_final", "max_platen_force_N", "displacement_at_max_force_m",
                   "void_ratio_at_stress_<Pa>_Pa", "psd_d50_final_m", "fines_fraction_final",
                   "layer_<k>_passing_percent_at_0.025_dmax", "layer_<k>_passing_percent_at_0.25_dmax",
                   "layer_<k>_largest_fragment_m"};
  check_run("oedometer_2d", c);
}
