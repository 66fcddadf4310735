// Per-layer sieve curves (output.psd_layers, Liu et al. 2019 §4.3.3) and the load–displacement
// file of a multi-grain run, through the CLI on a rigid two-layer packing: the top layer holds
// two 1 mm spheres, the bottom layer two 2 mm spheres, so each layer's curve steps from 0 to
// 100 % between the sieves around its own size.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support/CliRunner.h"

namespace fs = std::filesystem;
using crumble::testing_support::run_cli;
using crumble::testing_support::slurp;

namespace {

std::string scenario(const std::string& layers) {
  return R"({
  "name": "layers_test", "engine": {"type": "lsdem"}, "breakage": {"type": "none"},
  "container": {"lx": 0.008, "ly": 0.004, "height": 0.0045},
  "packing": {"type": "grains", "grains": [
     {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.0015, 0.002, 0.00101]},
     {"shape": {"type": "sphere", "radius": 0.001}, "position": [0.0045, 0.002, 0.00101]},
     {"shape": {"type": "sphere", "radius": 0.0005}, "position": [0.0015, 0.002, 0.0026]},
     {"shape": {"type": "sphere", "radius": 0.0005}, "position": [0.0045, 0.002, 0.0026]}]},
  "loading": {"mode": "strain_rate", "strain_rate": 1.0, "stop_strain": 0.001},
  "time_step": 1e-6, "simulation": {"max_steps": 40, "sample_every": 10},
  "output": {"psd_layers": )" + layers + R"(, "plots": false, "vtk_final": false}
})";
}

std::string write_scenario(const std::string& name, const std::string& text) {
  return crumble::testing_support::scenario_file("crumble_layers_test", name, text);
}

}  // namespace

TEST(LayerOutputs, SieveCurvePerLayerAndLoadDisplacement) {
  const std::string file = write_scenario("two_layers.json", scenario("2"));
  const fs::path out = fs::temp_directory_path() / "crumble_layers_test" / "run";
  fs::remove_all(out);
  const auto r = run_cli("run " + file + " --out " + out.string() + " --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  // layer -> sieve (m) -> percent passing
  std::map<int, std::map<double, double>> pass;
  std::istringstream in(slurp(out / "psd_layers.csv"));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "layer,layer_top_m,layer_bottom_m,layer_mass_kg,sieve_diameter_m,percent_passing_by_mass");
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 6u) << line;
    pass[std::stoi(f[0])][std::stod(f[4])] = std::stod(f[5]);
  }
  ASSERT_EQ(pass.size(), 2u);
  // Sieves are Liu et al. 2019's (mm) × d_max / 40 mm = × 0.05: 2.25, 2, 1.775, 1.25, 1, 0.8 … mm.
  auto at = [&](int layer, double sieve) {
    for (const auto& [s, p] : pass[layer])
      if (std::abs(s - sieve) < 1e-9) return p;
    ADD_FAILURE() << "no sieve " << sieve << " in layer " << layer;
    return -1.0;
  };
  EXPECT_DOUBLE_EQ(at(1, 1.25e-3), 100.0);  // top: 1 mm spheres
  EXPECT_DOUBLE_EQ(at(1, 0.8e-3), 0.0);
  EXPECT_DOUBLE_EQ(at(2, 2.25e-3), 100.0);  // bottom: 2 mm spheres
  EXPECT_DOUBLE_EQ(at(2, 1.775e-3), 0.0);
  const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_NEAR(summary["layer_1_largest_fragment_m"].get<double>(), 1e-3, 1e-9);
  EXPECT_NEAR(summary["layer_2_largest_fragment_m"].get<double>(), 2e-3, 1e-9);
  // load_displacement.csv: one row per sample, displacement from 0 and growing.
  std::istringstream ld(slurp(out / "load_displacement.csv"));
  std::getline(ld, line);
  EXPECT_EQ(line, "platen_displacement_m,platen_force_N");
  int rows = 0;
  double last = -1;
  while (std::getline(ld, line)) {
    const double d = std::stod(line.substr(0, line.find(',')));
    EXPECT_GE(d, last);
    last = d;
    ++rows;
  }
  EXPECT_GE(rows, 2);
  EXPECT_TRUE(summary.contains("displacement_at_max_force_m"));
}

TEST(LayerOutputs, BadLayerCountNamesThePath) {
  const std::string file = write_scenario("bad_layers.json", scenario("-1"));
  const auto r = run_cli("run " + file + " --out " + (fs::temp_directory_path() / "crumble_layers_test" / "bad").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("/output/psd_layers"), std::string::npos) << r.output;
}
