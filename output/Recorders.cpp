#include "output/Recorders.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "base/Format.h"
#include "core/Measures.h"
#include "core/Simulation.h"
#include "output/LayerOutputs.h"
#include "output/OutputReference.h"
#include "output/Writers.h"

namespace crumble {

using Json = nlohmann::json;

namespace {


// Single-grain crushing (Zhu & Zhao 2019 §4.2): the first breakage gives the crushing force,
// the characteristic strength F/d² and the fragments.
class CrushingRecorder : public Observer {
 public:
  std::string name() const override { return "crushing"; }
  explicit CrushingRecorder(std::string dir) : dir_(std::move(dir)) {}
  void on_start(const Simulation& sim, const RunState&) override {
    if (!sim.grains().empty()) d_ = sim.grains().front().shape->equivalent_diameter();
  }
  void on_sample(const Simulation&, const RunState& s) override { max_force_ = std::max(max_force_, s.platen_force); }
  void on_breakage(const Simulation&, const BreakageEvent& e) override {
    if (done_) return;
    done_ = true;
    // The model's force at failure: peridynamics reports the force reached when the grain
    // split (force_at_split_N); other models fail under the contact forces given, so the
    // largest of them. Stress models also give the equivalent stress at failure.
    const double split = e.analysis.figure("force_at_split_N", 0);
    force_ = split > 0 ? split : e.analysis.load;
    stress_ = e.analysis.figure("equivalent_stress_Pa", -1);
    platen_ = e.platen_stress;
    diam_ = e.child_diameters;
  }
  void on_finish(const Simulation&, const RunState&, RunSummary& sum) override {
    sum.extra["diameter_m"] = d_;
    sum.extra["max_platen_force_N"] = max_force_;
    const LoadDisplacement ld = write_load_displacement_csv(dir_);
    if (!ld.load.empty()) sum.extra["displacement_at_max_force_m"] = ld.displacement_at_peak;
    if (!done_) return;
    sum.extra["crushing_force_N"] = force_;
    if (stress_ >= 0) sum.extra["crushing_stress_Pa"] = stress_;
    sum.extra["characteristic_strength_Pa"] = force_ / (d_ * d_);
    sum.extra["fragment_count"] = static_cast<double>(diam_.size());
    sum.extra_arrays["fragment_diameters_m"] = diam_;
  }

 private:
  std::string dir_;
  double d_ = 0, force_ = 0, platen_ = 0, max_force_ = 0, stress_ = -1;
  bool done_ = false;
  std::vector<double> diam_;
};

// ncl.csv (void ratio and grain count against log stress), and the NCL slope and fractal
// dimension for summary.json. Read from the finished series.csv (the SeriesWriter is
// attached first), so a resumed run covers its whole history.
class CompressionRecorder : public Observer {
 public:
  std::string name() const override { return "compression"; }
  explicit CompressionRecorder(std::string dir) : dir_(std::move(dir)) {}
  void on_finish(const Simulation& sim, const RunState&, RunSummary& sum) override {
    const auto rows = read_csv(dir_ + "/series.csv");
    for (std::size_t i = 1; i < rows.size(); ++i) {
      if (rows[i].size() < 8) continue;
      stress_.push_back(std::atof(rows[i][3].c_str()));
      e_.push_back(std::atof(rows[i][6].c_str()));
      n_.push_back(static_cast<std::size_t>(std::atol(rows[i][7].c_str())));
    }
    std::ostringstream os;
    os << std::setprecision(10) << csv_header("ncl.csv") << '\n';
    for (std::size_t i = 0; i < stress_.size(); ++i)
      if (stress_[i] > 0) os << stress_[i] << ',' << std::log10(stress_[i]) << ',' << e_[i] << ',' << n_[i] << '\n';
    write_file_atomic(dir_ + "/ncl.csv", os.str());
    // Zhu & Zhao 2019 §5: the NCL is about linear in log e – log σ (slope ≈ −0.52 there); fit
    // over the upper part of the loading (σ ≥ 0.3 σ_max), also as e – log σ (C_c).
    const NclFit ncl = fit_ncl_upper(stress_, e_);
    if (std::isfinite(ncl.loglog_slope)) sum.extra["ncl_loglog_slope"] = ncl.loglog_slope;
    if (std::isfinite(ncl.compression_index)) sum.extra["ncl_compression_index"] = ncl.compression_index;
    psd_summary(sum, sim.context().dimension);
    std::vector<double> d;
    for (const auto& g : sim.grains()) d.push_back(g.shape->equivalent_diameter());
    // Only meaningful once grains have broken into a spread of sizes.
    const double D = sum.breakage_events > 0 ? fractal_dimension(d) : std::nan("");
    if (std::isfinite(D)) sum.extra["fractal_dimension_final"] = D;
  }

 private:
  // psd_summary.csv: per table of the finished psd.csv, the fractal dimension read from the
  // PSD by mass and Hardin's relative breakage against the initial table (core/Measures.h);
  // summary.json relative_breakage_final. From the file, so a resumed run covers its history.
  void psd_summary(RunSummary& sum, int dimension) const {
    struct Table {
      std::string label, stress, strain;
      std::vector<double> sieves, passing;
    };
    std::vector<Table> tables;
    const auto rows = read_csv(dir_ + "/psd.csv");
    for (std::size_t i = 1; i < rows.size(); ++i) {
      if (rows[i].size() < 5) continue;
      if (tables.empty() || tables.back().label != rows[i][0]) tables.push_back({rows[i][0], rows[i][1], rows[i][4], {}, {}});
      tables.back().sieves.push_back(std::atof(rows[i][2].c_str()));
      tables.back().passing.push_back(std::atof(rows[i][3].c_str()));
    }
    const Table* initial = nullptr;
    for (const auto& t : tables)
      if (t.label == "initial") initial = &t;
    std::ostringstream os;
    os << std::setprecision(10) << csv_header("psd_summary.csv") << '\n';
    auto cell = [](double v) { return std::isfinite(v) ? fmt_num(v) : std::string(); };  // never NaN in a file
    for (const auto& t : tables) {
      const double D = fractal_dimension_by_mass(t.sieves, t.passing, dimension);
      const double br = initial && initial->sieves == t.sieves
                            ? relative_breakage_sieved(t.sieves, initial->passing, t.passing)
                            : std::nan("");
      os << t.label << ',' << t.stress << ',' << t.strain << ',' << cell(D) << ',' << cell(br) << ','
         << fmt_num(kHardinCutoff) << '\n';
      if (t.label == "final" && std::isfinite(br)) sum.extra["relative_breakage_final"] = br;
    }
    write_file_atomic(dir_ + "/psd_summary.csv", os.str());
  }

  std::string dir_;
  std::vector<double> stress_, e_;
  std::vector<std::size_t> n_;
};

// Figures `crumble compare` tabulates, in summary.json: the void ratio at each reported
// stress or strain level (output.psd_at_stress / psd_at_strain: interpolated between the two
// series samples around the first crossing, core/Measures.h value_at_level, of the stress
// core/Loading.h level_stress counts; absent for a level not reached; read from the
// finished series.csv so a resumed run covers its whole history), and d50 and the fines fraction of the final size distribution by mass.
class ReportRecorder : public Observer {
 public:
  std::string name() const override { return "report"; }
  ReportRecorder(std::string dir, std::vector<double> stresses, std::vector<double> strains, double fines_size)
      : dir_(std::move(dir)), stresses_(std::move(stresses)), strains_(std::move(strains)), fines_size_(fines_size) {}
  void on_finish(const Simulation& sim, const RunState&, RunSummary& sum) override {
    const auto rows = read_csv(dir_ + "/series.csv");
    std::vector<double> stress, strain, voids;
    const std::string& mode = sim.loading().settings().mode;
    for (std::size_t i = 1; i < rows.size(); ++i) {
      if (rows[i].size() < 8) continue;
      // Columns: platen_stress_Pa 3, target_stress_Pa 4 (core/Loading.h level_stress).
      stress.push_back(level_stress(mode, std::atof(rows[i][3].c_str()), std::atof(rows[i][4].c_str())));
      strain.push_back(std::atof(rows[i][5].c_str()));
      voids.push_back(std::atof(rows[i][6].c_str()));
    }
    for (double s : stresses_) {
      const double e = value_at_level(stress, voids, s);
      if (std::isfinite(e)) sum.extra[void_ratio_stress_key(s)] = e;
    }
    for (double s : strains_) {
      const double e = value_at_level(strain, voids, s);
      if (std::isfinite(e)) sum.extra[void_ratio_strain_key(s)] = e;
    }
    // Final PSD by mass: removed fines count at size 0 (Harmon et al. 2020 §3.4: removed
    // particles stay in the PSD).
    std::vector<double> sizes, masses;
    double fines = sum.mass_removed, total = sum.mass_removed;
    for (const auto& g : sim.grains()) {
      const double d = g.shape->equivalent_diameter();
      const double m = g.shape->volume() * sim.context().materials[g.material].density;
      sizes.push_back(d);
      masses.push_back(m);
      total += m;
      if (d < fines_size_) fines += m;
    }
    if (sum.mass_removed > 0) {
      sizes.push_back(0.0);
      masses.push_back(sum.mass_removed);
    }
    const Gradation g = gradation(sizes, masses);
    if (std::isfinite(g.d50)) sum.extra["psd_d50_final_m"] = g.d50;
    if (std::isfinite(g.d10)) sum.extra["psd_d10_final_m"] = g.d10;
    if (std::isfinite(g.d60)) sum.extra["psd_d60_final_m"] = g.d60;
    if (std::isfinite(g.uniformity)) sum.extra["psd_uniformity_final"] = g.uniformity;
    if (total > 0) sum.extra["fines_fraction_final"] = fines / total;
    sum.extra["fines_size_m"] = fines_size_;
  }

 private:
  std::string dir_;
  std::vector<double> stresses_, strains_;
  double fines_size_;
};

}  // namespace

std::string void_ratio_stress_key(double stress) { return "void_ratio_at_stress_" + fmt_num(stress) + "_Pa"; }
std::string void_ratio_strain_key(double strain) { return "void_ratio_at_strain_" + fmt_num(strain); }

std::shared_ptr<Observer> make_crushing_recorder(std::string dir) {
  return std::make_shared<CrushingRecorder>(std::move(dir));
}

std::shared_ptr<Observer> make_compression_recorder(std::string dir) {
  return std::make_shared<CompressionRecorder>(std::move(dir));
}

std::shared_ptr<Observer> make_report_recorder(std::string dir, std::vector<double> stresses,
                                               std::vector<double> strains, double fines_size) {
  return std::make_shared<ReportRecorder>(std::move(dir), std::move(stresses), std::move(strains), fines_size);
}

}  // namespace crumble
