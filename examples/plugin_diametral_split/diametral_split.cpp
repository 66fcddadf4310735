// Example plugin: a breakage model a user could add without touching crumble.
//
// `breakage.type = "diametral_split"`: a grain fails when its largest contact force F
// reaches its characteristic strength σ_f times d² (the characteristic tensile stress of a
// grain between two platens, σ = F/d², Jaeger 1967; the measure Zhu & Zhao 2019 use for
// their single-grain strengths, §4.2), and splits in two along the plane that contains the
// line from that contact to the centroid (a diametral, Brazilian-type split). σ_f is drawn
// per grain from a Weibull distribution with size effect (Harmon et al. 2020, eq. 12), and
// children inherit it with eq. 13.
//
// Options ("breakage": {"type": "diametral_split", ...}):
//   strength            Pa, > 0, default 40e6: σ_0 of the Weibull distribution at d_c
//   reference_diameter  m, > 0, default 2e-3: d_c
//   weibull_modulus     > 0, default 3: m
#include <cmath>
#include <memory>

#include "core/BreakageModel.h"
#include "core/Config.h"
#include "core/Weibull.h"
#include "scenarios/Plugins.h"

namespace {

using namespace crumble;

constexpr const char* kStrength = "characteristic_strength_Pa";

class DiametralSplit final : public BreakageModel {
 public:
  explicit DiametralSplit(const WeibullParams& w) : w_(w) {}
  std::string name() const override { return "diametral_split"; }
  std::vector<std::string> figure_names() const override { return {"characteristic_stress_Pa"}; }

  void assign_strength(Grain& g, const Material&, Rng& rng) const override {
    g.strength.set(kStrength, weibull_sample(w_, g.shape->equivalent_diameter(), rng.uniform()));
  }
  void inherit_strength(const Grain& parent, Grain& child, const Material&, Rng&) const override {
    child.strength.set(kStrength, weibull_size_effect(parent.strength.get(kStrength), child.shape->equivalent_diameter(),
                                                      parent.shape->equivalent_diameter(), w_.modulus));
  }
  // The force at which a grain fails: the Simulation's screening skips weaker loads.
  double threshold_force(const Grain& g) const override {
    const double d = g.shape->equivalent_diameter();
    return g.strength.get(kStrength) * d * d;
  }

  BreakageAnalysis analyse(const Grain& g, const Material&, std::span<const Contact> contacts) const override {
    BreakageAnalysis a;
    const Contact* strongest = nullptr;
    for (const Contact& c : contacts)
      if (!strongest || norm(c.force) > norm(strongest->force)) strongest = &c;
    if (!strongest) {
      a.outcome = "no_load";
      return a;
    }
    const double d = g.shape->equivalent_diameter();
    a.load = norm(strongest->force);
    a.set_figure("characteristic_stress_Pa", a.load / (d * d));
    if (a.load < threshold_force(g)) {
      a.outcome = "intact";
      return a;
    }
    // The loading line, contact point → centroid, in the grain's frame; the split plane
    // contains it and the centroid. Its normal is the loading line crossed with the body
    // axis least aligned with it (deterministic).
    Vec3 line = g.to_local(strongest->point);
    if (!(norm(line) > 1e-12 * d)) line = g.orientation.conjugate().rotate(strongest->force);
    if (!(norm(line) > 0)) {
      a.outcome = "degenerate";
      return a;
    }
    line = line / norm(line);
    const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    Vec3 least = axes[0];
    for (const Vec3& e : axes)
      if (std::abs(dot(e, line)) < std::abs(dot(least, line))) least = e;
    const Vec3 n = cross(line, least);
    CuttingSurfaces cut;
    cut.planes.push_back({n / norm(n), 0.0});
    a.broken = true;
    a.fracture = Fracture{cut};
    a.outcome = "split";
    return a;
  }

 private:
  WeibullParams w_;
};

}  // namespace

extern "C" int crumble_plugin_abi() { return crumble::kPluginAbi; }

extern "C" void crumble_plugin_register(crumble::PluginRegistrar& r) {
  r.breakage_models.add(
      {"diametral_split",
       "splits a grain in two through its strongest contact once F/d^2 reaches a Weibull strength (example plugin)",
       [](const crumble::Config& c, const crumble::EngineContext&) -> std::unique_ptr<crumble::BreakageModel> {
         crumble::WeibullParams w;
         w.variant = "weibull";
         w.sigma0 = c.positive("strength", 40e6);
         w.d0 = c.positive("reference_diameter", 2e-3);
         w.modulus = c.positive("weibull_modulus", 3);
         return std::make_unique<DiametralSplit>(w);
       },
       {},
       {2, 3}});
  // A named method ("method": "diametral_split_lsdem"): the engine, model and builder it
  // selects, each filled in only where the scenario leaves it out.
  r.methods.add({"diametral_split_lsdem",
                 "level-set DEM + diametral_split + level-set fragments (example plugin)",
                 {{"engine.type", "lsdem", "example plugin"},
                  {"breakage.type", "diametral_split", "example plugin"},
                  {"fragments.type", "level_set", "example plugin"}}});
}
