#include "breakage/bonded_particles/BondedParticles.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "breakage/bonded_particles/BpmSystem.h"

namespace crumble {

namespace {

using Clock = std::chrono::steady_clock;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("bonded_particles: " + what);
}

struct RunResult {
  bool split = false;
  double lambda = 0;
  long steps = 0;
  std::string outcome;
  std::vector<char> intact_at_split;
};

// Load factor λ(n) = min(λ_max, rate·n); explicit steps until two major pieces (then
// post_split_steps more at the load of the split), or the full load held at rest, or the cap.
//
// Elastic preload (option elastic_preload): until the first bond breaks the array is linear,
// and the damped ramp follows the static solution. So the static state for λ = 1 is solved
// once, the factor λ_first at which its most loaded bond breaks is found, and the dynamics
// start from preload_fraction·λ_first at rest; a grain that stays below that at the full load
// is intact without dynamics (steps 0).
RunResult run(bpm::System& sys, const bpm::Array& a, double rate, double lambda_max, const BpmOptions& o) {
  RunResult r;
  double lambda0 = 0;
  if (o.elastic_preload) {
    const int it = sys.static_unit_solution(1e-8, 20 * static_cast<int>(a.size()) + 200);
    const double ratio = sys.unit_stress_ratio();
    if (it >= 0 && ratio > 0 && std::isfinite(ratio)) {
      lambda0 = o.preload_fraction / ratio;
      if (lambda0 >= lambda_max) {
        r.lambda = lambda_max;
        r.outcome = "intact";
        return r;
      }
      sys.start_from_static(lambda0);
    }
  }
  const double dt = sys.stable_dt();
  long full_at = -1, split_at = -1, broken_seen = 0, last_break = 0;
  for (long n = 1;; ++n) {
    const double lambda = split_at >= 0 ? r.lambda : std::min(lambda_max, lambda0 + rate * static_cast<double>(n));
    if (lambda >= lambda_max && full_at < 0) full_at = n;
    if (sys.step(dt, lambda, o.damping) > 0) last_break = n;
    r.steps = n;
    r.lambda = lambda;
    if (split_at >= 0) {
      if (n - split_at >= o.post_split_steps || n >= o.max_steps) break;
      continue;
    }
    if (n % o.check_interval == 0 || n >= o.max_steps) {
      if (sys.broken() != broken_seen) {
        broken_seen = sys.broken();
        if (bpm::major_count(bpm::components(a, sys.intact()), o.min_child_fraction, o.min_piece_elements) >= 2) {
          r.split = true;
          r.outcome = "split";
          r.intact_at_split = sys.intact();
          split_at = n;
          if (o.post_split_steps <= 0) break;
          continue;
        }
      }
      if (full_at >= 0 && n - full_at >= o.hold_steps) {
        const double w = std::abs(sys.load_work(lambda));
        // At rest, or no bond broken for quiet_steps at the full load (a loose chip under a
        // contact may keep moving without the grain coming apart).
        if (sys.kinetic_energy() <= o.ke_tolerance * w || n - std::max(full_at, last_break) >= o.quiet_steps) {
          r.outcome = "intact";
          break;
        }
      }
      if (n >= o.max_steps) {
        r.outcome = "step_limit";
        break;
      }
    }
  }
  return r;
}

std::int32_t nearest(const bpm::Array& a, const Vec3& p, double* dist) {
  std::int32_t best = 0;
  double d2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = norm2(a.points[i] - p);
    if (d < d2) {
      d2 = d;
      best = static_cast<std::int32_t>(i);
    }
  }
  *dist = std::sqrt(d2);
  return best;
}

std::vector<std::int32_t> zone(const bpm::Array& a, std::int32_t centre, double radius) {
  std::vector<std::int32_t> z;
  const double r2 = radius * radius;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (norm2(a.points[i] - a.points[centre]) <= r2) z.push_back(static_cast<std::int32_t>(i));
  return z;
}

double element_diameter(const BpmOptions& o, double d_e) {
  return o.element_diameter > 0 ? o.element_diameter : d_e / o.elements_across;
}

// Bond law from the grain's material: ks/kn from ν, kn so that the array's modulus along
// the load axis (array y in 2D, z in 3D) is the material's E.
bpm::BondLaw bond_law(int dim, double d, const Material& m, const BpmOptions& o, double factor) {
  bpm::BondLaw law;
  law.radius = o.radius_multiplier * 0.5 * d;
  law.kn = 1.0;
  law.ks = o.ks_kn_ratio >= 0 ? o.ks_kn_ratio : bpm::shear_ratio_for_poisson(dim, m.poisson);
  const double e1 = bpm::array_young(dim, d, law, dim == 2 ? 1 : 2);
  require(e1 > 0, "the bond stiffness gives the element array no stiffness");
  law.kn = m.young / e1;
  law.ks *= law.kn;
  law.normal_strength = o.normal_strength * factor;
  law.shear_strength = o.shear_strength * factor;
  law.friction = m.friction;
  return law;
}

// Rotation taking the array's load axis (y in 2D, z in 3D) onto the unit vector a.
Quat axis_onto(int dim, const Vec3& a) {
  if (dim == 2) return Quat::from_axis_angle({0, 0, 1}, std::atan2(a.y, a.x) - kPi / 2);
  if (a.z > 1 - 1e-12) return Quat{};
  if (a.z < -1 + 1e-12) return Quat::from_axis_angle({1, 0, 0}, kPi);
  return Quat::from_axis_angle(cross(Vec3{0, 0, 1}, a), std::acos(std::clamp(a.z, -1.0, 1.0)));
}

// The pieces for the fragment builders: major components become clusters 0..k−1 (largest
// first); each minor one joins the cluster of the element nearest to any of its elements.
PointClusters clusters_of(const bpm::Array& a, const std::vector<char>& intact, double min_fraction,
                          long min_elements) {
  const auto c = bpm::components(a, intact);
  std::vector<int> order(c.count);
  for (int k = 0; k < c.count; ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return c.size[x] > c.size[y]; });
  const long total = static_cast<long>(a.size());
  std::vector<int> id(c.count, -1);
  int majors = 0;
  for (int k : order)
    if ((static_cast<double>(c.size[k]) >= min_fraction * static_cast<double>(total) && c.size[k] >= min_elements) ||
        majors == 0)
      id[k] = majors++;
  PointClusters pc;
  pc.spacing = a.d;
  pc.points = a.points;
  pc.clusters = majors;
  pc.cluster.assign(a.size(), -1);
  for (std::size_t i = 0; i < a.size(); ++i) pc.cluster[i] = id[c.label[i]];
  // Fines: nearest element of a major piece (ties: lower index), deterministic.
  for (int k = 0; k < c.count; ++k) {
    if (id[k] >= 0) continue;
    double best = std::numeric_limits<double>::infinity();
    int to = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (c.label[i] != k) continue;
      for (std::size_t j = 0; j < a.size(); ++j) {
        if (id[c.label[j]] < 0) continue;
        const double d = norm2(a.points[i] - a.points[j]);
        if (d < best) {
          best = d;
          to = id[c.label[j]];
        }
      }
    }
    for (std::size_t i = 0; i < a.size(); ++i)
      if (c.label[i] == k) pc.cluster[i] = to;
  }
  pc.on_surface.assign(a.size(), 0);
  for (std::size_t i = 0; i < a.size(); ++i) pc.on_surface[i] = a.coordination[i] < a.full_coordination();
  pc.fracture_points.assign(majors, {});
  for (std::size_t b = 0; b < a.bonds.size(); ++b) {
    if (intact[b]) continue;
    const int x = pc.cluster[a.bonds[b].i], y = pc.cluster[a.bonds[b].j];
    if (x == y) continue;
    const Vec3 mid = 0.5 * (a.points[a.bonds[b].i] + a.points[a.bonds[b].j]);
    pc.fracture_points[x].push_back(mid);
    pc.fracture_points[y].push_back(mid);
  }
  return pc;
}

}  // namespace

// ---------------------------------------------------------------- options

const OptionTable& bonded_particles_options() {
  using S = BpmOptions;
  static const OptionTable t = [] {
    const double inf = std::numeric_limits<double>::infinity();
    return OptionTable{
        // Discretisation (DA-BPM, "Densely arrayed BPM").
        opt::number("element_diameter", &S::element_diameter, 0, 1, "m",
                    "diameter of the densely arrayed elements (the same in every grain and fragment, as in the "
                    "DA-BPM paper); 0 = the grain's d_e / elements_across"),
        opt::number("elements_across", &S::elements_across, 2, 200, "",
                    "elements across a grain's equivalent diameter when element_diameter is 0"),
        opt::integer("min_elements", &S::min_elements, 2, 100'000'000,
                     "a grain of fewer elements cannot break (outcome too_few_elements)"),
        // Parallel bonds (DA-BPM, "Parallel bond"; Potyondy & Cundall 2004).
        opt::positive("normal_strength", &S::normal_strength, "Pa", "tensile strength of a parallel bond"),
        opt::positive("shear_strength", &S::shear_strength, "Pa", "shear strength of a parallel bond"),
        opt::number("radius_multiplier", &S::radius_multiplier, 0.01, 1, "", "bond radius / element radius"),
        opt::number("ks_kn_ratio", &S::ks_kn_ratio, -1, 10, "",
                    "shear / normal bond stiffness; negative = from the material's Poisson ratio "
                    "((1-3ν)/(1+ν) in 2D, (1-4ν)/(1+ν) in 3D, 0 beyond ν = 1/3, 1/4)"),
        opt::number("weibull_modulus", &S::weibull_modulus, 0, 100, "",
                    "Weibull scatter of a grain's bond strengths (crumble's addition; 0 = none, as in the paper)"),
        opt::number("threshold_fraction", &S::threshold_fraction, 0, 10, "",
                    "screening force = this × the diametral crushing estimate (π/2)σd (2D, N/m), σd²/0.9 (3D)"),
        // Loading and integration.
        opt::number("zone_radius_factor", &S::zone_radius_factor, 0, 100, "",
                    "a contact force acts on the elements within this many element diameters of the nearest one"),
        opt::number("contact_tolerance_factor", &S::contact_tolerance_factor, 0, inf, "",
                    "a contact farther than this × element diameter from every element: outcome contact_off_grain"),
        opt::number("damping", &S::damping, 0, 0.99, "", "local non-viscous damping coefficient α (Cundall)"),
        opt::integer("ramp_steps", &S::ramp_steps, 1, 1'000'000'000, "steps over which the contact forces grow to full"),
        opt::boolean("elastic_preload", &S::elastic_preload,
                     "start from the static solution just below the first bond failure (intact at once if none fails)"),
        opt::number("preload_fraction", &S::preload_fraction, 0, 1, "", "of the load factor that breaks the first bond"),
        opt::integer("hold_steps", &S::hold_steps, 0, 1'000'000'000, "least steps at full load before an intact verdict"),
        opt::number("ke_tolerance", &S::ke_tolerance, 0, 1, "",
                    "at rest when the kinetic energy <= this × the work of the loads"),
        opt::integer("quiet_steps", &S::quiet_steps, 1, 1'000'000'000,
                     "intact too when no bond has broken for this many steps at the full load"),
        opt::integer("post_split_steps", &S::post_split_steps, 0, 1'000'000'000,
                     "steps integrated at the split load after the first split"),
        opt::integer("max_steps", &S::max_steps, 1, 1'000'000'000'000L, "steps per analysis at most (outcome step_limit)"),
        opt::integer("check_interval", &S::check_interval, 1, 1'000'000, "steps between connectivity and rest checks"),
        opt::number("min_child_fraction", &S::min_child_fraction, 0, 0.5, "",
                    "pieces with fewer elements are fines, attached to the nearest piece"),
        opt::integer("min_piece_elements", &S::min_piece_elements, 1, 100'000'000,
                     "pieces of fewer elements are fines too (an absolute floor on the fragment size)"),
    };
  }();
  return t;
}

BpmOptions bpm_options_from_config(const Config& cfg) {
  cfg.string("type", "bonded_particles");
  BpmOptions o;
  read_options(cfg, bonded_particles_options(), o);
  return o;
}

void validate(const BpmOptions& o) {
  // Every option in its declared range (bonded_particles_options).
  check_options(bonded_particles_options(), o, "bonded_particles");
}

double bpm_crush_estimate(int dimension, double sigma, double d) {
  return dimension == 2 ? 0.5 * kPi * sigma * d : sigma * d * d / 0.9;
}

// ---------------------------------------------------------------- the model

BondedParticlesModel::BondedParticlesModel(BpmOptions o) : o_(std::move(o)) { validate(o_); }

ScreeningSettings BondedParticlesModel::default_screening() const {
  ScreeningSettings s;
  s.min_contacts = 2;
  s.force_threshold = true;
  return s;
}

void BondedParticlesModel::assign_strength(Grain& g, const Material&, Rng& rng) const {
  require(g.shape != nullptr, "grain without a shape");
  double f = 1.0;
  if (o_.weibull_modulus > 0) {
    // Weibull factor of mean 1: (−ln(1 − U))^(1/m) / Γ(1 + 1/m).
    const double u = rng.uniform();
    f = std::pow(-std::log1p(-u), 1.0 / o_.weibull_modulus) / std::tgamma(1.0 + 1.0 / o_.weibull_modulus);
    f = std::max(f, 1e-3);
  }
  const double d = g.shape->equivalent_diameter();
  g.strength.set(kFactor, f);
  g.strength.set(kThreshold, o_.threshold_fraction * bpm_crush_estimate(g.shape->dimension(), f * o_.normal_strength, d));
}

void BondedParticlesModel::inherit_strength(const Grain& parent, Grain& child, const Material&, Rng&) const {
  require(parent.shape && child.shape, "grain without a shape");
  // The pieces keep their elements and bonds (DA-BPM): the same bond strengths; smaller
  // pieces are stronger per area only through their fewer elements.
  const double f = parent.strength.get_or(kFactor, 1.0);
  const double d = child.shape->equivalent_diameter();
  child.strength.set(kFactor, f);
  child.strength.set(kThreshold,
                     o_.threshold_fraction * bpm_crush_estimate(child.shape->dimension(), f * o_.normal_strength, d));
}

double BondedParticlesModel::load_measure(const Grain&, const Material&, std::span<const Contact> contacts) const {
  double f = 0;
  for (const auto& c : contacts)
    if (is_finite(c.force)) f = std::max(f, norm(c.force));
  return f;
}

BreakageAnalysis BondedParticlesModel::analyse(const Grain& g, const Material& m,
                                               std::span<const Contact> contacts) const {
  const auto t0 = Clock::now();
  BreakageAnalysis a;
  long elements = 0, bonds = 0, steps = 0, broken = 0;
  double force_at_split = 0, deca = 0, pores = 0;
  int pieces = 0;
  auto finish = [&](const std::string& outcome) {
    a.outcome = outcome;
    a.figures = {{"elements", static_cast<double>(elements)},
                 {"bonds", static_cast<double>(bonds)},
                 {"steps", static_cast<double>(steps)},
                 {"broken_bonds", static_cast<double>(broken)},
                 {"force_at_split_N", force_at_split},
                 {"pieces", static_cast<double>(pieces)},
                 {"largest_piece_deca_m", deca},
                 {"inner_pore_volume_m3", pores}};
    a.wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return a;
  };
  require(g.shape != nullptr, "grain " + std::to_string(g.id) + " has no shape");
  const int dim = g.shape->dimension();
  const double factor = g.strength.get_or(kFactor, 0);
  require(factor > 0 && std::isfinite(factor),
          "grain " + std::to_string(g.id) + " has no bond strength factor (assign_strength not called?)");
  const Quat& q = g.orientation;
  const double qn = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  require(std::isfinite(qn) && qn > 0 && is_finite(g.position), "grain " + std::to_string(g.id) + " has a non-finite pose");
  const Quat to_body = q.normalized().conjugate();
  struct Local {
    Vec3 point, force;
  };
  std::vector<Local> loads;
  for (const auto& c : contacts) {
    require(is_finite(c.point) && is_finite(c.force), "non-finite contact point or force on grain " + std::to_string(g.id));
    if (norm2(c.force) == 0) continue;
    Local l{to_body.rotate(c.point - g.position), to_body.rotate(c.force)};
    if (dim == 2) l.point.z = l.force.z = 0;  // the grain's plane
    if (norm2(l.force) == 0) continue;
    loads.push_back(l);
  }
  for (const auto& l : loads) a.load = std::max(a.load, norm(l.force));
  if (loads.size() < 2) return finish("no_load");

  // Array frame: the load axis along the largest force (orientation-free strength).
  std::size_t big = 0;
  for (std::size_t k = 1; k < loads.size(); ++k)
    if (norm2(loads[k].force) > norm2(loads[big].force)) big = k;
  const Quat frame = axis_onto(dim, normalized(loads[big].force));
  const Quat to_frame = frame.conjugate();
  for (auto& l : loads) {
    l = {to_frame.rotate(l.point), to_frame.rotate(l.force)};
    if (dim == 2) l.point.z = l.force.z = 0;
  }

  const double d_e = g.shape->equivalent_diameter();
  const double d = element_diameter(o_, d_e);
  const bpm::Array arr = bpm::dense_array(*g.shape, d, frame);
  elements = static_cast<long>(arr.size());
  bonds = static_cast<long>(arr.bonds.size());
  // The paper's inner-pore correction: the pores between the elements belong to the grain.
  pores = static_cast<double>(arr.size()) * (bpm::cell_volume(dim, d) - bpm::element_volume(dim, d));
  if (elements < o_.min_elements || arr.bonds.empty()) return finish("too_few_elements");

  std::vector<std::int32_t> centre(loads.size());
  for (std::size_t k = 0; k < loads.size(); ++k) {
    double dist = 0;
    centre[k] = nearest(arr, loads[k].point, &dist);
    if (dist > o_.contact_tolerance_factor * d) return finish("contact_off_grain");
  }
  const double zr = o_.zone_radius_factor * d * (1 + 1e-9);
  const bpm::BondLaw law = bond_law(dim, d, m, o_, factor);
  bpm::System sys(arr, law, m.density / bpm::packing_fraction(dim));
  sys.fix(zone(arr, centre[big], zr));
  for (std::size_t k = 0; k < loads.size(); ++k)
    if (k != big) sys.add_load(zone(arr, centre[k], zr), loads[k].force);
  const RunResult r = run(sys, arr, 1.0 / static_cast<double>(o_.ramp_steps), 1.0, o_);
  steps = r.steps;
  broken = sys.broken();
  if (r.split) {
    PointClusters pc = clusters_of(arr, sys.intact(), o_.min_child_fraction, o_.min_piece_elements);
    if (pc.clusters < 2 && !r.intact_at_split.empty()) pc = clusters_of(arr, r.intact_at_split, o_.min_child_fraction, o_.min_piece_elements);
    pc.frame = frame;
    force_at_split = r.lambda * a.load;
    pieces = pc.clusters;
    if (pc.clusters < 2) return finish("split_into_fines");
    // The paper's DECA correction: a piece of n elements has the area (volume) of n cells.
    std::vector<long> n(pc.clusters, 0);
    for (int c : pc.cluster) ++n[c];
    const double cell = bpm::cell_volume(dim, d);
    const double v = static_cast<double>(*std::max_element(n.begin(), n.end())) * cell;
    deca = dim == 2 ? 2 * std::sqrt(v / kPi) : std::cbrt(6 * v / kPi);
    a.broken = true;
    a.fracture = std::move(pc);
  }
  return finish(r.outcome);
}

std::unique_ptr<BreakageModel> make_bonded_particles(const Config& cfg, const EngineContext&) {
  return std::make_unique<BondedParticlesModel>(bpm_options_from_config(cfg));
}

// ---------------------------------------------------------------- single-grain crushing

BpmCrushResult bpm_crush_single_grain(const Shape& shape, const Material& m, const BpmOptions& o,
                                      double strength_factor) {
  validate(o);
  BpmCrushResult res;
  const int dim = shape.dimension();
  const double d_e = shape.equivalent_diameter();
  const double d = element_diameter(o, d_e);
  const bpm::Array arr = bpm::dense_array(shape, d);
  res.elements = static_cast<long>(arr.size());
  res.bonds = static_cast<long>(arr.bonds.size());
  require(res.elements >= o.min_elements, "too few elements");
  const Aabb b = shape.bounds();
  const Vec3 up = dim == 2 ? Vec3{0, 1, 0} : Vec3{0, 0, 1};
  double dist = 0;
  const auto top = nearest(arr, up * dot(b.hi, up), &dist);
  const auto bottom = nearest(arr, up * dot(b.lo, up), &dist);
  const double zr = o.zone_radius_factor * d * (1 + 1e-9);
  const bpm::BondLaw law = bond_law(dim, d, m, o, strength_factor);
  bpm::System sys(arr, law, m.density / bpm::packing_fraction(dim));
  sys.fix(zone(arr, bottom, zr));
  // Unit load at λ = 1 of the estimate; the ramp reaches the estimate in ramp_steps.
  const double F0 = bpm_crush_estimate(dim, law.normal_strength, d_e);
  sys.add_load(zone(arr, top, zr), up * -F0);
  // The ramp goes on to 20× the estimate at most (then: step_limit).
  BpmOptions oc = o;
  oc.max_steps = std::min(o.max_steps, 20 * o.ramp_steps);
  const RunResult r = run(sys, arr, 1.0 / static_cast<double>(o.ramp_steps), std::numeric_limits<double>::infinity(), oc);
  res.steps = r.steps;
  res.broken_bonds = sys.broken();
  res.outcome = r.outcome;
  res.split = r.split;
  if (r.split) res.force = r.lambda * F0;
  res.clusters = clusters_of(arr, sys.intact(), o.min_child_fraction, o.min_piece_elements);
  res.pieces = res.split ? res.clusters.clusters : 1;
  return res;
}

}  // namespace crumble
