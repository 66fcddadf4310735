// Output writers, attached to the Simulation as Observers. Every file is written to a
// temporary name and renamed into place when complete (no half-written results).
#pragma once
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/Observer.h"
#include "core/Simulation.h"

namespace crumble {

// Write `content` to `path` atomically (temporary file + rename).
void write_file_atomic(const std::string& path, const std::string& content);

// An append-only CSV written to `<path>.part` and renamed to `path` when finished. When a
// run resumes (`keep_until_step` >= 0), the rows of the earlier file (finished or .part)
// whose `step` column is at most `keep_until_step` are carried over first: matched by the
// integer step, never by a printed time.
class CsvStream {
 public:
  CsvStream(std::string path, const std::string& header, long keep_until_step = -1);
  ~CsvStream();
  std::ofstream& row() { return out_; }
  void finish();

 private:
  std::string path_;
  std::ofstream out_;
  bool done_ = false;
};

// series.csv: time, stress, strain, void ratio, grain count, breakage events (+ more), and
// last `k0`: the lateral stress ratio σ_h/σ_v (core/Measures.h) from the engine's side-wall
// forces (Engine::wall_force) and the platen stress; empty where it is undefined (no
// vertical stress yet, an open scene). summary.json: k0_final, the last defined value.
class SeriesWriter : public Observer {
 public:
  std::string name() const override { return "series"; }
  // resume_step >= 0: continue the series of a run resumed at that step.
  explicit SeriesWriter(const std::string& dir, long resume_step = -1);
  void on_sample(const Simulation&, const RunState& s) override;
  void on_finish(const Simulation&, const RunState&, RunSummary&) override;

 private:
  CsvStream csv_;
  long last_step_ = -1;
  double last_k0_ = std::nan("");
};

// K0 = σ_h/σ_v of the current state (core/Measures.h lateral_stress, lateral_stress_ratio):
// the side walls' forces over their loaded areas (sample height = platen height) against
// the platen stress. NaN for an open scene, a container without side walls or σ_v <= 0.
double current_k0(const Simulation& sim, const RunState& s);

// events.csv: one row per breakage analysis, the common columns first, then one column per
// figure the model declares (BreakageModel::figure_names, in that order);
// breakage_per_mpa.csv: crushing events per MPa of platen stress.
class EventsWriter : public Observer {
 public:
  std::string name() const override { return "events"; }
  // resume_step >= 0: continue the rows of a run resumed at that step. intact false: only the
  // analyses that broke their grain get a row (output.intact_analyses).
  EventsWriter(const std::string& dir, std::vector<std::string> figure_names, long resume_step = -1,
               bool intact = true);
  void on_analysis(const Simulation&, const AnalysisRecord& r) override;
  void on_breakage(const Simulation&, const BreakageEvent& e) override;
  // Every row of a step is on disk before the step's sample (and checkpoint) is written.
  void on_sample(const Simulation&, const RunState&) override;
  void on_finish(const Simulation&, const RunState&, RunSummary&) override;

 private:
  void flush_pending();
  void write_figures(const BreakageAnalysis& a);
  std::string dir_;
  std::vector<std::string> figures_;
  CsvStream csv_;
  bool intact_ = true;
  bool has_pending_ = false;
  AnalysisRecord pending_;
};

// psd.csv: particle size distribution by mass (removed fines counted in the finest bin)
// when the platen stress first reaches each requested level (`level_<Pa>`), when the axial
// strain first reaches each requested strain (`strain_<value>`), and at the end. Every row
// carries the step of the sample its table was taken at.
class PsdWriter : public Observer {
 public:
  std::string name() const override { return "psd"; }
  // A resumed run (resume_step >= 0) keeps the earlier run's tables taken at or before that
  // step; a psd.csv without a step column is kept up to resume_stress (and resume_strain).
  PsdWriter(const std::string& dir, std::vector<double> levels, double resume_stress = -1,
            std::vector<double> strain_levels = {}, double resume_strain = -1, long resume_step = -1);
  void on_start(const Simulation& sim, const RunState& s) override;
  void on_sample(const Simulation& sim, const RunState& s) override;
  void on_finish(const Simulation& sim, const RunState& s, RunSummary&) override;

 private:
  void table(const Simulation& sim, const RunState& s, const std::string& label);
  void write() const;
  std::string dir_;
  std::vector<double> levels_, strains_;
  std::size_t next_ = 0, next_strain_ = 0;
  std::string rows_;
  double d_max_ = 0;
  bool resumed_ = false;
  bool initial_kept_ = false;  // a resumed run kept the earlier run's initial table
};

// Shape descriptors of one grain (geometry/ShapeMetrics.h): 2D circularity (Harmon et al.
// 2020 eq. 23), best-fit-ellipse aspect ratio and sieve size (eq. 21) from the outline; 3D
// Wadell sphericity and Zingg EI, FI from the surface mesh (its own mass properties, so
// area and volume belong to the same surface). Unused fields stay NaN.
struct GrainShapeMetrics {
  double circularity = std::nan(""), aspect_ratio = std::nan(""), sieve_size = std::nan("");
  double sphericity = std::nan(""), elongation = std::nan(""), flatness = std::nan("");
};
GrainShapeMetrics grain_shape_metrics(const Shape& shape);

// grain_shape_metrics computed once per Shape (shared and immutable: a grain that breaks is
// replaced by fragments with shapes of their own) and kept while a grain still uses it. A
// sample looks up every grain's shape, then sweep() releases the shapes it did not look up:
// each sample computes the descriptors of the new shapes only. Several writers may share one
// cache, each looking up every grain before its sweep.
class ShapeMetricsCache {
 public:
  const GrainShapeMetrics& get(const Shape::Ptr& shape);
  void sweep();
  std::size_t computed() const { return computed_; }  // descriptors computed so far

 private:
  std::map<const Shape*, std::pair<Shape::Ptr, GrainShapeMetrics>> cache_, now_;
  std::size_t computed_ = 0;
};

// shape.csv: number means of the grains' shape descriptors against strain and stress, one row
// per series sample (time_s, step, axial_strain, platen_stress_Pa, grains, then 2D
// mean_circularity, mean_aspect_ratio, mean_sieve_size_m; 3D mean_sphericity, mean_EI,
// mean_FI). Metrics are computed once per Shape (ShapeMetricsCache).
class ShapeWriter : public Observer {
 public:
  std::string name() const override { return "shape"; }
  // resume_step >= 0: continue the rows of a run resumed at that step. cache: shared with the
  // VtkWriter of the run (each descriptor computed once for both); null: a cache of its own.
  ShapeWriter(const std::string& dir, int dimension, long resume_step = -1,
              std::shared_ptr<ShapeMetricsCache> cache = nullptr);
  void on_start(const Simulation& sim, const RunState& s) override { on_sample(sim, s); }  // the strain-0 row
  void on_sample(const Simulation& sim, const RunState& s) override;
  void on_finish(const Simulation&, const RunState&, RunSummary& sum) override;

 private:
  int dim_;
  CsvStream csv_;
  long last_step_ = -1;
  std::shared_ptr<ShapeMetricsCache> cache_;
  std::vector<double> last_means_;
};

// ParaView output (VtkWriter, AnalysisVtkWriter): output/VtkWriter.h.

// Rows of a CSV file (header first), split at commas; empty when the file is missing.
std::vector<std::vector<std::string>> read_csv(const std::string& path);

// The header and the breakage rows of an events.csv (a row with children or removed fines;
// an analysis that left its grain whole has neither), read line by line: a stress-model run
// writes one row per grain per check, millions of them, which read_csv would hold in memory
// (6.4 GB for the full Harmon et al. 2020 oedometer). Empty when the file is missing.
std::vector<std::vector<std::string>> read_breakage_rows(const std::string& events_csv);

nlohmann::json summary_json(const RunSummary& s, const std::string& scenario, const std::string& engine,
                            const std::string& breakage, const std::string& fragments, std::uint64_t seed,
                            int threads);

// Open scenes (jaw crusher, Harmon et al. 2020 §4.2): product_psd.csv — the size
// distribution by mass of what left through the discharge, at sieve sizes (the minor-axis
// approximation of §4.2, core/Measures.h sieve_size), with the fines removed inside the
// scene counted as passing every sieve (§3.4: removed particles count in the PSD);
// product.csv — one row per grain that left; summary figures product_mass_kg, product_d50_m
// and the scene's own figures.
class ProductWriter : public Observer {
 public:
  std::string name() const override { return "product"; }
  ProductWriter(const std::string& dir, std::map<std::string, double> figures);
  void on_finish(const Simulation& sim, const RunState& s, RunSummary& sum) override;

 private:
  std::string dir_;
  std::map<std::string, double> figures_;
};

}  // namespace crumble
