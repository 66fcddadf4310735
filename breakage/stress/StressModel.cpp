#include "breakage/stress/StressModel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>

#include "core/Weibull.h"
#include "geometry/SymmetricEigen.h"

namespace crumble {

namespace {

using Clock = std::chrono::steady_clock;

void require(bool ok, const std::string& msg) {
  if (!ok) throw std::invalid_argument("stress: " + msg);
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace

// ---------------------------------------------------------------- options

// The criteria are declared once, in their own table (Criteria.cpp): the choices of
// "criterion" and the per-criterion defaults below are read from it.
const OptionTable& stress_options() {
  using S = StressOptions;
  static const OptionTable t = [] {
    std::string strengths, tensile;
    for (const auto& c : stress::criteria()) {
      strengths += (strengths.empty() ? "" : ", ") + c.name + " " + option_number_text(c.default_strength);
      if (c.default_tensile_strength > 0)
        tensile += (tensile.empty() ? "" : ", ") + c.name + " " + option_number_text(c.default_tensile_strength);
    }
    // The criterion is read first: it gives the defaults of the two strengths.
    const auto entry = [](const S& o) { return stress::find_criterion(o.criterion); };
    return OptionTable{
        opt::choice("criterion", &S::criterion, stress::criterion_names(),
                    "yield criterion of the average stress (Harmon et al. 2020 §3.1, eqs. 7–10)"),
        opt::positive("strength", &S::strength, "Pa",
                      "characteristic strength σ0 at reference_diameter (Harmon et al. 2020, eqs. 11–12)")
            .depends<S>("per criterion (Harmon et al. 2020 Table 2): " + strengths + " Pa",
                        [entry](const S& o) { return entry(o)->default_strength; }),
        opt::positive("tensile_strength", &S::tensile_strength, "Pa",
                      "tensile strength (Harmon et al. 2020, eq. 8); an error with a criterion without one")
            .depends<S>("per criterion (Table 2): " + tensile + " Pa",
                        [entry](const S& o) { return entry(o)->default_tensile_strength; })
            .when<S>([entry](const S& o) { return entry(o)->default_tensile_strength > 0; }),
        opt::positive("weibull_modulus", &S::weibull_modulus, "", "Weibull modulus m of eqs. 11–13 (Table 2)"),
        opt::positive("reference_diameter", &S::reference_diameter, "m",
                      "d0 of eqs. 11–12 (Table 2: characteristic diameter d_c = 2 mm)"),
        opt::boolean("weibull", &S::weibull,
                     "strength per grain by inverse-transform sampling (eq. 12), one variate per grain; false: σ0 "
                     "scaled to the grain's size by eq. 13"),
        opt::number("min_piece_fraction", &S::min_piece_fraction, 0, 0.45, "",
                    "the fracture plane is moved along its normal until each side holds at least this fraction of "
                    "the grain (2D: area); 0 = the plane through the contacts as is (our decision, not the paper's)"),
        opt::number("min_piece_diameter", &S::min_piece_diameter, 0, 1, "m",
                    "each side of the fracture plane holds at least the volume (2D: area) of a sphere (disc) of "
                    "this diameter, and a grain of less than twice that is not broken (outcome too_small): Harmon "
                    "et al. 2020 §3.4, first method, breakage halted at a minimum size; 0 = off"),
        opt::number("min_piece_thickness", &S::min_piece_thickness, 0, 1, "m",
                    "each side of the fracture plane reaches at least this far from it along its normal; a grain "
                    "less than twice that thick along the normal is cut across instead (2D: through its centroid, "
                    "perpendicular to the plane) or, when that fails too or in 3D, not broken (outcome too_small): "
                    "min_piece_diameter by thickness, so that a long slab is not cut along its length into strips "
                    "its grid cannot resolve (Harmon et al. 2020 §3.4, first method; ours); 0 = off"),
        opt::choice("plane_fallback", &S::plane_fallback, {"centroid", "shift"},
                    "when the plane through the contacts leaves less than min_piece_fraction on one side: centroid = "
                    "the centroid replaces the weakest point first (Harmon et al. 2020 §3.3 fill-in), the shift only "
                    "if that fails too; shift = only shift the plane"),
    };
  }();
  return t;
}

StressOptions stress_options_from_config(const Config& cfg) {
  StressOptions o;
  read_options(cfg, stress_options(), o);
  if (cfg.has("tensile_strength") && !(stress::find_criterion(o.criterion)->default_tensile_strength > 0))
    cfg.fail("tensile_strength", "only the max_principal criterion has a tensile strength (Harmon et al. 2020, "
                                 "eq. 8); this scenario's criterion is '" + o.criterion + "'");
  return o;
}

// ---------------------------------------------------------------- stress

Mat3 average_stress(const Vec3& centroid, double volume, std::span<const Contact> contacts) {
  require(volume > 0 && std::isfinite(volume), "grain volume must be > 0");
  // Harmon et al. 2020, eq. 5: σ̄ = (1/V) Σ x_c ⊗ F_c, then symmetrised.
  Mat3 s;
  for (const auto& c : contacts) {
    const Vec3 x = c.point - centroid;
    const double xv[3] = {x.x, x.y, x.z}, fv[3] = {c.force.x, c.force.y, c.force.z};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) s(i, j) += xv[i] * fv[j];
  }
  Mat3 sym;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sym(i, j) = 0.5 * (s(i, j) + s(j, i)) / volume;
  return sym;
}

stress::Principal principal_stresses(const Mat3& sigma, int dimension) {
  stress::Principal p{};
  if (dimension == 2) {
    // eq. 6 on the in-plane block; plane stress: the third principal value is 0.
    const PrincipalAxes2 pa = principal_axes_2d(sigma(0, 0), 0.5 * (sigma(0, 1) + sigma(1, 0)), sigma(1, 1));
    p = {pa.values[1], pa.values[0], 0.0};
  } else {
    const PrincipalAxes pa = principal_axes(sigma);  // eq. 6
    p = {pa.moments.z, pa.moments.y, pa.moments.x};
  }
  std::sort(p.begin(), p.end(), [](double a, double b) { return a > b; });
  return p;
}

// ---------------------------------------------------------------- fracture plane

std::optional<CutPlane> fracture_plane(const std::vector<Vec3>& points, const Vec3& strongest_force, int dimension,
                                       double length_scale) {
  require(length_scale > 0 && std::isfinite(length_scale), "length scale must be > 0");
  require(is_finite(strongest_force), "non-finite force");
  for (const auto& p : points) require(is_finite(p), "non-finite contact point");
  require(!points.empty(), "a fracture plane needs at least one contact point");
  const double tol = 1e-6 * length_scale;  // lengths below this are coincident points
  const Vec3 p1 = points.front();
  auto make = [&](Vec3 n) -> std::optional<CutPlane> {
    n = normalized(n);
    const CutPlane c{n, dot(n, p1)};
    if (!is_finite(c.normal) || !std::isfinite(c.offset)) return std::nullopt;
    return c;
  };

  if (dimension == 2) {
    // eq. 18: the line through the two strongest contacts (the centroid fills in).
    Vec3 p2 = points.size() >= 2 ? points[1] : Vec3{};
    Vec3 a{p2.x - p1.x, p2.y - p1.y, 0};
    if (norm(a) <= tol) {  // coincident: the line through p1 along the strongest force
      a = {strongest_force.x, strongest_force.y, 0};
      if (!(norm(a) > 0)) return std::nullopt;
    }
    return make({-a.y, a.x, 0});
  }

  // 3D, eqs. 19–20: the plane through the three strongest contacts (the centroid fills in).
  require(points.size() >= 2, "a 3D fracture plane needs at least two contact points");
  std::vector<Vec3> P(points.begin(), points.begin() + std::min<std::size_t>(3, points.size()));
  if (P.size() < 3) P.push_back(Vec3{});
  const Vec3 n = cross(P[1] - P[0], P[2] - P[0]);
  if (norm(n) > tol * length_scale) return make(n);

  // Collinear or coincident points: their line (the longest chord), or the force.
  Vec3 a;
  for (std::size_t i = 0; i < P.size(); ++i)
    for (std::size_t j = i + 1; j < P.size(); ++j)
      if (norm(P[j] - P[i]) > norm(a)) a = P[j] - P[i];
  const double fn = norm(strongest_force);
  if (norm(a) <= tol) {
    if (!(fn > 0)) return std::nullopt;
    a = strongest_force;
  }
  a = normalized(a);
  // 1. The plane through the line containing the strongest force direction.
  if (fn > 0) {
    const Vec3 m = cross(a, strongest_force / fn);
    if (norm(m) > 1e-6) return make(m);
  }
  // 2. The force along the line (diametral load): a meridian plane of the line, normal to
  //    the body axis least aligned with it.
  const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(dot(axes[i], a)) < std::abs(dot(axes[k], a))) k = i;
  return make(axes[k] - a * dot(axes[k], a));
}

namespace {

// Heights along `normal` of a lattice of cell centres inside the shape (24³ in 3D, 64² in
// 2D, over the shape's bounds), sorted: their quantiles are the offsets that leave a given
// volume fraction on the negative side.
std::vector<double> inside_heights(const Shape& shape, const Vec3& normal) {
  const Aabb b = shape.bounds();
  const bool flat = shape.dimension() == 2;
  const int n = flat ? 64 : 24;
  const Vec3 size = b.hi - b.lo;
  std::vector<double> h;
  h.reserve(static_cast<std::size_t>(n) * n * (flat ? 1 : n));
  for (int k = 0; k < (flat ? 1 : n); ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 p{b.lo.x + size.x * (i + 0.5) / n, b.lo.y + size.y * (j + 0.5) / n,
                     flat ? 0.0 : b.lo.z + size.z * (k + 0.5) / n};
        if (shape.contains(p)) h.push_back(dot(normal, p));
      }
  std::sort(h.begin(), h.end());
  return h;
}

}  // namespace

double smaller_side_fraction(const Shape& shape, const CutPlane& plane) {
  const std::vector<double> h = inside_heights(shape, plane.normal);
  if (h.empty()) return 0;
  const auto below = static_cast<double>(std::lower_bound(h.begin(), h.end(), plane.offset) - h.begin());
  const double f = below / static_cast<double>(h.size());
  return std::min(f, 1 - f);
}

CutPlane clamp_plane_to_interior(const Shape& shape, const CutPlane& plane, double fraction) {
  require(fraction < 0.5, "min_piece_fraction must be < 0.5");
  if (!(fraction > 0)) return plane;
  const std::vector<double> h = inside_heights(shape, plane.normal);
  if (h.size() < 16) return plane;  // too thin to sample: leave the paper's plane alone
  const std::size_t m = h.size();
  const std::size_t q = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(m)));
  const double lo = h[std::min(q, m - 1)], hi = h[m - 1 - std::min(q, m - 1)];
  CutPlane out = plane;
  if (lo <= hi) out.offset = std::clamp(plane.offset, lo, hi);
  return out;
}

std::optional<CutPlane> keep_piece_thickness(const Shape& shape, const CutPlane& plane, double thickness) {
  if (!(thickness > 0)) return plane;
  const std::vector<double> h = inside_heights(shape, plane.normal);
  if (h.empty()) return plane;
  const double lo = h.front() + thickness, hi = h.back() - thickness;
  if (lo > hi) return std::nullopt;
  CutPlane out = plane;
  out.offset = std::clamp(plane.offset, lo, hi);
  return out;
}

// ---------------------------------------------------------------- the model

StressModel::StressModel(StressOptions o, int dimension)
    : o_(std::move(o)), dim_(dimension), entry_(stress::find_criterion(o_.criterion)) {
  require(entry_ != nullptr, "unknown criterion '" + o_.criterion + "'; known: " + joined(stress::criterion_names()));
  require(dim_ == 2 || dim_ == 3, "dimension must be 2 or 3");
  // 0 (the struct's default): the criterion's Table 2 value; then every option in its
  // declared range (stress_options).
  if (o_.strength <= 0) o_.strength = entry_->default_strength;
  if (o_.tensile_strength <= 0) o_.tensile_strength = entry_->default_tensile_strength;
  check_options(stress_options(), o_, "stress");
  criterion_ = entry_->make();
}

std::vector<std::string> StressModel::figure_names() const {
  std::vector<std::string> f{"sigma_1_Pa", "sigma_2_Pa"};
  if (dim_ == 3) f.push_back("sigma_3_Pa");
  f.push_back("equivalent_stress_Pa");
  f.push_back("strength_Pa");
  if (entry_->default_tensile_strength > 0) f.push_back("tensile_strength_Pa");
  f.push_back("plane_through_centroid");
  return f;
}

ScreeningSettings StressModel::default_screening() const {
  ScreeningSettings s;
  s.min_diameter = 0;
  s.force_threshold = false;
  s.max_unbalanced_force_ratio = 0;
  s.max_unbalanced_moment_ratio = 0;
  s.min_contacts = dim_ == 2 ? 1 : 2;
  return s;
}

void StressModel::assign_strength(Grain& g, const Material&, Rng& rng) const {
  require(g.shape != nullptr, "grain without a shape");
  const double d = g.shape->equivalent_diameter();
  // Harmon et al. 2020, eq. 12: σ_c = σ0 (−(d0/d)³ ln(1 − P_f))^(1/m), P_f ~ U(0, 1); one
  // variate per grain. Without Weibull: σ0 at d0, scaled to d by eq. 13.
  const double u = rng.uniform();
  auto sample = [&](double sigma0) {
    if (!o_.weibull) return weibull_size_effect(sigma0, d, o_.reference_diameter, o_.weibull_modulus);
    WeibullParams p;
    p.variant = "weibull";
    p.sigma0 = sigma0;
    p.d0 = o_.reference_diameter;
    p.modulus = o_.weibull_modulus;
    return weibull_sample(p, d, u);
  };
  g.strength.set(stress::kStrength, sample(o_.strength));
  if (entry_->default_tensile_strength > 0) g.strength.set(stress::kTensileStrength, sample(o_.tensile_strength));
}

void StressModel::inherit_strength(const Grain& parent, Grain& child, const Material&, Rng&) const {
  require(parent.shape && child.shape, "grain without a shape");
  const double dp = parent.shape->equivalent_diameter(), dc = child.shape->equivalent_diameter();
  // Harmon et al. 2020, eq. 13: σ_a / σ_b = (d_a / d_b)^(−3/m).
  for (const char* key : {stress::kStrength, stress::kTensileStrength}) {
    if (!parent.strength.has(key)) continue;
    child.strength.set(key, weibull_size_effect(parent.strength.get(key), dc, dp, o_.weibull_modulus));
  }
  require(child.strength.has(stress::kStrength), "parent grain has no strength_Pa (assign_strength not called?)");
}

double StressModel::load_measure(const Grain& g, const Material&, std::span<const Contact> contacts) const {
  std::vector<Contact> loaded;
  for (const auto& c : contacts)
    if (is_finite(c.point) && is_finite(c.force) && norm2(c.force) > 0) loaded.push_back(c);
  if (loaded.empty() || !g.shape || !is_finite(g.position)) return 0;
  const double eq = criterion_->equivalent_stress(principal_stresses(average_stress(g.position, g.shape->volume(), loaded), dim_));
  return std::isfinite(eq) ? eq : 0;
}

BreakageAnalysis StressModel::analyse(const Grain& g, const Material&, std::span<const Contact> contacts) const {
  const auto t0 = Clock::now();
  BreakageAnalysis a;
  auto finish = [&](const std::string& outcome) {
    a.outcome = outcome;
    a.wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return a;
  };
  require(g.shape != nullptr, "grain " + std::to_string(g.id) + " has no shape");
  require(g.shape->dimension() == dim_, "grain " + std::to_string(g.id) + " is not " + std::to_string(dim_) + "D");
  require(g.strength.has(stress::kStrength),
          "grain " + std::to_string(g.id) + " has no strength_Pa (assign_strength not called?)");
  require(is_finite(g.position) && std::isfinite(g.orientation.w) && std::isfinite(g.orientation.x) &&
              std::isfinite(g.orientation.y) && std::isfinite(g.orientation.z),
          "grain " + std::to_string(g.id) + " has a non-finite pose");

  std::vector<Contact> loaded;
  for (const auto& c : contacts) {
    require(is_finite(c.point) && is_finite(c.force),
            "non-finite contact point or force on grain " + std::to_string(g.id));
    if (norm2(c.force) == 0) continue;
    loaded.push_back(c);
    a.load = std::max(a.load, norm(c.force));
  }

  const Mat3 sigma = average_stress(g.position, g.shape->volume(), loaded);
  const stress::Principal p = principal_stresses(sigma, dim_);
  const double eq = criterion_->equivalent_stress(p);
  a.set_figure("sigma_1_Pa", p[0]);
  a.set_figure("sigma_2_Pa", p[1]);
  if (dim_ == 3) a.set_figure("sigma_3_Pa", p[2]);
  a.set_figure("equivalent_stress_Pa", eq);
  a.set_figure("strength_Pa", g.strength.get(stress::kStrength));
  if (entry_->default_tensile_strength > 0)
    a.set_figure("tensile_strength_Pa", g.strength.get_or(stress::kTensileStrength, 0));
  if (loaded.empty()) return finish("no_load");
  if (!criterion_->fails(p, g.strength)) return finish("intact");

  const std::vector<const Contact*> order = strongest_first(loaded);
  if (dim_ == 3 && order.size() < 2) return finish("single_contact");  // held off until a second contact

  const double fraction = piece_fraction(*g.shape);
  if (fraction >= 0.5) return finish("too_small");
  const std::size_t need = dim_ == 3 ? 3 : 2;
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < order.size() && i < need; ++i) pts.push_back(g.to_local(order[i]->point));
  const Vec3 f_body = g.orientation.conjugate().rotate(order.front()->force);
  const auto plane = fracture_plane(pts, f_body, dim_, g.shape->equivalent_diameter());
  if (!plane) return finish("degenerate_contacts");
  bool centroid_fallback = false;
  const auto cut = place_plane(*g.shape, *plane, pts, f_body, fraction, centroid_fallback);
  a.set_figure("plane_through_centroid", centroid_fallback ? 1.0 : 0.0);
  if (!cut) return finish("too_small");
  a.broken = true;
  a.fracture = CuttingSurfaces{{*cut}};
  return finish("split");
}

// The strongest first of §3.3's points, one per contact partner (the point of its strongest
// contact).
std::vector<const Contact*> StressModel::strongest_first(const std::vector<Contact>& loaded) {
  std::map<long, const Contact*> strongest;
  for (const auto& c : loaded) {
    const long key = c.is_wall() ? -2 - static_cast<long>(c.wall) : static_cast<long>(c.b);
    auto it = strongest.find(key);
    if (it == strongest.end() || norm2(c.force) > norm2(it->second->force)) strongest[key] = &c;
  }
  std::vector<const Contact*> order;
  for (const auto& [k, c] : strongest) order.push_back(c);
  std::stable_sort(order.begin(), order.end(),
                   [](const Contact* x, const Contact* y) { return norm2(x->force) > norm2(y->force); });
  return order;
}

// The cut of a failed grain from the plane through its contacts; std::nullopt when the grain
// cannot give two pieces of the minimum size (too_small).
std::optional<CutPlane> StressModel::place_plane(const Shape& shape, CutPlane plane, const std::vector<Vec3>& pts,
                                                 const Vec3& f_body, double fraction, bool& centroid_fallback) const {
  // The strongest contacts along one face (a flat grain wedged by its two corners, three
  // contacts around one pole) put the plane through the contacts (eqs. 18–20) along the
  // surface: it would shave a sliver. The centroid then takes the weakest point's place,
  // as §3.3 lets it fill in for a missing contact (our reading; plane_fallback "centroid").
  // Only if that fails too is the plane shifted (min_piece_fraction, below).
  const std::size_t need = dim_ == 3 ? 3 : 2;
  if (o_.plane_fallback == "centroid" && fraction > 0 && pts.size() == need &&
      smaller_side_fraction(shape, plane) < fraction) {
    const std::vector<Vec3> fewer(pts.begin(), pts.end() - 1);
    const auto alt = fracture_plane(fewer, f_body, dim_, shape.equivalent_diameter());
    if (alt && smaller_side_fraction(shape, *alt) >= fraction) {
      plane = *alt;
      centroid_fallback = true;
    }
  }
  // §3.3 fixes the plane's orientation by the contacts (eqs. 18–20); its offset is kept
  // inside the grain so that both pieces are meaningful (StressOptions::min_piece_fraction,
  // min_piece_diameter, min_piece_thickness).
  const double t = o_.min_piece_thickness;
  auto cut = keep_piece_thickness(shape, clamp_plane_to_interior(shape, plane, fraction), t);
  if (cut || dim_ != 2) return cut;
  // 2D, a grain thinner than 2t along the normal (a slab loaded at its two ends, which the
  // plane through the contacts would split along its length): cut across it instead, through
  // its centroid (the body origin) perpendicular to that plane (ours).
  const CutPlane across{{-plane.normal.y, plane.normal.x, 0}, 0.0};
  return keep_piece_thickness(shape, clamp_plane_to_interior(shape, across, fraction), t);
}

double StressModel::piece_fraction(const Shape& g) const {
  const double d = o_.min_piece_diameter;
  const double vmin = dim_ == 3 ? kPi * d * d * d / 6 : kPi * d * d / 4;
  return std::max(o_.min_piece_fraction, vmin / g.volume());
}

std::unique_ptr<BreakageModel> make_stress(const Config& cfg, const EngineContext& ctx) {
  StressOptions o = stress_options_from_config(cfg);
  try {
    return std::make_unique<StressModel>(std::move(o), ctx.dimension);
  } catch (const std::invalid_argument& e) {
    cfg.fail("", e.what());
  }
}

}  // namespace crumble
