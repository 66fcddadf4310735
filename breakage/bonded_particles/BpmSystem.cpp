#include "breakage/bonded_particles/BpmSystem.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

namespace crumble::bpm {

double packing_fraction(int dimension) {
  return dimension == 2 ? kPi / (2.0 * std::sqrt(3.0)) : kPi / (3.0 * std::sqrt(2.0));
}

double cell_volume(int dimension, double d) {
  return dimension == 2 ? 0.5 * std::sqrt(3.0) * d * d : d * d * d / std::sqrt(2.0);
}

double element_volume(int dimension, double d) {
  return dimension == 2 ? 0.25 * kPi * d * d : kPi * d * d * d / 6.0;
}

namespace {

// Bonds between centres one diameter apart, found through a hash grid.
void link(Array& a) {
  const double d = a.d;
  // Cells a little larger than d: two centres exactly d apart may round into cells two apart.
  const double cell = 1.01 * d;
  auto key = [&](const Vec3& p) {
    return std::array<long, 3>{static_cast<long>(std::floor(p.x / cell)), static_cast<long>(std::floor(p.y / cell)),
                               static_cast<long>(std::floor(p.z / cell))};
  };
  struct Hash {
    std::size_t operator()(const std::array<long, 3>& k) const {
      return static_cast<std::size_t>(k[0] * 73856093L ^ k[1] * 19349663L ^ k[2] * 83492791L);
    }
  };
  std::unordered_map<std::array<long, 3>, std::vector<std::int32_t>, Hash> grid;
  for (std::size_t i = 0; i < a.points.size(); ++i) grid[key(a.points[i])].push_back(static_cast<std::int32_t>(i));
  a.bonds.clear();
  a.coordination.assign(a.points.size(), 0);
  const double lo = d * (1 - 1e-6), hi = d * (1 + 1e-6);
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    const auto k = key(a.points[i]);
    std::vector<std::int32_t> near;
    for (long dz = -1; dz <= 1; ++dz)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dx = -1; dx <= 1; ++dx) {
          auto it = grid.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == grid.end()) continue;
          for (auto j : it->second)
            if (j > static_cast<std::int32_t>(i)) near.push_back(j);
        }
    std::sort(near.begin(), near.end());  // bond order independent of the hash layout
    for (auto j : near) {
      const Vec3 r = a.points[j] - a.points[i];
      const double L = norm(r);
      if (L >= lo && L <= hi) {
        a.bonds.push_back({static_cast<std::int32_t>(i), j, r / L});
        ++a.coordination[i];
        ++a.coordination[j];
      }
    }
  }
}

}  // namespace

Array array_from_points(int dimension, double d, std::vector<Vec3> points) {
  if (!(d > 0) || !std::isfinite(d)) throw std::invalid_argument("bonded_particles: element diameter must be > 0");
  if (dimension != 2 && dimension != 3) throw std::invalid_argument("bonded_particles: dimension must be 2 or 3");
  Array a;
  a.dimension = dimension;
  a.d = d;
  a.points = std::move(points);
  link(a);
  return a;
}

Array dense_array(const Shape& shape, double d, const Quat& frame) {
  const Aabb b = shape.bounds();
  const double R = std::max(norm(b.lo), norm(b.hi)) + d;
  std::vector<Vec3> pts;
  if (shape.dimension() == 2) {
    // Hexagonal (triangular) array: rows along x, row spacing (√3/2)·d.
    const double h = 0.5 * std::sqrt(3.0) * d;
    const long J = static_cast<long>(std::ceil(R / h)) + 1;
    for (long j = -J; j <= J; ++j) {
      const long I = static_cast<long>(std::ceil(R / d)) + 1 + std::abs(j);
      for (long i = -I; i <= I; ++i) {
        const Vec3 p{(static_cast<double>(i) + 0.5 * static_cast<double>(j)) * d, static_cast<double>(j) * h, 0};
        if (norm2(p) > R * R) continue;
        if (shape.contains(frame.rotate(p))) pts.push_back(p);
      }
    }
  } else {
    // Face-centred cubic: cube edge √2·d, sites (i, j, k)·(edge/2) with i + j + k even.
    const double s = d / std::sqrt(2.0);
    const long K = static_cast<long>(std::ceil(R / s)) + 1;
    for (long k = -K; k <= K; ++k)
      for (long j = -K; j <= K; ++j)
        for (long i = -K; i <= K; ++i) {
          if (((i + j + k) % 2 + 2) % 2 != 0) continue;
          const Vec3 p{static_cast<double>(i) * s, static_cast<double>(j) * s, static_cast<double>(k) * s};
          if (norm2(p) > R * R) continue;
          if (shape.contains(frame.rotate(p))) pts.push_back(p);
        }
  }
  return array_from_points(shape.dimension(), d, std::move(pts));
}

double shear_ratio_for_poisson(int dimension, double nu) {
  const double r = dimension == 2 ? (1 - 3 * nu) / (1 + nu) : (1 - 4 * nu) / (1 + nu);
  return std::max(0.0, r);
}

double array_young(int dimension, double d, const BondLaw& law, int axis) {
  // Bond directions of one element of the perfect array, and the bond cross-section.
  std::vector<Vec3> dirs;
  if (dimension == 2) {
    for (int k = 0; k < 6; ++k) dirs.push_back({std::cos(k * kPi / 3), std::sin(k * kPi / 3), 0});
  } else {
    for (int a = 0; a < 3; ++a)
      for (int sa : {-1, 1})
        for (int sb : {-1, 1}) {
          Vec3 v;
          v[a] = sa;
          v[(a + 1) % 3] = sb;
          dirs.push_back(v / std::sqrt(2.0));
        }
  }
  const double A = dimension == 2 ? 2 * law.radius : kPi * law.radius * law.radius;
  const double Kn = law.kn * A, Ks = law.ks * A, V = cell_volume(dimension, d);
  // Energy density of a uniform strain ε (Voigt vector, engineering shears): each element
  // owns half of each of its bonds; bond stretch L n·ε·n, shear slip L (εn − (n·ε·n) n).
  const int nv = dimension == 2 ? 3 : 6;
  auto energy = [&](const std::array<double, 6>& e) {
    Mat3 eps{};
    if (dimension == 2) {
      eps(0, 0) = e[0], eps(1, 1) = e[1], eps(0, 1) = eps(1, 0) = 0.5 * e[2];
    } else {
      eps(0, 0) = e[0], eps(1, 1) = e[1], eps(2, 2) = e[2];
      eps(1, 2) = eps(2, 1) = 0.5 * e[3], eps(0, 2) = eps(2, 0) = 0.5 * e[4], eps(0, 1) = eps(1, 0) = 0.5 * e[5];
    }
    double w = 0;
    for (const auto& n : dirs) {
      const Vec3 en = eps * n * d;
      const double dn = dot(en, n);
      const Vec3 s = en - n * dn;
      w += 0.5 * (0.5 * Kn * dn * dn + 0.5 * Ks * dot(s, s));
    }
    return w / V;
  };
  // C = Hessian of the quadratic energy; E along `axis` = 1 / (C⁻¹)_aa.
  std::vector<double> C(nv * nv);
  for (int p = 0; p < nv; ++p)
    for (int q = 0; q < nv; ++q) {
      std::array<double, 6> ep{}, eq{}, epq{};
      ep[p] = 1, eq[q] = 1, epq[p] += 1, epq[q] += 1;
      C[p * nv + q] = energy(epq) - energy(ep) - energy(eq);
    }
  // Solve C x = e_axis (Gauss–Jordan with partial pivoting); E = 1 / x_axis.
  const int ax = dimension == 2 ? std::min(axis, 1) : axis;
  std::vector<double> M = C, rhs(nv, 0.0);
  rhs[ax] = 1;
  for (int c = 0; c < nv; ++c) {
    int piv = c;
    for (int r = c + 1; r < nv; ++r)
      if (std::abs(M[r * nv + c]) > std::abs(M[piv * nv + c])) piv = r;
    if (!(std::abs(M[piv * nv + c]) > 0)) return 0;  // a mechanism (no stiffness)
    for (int k = 0; k < nv; ++k) std::swap(M[c * nv + k], M[piv * nv + k]);
    std::swap(rhs[c], rhs[piv]);
    for (int r = 0; r < nv; ++r) {
      if (r == c) continue;
      const double f = M[r * nv + c] / M[c * nv + c];
      for (int k = 0; k < nv; ++k) M[r * nv + k] -= f * M[c * nv + k];
      rhs[r] -= f * rhs[c];
    }
  }
  const double x = rhs[ax] / M[ax * nv + ax];
  return x > 0 ? 1.0 / x : 0.0;
}

// ---------------------------------------------------------------- dynamics

System::System(const Array& a, const BondLaw& law, double density) : a_(a), law_(law) {
  const double R = law.radius, r = 0.5 * a.d;
  if (a.dimension == 2) {
    area_ = 2 * R;                // 2R̄ × 1 m
    inertia_ = 2 * R * R * R / 3;  // (2R̄)³ / 12
    polar_ = 2 * inertia_;        // unused in 2D (no twist)
    mass_ = density * kPi * r * r;
    rot_inertia_ = 0.5 * mass_ * r * r;
  } else {
    area_ = kPi * R * R;
    inertia_ = 0.25 * kPi * R * R * R * R;
    polar_ = 2 * inertia_;
    mass_ = density * kPi * a.d * a.d * a.d / 6;
    rot_inertia_ = 0.4 * mass_ * r * r;
  }
  const std::size_t n = a.size();
  u_.assign(n, {});
  v_.assign(n, {});
  th_.assign(n, {});
  w_.assign(n, {});
  f_.assign(n, {});
  m_.assign(n, {});
  fext_.assign(n, {});
  fixed_.assign(n, 0);
  intact_.assign(a.bonds.size(), 1);
}

void System::fix(const std::vector<std::int32_t>& e) {
  for (auto i : e) fixed_[i] = 1;
}

void System::add_load(const std::vector<std::int32_t>& e, const Vec3& force) {
  if (e.empty()) return;
  const Vec3 share = force / static_cast<double>(e.size());
  for (auto i : e) fext_[i] += share;
}

double System::stable_dt() const {
  const int Z = a_.full_coordination();
  const double r = 0.5 * a_.d;
  const double kt = Z * (law_.kn + law_.ks) * area_;
  const double kr = Z * (law_.kn * inertia_ + law_.ks * polar_ + law_.ks * area_ * r * r);
  return 0.5 * std::min(std::sqrt(mass_ / kt), std::sqrt(rot_inertia_ / kr));
}

int System::step(double dt, double lambda, double alpha) {
  const std::size_t n = a_.size();
  for (std::size_t i = 0; i < n; ++i) {
    f_[i] = fext_[i] * lambda;
    m_[i] = {};
  }
  const double r = 0.5 * a_.d, R = law_.radius;
  const double KnA = law_.kn * area_, KsA = law_.ks * area_, KnI = law_.kn * inertia_, KsJ = law_.ks * polar_;
  int broke = 0;
  for (std::size_t b = 0; b < a_.bonds.size(); ++b) {
    const Bond& B = a_.bonds[b];
    const Vec3 nr = B.n * r;
    // Relative displacement of the bond's contact point (j's side − i's side); a rigid
    // rotation u = ω × x, θ = ω gives zero.
    const Vec3 delta = (u_[B.j] - cross(th_[B.j], nr)) - (u_[B.i] + cross(th_[B.i], nr));
    const double dn = dot(delta, B.n);
    const Vec3 ds = delta - B.n * dn;
    if (!intact_[b]) {
      if (dn >= 0) continue;  // apart: no contact
      // Compression-only contact with Coulomb friction (shear from the reference state).
      const double fn = KnA * dn;  // < 0
      Vec3 fs = ds * KsA;
      const double cap = law_.friction * std::abs(fn), fsn = norm(fs);
      if (fsn > cap) fs = fs * (cap / fsn);
      const Vec3 Fi = B.n * fn + fs;
      f_[B.i] += Fi;
      f_[B.j] -= Fi;
      m_[B.i] += cross(nr, Fi);
      m_[B.j] += cross(nr, Fi);
      continue;
    }
    const Vec3 dth = th_[B.j] - th_[B.i];
    const double tw = dot(dth, B.n);
    const Vec3 bend = dth - B.n * tw;
    // Peak stresses of the parallel bond (Potyondy & Cundall 2004): tension positive.
    const double sigma = law_.kn * dn + law_.kn * R * norm(bend);
    const double tau = law_.ks * norm(ds) + law_.ks * R * std::abs(tw);
    if (sigma >= law_.normal_strength || tau >= law_.shear_strength) {
      intact_[b] = 0;
      ++broken_count_;
      ++broke;
      continue;
    }
    const Vec3 Fi = B.n * (KnA * dn) + ds * KsA;  // force on i; j gets −Fi
    const Vec3 Mi = cross(nr, Fi) + bend * KnI + B.n * (KsJ * tw);
    f_[B.i] += Fi;
    f_[B.j] -= Fi;
    m_[B.i] += Mi;
    m_[B.j] += cross(nr, Fi) - bend * KnI - B.n * (KsJ * tw);
  }
  // Local non-viscous damping (Cundall): each component reduced by α|F| against its velocity.
  auto damp = [alpha](double F, double v) { return v == 0 ? F : F - alpha * std::abs(F) * (v > 0 ? 1.0 : -1.0); };
  for (std::size_t i = 0; i < n; ++i) {
    if (fixed_[i]) continue;
    for (int k = 0; k < 3; ++k) {
      v_[i][k] += damp(f_[i][k], v_[i][k]) / mass_ * dt;
      w_[i][k] += damp(m_[i][k], w_[i][k]) / rot_inertia_ * dt;
    }
    u_[i] += v_[i] * dt;
    th_[i] += w_[i] * dt;
  }
  return broke;
}

namespace {
// Deformation of a parallel bond between the contact points of its two elements (radius r
// along the bond normal): normal and shear opening, twist and bending rotation.
struct BondDeformation {
  Vec3 nr, ds, bend;
  double dn = 0, tw = 0;
};
BondDeformation deformation(const Bond& B, double r, const std::vector<Vec3>& u, const std::vector<Vec3>& th) {
  BondDeformation d;
  d.nr = B.n * r;
  const Vec3 delta = (u[B.j] - cross(th[B.j], d.nr)) - (u[B.i] + cross(th[B.i], d.nr));
  d.dn = dot(delta, B.n);
  d.ds = delta - B.n * d.dn;
  const Vec3 dth = th[B.j] - th[B.i];
  d.tw = dot(dth, B.n);
  d.bend = dth - B.n * d.tw;
  return d;
}
}  // namespace

void System::bond_forces(const std::vector<Vec3>& u, const std::vector<Vec3>& th, std::vector<Vec3>& f,
                         std::vector<Vec3>& m) const {
  const std::size_t n = a_.size();
  f.assign(n, {});
  m.assign(n, {});
  const double r = 0.5 * a_.d;
  const double KnA = law_.kn * area_, KsA = law_.ks * area_, KnI = law_.kn * inertia_, KsJ = law_.ks * polar_;
  for (std::size_t b = 0; b < a_.bonds.size(); ++b) {
    if (!intact_[b]) continue;
    const Bond& B = a_.bonds[b];
    const BondDeformation d = deformation(B, r, u, th);
    const Vec3 Fi = B.n * (KnA * d.dn) + d.ds * KsA;
    const Vec3 Mr = d.bend * KnI + B.n * (KsJ * d.tw);
    f[B.i] += Fi;
    f[B.j] -= Fi;
    m[B.i] += cross(d.nr, Fi) + Mr;
    m[B.j] += cross(d.nr, Fi) - Mr;
  }
}

double System::stress_ratio(const std::vector<Vec3>& u, const std::vector<Vec3>& th) const {
  const double r = 0.5 * a_.d, R = law_.radius;
  double worst = 0;
  for (std::size_t b = 0; b < a_.bonds.size(); ++b) {
    if (!intact_[b]) continue;
    const Bond& B = a_.bonds[b];
    const BondDeformation d = deformation(B, r, u, th);
    const double sigma = law_.kn * d.dn + law_.kn * R * norm(d.bend);
    const double tau = law_.ks * norm(d.ds) + law_.ks * R * std::abs(d.tw);
    worst = std::max({worst, sigma / law_.normal_strength, tau / law_.shear_strength});
  }
  return worst;
}

int System::static_unit_solution(double tol, int max_iter) {
  // K x = F with K x = −(bond forces of x); unknowns: translations and rotations of the free
  // elements. Jacobi preconditioner from each element's bond stiffness sums.
  const std::size_t n = a_.size();
  const double r = 0.5 * a_.d;
  const double KnA = law_.kn * area_, KsA = law_.ks * area_, KnI = law_.kn * inertia_, KsJ = law_.ks * polar_;
  std::vector<double> pt(n, 0.0), pr(n, 0.0);
  for (std::size_t b = 0; b < a_.bonds.size(); ++b) {
    if (!intact_[b]) continue;
    for (auto e : {a_.bonds[b].i, a_.bonds[b].j}) {
      pt[e] += KnA + KsA;
      pr[e] += KnI + KsJ + KsA * r * r;
    }
  }
  const bool two = a_.dimension == 2;
  auto mask = [&](std::vector<Vec3>& x, std::vector<Vec3>& t) {  // fixed elements, 2D plane
    for (std::size_t i = 0; i < n; ++i) {
      if (fixed_[i]) x[i] = t[i] = {};
      if (two) x[i].z = 0, t[i].x = t[i].y = 0;
    }
  };
  std::vector<Vec3> x(n), t(n), rx = fext_, rt(n), zx(n), zt(n), px(n), ptt(n), qx, qt;
  mask(rx, rt);
  auto precond = [&]() {
    for (std::size_t i = 0; i < n; ++i) {
      zx[i] = pt[i] > 0 ? rx[i] / pt[i] : Vec3{};
      zt[i] = pr[i] > 0 ? rt[i] / pr[i] : Vec3{};
    }
  };
  auto dotv = [&](const std::vector<Vec3>& a1, const std::vector<Vec3>& a2, const std::vector<Vec3>& b1,
                  const std::vector<Vec3>& b2) {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += dot(a1[i], b1[i]) + dot(a2[i], b2[i]);
    return s;
  };
  precond();
  px = zx, ptt = zt;
  double rz = dotv(rx, rt, zx, zt);
  const double b0 = std::sqrt(dotv(rx, rt, rx, rt));
  int it = 0;
  bool converged = b0 == 0;
  for (; it < max_iter && !converged; ++it) {
    bond_forces(px, ptt, qx, qt);
    for (std::size_t i = 0; i < n; ++i) qx[i] = -qx[i], qt[i] = -qt[i];
    mask(qx, qt);
    const double pq = dotv(px, ptt, qx, qt);
    if (!(pq > 0)) break;  // a mechanism: a piece not held by the fixed zone
    const double alpha = rz / pq;
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += px[i] * alpha;
      t[i] += ptt[i] * alpha;
      rx[i] -= qx[i] * alpha;
      rt[i] -= qt[i] * alpha;
    }
    converged = std::sqrt(dotv(rx, rt, rx, rt)) <= tol * b0;
    precond();
    const double rz1 = dotv(rx, rt, zx, zt);
    const double beta = rz1 / rz;
    rz = rz1;
    for (std::size_t i = 0; i < n; ++i) {
      px[i] = zx[i] + px[i] * beta;
      ptt[i] = zt[i] + ptt[i] * beta;
    }
  }
  u1_ = x;
  th1_ = t;
  unit_ratio_ = stress_ratio(x, t);
  return converged ? it : -1;
}

void System::start_from_static(double lambda0) {
  for (std::size_t i = 0; i < a_.size(); ++i) {
    u_[i] = u1_[i] * lambda0;
    th_[i] = th1_[i] * lambda0;
    v_[i] = w_[i] = {};
  }
}

double System::kinetic_energy() const {
  double e = 0;
  for (std::size_t i = 0; i < a_.size(); ++i) e += 0.5 * (mass_ * dot(v_[i], v_[i]) + rot_inertia_ * dot(w_[i], w_[i]));
  return e;
}

double System::load_work(double lambda) const {
  double w = 0;
  for (std::size_t i = 0; i < a_.size(); ++i) w += lambda * dot(fext_[i], u_[i]);
  return w;
}

// ---------------------------------------------------------------- pieces

Components components(const Array& a, const std::vector<char>& intact) {
  std::vector<int> parent(a.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t b = 0; b < a.bonds.size(); ++b)
    if (intact[b]) {
      const int x = find(a.bonds[b].i), y = find(a.bonds[b].j);
      if (x != y) parent[std::max(x, y)] = std::min(x, y);
    }
  Components c;
  c.label.assign(a.size(), -1);
  std::vector<int> id(a.size(), -1);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const int root = find(static_cast<int>(i));
    if (id[root] < 0) {
      id[root] = c.count++;
      c.size.push_back(0);
    }
    c.label[i] = id[root];
    ++c.size[id[root]];
  }
  return c;
}

int major_count(const Components& c, double min_fraction, long min_elements) {
  long total = 0;
  for (long s : c.size) total += s;
  int k = 0;
  for (long s : c.size)
    if (static_cast<double>(s) >= min_fraction * static_cast<double>(total) && s >= std::max(1L, min_elements)) ++k;
  return k;
}

}  // namespace crumble::bpm
