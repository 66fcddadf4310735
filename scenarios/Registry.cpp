#include "scenarios/Registry.h"

#include "crumble_config.h"

#include "backends/lsdem/LsdemEngine.h"
#include "breakage/none/NoBreakage.h"
#if CRUMBLE_WITH_BULLET
#include "backends/bullet/BulletEngine.h"
#endif
#if CRUMBLE_WITH_ODE
#include "backends/ode/OdeEngine.h"
#endif
#if CRUMBLE_WITH_CGAL
#include "breakage/block_beam/BlockBeam.h"
#include "geometry/alpha_shape/AlphaShapeBuilder.h"
#endif
#include "breakage/bonded_particles/BondedParticles.h"
#include "breakage/peridynamics/Peridynamics.h"
#include "breakage/stress/StressModel.h"
#include "geometry/level_set/LevelSetBuilder.h"
#include "scenarios/Sections.h"

namespace crumble {

template <class F>
void Table<F>::add(RegistryEntry<F> e) {
  for (auto& x : entries_)
    if (x.name == e.name) throw std::invalid_argument(seam_ + " '" + e.name + "' is registered twice");
  entries_.push_back(std::move(e));
}

template <class F>
std::string Table<F>::names() const {
  std::string s;
  for (const auto& e : entries_) s += (s.empty() ? "" : ", ") + e.name;
  return s;
}

template <class F>
const RegistryEntry<F>& Table<F>::find(const std::string& name, const std::string& where) const {
  for (const auto& e : entries_)
    if (e.name == name) return e;
  const std::string why = not_compiled_reason(seam_, name);
  if (!why.empty()) throw ConfigError(where, "'" + name + "' is not available in this build: " + why);
  throw ConfigError(where, "unknown " + seam_ + " '" + name + "'; known: " + names());
}

template class Table<EngineFactory>;
template class Table<ModelFactory>;
template class Table<BuilderFactory>;

// ---- The explicit registration tables. Adding an implementation = one line here. ----

Table<EngineFactory>& engines() {
  static Table<EngineFactory> t = [] {
    Table<EngineFactory> t("engine");
    t.add({"lsdem", "in-house level-set DEM (Harmon et al. 2020 §2), explicit, 2D and 3D",
           [](const Config& c, const EngineContext& ctx) { return make_lsdem_engine(c, ctx); }, {}, {2, 3},
           lsdem_options()});
#if CRUMBLE_WITH_BULLET
    t.add({"bullet", "Bullet 3 rigid bodies, projected Gauss-Seidel contact dynamics (Zhu & Zhao 2019)",
           [](const Config& c, const EngineContext& ctx) { return make_bullet_engine(c, ctx); }, {}, {3},
           bullet_options()});
#endif
#if CRUMBLE_WITH_ODE
    t.add({"ode", "Open Dynamics Engine 0.16 rigid bodies, QuickStep (projected SOR) contact dynamics, Coulomb "
                  "friction (dContactApprox1)",
           [](const Config& c, const EngineContext& ctx) { return make_ode_engine(c, ctx); }, {}, {3},
           ode_options()});
#endif
    return t;
  }();
  return t;
}

Table<ModelFactory>& breakage_models() {
  static Table<ModelFactory> t = [] {
    Table<ModelFactory> t("breakage model");
    t.add({"none", "grains never break (rigid runs)",
           [](const Config& c, const EngineContext&) { return make_no_breakage(c); }, {}, {2, 3}, {}});
    t.add({"peridynamics", "LPS peridynamics with critical-stretch bonds (Zhu & Zhao 2019)", make_peridynamics, {}, {3},
           peridynamics_options()});
    t.add({"stress", "average-stress criterion, Weibull strengths, planar split through the strongest contacts "
                     "(Harmon et al. 2020, eqs. 5-13, 18-20)",
           make_stress, stress::criterion_names(), {2, 3}, stress_options()});
    t.add({"bonded_particles", "densely arrayed bonded particles with parallel bonds (the DA-BPM paper)", make_bonded_particles, {}, {2, 3}, bonded_particles_options()});
#if CRUMBLE_WITH_CGAL
    t.add({"block_beam", "tetrahedral blocks joined by beams that break at their tensile or shear strength (Liu et al. 2019, §2.1, §2.3)", make_block_beam, {}, {3}, block_beam_options()});
#endif
    return t;
  }();
  return t;
}

Table<BuilderFactory>& fragment_builders() {
  static Table<BuilderFactory> t = [] {
    Table<BuilderFactory> t("fragment builder");
#if CRUMBLE_WITH_CGAL
    t.add({"alpha_shape", "alpha-shape polyhedra of point clusters (CGAL, Zhu & Zhao 2019 §3.2); plane cuts of the parent mesh",
           [](const Config& c, const EngineContext& x) { return make_alpha_shape_builder(c, x); }, {}, {3},
           alpha_shape_options()});
#endif
    t.add({"level_set",
           "level-set children: plane cuts phi3 = max(phi1, -phi2), phi4 = max(phi1, phi2) (Harmon et al. 2020, "
           "eqs. 14-15); point clusters by nearest cluster",
           [](const Config& c, const EngineContext& x) { return make_level_set_builder(c, x); }, {}, {2, 3},
           level_set_options()});
    return t;
  }();
  return t;
}

namespace {
template <class T>
void collect(const char* seam, const T& table, std::vector<NamedOptions>& out) {
  for (const auto& e : table.entries()) out.push_back({seam, e.name, e.description, &e.options});
}
}  // namespace

std::vector<NamedOptions> registered_options() {
  std::vector<NamedOptions> out;
  collect("engine", engines(), out);
  collect("breakage model", breakage_models(), out);
  collect("fragment builder", fragment_builders(), out);
  for (const auto& s : scenario_sections()) out.push_back({"scenario section", s.name, s.description, s.options});
  return out;
}

std::vector<NamedOptions> find_options(const std::string& name, const std::string& where) {
  std::vector<NamedOptions> found;
  std::string known;
  for (auto& n : registered_options()) {
    known += (known.empty() ? "" : ", ") + n.name;
    if (n.name == name) found.push_back(n);
  }
  if (!found.empty()) return found;
  for (const char* seam : {"engine", "fragment builder"}) {
    const std::string why = not_compiled_reason(seam, name);
    if (!why.empty()) throw ConfigError(where, "'" + name + "' is not available in this build: " + why);
  }
  throw ConfigError(where, "unknown implementation '" + name + "'; known: " + known);
}

std::vector<NotCompiled> not_compiled() {
  std::vector<NotCompiled> out;
  if (!CRUMBLE_WITH_BULLET) out.push_back({"engine", "bullet", "built with CRUMBLE_WITH_BULLET=OFF"});
  if (!CRUMBLE_WITH_ODE) out.push_back({"engine", "ode", "built with CRUMBLE_WITH_ODE=OFF"});
  if (!CRUMBLE_WITH_CGAL) {
    out.push_back({"breakage model", "block_beam", "built with CRUMBLE_WITH_CGAL=OFF"});
    out.push_back({"fragment builder", "alpha_shape", "built with CRUMBLE_WITH_CGAL=OFF"});
  }
  return out;
}

std::string not_compiled_reason(const std::string& seam, const std::string& name) {
  for (const auto& n : not_compiled())
    if (n.seam == seam && n.name == name) return n.reason;
  return "";
}

}  // namespace crumble
