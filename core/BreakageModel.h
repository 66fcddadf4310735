// The breakage-model seam. `analyse` is pure and thread-safe: the Simulation calls it for
// several grains at once (one grain per task). The model owns its per-grain strength
// values (Grain::strength), its screening and schedule defaults, and the figures it
// reports for each analysis.
#pragma once
#include <cmath>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/Contact.h"
#include "core/Fracture.h"
#include "core/Grain.h"
#include "core/Rng.h"
#include "core/Schedule.h"
#include "core/Screening.h"

namespace crumble {

// Per-point data of one analysis, for writers that draw it (e.g. the peridynamic lattice
// with its damage, output.vtk_analyses): points in the analysed grain's body frame, and
// fields named with their unit, one value (scalars) or one body-frame vector (vectors) per
// point. Every value is finite.
struct AnalysisPointCloud {
  std::vector<Vec3> points;
  std::vector<std::pair<std::string, std::vector<double>>> scalars;
  std::vector<std::pair<std::string, std::vector<Vec3>>> vectors;
};

// The outcome of one breakage analysis of one grain.
struct BreakageAnalysis {
  bool broken = false;
  std::optional<Fracture> fracture;  // set when broken
  std::string outcome;               // short word for events.csv: intact, split, no_load, ...
  double load = 0;                   // largest contact force considered, N
  double wall_ms = 0;                // wall time of the analysis
  // Model-specific figures, named with their unit (e.g. "points", "force_at_split_N",
  // "sigma_1_Pa"); the names are those of BreakageModel::figure_names().
  std::vector<std::pair<std::string, double>> figures;
  // Optional per-point data (null when the model has none); shared, so records copy it cheaply.
  std::shared_ptr<const AnalysisPointCloud> points;

  void set_figure(const std::string& name, double v) {
    for (auto& f : figures)
      if (f.first == name) {
        f.second = v;
        return;
      }
    figures.emplace_back(name, v);
  }
  // The figure's value, or `def` when the model did not set it.
  double figure(const std::string& name, double def = 0) const {
    for (const auto& f : figures)
      if (f.first == name) return f.second;
    return def;
  }
};

class BreakageModel {
 public:
  virtual ~BreakageModel() = default;
  virtual std::string name() const = 0;
  // False for models that never break anything (the Simulation then skips contacts).
  virtual bool active() const { return true; }

  // Strength of a grain of the initial packing (Weibull sampling).
  virtual void assign_strength(Grain& g, const Material& m, Rng& rng) const = 0;
  // Strength of a child from its parent (Weibull size effect).
  virtual void inherit_strength(const Grain& parent, Grain& child, const Material& m, Rng& rng) const = 0;

  // Decide whether `g`, loaded by `contacts` (forces on g, world frame), breaks. The
  // fracture is expressed in g's body frame.
  virtual BreakageAnalysis analyse(const Grain& g, const Material& m, std::span<const Contact> contacts) const = 0;

  // Threads one analysis may use from now on. The Simulation calls it before each batch of
  // analyses: all of its threads when the batch holds one grain, else 1 (one grain per
  // thread). A model whose results depend on it must ignore it; the default does.
  virtual void set_analysis_threads(int threads) const { (void)threads; }

  // The figures analyse() reports, in a fixed order (one events.csv column each).
  virtual std::vector<std::string> figure_names() const { return {}; }
  // Screening and schedule this model's method prescribes; a scenario's "screening" and
  // "schedule" objects override each value.
  virtual ScreeningSettings default_screening() const { return {}; }
  virtual ScheduleSettings default_schedule() const { return {0.0, 100}; }
  // Screening force of g, N: a grain whose largest contact force is below it is not
  // analysed (when ScreeningSettings::force_threshold is on).
  virtual double threshold_force(const Grain&) const { return 0; }

  // A per-grain scalar that says how hard the grain is loaded by `contacts` in the model's
  // own terms, for writers (a VTK cell field): its name, ending in its unit, and its value
  // (finite). Cheap: no analysis is run. An empty name means the model has none.
  virtual std::string load_measure_name() const { return {}; }
  virtual double load_measure(const Grain&, const Material&, std::span<const Contact>) const { return 0; }
};

// A contact's point (from the grain's centroid) and force, in the grain's body frame.
struct BodyLoad {
  Vec3 point, force;
};

// The contacts on g in its body frame, those without force left out. Throws
// std::invalid_argument, the message led by "MODEL: ", when g's pose or a contact's point
// or force is not finite.
inline std::vector<BodyLoad> body_frame_loads(const Grain& g, std::span<const Contact> contacts,
                                              const std::string& model) {
  auto require = [&](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument(model + ": " + what);
  };
  std::vector<BodyLoad> loads;
  const Quat& q = g.orientation;
  const double qn = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  require(std::isfinite(qn) && qn > 0 && is_finite(g.position), "grain " + std::to_string(g.id) + " has a non-finite pose");
  const Quat to_body = q.normalized().conjugate();  // body ← world
  for (const auto& c : contacts) {
    require(is_finite(c.point) && is_finite(c.force), "non-finite contact point or force on grain " + std::to_string(g.id));
    if (norm2(c.force) == 0) continue;
    loads.push_back({to_body.rotate(c.point - g.position), to_body.rotate(c.force)});
  }
  return loads;
}

// The index of the largest force among `loads` (the first of equals; 0 when there is none).
inline std::size_t largest_load(const std::vector<BodyLoad>& loads) {
  std::size_t largest = 0;
  for (std::size_t k = 1; k < loads.size(); ++k)
    if (norm2(loads[k].force) > norm2(loads[largest].force)) largest = k;
  return largest;
}

}  // namespace crumble
