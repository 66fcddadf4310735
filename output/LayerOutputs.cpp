#include "output/LayerOutputs.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "core/Measures.h"
#include "output/OutputReference.h"
#include "output/Writers.h"

namespace crumble {

LoadDisplacement write_load_displacement_csv(const std::string& dir) {
  // From the finished series.csv (platen height and force, found by their column names): a
  // resumed run's series holds the rows of the run it continues, so the curve is whole.
  std::vector<double> h, f;
  const auto rows = read_csv(dir + "/series.csv");
  if (rows.empty()) return {};
  const auto& head = rows.front();
  const auto col = [&](const char* name) {
    return static_cast<std::size_t>(std::find(head.begin(), head.end(), name) - head.begin());
  };
  const std::size_t ch = col("platen_height_m"), cf = col("platen_force_N");
  if (ch >= head.size() || cf >= head.size())
    throw std::runtime_error(dir + "/series.csv has no platen_height_m or platen_force_N column");
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (rows[i].size() > std::max(ch, cf)) {
      h.push_back(std::atof(rows[i][ch].c_str()));
      f.push_back(std::atof(rows[i][cf].c_str()));
    }
  LoadDisplacement ld = load_displacement(h, f);
  std::ostringstream os;
  os << std::setprecision(10) << csv_header("load_displacement.csv") << '\n';
  for (std::size_t i = 0; i < ld.load.size(); ++i) os << ld.displacement[i] << ',' << ld.load[i] << '\n';
  write_file_atomic(dir + "/load_displacement.csv", os.str());
  return ld;
}

void LoadDisplacementWriter::on_finish(const Simulation&, const RunState&, RunSummary& sum) {
  const LoadDisplacement ld = write_load_displacement_csv(dir_);
  if (!ld.load.empty()) {
    sum.extra["displacement_at_max_force_m"] = ld.displacement_at_peak;
    sum.extra["max_platen_force_N"] = ld.peak_load;
  }
}

void LayerPsdWriter::on_start(const Simulation& sim, const RunState&) {
  if (!layer_of_.empty()) return;
  const int up = sim.context().dimension == 2 ? 1 : 2;
  auto height = [up](const Vec3& p) { return up == 1 ? p.y : p.z; };
  double lo = 1e300, hi = -1e300;
  for (const auto& g : sim.grains()) {
    lo = std::min(lo, height(g.position));
    hi = std::max(hi, height(g.position));
    d_max_ = std::max(d_max_, g.shape->equivalent_diameter());
  }
  const double span = std::max(hi - lo, 1e-12);
  z_lo_.assign(layers_, 0);
  z_hi_.assign(layers_, 0);
  for (int k = 0; k < layers_; ++k) {  // layer k+1 from the top
    z_hi_[k] = hi - span * k / layers_;
    z_lo_[k] = hi - span * (k + 1) / layers_;
  }
  for (const auto& g : sim.grains()) {
    const int from_top = std::clamp(static_cast<int>((hi - height(g.position)) / span * layers_), 0, layers_ - 1);
    layer_of_[g.origin >= 0 ? g.origin : g.id] = from_top + 1;
  }
}

void LayerPsdWriter::on_finish(const Simulation& sim, const RunState&, RunSummary& sum) {
  // Liu et al. 2019 §4.3.3 sieves (mm) for 4 cm spheres, scaled to this packing's largest grain.
  std::vector<double> sieves;
  for (double mm : {45.0, 40.0, 35.5, 25.0, 20.0, 16.0, 10.0, 7.1, 5.0, 3.1, 2.5, 1.7, 1.0})
    sieves.push_back(mm * 1e-3 * d_max_ / 0.04);
  std::vector<std::vector<double>> sizes(layers_), masses(layers_);
  std::vector<double> largest(layers_, 0.0);
  for (const auto& g : sim.grains()) {
    auto it = layer_of_.find(g.origin >= 0 ? g.origin : g.id);
    if (it == layer_of_.end()) continue;
    const int k = it->second - 1;
    sizes[k].push_back(g.shape->equivalent_diameter());
    masses[k].push_back(g.shape->volume() * sim.context().materials[g.material].density);
    largest[k] = std::max(largest[k], sizes[k].back());
  }
  std::ostringstream os;
  os << std::setprecision(10) << csv_header("psd_layers.csv") << '\n';
  for (int k = 0; k < layers_; ++k) {
    double m = 0;
    for (double x : masses[k]) m += x;
    const std::vector<double> pass = percent_passing(sizes[k], masses[k], sieves);
    for (std::size_t i = 0; i < sieves.size(); ++i)
      os << k + 1 << ',' << z_hi_[k] << ',' << z_lo_[k] << ',' << m << ',' << sieves[i] << ',' << pass[i] << '\n';
    const std::vector<double> key = percent_passing(sizes[k], masses[k], {0.025 * d_max_, 0.25 * d_max_});
    const std::string p = "layer_" + std::to_string(k + 1) + "_";
    sum.extra[p + "passing_percent_at_0.025_dmax"] = key[0];
    sum.extra[p + "passing_percent_at_0.25_dmax"] = key[1];
    sum.extra[p + "largest_fragment_m"] = largest[k];
  }
  write_file_atomic(dir_ + "/psd_layers.csv", os.str());
}

}  // namespace crumble
