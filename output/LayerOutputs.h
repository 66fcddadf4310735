// Outputs of a plate pressed onto layers of grains (Liu et al. 2019 §4): the load–displacement
// curve of any multi-grain run, and sieve curves per layer of the initial packing.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "core/Measures.h"
#include "core/Observer.h"
#include "core/Simulation.h"

namespace crumble {

// Writes DIR/load_displacement.csv (platen displacement from its first sample, platen force)
// from the run's finished DIR/series.csv, so a resumed run gets the whole curve; returns it.
LoadDisplacement write_load_displacement_csv(const std::string& dir);

// load_displacement.csv of a multi-grain run; summary.json gets displacement_at_max_force_m and
// max_platen_force_N. (Single-grain scenes write the same file from their own recorder.)
class LoadDisplacementWriter : public Observer {
 public:
  std::string name() const override { return "load_displacement"; }
  explicit LoadDisplacementWriter(std::string dir) : dir_(std::move(dir)) {}
  void on_finish(const Simulation&, const RunState& s, RunSummary& sum) override;

 private:
  std::string dir_;
};

// psd_layers.csv (output.psd_layers = N > 0): the grains of the initial packing are put into
// N layers of equal height by their starting centroid height (layer 1 at the top, as Liu et
// al. 2019 §4.2 number them); every fragment belongs to the layer of the grain it descends
// from (Grain::origin). Per layer, the percent of the layer's mass passing each sieve
// (Liu et al. 2019's sieves, 1–45 mm, scaled by d_max / 40 mm, then the psd.csv sieves). Mass
// removed from the engine (fines_diameter) has no layer and is left out. summary.json gets
// layer_K_passing_percent_at_{0.025,0.25}_dmax (the paper's 1 mm and 10 mm for 4 cm spheres)
// and layer_K_largest_fragment_m.
class LayerPsdWriter : public Observer {
 public:
  std::string name() const override { return "psd_layers"; }
  LayerPsdWriter(std::string dir, int layers) : dir_(std::move(dir)), layers_(layers) {}
  void on_start(const Simulation& sim, const RunState& s) override;
  void on_finish(const Simulation& sim, const RunState& s, RunSummary& sum) override;

 private:
  std::string dir_;
  int layers_;
  std::map<long, int> layer_of_;  // origin grain id → layer (1 = top)
  std::vector<double> z_lo_, z_hi_;
  double d_max_ = 0;
};

}  // namespace crumble
