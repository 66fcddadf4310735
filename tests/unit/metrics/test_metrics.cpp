// The sweep metrics (tools/Metrics.h) on hand-made run outputs, and the error–cost front
// (tools/Sweep.h): each value is the figure put in, with its unit; the relative error is
// |x − x_ref| / |x_ref| exactly (1e-15); the front follows Pareto dominance on small cases
// worked by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include <nlohmann/json.hpp>

#include "output/Recorders.h"
#include "tools/Compare.h"
#include "tools/Metrics.h"
#include "run/RunPipeline.h"
#include "tools/Sweep.h"

namespace fs = std::filesystem;
using Json = nlohmann::json;
using crumble::find_metric;
using crumble::RunOutputs;

namespace {

RunOutputs run_with(Json summary) {
  RunOutputs r;
  r.summary = std::move(summary);
  return r;
}

const std::vector<std::string> kEventsHeader = {
    "time_s", "step", "platen_stress_Pa", "grain", "diameter_m", "generation", "wall_ms", "outcome", "max_force_N",
    "children", "child_volumes_m3", "child_diameters_m", "removed_volume_m3", "fragment_method"};

}  // namespace

TEST(Metrics, SummaryFiguresWithTheirUnits) {
  const RunOutputs r = run_with({{"crushing_force_N", 181.5}, {"characteristic_strength_Pa", 4.5375e7},
                                 {"grains_final", 4}, {"psd_d50_final_m", 1.2e-3}, {"fines_fraction_final", 0.02},
                                 {"void_ratio_final", 0.61}, {"mean_sphericity_final", 0.8}});
  const struct {
    const char* name;
    const char* unit;
    double value;
  } cases[] = {{"crushing_force", "N", 181.5},       {"characteristic_strength", "Pa", 4.5375e7},
               {"grains_final", "1", 4},             {"psd_d50", "m", 1.2e-3},
               {"fines_fraction", "1", 0.02},        {"void_ratio_final", "1", 0.61},
               {"mean_sphericity_final", "1", 0.8}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto m = find_metric(c.name, "test");
    EXPECT_EQ(m.unit, c.unit);
    const auto v = m.value(r, m.name);
    ASSERT_TRUE(v.has_value());
    EXPECT_EQ(*v, c.value);
  }
  // Figures the run does not have are absent, not 0.
  for (const char* n : {"crushing_stress", "mean_circularity_final", "fractal_dimension", "first_breakage_stress"})
    EXPECT_FALSE(find_metric(n, "test").value(r, n).has_value()) << n;
  // Every metric has a unit and a description.
  for (const auto& m : crumble::metrics()) {
    EXPECT_FALSE(m.unit.empty()) << m.name;
    EXPECT_FALSE(m.description.empty()) << m.name;
  }
}

TEST(Metrics, StressAtFirstBreakageFromEventsCsv) {
  RunOutputs r = run_with(Json::object());
  r.events = {kEventsHeader,
              // analyses that left the grain whole: no children, nothing removed
              {"0.01", "200", "2.3e6", "0", "0.002", "0", "70", "intact", "80", "0", "", "", "0", ""},
              {"0.02", "400", "4.1e6", "3", "0.002", "0", "70", "intact", "90", "0", "", "", "0", ""},
              // every child a fine: no child in the engine, but a breakage
              {"0.03", "600", "5.5e6", "1", "0.0003", "1", "70", "split", "150", "0", "", "", "1e-12", "hull"},
              {"0.04", "800", "6.2e6", "0", "0.002", "0", "70", "split", "180", "2", "1;1", "1;1", "0", "hull"}};
  const auto m = find_metric("first_breakage_stress", "test");
  EXPECT_EQ(m.unit, "Pa");
  ASSERT_TRUE(m.value(r, m.name).has_value());
  EXPECT_EQ(*m.value(r, m.name), 5.5e6);
  // Columns are found by name: a layout with an extra column first reads the same.
  RunOutputs shifted = r;
  for (auto& row : shifted.events) row.insert(row.begin(), row == shifted.events[0] ? "extra" : "x");
  EXPECT_EQ(*m.value(shifted, m.name), 5.5e6);
  r.events.resize(3);  // only the intact analyses
  EXPECT_FALSE(m.value(r, m.name).has_value());
  r.events.clear();  // no events.csv
  EXPECT_FALSE(m.value(r, m.name).has_value());
}

TEST(Metrics, VoidRatioAtReportedLevels) {
  const RunOutputs r = run_with({{crumble::void_ratio_stress_key(1e6), 0.70},
                                 {crumble::void_ratio_stress_key(5e6), 0.55},
                                 {crumble::void_ratio_strain_key(0.05), 0.18}});
  // Any spelling of the level names the same summary figure.
  for (const char* n : {"void_ratio_at_stress_1e6", "void_ratio_at_stress_1000000", "void_ratio_at_stress_1e+06_Pa"}) {
    const auto m = find_metric(n, "test");
    EXPECT_EQ(m.unit, "1");
    ASSERT_TRUE(m.value(r, m.name).has_value()) << n;
    EXPECT_EQ(*m.value(r, m.name), 0.70) << n;
  }
  EXPECT_EQ(*find_metric("void_ratio_at_strain_0.05", "t").value(r, "void_ratio_at_strain_0.05"), 0.18);
  // A level the run did not reach (or report): no value.
  const auto m2 = find_metric("void_ratio_at_stress_2e6", "test");
  EXPECT_FALSE(m2.value(r, m2.name).has_value());
  // The levels a run reports are offered by default, stress levels first, in order.
  const auto avail = crumble::available_metrics(r);
  ASSERT_EQ(avail.size(), 3u);
  EXPECT_EQ(*avail[0].value(r, avail[0].name), 0.70);
  EXPECT_EQ(*avail[1].value(r, avail[1].name), 0.55);
  EXPECT_EQ(*avail[2].value(r, avail[2].name), 0.18);
}

TEST(Metrics, UnknownNamesListTheKnownOnes) {
  for (const char* bad : {"crushing_forc", "void_ratio_at_stress_", "void_ratio_at_stress_abc", "void_ratio_at_stress_-1", ""}) {
    try {
      find_metric(bad, "--metric x");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const crumble::InputError& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find("--metric x"), std::string::npos) << w;
      EXPECT_NE(w.find("crushing_force (N)"), std::string::npos) << w;
      EXPECT_NE(w.find("void_ratio_at_stress_<Pa>"), std::string::npos) << w;
    }
  }
}

TEST(Metrics, AvailableAreTheFiguresARunHas) {
  const RunOutputs r = run_with({{"crushing_force_N", 180.0}, {"grains_final", 5}, {"wall_seconds", 3.0}});
  std::vector<std::string> names;
  for (const auto& m : crumble::available_metrics(r)) names.push_back(m.name);
  EXPECT_EQ(names, (std::vector<std::string>{"crushing_force", "grains_final"}));
  EXPECT_TRUE(crumble::available_metrics(run_with(nullptr)).empty());
}

TEST(Metrics, RelativeError) {
  EXPECT_NEAR(*crumble::relative_error(198.0, 180.0), 0.1, 1e-15);
  EXPECT_NEAR(*crumble::relative_error(162.0, 180.0), 0.1, 1e-15);
  EXPECT_NEAR(*crumble::relative_error(-0.5, -0.4), 0.25, 1e-15);
  EXPECT_EQ(*crumble::relative_error(180.0, 180.0), 0.0);
  EXPECT_FALSE(crumble::relative_error(1.0, 0.0).has_value());  // undefined, not inf or NaN
  EXPECT_FALSE(crumble::relative_error(std::nullopt, 1.0).has_value());
  EXPECT_FALSE(crumble::relative_error(1.0, std::nullopt).has_value());
}

TEST(Metrics, ReadsARunFolder) {
  const fs::path d = fs::temp_directory_path() / "crumble_metrics_test";
  fs::remove_all(d);
  fs::create_directories(d);
  std::ofstream(d / "summary.json") << R"({"crushing_force_N": 175.25})";
  std::ofstream(d / "events.csv") << "time_s,step,platen_stress_Pa,children,removed_volume_m3\n0.1,10,3e6,2,0\n";
  const auto r = crumble::read_run_outputs(d.string());
  EXPECT_EQ(*find_metric("crushing_force", "t").value(r, "crushing_force"), 175.25);
  EXPECT_EQ(*find_metric("first_breakage_stress", "t").value(r, "first_breakage_stress"), 3e6);
  // A missing or broken folder: no figures, no throw.
  std::ofstream(d / "summary.json") << "{broken";
  EXPECT_FALSE(crumble::read_run_outputs(d.string()).summary.is_object());
  EXPECT_TRUE(crumble::read_run_outputs((d / "none").string()).events.empty());
}

TEST(Pareto, FrontByHand) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  // cost, error:   (1, .5) (2, .1) (3, .2) (4, 0)  -> (3, .2) is dominated by (2, .1)
  EXPECT_EQ(crumble::pareto_front({1, 2, 3, 4}, {0.5, 0.1, 0.2, 0}), (std::vector<bool>{true, true, false, true}));
  // Equal error at a higher cost is dominated; equal cost and error: both stay.
  EXPECT_EQ(crumble::pareto_front({1, 2, 1}, {0.1, 0.1, 0.1}), (std::vector<bool>{true, false, true}));
  // A failed run (NaN) is off the front and dominates nothing; a metric never reached (inf)
  // is off the front.
  EXPECT_EQ(crumble::pareto_front({0.1, 1, 5}, {inf, 0.3, 0}), (std::vector<bool>{false, true, true}));
  EXPECT_EQ(crumble::pareto_front({nan, 1, 5}, {0, 0.3, 0}), (std::vector<bool>{false, true, true}));
  EXPECT_EQ(crumble::pareto_front({0.5, 1}, {nan, 0.3}), (std::vector<bool>{false, true}));
  EXPECT_TRUE(crumble::pareto_front({}, {}).empty());
}

// breakage_events_at_stress_<Pa>: the breakage rows (children or removed fines; intact
// analyses do not count) before the first row at or above the level, for a level the run
// reached (its void ratio is in summary.json); nothing for a level it did not reach.
TEST(Metrics, BreakageEventsBeforeAReportedLevel) {
  RunOutputs r = run_with({{crumble::void_ratio_stress_key(5e6), 0.55}, {crumble::void_ratio_stress_key(1e7), 0.45}});
  // Rows at a platen stress with a number of children and a removed volume.
  auto row = [](const char* stress, const char* children, const char* removed) {
    return std::vector<std::string>{"0", "0", stress, "0", "0.002", "0", "70", "split", "1", children, "", "", removed, "hull"};
  };
  r.events = {kEventsHeader,      row("2.3e6", "0", "0"),     row("4.1e6", "2", "0"), row("4.9e6", "0", "1e-12"),
              row("5.0e6", "2", "0"), row("4.8e6", "2", "0"), row("9.9e6", "2", "0")};
  const auto m5 = find_metric("breakage_events_at_stress_5e6", "test");
  EXPECT_EQ(m5.unit, "1");
  ASSERT_TRUE(m5.value(r, m5.name).has_value());
  EXPECT_EQ(*m5.value(r, m5.name), 2);  // the row at 5.0e6 and all after it are past the level
  const auto m10 = find_metric("breakage_events_at_stress_1e7", "test");
  EXPECT_EQ(*m10.value(r, m10.name), 5);
  const auto m8 = find_metric("breakage_events_at_stress_8e6", "test");  // not reported
  EXPECT_FALSE(m8.value(r, m8.name).has_value());
  EXPECT_THROW(find_metric("breakage_events_at_stress_x", "test"), std::exception);
}
