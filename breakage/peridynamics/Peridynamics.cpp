#include "breakage/peridynamics/Peridynamics.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "breakage/peridynamics/PdClusters.h"
#include "breakage/peridynamics/PdKernel.h"
#include "breakage/peridynamics/PdLattice.h"
#include "breakage/peridynamics/PdSystem.h"
#include "core/Weibull.h"
#include "base/BuildCounters.h"

namespace crumble {

using pd::Lattice;
using pd::PdSystem;

namespace {

using Clock = std::chrono::steady_clock;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("peridynamics: " + what);
}

struct Load {
  std::vector<std::int32_t> points;
  Vec3 force;  // N at load factor 1
};

struct RunResult {
  bool split = false;
  double lambda = 0;  // load factor at the split (or at the end)
  long steps = 0;
  long broken_bonds = 0;
  int static_iterations = 0;
  double lambda_first = 0;  // load factor at which the static solution breaks its first bond (0: no preload)
  long hold_steps = 0;           // steps at full load (to the split or the end)
  double quiet_transits_max = 0;  // longest stretch at full load without a newly broken bond, in wave transits
  double dt = 0;
  std::string outcome;
  std::vector<double> alive_at_split;  // bond state when the split was first seen
};

// Lattice points within `radius` of point `centre` (the contact zone, Zhu & Zhao 2019 Fig. 4).
std::vector<std::int32_t> zone(const Lattice& L, std::int32_t centre, double radius) {
  std::vector<std::int32_t> z;
  const double r2 = radius * radius;
  for (std::size_t i = 0; i < L.size(); ++i)
    if (norm2(L.points[i] - L.points[centre]) <= r2) z.push_back(static_cast<std::int32_t>(i));
  return z;
}

std::int32_t nearest_point(const Lattice& L, const Vec3& p, double* dist) {
  std::int32_t best = 0;
  double d2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < L.size(); ++i) {
    const double d = norm2(L.points[i] - p);
    if (d < d2) {
      d2 = d;
      best = static_cast<std::int32_t>(i);
    }
  }
  *dist = std::sqrt(d2);
  return best;
}

// The common driver: load factor λ(t) = min(λ_max, ramp·t), explicit steps until the
// lattice has two major pieces, or the full load has been held and the motion has died
// down, or the step cap.
//
// Elastic preload (option elastic_preload): until the first bond breaks the grain is a
// linear elastic solid, and a ramp slow against the grain's wave transit time (§5: ≳ 100
// transits) follows the static solution u(t) = λ(t)·u1 with velocity ramp·u1. So the
// static solution u1 for unit load is computed once (conjugate gradients), the factor
// λ_first at which its most stretched bond would break is found, and the dynamics start
// at t0 = preload_fraction·λ_first / ramp from that quasi-static state. A grain whose
// static stretches stay below preload_fraction·s_c at the full load ends there (intact).
RunResult run(PdSystem& sys, double ramp, double lambda_max, double d_e, double c_p, const PdOptions& o) {
  RunResult r;
  double t0 = 0;
  if (o.elastic_preload) {
    int iterations = 0;
    const auto u1 = sys.static_unit_solution(o.preload_tolerance, 20000, &iterations, o.threads);
    r.static_iterations = iterations;
    r.lambda_first = sys.first_break_factor(u1);
    const double lambda0 = o.preload_fraction * r.lambda_first;
    if (lambda0 >= lambda_max) {
      sys.set_state(u1, lambda_max, 0.0);
      r.lambda = lambda_max;
      r.outcome = "intact";
      return r;
    }
    sys.set_state(u1, lambda0, ramp);
    t0 = lambda0 / ramp;
  }
  const double dt = o.dt_safety * (o.dt_rule == "spectral" ? sys.spectral_dt(40, o.threads) : sys.stable_dt());
  r.dt = dt;
  // c_p: P-wave speed (with the analysis' density); sets the damping frequency and hold time.
  const double transit = d_e / c_p;
  const double damping = 2.0 * o.damping_ratio * kPi * c_p / d_e;
  const long check = std::max<long>(1, o.check_interval);
  long broken_seen = 0;
  double t_full = -1;   // time the full load was reached
  double t_split = -1;  // time the first split was seen; the load then stays at its value
  long bonds_seen = -1;  // at full load: broken bonds at the last change, and its time
  double t_change = -1;
  const pd::Lattice& L = sys.lattice();
  for (long n = 0;; ++n) {
    const double t = t0 + n * dt;
    const double lambda = t_split >= 0 ? r.lambda : std::min(lambda_max, ramp * t);
    if (lambda >= lambda_max && t_full < 0) t_full = t;
    sys.step(dt, lambda, damping, o.threads);
    r.steps = n + 1;
    if (t_full >= 0 && t_split < 0) ++r.hold_steps;
    r.lambda = lambda;
    if (t_split >= 0) {
      if (t - t_split >= o.post_split_transits * transit || r.steps >= o.max_steps) break;
      continue;
    }
    if (r.steps % check == 0 || r.steps >= o.max_steps) {
      const long broken = sys.broken_face_bonds();
      if (broken != broken_seen) {
        broken_seen = broken;
        const auto comp = pd::face_components(L, sys.alive());
        if (pd::major_count(comp, o.min_child_fraction) >= 2) {
          r.split = true;
          r.outcome = "split";
          r.alive_at_split = sys.alive();
          t_split = t;
          if (o.post_split_transits <= 0) break;
          continue;
        }
      }
      if (t_full >= 0) {  // at full load: how long since a bond last broke (figure quiet_transits_max)
        const long b = sys.broken_bonds();
        if (b != bonds_seen) bonds_seen = b, t_change = t;
        r.quiet_transits_max = std::max(r.quiet_transits_max, (t - t_change) / transit);
      }
      if (t_full >= 0 && t - t_full >= o.hold_transits * transit) {
        const double ke = sys.kinetic_energy();
        const double w = std::abs(sys.external_work_at_rest());
        if (ke <= o.ke_tolerance * w || t - t_full >= o.max_hold_transits * transit) {
          r.outcome = "intact";
          break;
        }
      }
      if (r.steps >= o.max_steps) {
        r.outcome = "step_limit";
        break;
      }
    }
  }
  r.broken_bonds = sys.broken_bonds();
  return r;
}

double p_wave_speed(const pd::LpsMaterial& m) { return std::sqrt((m.bulk + 4.0 * m.shear / 3.0) / m.density); }

pd::LpsMaterial analysis_material(const Material& m, const PdOptions& o) {
  return pd::LpsMaterial::from_young(m.young, m.poisson, m.density * o.density_scale);
}

// Zhu & Zhao 2019 eq. 5 with the size correction of eq. 16: s_c = s_c(eq. 5, δ) · √(d / d_ref).
// With δ ∝ d the product does not depend on d, so strength depends on G_c only.
double grain_critical_stretch(double gc, const pd::LpsMaterial& mat, double horizon, double d_e, const PdOptions& o) {
  return pd::critical_stretch(gc, mat.bulk, mat.shear, horizon) * std::sqrt(d_e / o.d_ref);
}

// Rotation taking the z axis onto the unit vector a (the shortest one).
Quat z_onto(const Vec3& a) {
  if (a.z > 1 - 1e-12) return Quat{};
  if (a.z < -1 + 1e-12) return Quat::from_axis_angle({1, 0, 0}, kPi);
  return Quat::from_axis_angle(cross(Vec3{0, 0, 1}, a), std::acos(std::clamp(a.z, -1.0, 1.0)));
}

Lattice grain_lattice(const Shape& shape, const PdOptions& o, double d_e, const Quat& frame = Quat{}) {
  const double h = o.spacing_fraction * d_e;
  auto pts = pd::lattice_points(shape, h, frame);
  double V = 0;
  if (o.volume_correction && !pts.empty()) V = shape.volume() / static_cast<double>(pts.size());
  if (pts.empty()) return Lattice{};
  count_built(Representation::PdLattice);
  return pd::build_lattice(pts, h, o.horizon_factor, o.partial_volumes, V);
}

}  // namespace

// ---------------------------------------------------------------- options

const OptionTable& peridynamics_options() {
  using S = PdOptions;
  static const OptionTable t = [] {
    const double inf = std::numeric_limits<double>::infinity();
    return OptionTable{
        // Strength (Zhu & Zhao 2019 §4, eqs. 12–15).
        opt::positive("gc0", &S::gc0, "J/m²", "reference critical energy release rate G_c0 at d0 (Zhu & Zhao 2019, eq. 13)"),
        opt::positive("d0", &S::d0, "m", "reference diameter of gc0 (eq. 13)"),
        opt::positive("weibull_modulus", &S::weibull_modulus, "", "Weibull modulus ψ (eq. 13)"),
        opt::boolean("weibull", &S::weibull, "false: every grain has G_c0 scaled by eq. 15 only (deterministic)"),
        opt::number("weibull_a", &S::weibull_a, -inf, 0, "", "a of the linear fit of eq. 12"),
        opt::number("weibull_b", &S::weibull_b, 1, inf, "", "b of the linear fit of eq. 12"),
        opt::number("threshold_force_ref", &S::threshold_force_ref, 0, inf, "N",
                    "screening force of the reference grain, scaled as F_ref·√(G_c/G_c0)·(d/d0)² (eqs. 12, 14)"),
        // Discretisation (§3.1).
        opt::number("spacing_fraction", &S::spacing_fraction, 1e-3, 0.5, "", "lattice spacing / d_e"),
        opt::number("horizon_factor", &S::horizon_factor, 1, 8, "", "horizon δ / spacing"),
        opt::mapped_choice("lattice_alignment", &S::align_lattice_to_load, {{"load", true}, {"body", false}},
                    "\"load\": one lattice axis along the largest contact force (orientation-free strength); "
                    "\"body\": the body axes"),
        opt::boolean("partial_volumes", &S::partial_volumes,
                     "neighbours weighted by the part of their cell inside δ (isotropic E, +10 % strength)"),
        opt::boolean("volume_correction", &S::volume_correction, "point volume = grain volume / points (else spacing³)"),
        opt::integer("min_points", &S::min_points, 2, 100'000'000, "fewer lattice points: outcome too_few_points"),
        opt::positive("d_ref", &S::d_ref, "m", "size correction of the critical stretch (eq. 16)"),
        // Loading (§3.1, §5).
        opt::number("zone_radius_factor", &S::zone_radius_factor, 0, 100, "", "contact zone radius / spacing"),
        opt::number("contact_tolerance_factor", &S::contact_tolerance_factor, 0, inf, "",
                    "a contact farther than this × spacing from the lattice: outcome contact_off_grain"),
        opt::positive("loading_rate_large", &S::rate_large, "N/s", "force ramp rate for d_e ≥ loading_rate_size_large (§5)"),
        opt::positive("loading_rate_medium", &S::rate_medium, "N/s", "force ramp rate between the two sizes (§5)"),
        opt::positive("loading_rate_small", &S::rate_small, "N/s", "force ramp rate for d_e < loading_rate_size_small (§5)"),
        opt::positive("loading_rate_size_large", &S::size_large, "m", "size above which loading_rate_large applies"),
        opt::positive("loading_rate_size_small", &S::size_small, "m", "size below which loading_rate_small applies"),
        // Time integration.
        opt::number("dt_safety", &S::dt_safety, 1e-3, 1, "", "fraction of the stable step"),
        opt::choice("dt_rule", &S::dt_rule, {"spectral", "silling_askari"},
                    "stable step from the largest eigenfrequency, or the Silling–Askari bound (≈ 2.2× smaller)"),
        opt::number("density_scale", &S::density_scale, 1, 1e8, "",
                    "density scaling inside the analysis (measured: +1 % on the crushing force)"),
        opt::boolean("elastic_preload", &S::elastic_preload,
                     "start from the static solution just below the first bond failure"),
        opt::number("preload_fraction", &S::preload_fraction, 0, 1, "", "of the load factor that breaks the first bond"),
        opt::number("preload_tolerance", &S::preload_tolerance, 1e-14, 1e-2, "", "relative residual of the static solve"),
        opt::number("damping_ratio", &S::damping_ratio, 0, 10, "", "mass-proportional damping ratio of the analysis"),
        opt::number("hold_transits", &S::hold_transits, 0, 1e6, "",
                    "least hold at full load, in P-wave transits of d_e, until the kinetic energy decays"),
        opt::number("max_hold_transits", &S::max_hold_transits, 0, 1e7, "", "give up waiting for rest after this"),
        opt::number("ke_tolerance", &S::ke_tolerance, 0, 1, "", "at rest when the kinetic energy ≤ this × the elastic work"),
        opt::number("post_split_transits", &S::post_split_transits, 0, 1e6, "", "wave transits integrated after the first split"),
        opt::integer("max_steps", &S::max_steps, 1, 1'000'000'000'000L, "steps per analysis at most (outcome step_limit)"),
        opt::integer("check_interval", &S::check_interval, 1, 1'000'000, "steps between connectivity and rest checks"),
        opt::integer("threads", &S::threads, 1, 1024,
                     "threads inside one analysis when a check analyses several grains (they already run in "
                     "parallel); a check that analyses one grain gives it all of the run's threads"),
        // Outcome (§3.2).
        opt::number("min_child_fraction", &S::min_child_fraction, 0, 0.5, "",
                    "smaller clusters are fines, attached to the nearest piece"),
    };
  }();
  return t;
}

PdOptions pd_options_from_config(const Config& cfg) {
  cfg.string("type", "peridynamics");
  PdOptions o;
  read_options(cfg, peridynamics_options(), o);
  try {
    validate(o);
  } catch (const std::invalid_argument& e) {
    cfg.fail("", e.what());
  }
  return o;
}

void validate(const PdOptions& o) {
  // Every option in its declared range (peridynamics_options), then what spans several.
  check_options(peridynamics_options(), o, "peridynamics");
  require(o.size_large >= o.size_small, "loading_rate_size_small <= loading_rate_size_large");
  // eq. 12 with U in [0, 1) must give a positive strength: (U − b)/a > 0 for a < 0 < 1 <= b.
  require(o.weibull_a < 0 && o.weibull_b >= 1, "weibull_a must be < 0 and weibull_b >= 1 (eq. 12 positive)");
}

// ---------------------------------------------------------------- strength

double pd_sample_gc(const PdOptions& o, double d, double u) {
  require(d > 0 && std::isfinite(d), "grain size must be > 0");
  WeibullParams p;
  p.variant = "linear";
  p.sigma0 = 1.0;
  p.d0 = o.d0;
  p.modulus = o.weibull_modulus;
  p.a = o.weibull_a;
  p.b = o.weibull_b;
  // eq. 12 gives σ/σ0 = (U − b)/a (d/d0)^(−3/ψ); eq. 13 is its square times G_c0.
  const double s = weibull_sample(p, d, u);
  return o.gc0 * s * s;
}

double pd_child_gc(const PdOptions& o, double gc_parent, double d_child, double d_parent) {
  require(d_child > 0 && d_parent > 0, "grain sizes must be > 0");
  // eq. 15 = eq. 14 squared
  const double s = weibull_size_effect(1.0, d_child, d_parent, o.weibull_modulus);
  return gc_parent * s * s;
}

double pd_threshold_force(const PdOptions& o, double gc, double d) {
  return o.threshold_force_ref * std::sqrt(gc / o.gc0) * (d / o.d0) * (d / o.d0);
}

double pd_loading_rate(const PdOptions& o, double d) {
  if (d >= o.size_large) return o.rate_large;
  if (d >= o.size_small) return o.rate_medium;
  return o.rate_small;
}

// ---------------------------------------------------------------- the model

PeridynamicsModel::PeridynamicsModel(PdOptions o) : o_(std::move(o)) { validate(o_); }

void PeridynamicsModel::assign_strength(Grain& g, const Material&, Rng& rng) const {
  require(g.shape != nullptr, "grain without a shape");
  const double d = g.shape->equivalent_diameter();
  const double gc = o_.weibull ? pd_sample_gc(o_, d, rng.uniform())
                               : o_.gc0 * std::pow(d / o_.d0, -6.0 / o_.weibull_modulus);  // eq. 15 from d0
  g.strength.set(kGc, gc);
  g.strength.set(kThreshold, pd_threshold_force(o_, gc, d));
}

void PeridynamicsModel::inherit_strength(const Grain& parent, Grain& child, const Material&, Rng&) const {
  require(parent.shape && child.shape, "grain without a shape");
  const double gc_parent = parent.strength.get_or(kGc, 0);
  require(gc_parent > 0, "parent grain has no G_c");
  const double dp = parent.shape->equivalent_diameter(), dc = child.shape->equivalent_diameter();
  const double gc = pd_child_gc(o_, gc_parent, dc, dp);
  child.strength.set(kGc, gc);
  child.strength.set(kThreshold, pd_threshold_force(o_, gc, dc));
}

namespace {
// The lattice of a split grain for writers (BreakageAnalysis::points), in the body frame:
// per point the damage (Silling & Askari 2005: the broken share of its bonds, by the
// bonds' partial-volume weights, 0 intact … 1 every bond broken), the piece it went to and
// its displacement at the end of the analysis. Null when a value is not finite.
std::shared_ptr<const AnalysisPointCloud> damage_cloud(const Lattice& L, const PdSystem& sys, const PointClusters& pc,
                                                       const Quat& frame) {
  auto cloud = std::make_shared<AnalysisPointCloud>();
  const std::size_t n = L.size();
  std::vector<double> damage(n, 0.0), piece(n, 0.0);
  std::vector<Vec3> u(n);
  const auto& alive = sys.alive();
  cloud->points.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    double total = 0, intact = 0;
    for (std::int32_t b = L.offsets[i]; b < L.offsets[i + 1]; ++b) {
      total += L.weight[b];
      intact += alive[b];
    }
    damage[i] = total > 0 ? std::clamp(1.0 - intact / total, 0.0, 1.0) : 0.0;
    piece[i] = i < pc.cluster.size() ? pc.cluster[i] : -1;
    const auto k = static_cast<std::int32_t>(i);
    u[i] = frame.rotate(Vec3{sys.displacement(k, 0), sys.displacement(k, 1), sys.displacement(k, 2)});
    cloud->points.push_back(frame.rotate(L.points[i]));
    if (!is_finite(u[i]) || !is_finite(cloud->points.back())) return nullptr;
  }
  cloud->scalars = {{"damage", std::move(damage)}, {"piece", std::move(piece)}};
  cloud->vectors = {{"displacement_m", std::move(u)}};
  return cloud;
}
}  // namespace

double PeridynamicsModel::load_measure(const Grain&, const Material&, std::span<const Contact> contacts) const {
  double f = 0;
  for (const auto& c : contacts)
    if (is_finite(c.force)) f = std::max(f, norm(c.force));
  return f;
}

namespace {

// Lattice frame: one lattice axis along the largest force (see PdOptions); the loads are
// turned into it.
Quat align_to_largest(std::vector<BodyLoad>& loads) {
  const Quat frame = z_onto(normalized(loads[largest_load(loads)].force));
  const Quat to_frame = frame.conjugate();
  for (auto& l : loads) l = {to_frame.rotate(l.point), to_frame.rotate(l.force)};
  return frame;
}

// The lattice point at the centre of each load's contact zone (the nearest); false when a
// load lies farther than contact_tolerance_factor × spacing from every point.
bool zone_centres(const Lattice& L, const std::vector<BodyLoad>& loads, const PdOptions& o,
                  std::vector<std::int32_t>& centre) {
  centre.resize(loads.size());
  for (std::size_t k = 0; k < loads.size(); ++k) {
    double dist = 0;
    centre[k] = nearest_point(L, loads[k].point, &dist);
    if (dist > o.contact_tolerance_factor * L.spacing) return false;
  }
  return true;
}

// Contact zones; the zone of the largest force is fixed, the others carry their force.
void load_zones(PdSystem& sys, const Lattice& L, const std::vector<BodyLoad>& loads,
                const std::vector<std::int32_t>& centre, const PdOptions& o) {
  const std::size_t largest = largest_load(loads);
  const double zr = o.zone_radius_factor * L.spacing * (1.0 + 1e-9);
  sys.fix(zone(L, centre[largest], zr));
  for (std::size_t k = 0; k < loads.size(); ++k)
    if (k != largest) sys.add_load(zone(L, centre[k], zr), loads[k].force);
}

// The pieces of a split lattice (in the lattice frame `frame`).
PointClusters split_pieces(const Lattice& L, const PdSystem& sys, const RunResult& r, const Quat& frame,
                           double min_child_fraction) {
  PointClusters pc = pd::point_clusters(L, sys.alive(), min_child_fraction);
  // A piece above the child size at the split may crumble into fines (< 3 %) during the
  // post-split transits; the split itself then decides the pieces.
  if (pc.clusters < 2 && !r.alive_at_split.empty()) pc = pd::point_clusters(L, r.alive_at_split, min_child_fraction);
  pc.frame = frame;  // lattice frame → body frame
  return pc;
}

}  // namespace

BreakageAnalysis PeridynamicsModel::analyse(const Grain& g, const Material& m,
                                            std::span<const Contact> contacts) const {
  const auto t0 = Clock::now();
  BreakageAnalysis a;
  long points = 0, bonds = 0, steps = 0;
  double force_at_split = 0, first_break_force = 0, hold_steps = 0, quiet_max = 0;
  const int threads = std::max(o_.threads, analysis_threads_.load());
  auto finish = [&](const std::string& outcome) {
    a.outcome = outcome;
    a.figures = {{"points", static_cast<double>(points)},
                 {"bonds", static_cast<double>(bonds)},
                 {"steps", static_cast<double>(steps)},
                 {"force_at_split_N", force_at_split},
                 {"first_break_force_N", first_break_force},
                 {"hold_steps", hold_steps},
                 {"quiet_transits_max", quiet_max},
                 {"threads", static_cast<double>(threads)}};
    a.wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return a;
  };
  require(g.shape != nullptr, "grain " + std::to_string(g.id) + " has no shape");
  require(g.shape->dimension() == 3, "needs a 3D grain, got " + g.shape->describe());
  const double gc = g.strength.get_or(kGc, 0);
  require(gc > 0 && std::isfinite(gc),
          "grain " + std::to_string(g.id) + " has no critical energy release rate (assign_strength not called?)");

  // Contact forces into the body frame (Zhu & Zhao 2019 §3.1).
  std::vector<BodyLoad> loads = body_frame_loads(g, contacts, "peridynamics");
  for (const auto& l : loads) a.load = std::max(a.load, norm(l.force));
  if (loads.size() < 2) return finish("no_load");
  const Quat frame = o_.align_lattice_to_load ? align_to_largest(loads) : Quat{};

  const double d_e = g.shape->equivalent_diameter();
  const Lattice L = grain_lattice(*g.shape, o_, d_e, frame);
  points = static_cast<long>(L.size());
  bonds = L.bonds();
  if (static_cast<long>(L.size()) < o_.min_points) return finish("too_few_points");
  std::vector<std::int32_t> centre;
  if (!zone_centres(L, loads, o_, centre)) return finish("contact_off_grain");
  const auto mat = analysis_material(m, o_);
  PdSystem sys(L, mat, grain_critical_stretch(gc, mat, L.horizon, d_e, o_));
  load_zones(sys, L, loads, centre, o_);

  // Linear ramp: the largest force grows at the size-dependent rate (§5).
  const double fmax = a.load;
  PdOptions ro = o_;
  ro.threads = threads;
  const RunResult r = run(sys, pd_loading_rate(o_, d_e) / fmax, 1.0, d_e, p_wave_speed(mat), ro);
  steps = r.steps;
  if (std::isfinite(r.lambda_first)) first_break_force = r.lambda_first * fmax;
  hold_steps = static_cast<double>(r.hold_steps);
  quiet_max = r.quiet_transits_max;
  if (!r.split) return finish(r.outcome);
  PointClusters pc = split_pieces(L, sys, r, frame, o_.min_child_fraction);
  force_at_split = r.lambda * fmax;
  if (pc.clusters < 2) return finish("split_into_fines");
  a.points = damage_cloud(L, sys, pc, frame);
  a.broken = true;
  a.fracture = std::move(pc);
  return finish(r.outcome);
}

std::unique_ptr<BreakageModel> make_peridynamics(const Config& cfg, const EngineContext& ctx) {
  if (ctx.dimension != 3) cfg.fail("type", "peridynamics needs a 3D scenario");
  return std::make_unique<PeridynamicsModel>(pd_options_from_config(cfg));
}

// ---------------------------------------------------------------- single-grain crushing

CrushResult crush_single_grain(const Shape& shape, const Material& m, double gc, const PdOptions& o) {
  validate(o);
  const auto t0 = Clock::now();
  CrushResult res;
  require(shape.dimension() == 3, "needs a 3D shape");
  const double d_e = shape.equivalent_diameter();
  res.diameter = d_e;
  const Lattice L = grain_lattice(shape, o, d_e);
  res.points = static_cast<long>(L.size());
  res.bonds = L.bonds();
  require(static_cast<long>(L.size()) >= o.min_points,
          "lattice of " + std::to_string(L.size()) + " points is below min_points = " + std::to_string(o.min_points));
  const auto mat = analysis_material(m, o);
  PdSystem sys(L, mat, grain_critical_stretch(gc, mat, L.horizon, d_e, o));
  double dist = 0;
  const Aabb b = shape.bounds();
  const std::int32_t top = nearest_point(L, {0, 0, b.hi.z}, &dist);
  const std::int32_t bottom = nearest_point(L, {0, 0, b.lo.z}, &dist);
  const double zr = o.zone_radius_factor * L.spacing * (1.0 + 1e-9);
  sys.fix(zone(L, bottom, zr));
  sys.add_load(zone(L, top, zr), {0, 0, -1.0});  // 1 N at load factor 1
  const RunResult r =
      run(sys, pd_loading_rate(o, d_e), std::numeric_limits<double>::infinity(), d_e, p_wave_speed(mat), o);
  res.steps = r.steps;
  res.static_iterations = r.static_iterations;
  res.dt = r.dt;
  res.broken_bonds = r.broken_bonds;
  res.outcome = r.outcome;
  res.split = r.split;
  if (r.split) {
    res.force = r.lambda;
    res.strength = res.force / (d_e * d_e);
  }
  res.clusters = pd::point_clusters(L, sys.alive(), o.min_child_fraction);
  res.fragments = res.split ? res.clusters.clusters : 1;
  res.fragment_volumes.assign(res.clusters.clusters, 0.0);
  for (int c : res.clusters.cluster) res.fragment_volumes[c] += L.point_volume;
  res.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return res;
}

// ---------------------------------------------------------------- kernel benchmark

std::string pd_kernel_bench(long steps, int threads) {
  require(steps >= 1, "bench needs steps >= 1");
  require(threads >= 1, "bench needs threads >= 1");
  // LAMMPS examples/peri: lattice sc 0.0005, region cylinder y 0 0 0.005 -0.005 0.0.
  const double h = 0.5e-3;
  std::vector<Vec3> pts;
  for (int k = -10; k <= 10; ++k)
    for (int j = -10; j <= 0; ++j)
      for (int i = -10; i <= 10; ++i)
        if (i * i + k * k <= 100) pts.push_back({i * h, j * h, k * h});
  const Lattice L = pd::build_lattice(pts, h, 3.0002, false);
  // LAMMPS's material: K = 14.9 GPa, μ = 14.9 GPa (pair_coeff), ρ = 2200; s00 = 0.0005.
  const pd::LpsMaterial mat{14.9e9, 14.9e9, 2200};
  // A smooth deformation so the kernel does real work (no bond reaches the critical stretch).
  // Every version of the kernel this CPU can run is timed on the same steps; the default
  // (best) one is the headline figure, and each version's end state is compared bitwise.
  struct Timed {
    double wall;
    std::vector<double> state;
  };
  auto time_isa = [&](const std::string& isa) {
    pd::kernel::select_isa(isa);
    PdSystem sys(L, mat, 0.0005);
    sys.set_displacement([](const Vec3& p) { return Vec3{2e-5 * p.x, -1e-5 * p.y * p.y / 5e-3, 2e-5 * p.z}; });
    const double dt = 0.8 * sys.stable_dt();
    const auto t0 = Clock::now();
    for (long s = 0; s < steps; ++s) sys.step(dt, 0.0, 0.0, threads);
    Timed t{std::chrono::duration<double>(Clock::now() - t0).count(), {}};
    for (std::size_t i = 0; i < L.size(); ++i) {
      const auto k = static_cast<std::int32_t>(i);
      const Vec3 f = sys.force_density(k);
      t.state.insert(t.state.end(), {sys.displacement(k, 0), sys.displacement(k, 1), sys.displacement(k, 2), f.x, f.y,
                                     f.z});
    }
    pd::kernel::select_isa("");
    return t;
  };
  const std::string best = pd::kernel::isa();
  const Timed head = time_isa(best);
  const double visits = static_cast<double>(L.bonds()) * steps;
  std::ostringstream os;
  os.precision(6);
  os << "{\"points\":" << L.size() << ",\"bonds\":" << L.bonds() << ",\"steps\":" << steps
     << ",\"threads\":" << threads << ",\"isa\":\"" << best << "\",\"paths\":{";
  bool first = true;
  for (const auto& isa : pd::kernel::available_isas()) {
    const Timed t = isa == best ? head : time_isa(isa);
    os << (first ? "" : ",") << "\"" << isa << "\":{\"seconds\":" << t.wall << ",\"bond_visits_per_second\":"
       << visits / t.wall << ",\"bitwise_equal_to_default\":" << (t.state == head.state ? "true" : "false") << "}";
    first = false;
  }
  os << "},\"wall_seconds\":" << head.wall << ",\"bond_visits_per_second\":" << visits / head.wall << "}";
  return os.str();
}

}  // namespace crumble
