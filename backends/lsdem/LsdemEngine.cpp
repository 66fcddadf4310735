#include "backends/lsdem/LsdemEngine.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <ctime>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/Rng.h"
#include "geometry/MeshDistance.h"

namespace crumble {

// ---- Per-shape data, shared by every grain of the shape ----
struct LsdemEngine::ShapeData {
  // Sphere tree over the nodes (median splits); leaves hold at most kLeaf nodes.
  struct Cluster {
    Vec3 c;
    double r;
    int begin, end;   // node range
    int left, right;  // children (-1: leaf)
  };
  Shape::Ptr shape;
  std::shared_ptr<const LevelSetGrid> grid;
  std::vector<Vec3> nodes;  // body frame, in cluster order
  std::vector<double> w;    // area (2D: length) per node
  std::vector<Cluster> clusters;
  double radius = 0;  // bounding sphere of the zero level (max |node| + h)
  Aabb box;           // nodes' box + h (body frame)
  double r_eq = 0;
  int users = 0;
};

struct LsdemEngine::Body {
  GrainId id = -1;
  ShapeData* sd = nullptr;
  int material = 0;
  Vec3 x, v, w;  // centroid, velocity (half step), angular velocity (world, half step)
  Quat q;
  Mat3 R;
  double m = 0, im = 0;
  Mat3 Ib, iIb;  // body-frame inertia and inverse (3D); 2D uses Ib(2,2)
  // Selective mass scaling: the mass before it (density-scaled: weight is md / mass_scale)
  // and its factor (m = md·sel, Ib likewise).
  double md = 0, sel = 1;
  Mat3 Ibd;
  Vec3 f, t;
  double moved = 0, turned = 0;  // |v|·dt and |ω|·dt of the last step
};

struct LsdemEngine::Item {
  int a = -1, b = -1;  // body indices; b < 0: wall index −1 − k
  std::pair<GrainId, GrainId> key;
  bool shape_wall = false;  // b indexes walls_kin_ instead of bodies_
  PairState* st = nullptr;  // persistent state of the key (pointer-stable)
  bool fresh = true;         // no state from the previous step
  Vec3 fa, ta, tb;
  Vec3 point, normal;
  double fsum = 0;
  double overlap = 0;  // deepest node penetration (m)
  double elastic = 0;  // energy in the normal spring (J; 2D: J/m)
  bool contact = false;
  long queries = 0, pen = 0, tree_queries = 0;
};

namespace {

using Clock = std::chrono::steady_clock;

Mat3 inverse(const Mat3& a) {
  Mat3 r;
  r(0, 0) = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
  r(0, 1) = a(0, 2) * a(2, 1) - a(0, 1) * a(2, 2);
  r(0, 2) = a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1);
  r(1, 0) = a(1, 2) * a(2, 0) - a(1, 0) * a(2, 2);
  r(1, 1) = a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0);
  r(1, 2) = a(0, 2) * a(1, 0) - a(0, 0) * a(1, 2);
  r(2, 0) = a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0);
  r(2, 1) = a(0, 1) * a(2, 0) - a(0, 0) * a(2, 1);
  r(2, 2) = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
  const double det = a(0, 0) * r(0, 0) + a(0, 1) * r(1, 0) + a(0, 2) * r(2, 0);
  if (!(std::abs(det) > 0)) throw std::invalid_argument("lsdem: singular inertia tensor");
  return r * (1.0 / det);
}

// Recursive median split of the nodes into a sphere tree (deterministic). Fills `tree` in
// depth-first order and the node permutation `idx`; returns the index of the subtree root.
constexpr int kLeaf = 16;
template <class Cluster>
int split(std::vector<int>& idx, int lo, int hi, const std::vector<Vec3>& p, std::vector<Cluster>& tree) {
  Aabb b;
  for (int i = lo; i < hi; ++i) b.extend(p[idx[i]]);
  Cluster c{b.center(), 0, lo, hi, -1, -1};
  for (int i = lo; i < hi; ++i) c.r = std::max(c.r, norm(p[idx[i]] - c.c));
  const int me = static_cast<int>(tree.size());
  tree.push_back(c);
  if (hi - lo <= kLeaf) return me;
  const Vec3 e = b.size();
  const int ax = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
  const int mid = (lo + hi) / 2;
  std::nth_element(idx.begin() + lo, idx.begin() + mid, idx.begin() + hi, [&](int a, int d) {
    return p[a][ax] < p[d][ax] || (p[a][ax] == p[d][ax] && a < d);
  });
  const int l = split(idx, lo, mid, p, tree);
  const int r = split(idx, mid, hi, p, tree);
  tree[me].left = l;
  tree[me].right = r;
  return me;
}

struct PenNode {
  int node;
  double p;
  Vec3 n;  // unit normal, world, from the partner towards the master
  Vec3 c;  // contact point (world): node moved half the penetration out
  double w;
};

struct Law {
  bool hertz = false;
  double kn = 0;      // linear
  double khertz = 0;  // (4/3) E* √R*
  double ks_ratio = 0;
  double zeta = 0;
  double mu = 0;
  double mstar = 0;
};

}  // namespace

// ---- Construction and grain management ----

LsdemEngine::LsdemEngine(LsdemSettings s, EngineContext ctx) : s_(std::move(s)), ctx_(std::move(ctx)) {
  if (ctx_.dimension != 2 && ctx_.dimension != 3) throw std::invalid_argument("lsdem: dimension must be 2 or 3");
  // Every option in its declared range (lsdem_options), then what spans several.
  check_options(lsdem_options(), s_, "lsdem");
  if (s_.contact_law == "hertz" && ctx_.dimension == 2)
    throw std::invalid_argument("lsdem: the hertz contact law is 3D only (2D contacts of cylinders are not Hertzian)");
  if (ctx_.materials.empty()) throw std::invalid_argument("lsdem: no material");
  for (const auto& m : ctx_.materials)
    if (!(m.density > 0) || !(m.friction >= 0) || !(m.wall_friction >= 0) ||
        (s_.contact_law == "hertz" && (!(m.young > 0) || !(m.poisson > -1 && m.poisson < 0.5))))
      throw std::invalid_argument("lsdem: a material has a non-positive density, negative friction or (hertz) a bad "
                                  "Young's modulus / Poisson ratio");
  if (s_.threads < 1) s_.threads = 1;
  if (s_.wall_kn == 0) s_.wall_kn = s_.kn;
  if (s_.selective_dt > 0 && s_.selective_dt_fraction > 0)
    throw std::invalid_argument("lsdem: give selective_dt or selective_dt_fraction, not both");
  if (s_.kn_reference_radius > 0 && s_.contact_law == "hertz")
    throw std::invalid_argument("lsdem: kn_reference_radius is for the linear law (the hertz law's stiffness already follows √R*)");
  target_dt_ = s_.selective_dt;
}

LsdemEngine::~LsdemEngine() = default;

std::size_t LsdemEngine::grain_count() const { return bodies_.size(); }

void LsdemEngine::set_container(const Container& c) {
  if (!(c.lx >= 0) || !(c.ly >= 0) || !(c.height >= 0) || !(c.platen_mass >= 0))
    throw std::invalid_argument("lsdem: container sizes and platen mass must be >= 0");
  container_ = c;
  has_container_ = true;
  platen_.reset(c.height);
}

// A shape's level set as this engine collides it. With sphere_representation "polyhedron" a
// sphere is the hull of its mesh, sampled on the sphere's own grid (same frame, same spacing),
// so that the faceted grains a polyhedral engine settled keep their contacts here.
std::shared_ptr<const LevelSetGrid> LsdemEngine::grid_of(const Shape& s) const {
  if (s_.exact_spheres || s.kind() != ShapeKind::Sphere || ctx_.dimension != 3) return s.level_set_ptr();
  const auto sphere = s.level_set_ptr();
  const MeshDistance hull(s.convex_hull());
  LevelSetOptions opt;
  opt.target_nodes = s.resolution().surface_nodes;
  opt.name = "shape " + s.describe() + " as its hull";
  return LevelSetGrid::sample(3, s.bounds(), sphere->spacing(), [&](const Vec3& p) { return hull.signed_distance(p); },
                              opt);
}

LsdemEngine::ShapeData& LsdemEngine::shape_data(const Shape::Ptr& s) {
  auto it = shapes_.find(s.get());
  if (it != shapes_.end()) return *it->second;
  auto d = std::make_shared<ShapeData>();
  d->shape = s;
  d->grid = grid_of(*s);
  const auto& gn = d->grid->nodes();
  const auto& gw = d->grid->node_weights();
  std::vector<int> idx(gn.size());
  std::iota(idx.begin(), idx.end(), 0);
  if (!gn.empty()) split(idx, 0, static_cast<int>(idx.size()), gn, d->clusters);
  const double h = d->grid->spacing();
  for (int i : idx) {
    d->nodes.push_back(gn[i]);
    d->w.push_back(gw[i]);
  }
  for (const auto& p : d->nodes) {
    d->radius = std::max(d->radius, norm(p));
    d->box.extend(p);
  }
  d->radius += h;
  d->box.lo -= Vec3{h, h, ctx_.dimension == 3 ? h : 0.0};
  d->box.hi += Vec3{h, h, ctx_.dimension == 3 ? h : 0.0};
  d->r_eq = 0.5 * s->equivalent_diameter();
  return *(shapes_[s.get()] = d);
}

void LsdemEngine::add_grain(const Grain& g) {
  if (!g.shape) throw std::invalid_argument("lsdem: grain " + std::to_string(g.id) + " has no shape");
  if (g.shape->dimension() != ctx_.dimension)
    throw std::invalid_argument("lsdem: grain " + std::to_string(g.id) + " shape " + g.shape->describe() + " is " +
                                std::to_string(g.shape->dimension()) + "D but the engine is " +
                                std::to_string(ctx_.dimension) + "D");
  if (g.material < 0 || g.material >= static_cast<int>(ctx_.materials.size()))
    throw std::invalid_argument("lsdem: grain " + std::to_string(g.id) + " has material index " +
                                std::to_string(g.material) + " out of range");
  if (index_.count(g.id)) throw std::invalid_argument("lsdem: grain id " + std::to_string(g.id) + " added twice");
  if (!is_finite(g.position) || !is_finite(g.velocity) || !is_finite(g.angular_velocity))
    throw std::invalid_argument("lsdem: grain " + std::to_string(g.id) + " has a non-finite state");
  ShapeData& sd = shape_data(g.shape);
  Body b;
  b.id = g.id;
  b.sd = &sd;
  b.sd->users++;
  b.material = g.material;
  const double rho = ctx_.materials[g.material].density;
  // Density scaling for quasi-static runs (Zhu & Zhao 2019 §5 scales masses by 70): mass and
  // inertia grow, the weight does not (gravity acts on the unscaled mass).
  b.m = rho * g.shape->volume() * s_.mass_scale;
  b.im = 1.0 / b.m;
  b.Ib = g.shape->mass_properties().inertia * (rho * s_.mass_scale);
  b.md = b.m;
  b.Ibd = b.Ib;
  b.x = g.position;
  b.v = g.velocity;
  b.w = g.angular_velocity;
  b.q = g.orientation.normalized();
  if (ctx_.dimension == 2) {
    // Motion in x–y, rotation about z only.
    b.x.z = 0;
    b.v.z = 0;
    b.w = {0, 0, b.w.z};
    const double c = b.q.w, sz = b.q.z;
    const double n = std::hypot(c, sz);
    b.q = n > 0 ? Quat{c / n, 0, 0, sz / n} : Quat{};
    if (!(b.Ib(2, 2) > 0)) throw std::invalid_argument("lsdem: 2D grain with no polar moment");
  } else {
    b.iIb = inverse(b.Ib);
  }
  b.R = b.q.matrix();
  index_[b.id] = bodies_.size();
  bodies_.push_back(b);
  near_valid_ = false;
  // After the push: a hertz stiffness bound depends on the grains present.
  if (target_dt_ > 0) apply_selective_scaling(bodies_.back());
}

void LsdemEngine::remove_grain(GrainId id) {
  auto it = index_.find(id);
  if (it == index_.end()) throw std::invalid_argument("lsdem: remove_grain of unknown grain " + std::to_string(id));
  const std::size_t k = it->second;
  ShapeData* sd = bodies_[k].sd;
  bodies_.erase(bodies_.begin() + static_cast<long>(k));
  index_.clear();
  for (std::size_t i = 0; i < bodies_.size(); ++i) index_[bodies_[i].id] = i;
  if (--sd->users == 0) shapes_.erase(sd->shape.get());
  // Its pair states go now (a grain added later under the same id starts afresh).
  for (auto* m : {&history_, &wall_history_})
    for (auto h = m->begin(); h != m->end();) h = h->first.first == id || h->first.second == id ? m->erase(h) : std::next(h);
  near_valid_ = false;  // body indices moved, states went
}

int LsdemEngine::add_shape_wall(const Shape::Ptr& shape, const Vec3& position, const Quat& orientation) {
  if (!shape) throw std::invalid_argument("lsdem: shape wall without a shape");
  if (shape->dimension() != ctx_.dimension)
    throw std::invalid_argument("lsdem: shape wall " + shape->describe() + " is " +
                                std::to_string(shape->dimension()) + "D but the engine is " +
                                std::to_string(ctx_.dimension) + "D");
  if (!is_finite(position)) throw std::invalid_argument("lsdem: shape wall position is not finite");
  ShapeData& sd = shape_data(shape);
  sd.users++;
  Body b;
  b.id = -1 - (kFirstShapeWall + static_cast<GrainId>(walls_kin_.size()));
  b.sd = &sd;
  b.x = position;
  b.q = orientation.normalized();
  if (ctx_.dimension == 2) {
    b.x.z = 0;
    const double n = std::hypot(b.q.w, b.q.z);
    b.q = Quat{b.q.w / n, 0, 0, b.q.z / n};
  }
  b.R = b.q.matrix();
  walls_kin_.push_back(b);
  shape_wall_force_.push_back({});
  return static_cast<int>(walls_kin_.size()) - 1;
}

void LsdemEngine::set_shape_wall_motion(int wall, const Vec3& v, const Vec3& w) {
  if (wall < 0 || wall >= static_cast<int>(walls_kin_.size()))
    throw std::invalid_argument("lsdem: no shape wall " + std::to_string(wall));
  if (!is_finite(v) || !is_finite(w)) throw std::invalid_argument("lsdem: shape wall motion is not finite");
  Body& b = walls_kin_[wall];
  b.v = v;
  b.w = w;
  if (ctx_.dimension == 2) {
    b.v.z = 0;
    b.w = {0, 0, w.z};
  }
}

int LsdemEngine::add_moving_wall(const MovingWall& w) {
  return add_shape_wall(w.shape, w.position, w.orientation);
}

void LsdemEngine::set_moving_wall(int wall, const WallKinematics& k) {
  if (wall < 0 || wall >= static_cast<int>(walls_kin_.size()))
    throw std::invalid_argument("lsdem: no moving wall " + std::to_string(wall));
  if (!is_finite(k.position)) throw std::invalid_argument("lsdem: moving wall position is not finite");
  set_shape_wall_motion(wall, k.velocity, k.angular_velocity);
  Body& b = walls_kin_[wall];
  b.x = k.position;
  b.q = k.orientation.normalized();
  if (ctx_.dimension == 2) {
    b.x.z = 0;
    const double n = std::hypot(b.q.w, b.q.z);
    b.q = Quat{b.q.w / n, 0, 0, b.q.z / n};
  }
  b.R = b.q.matrix();
}

Vec3 LsdemEngine::shape_wall_position(int wall) const { return walls_kin_.at(wall).x; }
Quat LsdemEngine::shape_wall_orientation(int wall) const { return walls_kin_.at(wall).q; }
Vec3 LsdemEngine::shape_wall_force(int wall) const { return shape_wall_force_.at(wall); }

void LsdemEngine::read_state(std::span<Grain> grains) const {
  for (auto& g : grains) {
    auto it = index_.find(g.id);
    if (it == index_.end()) continue;
    const Body& b = bodies_[it->second];
    g.position = b.x;
    g.orientation = b.q;
    g.velocity = b.v;
    g.angular_velocity = b.w;
  }
}

double LsdemEngine::kinetic_energy() const {
  double e = 0;
  for (const auto& b : bodies_) {
    e += 0.5 * b.m * norm2(b.v);
    if (ctx_.dimension == 2) {
      e += 0.5 * b.Ib(2, 2) * b.w.z * b.w.z;
    } else {
      const Vec3 wb = b.R.transposed() * b.w;
      e += 0.5 * dot(wb, b.Ib * wb);
    }
  }
  return e;
}

// Twice the highest contact frequency √(k/m_min) (max_stable_dt = dt_safety·√(m_min/k)): every
// grain is overdamped, and c·Δt ≤ 2·dt_safety keeps the explicit update stable.
bool LsdemEngine::set_relaxation_damping(bool on) {
  const double dt = max_stable_dt();
  relax_damping_ = on && std::isfinite(dt) ? 2 * s_.dt_safety / dt : 0;
  return true;
}

double LsdemEngine::stiffness_bound() const {
  if (s_.contact_law != "hertz") return std::max(s_.kn, s_.wall_kn);
  // Tangent stiffness dF/dδ = 2 E* √(R* δ) at δ_ref, with the stiffest E* (grain on a
  // rigid wall) and the largest R* (R* = R for a wall).
  double rmin = std::numeric_limits<double>::infinity(), rmax = 0;
  for (const auto& b : bodies_) {
    rmin = std::min(rmin, b.sd->r_eq);
    rmax = std::max(rmax, b.sd->r_eq);
  }
  double estar = 0;
  for (const auto& m : ctx_.materials) estar = std::max(estar, m.young / (1 - m.poisson * m.poisson));
  return 2 * estar * std::sqrt(rmax * s_.hertz_reference_overlap * rmin);
}

double LsdemEngine::max_stable_dt() const { return stable_dt(false); }

double LsdemEngine::unscaled_stable_dt() const { return stable_dt(true); }

double LsdemEngine::stable_dt(bool unscaled) const {
  if (bodies_.empty()) return std::numeric_limits<double>::infinity();
  if (s_.kn_reference_radius > 0) {
    // Every contact of a grain is at most as stiff as k·R/R_ref (R the grain's radius): its
    // own step is dt_safety·√(m·R_ref/(k·R)), and the stable step the smallest of them.
    double q = std::numeric_limits<double>::infinity();
    for (const auto& b : bodies_) q = std::min(q, (unscaled ? b.md : b.m) / b.sd->r_eq);
    return s_.dt_safety * std::sqrt(q * s_.kn_reference_radius / stiffness_bound());
  }
  double mmin = std::numeric_limits<double>::infinity();
  for (const auto& b : bodies_) mmin = std::min(mmin, unscaled ? b.md : b.m);
  return s_.dt_safety * std::sqrt(mmin / stiffness_bound());
}

void LsdemEngine::apply_selective_scaling(Body& b) const {
  // Own step dt_safety·√(m/k) = target at m = k·(target/dt_safety)² (k of its own contacts).
  double k = stiffness_bound();
  if (s_.kn_reference_radius > 0) k *= b.sd->r_eq / s_.kn_reference_radius;
  const double need = k * (target_dt_ / s_.dt_safety) * (target_dt_ / s_.dt_safety);
  set_selective_factor(b, target_dt_ > 0 && b.md < need ? need / b.md : 1.0);
}

void LsdemEngine::set_selective_factor(Body& b, double sel) const {
  if (sel == b.sel) return;
  b.sel = sel;
  b.m = sel == 1 ? b.md : b.md * sel;
  b.im = 1.0 / b.m;
  b.Ib = sel == 1 ? b.Ibd : b.Ibd * sel;
  if (ctx_.dimension == 3) b.iIb = inverse(b.Ib);
}

void LsdemEngine::fix_selective_target() {
  if (target_dt_ > 0 || bodies_.empty()) return;
  target_dt_ = s_.selective_dt_fraction * unscaled_stable_dt();
  for (auto& b : bodies_) apply_selective_scaling(b);
}

std::map<std::string, double> LsdemEngine::summary_figures() const {
  if (!(s_.selective_dt > 0) && !(s_.selective_dt_fraction > 0)) return {};
  double added = 0, total = 0, smax = 1;
  long scaled = 0;
  for (const auto& b : bodies_) {
    const double m = b.md / s_.mass_scale;  // true mass
    total += m;
    added += (b.sel - 1) * m;
    smax = std::max(smax, b.sel);
    scaled += b.sel > 1 ? 1 : 0;
  }
  return {{"selective_scaling_target_dt_s", target_dt_},
          {"selective_scaling_added_mass_kg", added},
          {"selective_scaling_added_mass_fraction", total > 0 ? added / total : 0.0},
          {"selective_scaling_max_factor", smax},
          {"selective_scaling_grains_scaled", static_cast<double>(scaled)}};
}

double LsdemEngine::added_kinetic_energy() const {
  double e = 0;
  for (const auto& b : bodies_) {
    if (!(b.sel > 1)) continue;
    // ½(s − 1)·m_true·(v² + ω·Î·ω), Î the inertia per unit mass of the scaled body.
    const double w = (b.sel - 1) * b.md / (s_.mass_scale * b.m);
    double rot;
    if (ctx_.dimension == 2) {
      rot = b.Ib(2, 2) * b.w.z * b.w.z;
    } else {
      const Vec3 wb = b.R.transposed() * b.w;
      rot = dot(wb, b.Ib * wb);
    }
    e += 0.5 * w * (b.m * norm2(b.v) + rot);
  }
  return e;
}

std::vector<LsdemEngine::Wall> LsdemEngine::walls() const {
  if (!has_container_ || container_.open) return {};  // open scenes: moving walls only
  return container_planes(container_, ctx_.dimension, platen_.position(), platen_.velocity());
}

// ---- One step ----

void LsdemEngine::step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("lsdem: time step must be > 0");
  const auto t0 = Clock::now();
  if (!(target_dt_ > 0) && s_.selective_dt_fraction > 0) fix_selective_target();
  compute_forces(dt);
  integrate(dt);
  stats_.steps++;
  stats_.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
}

namespace {

// Turns the penetrating nodes of one contact into node forces (see the header): fills the
// item's force/torque sums, contact summary and new tangential history.
template <class Item, class Body, class Hist>
void patch_forces(std::vector<PenNode>& P, const Law& L, const Body& A, const Body* B, const Vec3& wall_vel,
                  double dt, const std::vector<Hist>* old, std::vector<Hist>& hist_out, Item& out) {
  double S = 0, delta = 0;
  for (const auto& n : P) {
    S += n.p * n.w;
    delta = std::max(delta, n.p);
  }
  if (!(S > 0)) return;
  double Fn, k;
  if (L.hertz) {
    Fn = L.khertz * delta * std::sqrt(delta);
    k = 1.5 * L.khertz * std::sqrt(delta);
  } else {
    Fn = L.kn * delta;
    k = L.kn;
  }
  auto vel = [&](const Vec3& c) {
    Vec3 v = A.v + cross(A.w, c - A.x);
    if (B) v -= B->v + cross(B->w, c - B->x);
    else v -= wall_vel;
    return v;
  };
  // Mean normal and normal relative velocity, weighted by the node shares α_i.
  Vec3 nsum;
  double vn = 0;
  for (const auto& n : P) {
    const double a = n.p * n.w / S;
    nsum += n.n * a;
    vn += a * dot(vel(n.c), n.n);
  }
  const double Fd = -2 * L.zeta * std::sqrt(L.mstar * k) * vn;
  const double Ft = std::max(0.0, Fn + Fd);
  // Spread so that the vector sum of the normal forces has magnitude Ft.
  const double scale = Ft / std::max(norm(nsum), 0.5);
  const double ks = L.ks_ratio * k;
  const double cdamp_t = 2 * L.zeta * std::sqrt(L.mstar * ks);
  std::size_t o = 0;
  hist_out.clear();
  for (const auto& n : P) {
    const double a = n.p * n.w / S;
    const double fn = scale * a;
    Vec3 ft;
    if (old) {
      while (o < old->size() && (*old)[o].node < n.node) ++o;
      if (o < old->size() && (*old)[o].node == n.node) {
        // Rotate the stored force into the new tangent plane, keeping its magnitude.
        const Vec3 f0 = (*old)[o].ft;
        ft = f0 - n.n * dot(f0, n.n);
        const double l0 = norm(f0), l1 = norm(ft);
        if (l1 > 0) ft *= l0 / l1;
      }
    }
    const Vec3 v = vel(n.c);
    const Vec3 vt = v - n.n * dot(v, n.n);
    ft -= vt * (ks * a * dt);
    // Tangential viscous damping (same ζ), not stored in the spring; Coulomb caps the sum,
    // and while sliding the spring holds the capped force.
    Vec3 tt = ft - vt * (cdamp_t * a);
    const double cap = L.mu * fn, l = norm(tt);
    if (l > cap) {
      tt = l > 0 ? tt * (cap / l) : Vec3{};
      ft = tt;
    }
    hist_out.push_back({n.node, ft});
    const Vec3 f = n.n * fn + tt;
    out.fa += f;
    out.ta += cross(n.c - A.x, f);
    if (B) out.tb -= cross(n.c - B->x, f);
    const double fl = norm(f);
    out.point += n.c * fl;
    out.fsum += fl;
    out.normal += n.n * fn;
  }
  out.overlap = delta;
  // The normal spring's energy, ∫F_n dδ: ½·k_n·δ² (linear), (2/5)·k·δ^(5/2) (Hertz).
  out.elastic = (L.hertz ? 0.4 : 0.5) * Fn * delta;
  out.contact = true;
}

}  // namespace

void LsdemEngine::build_near() {
  // Bounding spheres hashed into a uniform grid of cells of the largest diameter plus the
  // skin (counting sort); each body's partners sorted, so the list's order — and with it the
  // order of the force sums — depends on the bodies' order only, not on when it was built.
  const int dim = ctx_.dimension;
  const std::size_t nb = bodies_.size();
  near_.clear();
  near_x0_.resize(nb);
  for (std::size_t i = 0; i < nb; ++i) near_x0_[i] = bodies_[i].x;
  near_valid_ = true;
  ++stats_.pair_list_builds;
  if (nb < 2) return;
  double rmax = 0;
  Aabb dom;
  for (const auto& b : bodies_) {
    rmax = std::max(rmax, b.sd->radius);
    dom.extend(b.x);
  }
  near_skin_ = s_.pair_list_skin * rmax;
  double cs = 2 * rmax + near_skin_;
  std::array<long, 3> nc{1, 1, 1};
  for (;;) {
    double cells = 1;
    for (int a = 0; a < dim; ++a) {
      nc[a] = static_cast<long>(std::floor((dom.hi[a] - dom.lo[a]) / cs)) + 1;
      cells *= nc[a];
    }
    if (cells <= 8.0 * nb + 4096) break;
    cs *= 1.5;  // grains spread far apart: coarser cells keep the table small
  }
  auto coord = [&](const Vec3& x, int a) { return std::min(nc[a] - 1, static_cast<long>((x[a] - dom.lo[a]) / cs)); };
  const std::size_t ncell = static_cast<std::size_t>(nc[0] * nc[1] * nc[2]);
  std::vector<std::size_t> cell(nb), start(ncell + 1, 0), sorted(nb);
  for (std::size_t i = 0; i < nb; ++i) {
    const Vec3& x = bodies_[i].x;
    cell[i] = static_cast<std::size_t>(coord(x, 0) + nc[0] * (coord(x, 1) + nc[1] * (dim == 3 ? coord(x, 2) : 0)));
    ++start[cell[i] + 1];
  }
  for (std::size_t c = 0; c < ncell; ++c) start[c + 1] += start[c];
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < nb; ++i) sorted[fill[cell[i]]++] = i;
  }
  for (std::size_t i = 0; i < nb; ++i) {
    const Body& A = bodies_[i];
    const std::size_t first = near_.size();
    const long cx = coord(A.x, 0), cy = coord(A.x, 1), cz = dim == 3 ? coord(A.x, 2) : 0;
    for (long dz = (dim == 3 ? -1 : 0); dz <= (dim == 3 ? 1 : 0); ++dz)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dx = -1; dx <= 1; ++dx) {
          const long x = cx + dx, y = cy + dy, z = cz + dz;
          if (x < 0 || y < 0 || z < 0 || x >= nc[0] || y >= nc[1] || z >= nc[2]) continue;
          const std::size_t c = static_cast<std::size_t>(x + nc[0] * (y + nc[1] * z));
          for (std::size_t k = start[c]; k < start[c + 1]; ++k) {
            const std::size_t j = sorted[k];
            if (j <= i) continue;
            const Body& B = bodies_[j];
            const double rr = A.sd->radius + B.sd->radius;
            if (norm2(A.x - B.x) > (rr + near_skin_) * (rr + near_skin_)) continue;
            // Master: the smaller grain (its nodes are looked up in the other's level set).
            const double va = A.sd->shape->volume(), vb = B.sd->shape->volume();
            const bool i_master = va < vb || (va == vb && A.id < B.id);
            NearPair e;
            e.i = static_cast<int>(i);
            e.j = static_cast<int>(j);
            e.a = i_master ? e.i : e.j;
            e.b = i_master ? e.j : e.i;
            e.rr = rr;
            e.key = {bodies_[e.a].id, bodies_[e.b].id};
            e.st = nullptr;
            near_.push_back(e);
          }
        }
    std::sort(near_.begin() + static_cast<long>(first), near_.end(),
              [](const NearPair& a, const NearPair& b) { return a.j < b.j; });
  }
  // Pair states that live on (found again by key; the map's nodes never move).
  if (!history_.empty())
    for (auto& e : near_) {
      auto h = history_.find(e.key);
      if (h != history_.end()) e.st = &h->second;
    }
}

namespace {

// The master A seen from the partner B: A's nodes in B's body frame, y = Rab·x + tab.
struct PairView {
  const LsdemEngine::Body& A;
  const LsdemEngine::Body& B;
  const LsdemEngine::ShapeData& sa;
  const LsdemEngine::ShapeData& sb;
  const LevelSetGrid& gb;
  Mat3 Rab;
  Vec3 tab;
  double skin;  // half a cell of B's grid
  PairView(const LsdemEngine::Body& a, const LsdemEngine::Body& b)
      : A(a), B(b), sa(*a.sd), sb(*b.sd), gb(*b.sd->grid), skin(0.5 * b.sd->grid->spacing()) {
    const Mat3 RbT = B.R.transposed();
    Rab = RbT * A.R;
    tab = RbT * (A.x - B.x);
  }
  Vec3 node_in_b(int i) const { return Rab * sa.nodes[i] + tab; }
  // Appends node i to P when it penetrates B.
  void visit(int i, std::vector<PenNode>& P) const {
    Vec3 g;
    const Vec3 y = node_in_b(i);
    const double phi = gb.value_gradient(y, g);
    if (phi >= 0) return;
    const double gn = norm(g);
    if (!(gn > 0)) return;
    const Vec3 n = B.R * (g / gn);
    const Vec3 X = A.R * sa.nodes[i] + A.x;
    P.push_back({i, -phi, n, X + n * (-0.5 * phi), sa.w[i]});
  }
};

// Full search: descend the master's node tree, pruning subtrees outside the partner's
// bounding sphere or box (in its frame) or farther than the skin; the nodes within the skin
// become the pair's candidates `cand`.
void search_nodes(const PairView& pv, std::vector<int>& cand, LsdemEngine::Item& it, int dim, double lipschitz,
                  std::vector<PenNode>& P) {
  const LsdemEngine::ShapeData &sa = pv.sa, &sb = pv.sb;
  const LevelSetGrid& gb = pv.gb;
  const double rb = sb.radius, skin = pv.skin;
  int stack[64];
  int top = 0;
  if (!sa.clusters.empty() && norm2(pv.B.x - pv.A.x) <= (sa.radius + rb) * (sa.radius + rb)) stack[top++] = 0;
  while (top > 0) {
    const auto& c = sa.clusters[stack[--top]];
    const Vec3 yc = pv.Rab * c.c + pv.tab;
    const double reach = c.r + skin;
    if (norm2(yc) > (reach + rb) * (reach + rb)) continue;
    bool out = false;
    for (int a = 0; a < dim && !out; ++a) out = yc[a] + reach < sb.box.lo[a] || yc[a] - reach > sb.box.hi[a];
    if (out) continue;
    // Each partial derivative of the trilinear interpolant of 1-Lipschitz samples is
    // a mean of edge slopes in [−1, 1], so |∇φ| ≤ √dim: the whole sphere is farther
    // than the skin from the partner when φ(centre) > √dim · r + skin.
    if (c.r > 0.5 * gb.spacing() || c.left >= 0) {
      ++it.tree_queries;
      if ((gb.inside_grid(yc) ? gb.value_inside(yc) : gb.value(yc)) > lipschitz * c.r + skin) continue;
    }
    if (c.left >= 0) {
      stack[top++] = c.right;
      stack[top++] = c.left;
      continue;
    }
    for (int i = c.begin; i < c.end; ++i) {
      const Vec3 y = pv.node_in_b(i);
      bool outside = false;
      for (int a = 0; a < dim && !outside; ++a) outside = y[a] < sb.box.lo[a] - skin || y[a] > sb.box.hi[a] + skin;
      if (outside) continue;
      ++it.queries;
      const double phi = gb.inside_grid(y) ? gb.value_inside(y) : gb.value(y);
      if (phi >= skin) continue;
      cand.push_back(i);
      if (phi < 0) pv.visit(i, P);
    }
  }
}

// The master A's nodes that penetrate B (a grain or a shape wall), appended to P with their
// penetration, the partner's normal, the contact point and the node's weight: only the
// candidates of the pair's last full search while the bound on their accumulated motion stays
// below the skin, else a full search (see the header).
void penetrating_nodes(const LsdemEngine::Body& A, const LsdemEngine::Body& B, LsdemEngine::Item& it, int dim,
                       std::vector<PenNode>& P) {
  const double lipschitz = std::sqrt(double(dim)) * (1 + 1e-9);
  const PairView pv(A, B);
  auto& ps = *it.st;
  const bool had = !it.fresh && ps.has_cand;
  const double drift =
      had ? ps.drift + A.moved + B.moved + A.turned * pv.sa.radius + B.turned * (pv.sa.radius + norm(A.x - B.x)) : 0;
  if (had && lipschitz * drift < pv.skin) {
    // No node outside the candidates can have reached the partner since the search.
    ps.drift = drift;
    for (int i : ps.cand) {
      ++it.queries;
      const Vec3 y = pv.node_in_b(i);
      if (pv.gb.inside_grid(y) && pv.gb.value_inside(y) < 0) pv.visit(i, P);
    }
    return;
  }
  ps.cand.clear();
  ps.drift = 0;
  ps.has_cand = true;
  search_nodes(pv, ps.cand, it, dim, lipschitz, P);
}

// The master A's nodes behind the plane wall wl, appended to P (the tree pruned by the
// clusters' bounding spheres).
void nodes_behind_wall(const LsdemEngine::Body& A, const WallPlane& wl, LsdemEngine::Item& it, std::vector<PenNode>& P) {
  const LsdemEngine::ShapeData& sa = *A.sd;
  int stack[64];
  int top = 0;
  if (!sa.clusters.empty()) stack[top++] = 0;
  while (top > 0) {
    const auto& c = sa.clusters[stack[--top]];
    const Vec3 xc = A.R * c.c + A.x;
    if (dot(xc - wl.point, wl.normal) > c.r) continue;
    if (c.left >= 0) {
      stack[top++] = c.right;
      stack[top++] = c.left;
      continue;
    }
    for (int i = c.begin; i < c.end; ++i) {
      const Vec3 X = A.R * sa.nodes[i] + A.x;
      const double s = dot(X - wl.point, wl.normal);
      ++it.queries;
      if (s >= 0) continue;
      P.push_back({i, -s, wl.normal, X + wl.normal * (-0.5 * s), sa.w[i]});
    }
  }
}

Law base_law(const LsdemSettings& s) {
  Law L;
  L.hertz = s.contact_law == "hertz";
  L.ks_ratio = s.ks_ratio;
  L.zeta = s.damping_ratio;
  return L;
}

// The law of grain A (material ma) on a wall, plane or shape.
Law wall_law(const LsdemSettings& s, double friction_scale, const Material& ma, const LsdemEngine::Body& A) {
  Law L = base_law(s);
  L.kn = s.kn_reference_radius > 0 ? s.wall_kn * (A.sd->r_eq / s.kn_reference_radius) : s.wall_kn;
  L.mu = ma.wall_friction * friction_scale;
  L.mstar = A.m;
  if (L.hertz) L.khertz = 4.0 / 3.0 * ma.young / (1 - ma.poisson * ma.poisson) * std::sqrt(A.sd->r_eq);
  return L;
}

// The law of grains A and B (materials ma, mb).
Law grain_law(const LsdemSettings& s, double friction_scale, const Material& ma, const Material& mb,
              const LsdemEngine::Body& A, const LsdemEngine::Body& B) {
  Law L = base_law(s);
  L.kn = s.kn_reference_radius > 0 ? s.kn * (std::min(A.sd->r_eq, B.sd->r_eq) / s.kn_reference_radius) : s.kn;
  L.mu = std::min(ma.friction, mb.friction) * friction_scale;
  L.mstar = A.m * B.m / (A.m + B.m);
  if (L.hertz) {
    const double estar = 1.0 / ((1 - ma.poisson * ma.poisson) / ma.young + (1 - mb.poisson * mb.poisson) / mb.young);
    const double rstar = A.sd->r_eq * B.sd->r_eq / (A.sd->r_eq + B.sd->r_eq);
    L.khertz = 4.0 / 3.0 * estar * std::sqrt(rstar);
  }
  return L;
}

}  // namespace

// One step's forces: broad phase (grain pairs, then walls), narrow phase, reduction.
void LsdemEngine::compute_forces(double dt) {
  const std::vector<Wall> W = walls();
  ++stamp_;
  items_.clear();
  collect_pair_items();
  const std::size_t npairs = collect_wall_items(W);
  narrow_phase(W, dt);
  reduce_forces(W, npairs);
}

bool LsdemEngine::near_list_stale() const {
  const std::size_t nb = bodies_.size();
  if (!near_valid_) return true;
  if (nb < 2) return false;
  double d1 = 0, d2 = 0;  // the two largest displacements since the build
  for (std::size_t i = 0; i < nb; ++i) {
    const double d = norm(bodies_[i].x - near_x0_[i]);
    if (d > d1) {
      d2 = d1;
      d1 = d;
    } else if (d > d2) {
      d2 = d;
    }
  }
  return d1 + d2 >= near_skin_;
}

void LsdemEngine::collect_pair_items() {
  // Broad phase: the Verlet list (build_near) holds every pair whose bounding spheres can
  // overlap until two grains have together moved farther than its skin.
  const bool rebuilt = near_list_stale();
  if (rebuilt) build_near();
  for (auto& e : near_) {
    if (norm2(bodies_[e.i].x - bodies_[e.j].x) > e.rr * e.rr) {
      // Out of reach this step: its state goes (as it would after any gap of one step).
      if (e.st) history_.erase(e.key);
      e.st = nullptr;
      continue;
    }
    Item& it = items_.emplace_back();
    it.a = e.a;
    it.b = e.b;
    it.key = e.key;
    bool inserted = false;
    if (!e.st) {
      auto [h, ins] = history_.try_emplace(e.key);
      e.st = &h->second;
      inserted = ins;
    }
    it.st = e.st;
    it.fresh = inserted || e.st->stamp != stamp_ - 1;
    if (it.fresh) *e.st = PairState{};
    e.st->stamp = stamp_;
  }
  // States of pairs that left the list at its rebuild (not in reach) go.
  if (rebuilt)
    for (auto h = history_.begin(); h != history_.end();) h = h->second.stamp != stamp_ ? history_.erase(h) : std::next(h);
}

std::size_t LsdemEngine::collect_wall_items(const std::vector<Wall>& W) {
  const std::size_t nb = bodies_.size();
  const std::size_t first_wall_item = items_.size();
  for (std::size_t i = 0; i < nb; ++i)
    for (std::size_t k = 0; k < walls_kin_.size(); ++k) {
      const Body &A = bodies_[i], &B = walls_kin_[k];
      const double rr = A.sd->radius + B.sd->radius;
      if (norm2(A.x - B.x) > rr * rr) continue;
      Item& it = items_.emplace_back();
      it.a = static_cast<int>(i);
      it.b = static_cast<int>(k);
      it.shape_wall = true;
      it.key = {A.id, B.id};
    }
  const std::size_t npairs = items_.size();
  for (std::size_t i = 0; i < nb; ++i)
    for (std::size_t k = 0; k < W.size(); ++k)
      if (dot(bodies_[i].x - W[k].point, W[k].normal) < bodies_[i].sd->radius) {
        Item& it = items_.emplace_back();
        it.a = static_cast<int>(i);
        it.b = -1 - static_cast<int>(k);
        it.key = {bodies_[i].id, -1 - W[k].id};
      }
  for (std::size_t k = first_wall_item; k < items_.size(); ++k) {
    Item& it = items_[k];
    auto [h, fresh] = wall_history_.try_emplace(it.key);
    it.st = &h->second;
    it.fresh = fresh || h->second.stamp != stamp_ - 1;
    if (it.fresh) h->second = PairState{};
    h->second.stamp = stamp_;
  }
  return npairs;
}

void LsdemEngine::narrow_phase(const std::vector<Wall>& W, double dt) {
  // In parallel over items; each writes only its own slot.
  const long nitems = static_cast<long>(items_.size());
#pragma omp parallel num_threads(s_.threads)
  {
    std::vector<PenNode> P;
    std::vector<NodeHist> hist_new;
#pragma omp for schedule(dynamic, 4)
    for (long ii = 0; ii < nitems; ++ii) {
      Item& it = items_[ii];
      const Body& A = bodies_[it.a];
      const Material& ma = ctx_.materials[A.material];
      const std::vector<NodeHist>* old = it.fresh ? nullptr : &it.st->hist;
      P.clear();
      if (it.b >= 0) {
        const Body& B = it.shape_wall ? walls_kin_[it.b] : bodies_[it.b];
        penetrating_nodes(A, B, it, ctx_.dimension, P);
        const Law L = it.shape_wall ? wall_law(s_, friction_scale_, ma, A)
                                    : grain_law(s_, friction_scale_, ma, ctx_.materials[B.material], A, B);
        it.pen = static_cast<long>(P.size());
        if (!P.empty()) patch_forces(P, L, A, &B, Vec3{}, dt, old, hist_new, it);
      } else {
        const Wall& wl = W[-1 - it.b];
        nodes_behind_wall(A, wl, it, P);
        const Law L = wall_law(s_, friction_scale_, ma, A);
        it.pen = static_cast<long>(P.size());
        if (!P.empty()) patch_forces(P, L, A, static_cast<const Body*>(nullptr), wl.velocity, dt, old, hist_new, it);
      }
      // The new tangential history replaces the old one (empty when out of contact).
      if (P.empty()) hist_new.clear();
      std::swap(it.st->hist, hist_new);
    }
  }
}

void LsdemEngine::apply_body_loads() {
  for (auto& b : bodies_) {
    b.f = ctx_.gravity * (b.md / s_.mass_scale);  // the weight of the true mass
    b.t = {};
    // Global damping acts on the mass before selective scaling, so that a scaled grain drifts
    // under a steady force as fast as it would unscaled (the added mass is inertia only);
    // the relaxation's damping acts on the stepped mass (it is there for stability).
    // (c·m = C_g·m_before + relax·m, the stepped m = m_before·sel.)
    const double c = s_.global_damping * global_damping_scale_ / b.sel + relax_damping_;
    if (c > 0) {
      b.f -= b.v * (c * b.m);
      if (ctx_.dimension == 2) {
        b.t.z -= c * b.Ib(2, 2) * b.w.z;
      } else {
        const Vec3 wb = b.R.transposed() * b.w;
        b.t -= b.R * (b.Ib * wb) * c;
      }
    }
  }
}

void LsdemEngine::reduce_forces(const std::vector<Wall>& W, std::size_t npairs) {
  // Reduction in the fixed item order.
  apply_body_loads();
  contacts_.clear();
  platen_force_ = 0;
  floor_force_ = 0;
  container_wall_force_.fill(0.0);
  for (auto& f : shape_wall_force_) f = {};
  elastic_energy_ = 0;
  long pairs_in_contact = 0, queries = 0, wall_checks = 0, pen = 0, tree = 0;
  for (std::size_t k = 0; k < items_.size(); ++k) {
    const Item& it = items_[k];
    if (it.b >= 0) queries += it.queries;
    else wall_checks += it.queries;
    pen += it.pen;
    tree += it.tree_queries;
    if (!it.contact) continue;
    elastic_energy_ += it.elastic;
    if (apply_contact(it, W)) ++pairs_in_contact;
  }
  // States of grain–wall contacts that no longer overlap go.
  for (auto h = wall_history_.begin(); h != wall_history_.end();)
    h = h->second.stamp != stamp_ ? wall_history_.erase(h) : std::next(h);
  stats_.node_queries += queries;
  stats_.tree_queries += tree;
  stats_.wall_node_checks += wall_checks;
  stats_.bbox_overlaps += static_cast<long>(npairs);
  stats_.contact_pairs += pairs_in_contact;
  stats_.penetrating_nodes += pen;
  stats_.last_bbox_overlaps = static_cast<long>(npairs);
  stats_.last_contact_pairs = pairs_in_contact;
  stats_.last_node_queries = queries;
}

bool LsdemEngine::apply_contact(const Item& it, const std::vector<Wall>& W) {
  Body& A = bodies_[it.a];
  A.f += it.fa;
  A.t += it.ta;
  Contact c;
  c.a = A.id;
  c.point = it.fsum > 0 ? it.point / it.fsum : it.point;
  c.normal = normalized(it.normal);
  c.force = it.fa;
  c.overlap = it.overlap;
  const bool grain_pair = !it.shape_wall && it.b >= 0;
  if (it.shape_wall) {
    c.wall = kFirstShapeWall + it.b;
    shape_wall_force_[it.b] -= it.fa;
  } else if (it.b >= 0) {
    Body& B = bodies_[it.b];
    B.f -= it.fa;
    B.t += it.tb;
    c.b = B.id;
  } else {
    const Wall& wl = W[-1 - it.b];
    c.wall = wl.id;
    if (wl.id == kFloor) floor_force_ += dot(it.fa, wl.normal);
    if (wl.id == kPlaten) platen_force_ += dot(it.fa, wl.normal);
    if (wl.id >= 0 && wl.id < static_cast<int>(container_wall_force_.size()))
      container_wall_force_[wl.id] += dot(it.fa, wl.normal);  // inward normal: the push outwards
  }
  contacts_.push_back(c);
  return grain_pair;
}

void LsdemEngine::integrate(double dt) {
  const int dim = ctx_.dimension;
  const long n = static_cast<long>(bodies_.size());
#pragma omp parallel for schedule(static) num_threads(s_.threads)
  for (long i = 0; i < n; ++i) {
    Body& b = bodies_[i];
    // Leapfrog: v(t+dt/2) = v(t−dt/2) + a(t) dt, x(t+dt) = x(t) + v(t+dt/2) dt.
    b.v += b.f * (b.im * dt);
    if (dim == 2) b.v.z = 0;
    b.x += b.v * dt;
    b.moved = norm(b.v) * dt;
    if (dim == 2) {
      b.w.z += b.t.z / b.Ib(2, 2) * dt;
      const double ang = b.w.z * dt;
      if (ang != 0) b.q = (Quat{std::cos(0.5 * ang), 0, 0, std::sin(0.5 * ang)} * b.q).normalized();
    } else {
      // Euler's equations in the body frame: I ω̇ = τ − ω × Iω.
      const Mat3 RT = b.R.transposed();
      Vec3 wb = RT * b.w;
      const Vec3 tb = RT * b.t;
      wb += b.iIb * (tb - cross(wb, b.Ib * wb)) * dt;
      b.w = b.R * wb;
      const double wn = norm(b.w);
      if (wn > 0) b.q = (Quat::from_axis_angle(b.w, wn * dt) * b.q).normalized();
    }
    b.R = b.q.matrix();
    b.turned = norm(b.w) * dt;
  }
  // Shape walls move kinematically.
  for (auto& b : walls_kin_) {
    b.x += b.v * dt;
    const double wn = norm(b.w);
    if (wn > 0) b.q = (Quat::from_axis_angle(b.w, wn * dt) * b.q).normalized();
    b.R = b.q.matrix();
    b.moved = norm(b.v) * dt;
    b.turned = wn * dt;
  }
  // Platen along the vertical axis.
  if (has_container_ && container_.height > 0 && !container_.open) {
    // Mass rule and semi-implicit update shared by every engine (core/Platen.h); the
    // global damping acts on the platen too, the relaxation's damping does not (a platen
    // damped as the grains are would creep under the settling stress and look at rest).
    double M = 0;
    if (platen_.force_driven() && !(container_.platen_mass > 0)) {
      for (const auto& b : bodies_) M += b.md;  // density-scaled masses (no selective scaling)
      M /= s_.mass_scale;
    }
    M = platen_mass(container_, M, s_.mass_scale);
    platen_.advance(dt, platen_force_, M, s_.global_damping * global_damping_scale_);
    // Relaxing, a platen the grains no longer push does not fly on upwards: the overlaps'
    // energy that launched it is what the relaxation removes (left to fly, it rose 45 mm
    // above the quick Zhu & Zhao packing and took 0.4 s to fall back under the settling stress).
    if (relax_damping_ > 0 && !(platen_force_ > 0) && platen_.velocity() > 0) platen_.sync(platen_.position(), 0.0);
  }
}

// ---- Checkpoint state ----

bool LsdemEngine::save_state(nlohmann::json& out) const {
  using J = nlohmann::json;
  // nlohmann writes the shortest decimal that reads back to the same double, so every
  // value below round-trips bit for bit.
  J bodies = J::array();
  for (const auto& b : bodies_)
    bodies.push_back(J::array({b.id, b.x.x, b.x.y, b.x.z, b.v.x, b.v.y, b.v.z, b.w.x, b.w.y, b.w.z, b.q.w, b.q.x,
                               b.q.y, b.q.z, b.moved, b.turned}));
  std::vector<const std::pair<const std::pair<GrainId, GrainId>, PairState>*> pairs;
  for (const auto* m : {&history_, &wall_history_})
    for (const auto& h : *m) pairs.push_back(&h);
  std::sort(pairs.begin(), pairs.end(), [](const auto* a, const auto* b) { return a->first < b->first; });
  J ps = J::array();
  for (const auto* p : pairs) {
    const PairState& st = p->second;
    J hist = J::array();
    for (const auto& n : st.hist) hist.push_back(J::array({n.node, n.ft.x, n.ft.y, n.ft.z}));
    ps.push_back(J{{"key", J::array({p->first.first, p->first.second})},
                   {"stamp", st.stamp},
                   {"drift", st.drift},
                   {"has_cand", st.has_cand},
                   {"cand", st.cand},
                   {"hist", hist}});
  }
  out = J{{"engine", "lsdem"},
          {"version", 1},
          {"stamp", stamp_},
          {"friction_scale", friction_scale_},
          {"platen", J::array({platen_.position(), platen_.velocity()})},
          {"platen_force", platen_force_},
          {"floor_force", floor_force_},
          {"bodies", bodies},
          {"pairs", ps}};
  // Shape walls: the pose they were integrated to, their motion over the last step and the
  // grains' force on them (the Simulation's energy bookkeeping reads it before the next step).
  if (!walls_kin_.empty()) {
    J walls = J::array();
    for (std::size_t k = 0; k < walls_kin_.size(); ++k) {
      const Body& b = walls_kin_[k];
      const Vec3& f = shape_wall_force_[k];
      walls.push_back(J::array({b.x.x, b.x.y, b.x.z, b.v.x, b.v.y, b.v.z, b.w.x, b.w.y, b.w.z, b.q.w, b.q.x, b.q.y,
                                b.q.z, b.moved, b.turned, f.x, f.y, f.z}));
    }
    out["walls"] = std::move(walls);
  }
  // Selective mass scaling (only when on: a run without it writes the state it always did):
  // the target step and every scaled grain's factor (fixed when the grain was added).
  if (s_.selective_dt > 0 || s_.selective_dt_fraction > 0) {
    J factors = J::array();
    for (const auto& b : bodies_)
      if (b.sel != 1) factors.push_back(J::array({b.id, b.sel}));
    out["selective_scaling"] = J{{"target_dt", target_dt_}, {"factors", factors}};
  }
  return true;
}

// Reads the checkpointed engine state; every error names the place (`at`) being read.
struct LsdemEngine::StateReader {
  using J = nlohmann::json;
  std::string at;
  [[noreturn]] void fail(const std::string& msg) const {
    throw std::invalid_argument("lsdem engine state" + (at.empty() ? std::string() : " at " + at) + ": " + msg);
  }
  double num(const J& v) const {
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail("expected a finite number, got " + v.dump());
    return v.get<double>();
  }
  long integer(const J& v) const {
    if (!v.is_number_integer()) fail("expected an integer, got " + v.dump());
    return v.get<long>();
  }
  const J& field(const J& o, const char* k) const {
    if (!o.is_object() || !o.contains(k)) fail(std::string("missing \"") + k + "\"");
    return o.at(k);
  }
  // Node indices below `nodes`.
  int node(const J& v, long nodes, const char* what) const {
    const long n = integer(v);
    if (n < 0 || n >= nodes) fail(std::string(what) + ": node index out of range");
    return static_cast<int>(n);
  }
};

namespace {

// One saved body [id, x(3), v(3), w(3), q(4), moved, turned] over its current state b.
void read_body(const LsdemEngine::StateReader& rd, const nlohmann::json& r, LsdemEngine::Body& b) {
  double v[15];
  for (int k = 0; k < 15; ++k) v[k] = rd.num(r[k + 1]);
  b.x = {v[0], v[1], v[2]};
  b.v = {v[3], v[4], v[5]};
  b.w = {v[6], v[7], v[8]};
  b.q = Quat{v[9], v[10], v[11], v[12]};
  if (std::abs(b.q.w * b.q.w + b.q.x * b.q.x + b.q.y * b.q.y + b.q.z * b.q.z - 1) > 1e-9) rd.fail("quaternion is not a unit");
  b.R = b.q.matrix();
  b.moved = v[13];
  b.turned = v[14];
}

}  // namespace

std::vector<std::pair<LsdemEngine::Body, Vec3>> LsdemEngine::read_walls(StateReader& rd, const nlohmann::json& j) const {
  rd.at = "walls";
  static const nlohmann::json none = nlohmann::json::array();
  const nlohmann::json& jw = j.contains("walls") ? j.at("walls") : none;
  if (!jw.is_array() || jw.size() != walls_kin_.size())
    rd.fail("expected " + std::to_string(walls_kin_.size()) + " shape walls (the scenario's moving walls), got " +
            std::to_string(jw.is_array() ? jw.size() : 0));
  std::vector<std::pair<Body, Vec3>> out;
  for (std::size_t k = 0; k < jw.size(); ++k) {
    rd.at = "walls/" + std::to_string(k);
    const nlohmann::json& r = jw[k];
    if (!r.is_array() || r.size() != 18) rd.fail("expected [x(3), v(3), w(3), q(4), moved, turned, force(3)]");
    // read_body reads [id, x(3), …, turned]: the wall's row without an id, then its force.
    nlohmann::json row = nlohmann::json::array({0});
    for (std::size_t i = 0; i < 15; ++i) row.push_back(r[i]);
    Body b = walls_kin_[k];
    read_body(rd, row, b);
    out.emplace_back(b, Vec3{rd.num(r[15]), rd.num(r[16]), rd.num(r[17])});
  }
  return out;
}

std::vector<LsdemEngine::Body> LsdemEngine::read_bodies(StateReader& rd, const nlohmann::json& jb) const {
  if (!jb.is_array() || jb.size() != bodies_.size())
    rd.fail("expected " + std::to_string(bodies_.size()) + " bodies (the checkpoint's grains), got " +
            std::to_string(jb.is_array() ? jb.size() : 0));
  // Bodies in the saved order: the broad phase and the force sums follow it.
  std::vector<Body> order;
  order.reserve(bodies_.size());
  std::vector<char> used(bodies_.size(), 0);
  for (std::size_t i = 0; i < jb.size(); ++i) {
    rd.at = "bodies/" + std::to_string(i);
    const nlohmann::json& r = jb[i];
    if (!r.is_array() || r.size() != 16) rd.fail("expected [id, x(3), v(3), w(3), q(4), moved, turned]");
    const GrainId id = rd.integer(r[0]);
    auto it = index_.find(id);
    if (it == index_.end() || used[it->second])
      rd.fail("grain " + std::to_string(id) + " is not in the checkpoint or listed twice");
    used[it->second] = 1;
    Body b = bodies_[it->second];
    read_body(rd, r, b);
    order.push_back(b);
  }
  return order;
}

std::pair<std::pair<GrainId, GrainId>, LsdemEngine::PairState> LsdemEngine::read_pair(const StateReader& rd,
                                                                                    const nlohmann::json& p) const {
  const nlohmann::json& key = rd.field(p, "key");
  if (!key.is_array() || key.size() != 2) rd.fail("key: expected [master id, partner id]");
  const std::pair<GrainId, GrainId> k{rd.integer(key[0]), rd.integer(key[1])};
  if (!index_.count(k.first) || (k.second >= 0 && !index_.count(k.second)))
    rd.fail("key names a grain that is not in the checkpoint");
  PairState st;
  st.stamp = rd.integer(rd.field(p, "stamp"));
  st.drift = rd.num(rd.field(p, "drift"));
  if (!rd.field(p, "has_cand").is_boolean()) rd.fail("has_cand: expected true or false");
  st.has_cand = p.at("has_cand").get<bool>();
  const long nodes = static_cast<long>(bodies_[index_.at(k.first)].sd->nodes.size());
  const nlohmann::json& cand = rd.field(p, "cand");
  if (!cand.is_array()) rd.fail("cand: expected an array of node indices");
  for (const auto& c : cand) st.cand.push_back(rd.node(c, nodes, "cand"));
  const nlohmann::json& h = rd.field(p, "hist");
  if (!h.is_array()) rd.fail("hist: expected an array of [node, fx, fy, fz]");
  for (const auto& e : h) {
    if (!e.is_array() || e.size() != 4) rd.fail("hist: expected [node, fx, fy, fz]");
    const int n = rd.node(e[0], nodes, "hist");
    st.hist.push_back({n, Vec3{rd.num(e[1]), rd.num(e[2]), rd.num(e[3])}});
  }
  return {k, std::move(st)};
}

void LsdemEngine::restore_state(const nlohmann::json& j) {
  using J = nlohmann::json;
  StateReader rd;
  if (!j.is_object()) rd.fail("expected an object");
  if (!rd.field(j, "engine").is_string() || j.at("engine").get<std::string>() != "lsdem")
    rd.fail("written by engine " + j.at("engine").dump() + ", not lsdem");
  if (rd.integer(rd.field(j, "version")) != 1) rd.fail("unknown version " + j.at("version").dump());
  std::vector<Body> order = read_bodies(rd, rd.field(j, "bodies"));
  const std::vector<std::pair<Body, Vec3>> walls = read_walls(rd, j);
  rd.at = "pairs";
  const J& jp = rd.field(j, "pairs");
  if (!jp.is_array()) rd.fail("expected an array");
  std::unordered_map<std::pair<GrainId, GrainId>, PairState, KeyHash> hist;
  rd.at = "stamp";
  const long stamp = rd.integer(rd.field(j, "stamp"));
  for (std::size_t i = 0; i < jp.size(); ++i) {
    rd.at = "pairs/" + std::to_string(i);
    if (!hist.insert(read_pair(rd, jp[i])).second) rd.fail("pair listed twice");
  }
  rd.at = "platen";
  const J& pl = rd.field(j, "platen");
  if (!pl.is_array() || pl.size() != 2) rd.fail("expected [position, velocity]");
  const double z = rd.num(pl[0]), vz = rd.num(pl[1]);
  rd.at = "";
  const double fs = rd.num(rd.field(j, "friction_scale"));
  const double pf = rd.num(rd.field(j, "platen_force")), ff = rd.num(rd.field(j, "floor_force"));
  const auto sel = read_selective(rd, j);
  // Everything checked: take it.
  bodies_ = std::move(order);
  index_.clear();
  for (std::size_t i = 0; i < bodies_.size(); ++i) index_[bodies_[i].id] = i;
  history_.clear();
  wall_history_.clear();
  for (auto& [k, st] : hist) (k.second < 0 ? wall_history_ : history_).emplace(k, std::move(st));
  near_valid_ = false;
  stamp_ = stamp;
  friction_scale_ = fs;
  platen_.sync(z, vz);
  platen_force_ = pf;
  floor_force_ = ff;
  for (std::size_t k = 0; k < walls.size(); ++k) {
    walls_kin_[k] = walls[k].first;
    shape_wall_force_[k] = walls[k].second;
  }
  target_dt_ = sel.first;
  for (auto& b : bodies_) {
    const auto f = sel.second.find(b.id);
    set_selective_factor(b, f == sel.second.end() ? 1.0 : f->second);
  }
}

std::pair<double, std::map<GrainId, double>> LsdemEngine::read_selective(StateReader& rd, const nlohmann::json& j) const {
  std::pair<double, std::map<GrainId, double>> out{target_dt_, {}};
  const bool on = s_.selective_dt > 0 || s_.selective_dt_fraction > 0;
  rd.at = "selective_scaling";
  if (!on) {
    if (j.contains("selective_scaling")) rd.fail("written with selective mass scaling, which this scenario does not use");
    return out;
  }
  const nlohmann::json& st = rd.field(j, "selective_scaling");
  out.first = rd.num(rd.field(st, "target_dt"));
  if (out.first < 0) rd.fail("target_dt: expected >= 0");
  const nlohmann::json& f = rd.field(st, "factors");
  if (!f.is_array()) rd.fail("factors: expected an array of [grain id, factor]");
  for (const auto& e : f) {
    if (!e.is_array() || e.size() != 2) rd.fail("factors: expected [grain id, factor]");
    const GrainId id = rd.integer(e[0]);
    const double s = rd.num(e[1]);
    if (!index_.count(id) || !(s >= 1) || !out.second.emplace(id, s).second)
      rd.fail("factors: grain " + std::to_string(id) + " is not in the checkpoint, listed twice, or has a factor below 1");
  }
  return out;
}

// ---- Factory and benchmark ----

const OptionTable& lsdem_options() {
  using S = LsdemSettings;
  static const OptionTable t = [] {
    const double inf = std::numeric_limits<double>::infinity();
    return OptionTable{
        opt::choice("contact_law", &S::contact_law, {"linear", "hertz"},
                    "normal force k_n·δ (\"linear\") or Hertzian (4/3)·E*·√R*·δ^(3/2) (\"hertz\", 3D only)"),
        opt::positive("kn", &S::kn, "N/m", "grain–grain normal stiffness (Harmon et al. 2020 Table 2); 2D: per metre of thickness"),
        opt::number("kn_reference_radius", &S::kn_reference_radius, 0, inf, "m",
                    "linear law: a contact's normal stiffness is kn (wall_kn) × R/this, R the smaller equivalent "
                    "radius of the pair (a wall contact: the grain's), so a fragment's own step falls with R rather "
                    "than R^1.5; 0 = kn for every contact"),
        opt::number("ks_ratio", &S::ks_ratio, 0, 10, "", "k_s / k_n (Harmon et al. 2020 Table 2)"),
        opt::number("wall_kn", &S::wall_kn, 0, inf, "N/m", "grain–wall normal stiffness; 0 = kn"),
        opt::number("damping_ratio", &S::damping_ratio, 0, 10, "", "contact critical-damping ratio ζ (Harmon et al. 2020 Table 2)"),
        opt::number("global_damping", &S::global_damping, 0, inf, "1/s", "global damping C_g (Harmon et al. 2020 Tables 1–2)"),
        opt::number("dt_safety", &S::dt_safety, 1e-6, 2, "", "stable step = dt_safety·√(m_min/k)"),
        opt::number("hertz_reference_overlap", &S::hertz_reference_overlap, 1e-9, 0.5, "",
                    "overlap / smallest equivalent radius at which the Hertz stiffness sets the stable step"),
        opt::positive("mass_scale", &S::mass_scale, "", "mass and inertia ×; weight unchanged (mass scaling)"),
        opt::number("selective_dt", &S::selective_dt, 0, inf, "s",
                    "selective mass scaling: a grain whose own stable step dt_safety·√(m/k) is below this gets "
                    "its mass and inertia × (this / own step)², weight unchanged; 0 = off"),
        opt::number("selective_dt_fraction", &S::selective_dt_fraction, 0, 1, "",
                    "selective mass scaling with the target step = this × the stable step of the packing first "
                    "stepped (the initial packing); 0 = off; not with selective_dt"),
        opt::mapped_choice("sphere_representation", &S::exact_spheres, {{"sphere", true}, {"polyhedron", false}},
                           "a sphere's level set: the sphere (\"sphere\") or the convex hull of its mesh "
                           "(\"polyhedron\": the 42-vertex icosphere Bullet and ODE collide by default, so a "
                           "packing they built loads on lsdem without their facets' overlaps; a level-set split still cuts "
                           "the sphere, so its children start overlapping: for rigid grains or alpha-shape fragments)"),
        opt::number("pair_list_skin", &S::pair_list_skin, 0, 10, "",
                    "broad phase: pairs within this × the largest bounding radius are listed, and the list is "
                    "rebuilt only when two grains may together have moved farther; 0 = rebuilt every step (same "
                    "results, bit for bit: only the speed changes)"),
    };
  }();
  return t;
}

std::unique_ptr<Engine> make_lsdem_engine(const Config& cfg, const EngineContext& ctx) {
  cfg.string("type", "lsdem");
  LsdemSettings s;
  read_options(cfg, lsdem_options(), s);
  s.threads = std::max(1, ctx.threads);
  if (s.contact_law == "hertz" && ctx.dimension == 2)
    cfg.fail("contact_law", "\"hertz\" is 3D only (2D contacts of cylinders are not Hertzian); use \"linear\"");
  if (s.kn_reference_radius > 0 && s.contact_law == "hertz")
    cfg.fail("kn_reference_radius", "is for the linear contact law (the hertz law's stiffness already follows √R*)");
  if (s.selective_dt > 0 && s.selective_dt_fraction > 0)
    cfg.fail("selective_dt_fraction", "give selective_dt (an absolute target step) or "
                                           "selective_dt_fraction, not both");
  return std::make_unique<LsdemEngine>(s, ctx);
}

void lsdem_bench_scene(LsdemEngine& e, const LsdemBenchScene& sc) {
  if (sc.grains <= 0 || sc.nodes <= 0 || sc.shapes <= 0 || sc.per_row <= 0 || !(sc.radius > 0))
    throw std::invalid_argument("lsdem_bench_scene: counts and radius must be > 0");
  if (e.grain_count() != 0) throw std::invalid_argument("lsdem_bench_scene: the engine must be empty");
  Rng rng(sc.seed);
  std::vector<Shape::Ptr> shapes;
  for (int i = 0; i < sc.shapes; ++i) {
    const Vec3 r{sc.radius * rng.uniform(0.8, 1.2), sc.radius * rng.uniform(0.8, 1.2),
                 sc.radius * rng.uniform(0.8, 1.2)};
    ShapeResolution res;
    res.surface_nodes = sc.nodes;
    shapes.push_back(Shape::superellipsoid(r, rng.uniform(0.4, 1.2), rng.uniform(0.4, 1.2), res));
  }
  const double a = 2.6 * sc.radius;
  Container box;
  box.lx = box.ly = a * sc.per_row;
  e.set_container(box);
  for (int i = 0; i < sc.grains; ++i) {
    Grain g;
    g.id = i;
    g.shape = shapes[i % sc.shapes];
    const int ix = i % sc.per_row, iy = (i / sc.per_row) % sc.per_row, iz = i / (sc.per_row * sc.per_row);
    g.position = {a * (ix + 0.5), a * (iy + 0.5), a * (iz + 0.5) + 0.2 * sc.radius};
    g.orientation = Quat::from_axis_angle({rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)},
                                          rng.uniform(0, 2 * kPi));
    g.velocity = Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)} * 0.05;
    e.add_grain(g);
  }
}

LsdemBenchResult lsdem_bench_phase(LsdemEngine& e, long steps, double dt) {
  if (steps <= 0) throw std::invalid_argument("lsdem_bench_phase: steps must be > 0");
  if (dt <= 0) dt = e.max_stable_dt();
  if (!std::isfinite(dt)) throw std::invalid_argument("lsdem_bench_phase: no grains (no stable step)");
  e.reset_stats();
  const auto t0 = Clock::now();
  const std::clock_t c0 = std::clock();
  for (long i = 0; i < steps; ++i) e.step(dt);
  const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
  const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
  const LsdemStats& st = e.stats();
  LsdemBenchResult r;
  r.steps = steps;
  r.seconds = sec;
  r.cpu_seconds = cpu;
  r.ms_per_step = 1e3 * sec / steps;
  r.cpu_ms_per_step = 1e3 * cpu / steps;
  r.steps_per_second = steps / sec;
  r.node_queries_per_second = st.node_queries / sec;
  r.mean_bbox_overlaps = double(st.bbox_overlaps) / steps;
  r.mean_contact_pairs = double(st.contact_pairs) / steps;
  r.mean_node_queries = double(st.node_queries) / steps;
  r.threads = e.settings().threads;
  return r;
}

}  // namespace crumble
