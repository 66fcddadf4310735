#include "breakage/peridynamics/PdSystem.h"
#include "geometry/Format.h"

#include "breakage/peridynamics/PdKernel.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace crumble::pd {

LpsMaterial LpsMaterial::from_young(double young, double poisson, double density) {
  if (!(young > 0) || !std::isfinite(young))
    throw std::invalid_argument("peridynamics: Young's modulus must be > 0, got " + fmt_num(young));
  if (!(poisson > -1.0 && poisson < 0.5))
    throw std::invalid_argument("peridynamics: Poisson's ratio must lie in (-1, 0.5), got " + fmt_num(poisson));
  if (!(density > 0) || !std::isfinite(density))
    throw std::invalid_argument("peridynamics: density must be > 0, got " + fmt_num(density));
  return {young / (3.0 * (1.0 - 2.0 * poisson)), young / (2.0 * (1.0 + poisson)), density};
}

double critical_stretch(double gc, double K, double mu, double horizon) {
  // Zhu & Zhao 2019 eq. 5
  const double denom = (3.0 * mu + std::pow(0.75, 4) * (K - 5.0 * mu / 3.0)) * horizon;
  if (!(gc > 0) || !std::isfinite(gc))
    throw std::invalid_argument("peridynamics: critical energy release rate G_c must be > 0, got " +
                                fmt_num(gc));
  if (!(denom > 0)) throw std::invalid_argument("peridynamics: eq. 5 has no real critical stretch for this K, μ");
  return std::sqrt(gc / denom);
}

PdSystem::PdSystem(const Lattice& lattice, const LpsMaterial& mat, double critical_stretch)
    : L_(lattice), mat_(mat), sc_(critical_stretch) {
  if (!(mat.bulk > 0) || !(mat.shear > 0) || !(mat.density > 0))
    throw std::invalid_argument("peridynamics: material needs K, μ, ρ > 0");
  if (!(critical_stretch > 0)) throw std::invalid_argument("peridynamics: critical stretch must be > 0");
  const std::size_t n = L_.size();
  const double V = L_.point_volume;
  rx_.resize(n);
  ry_.resize(n);
  rz_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    rx_[i] = L_.points[i].x;
    ry_[i] = L_.points[i].y;
    rz_[i] = L_.points[i].z;
  }
  pos_.assign(4 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    pos_[4 * i] = rx_[i];
    pos_[4 * i + 1] = ry_[i];
    pos_[4 * i + 2] = rz_[i];
  }
  for (auto* v : {&vx_, &vy_, &vz_, &fx_, &fy_, &fz_, &bx_, &by_, &bz_, &g_, &a_, &b_}) v->assign(n, 0.0);
  free_.assign(n, 1.0);
  alive_ = L_.weight;
  cur_.assign(alive_.size(), 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    // Zhu & Zhao 2019 eq. 3: weighted volume m = Σ ω |ξ|² V_j (ω = 1; V_j with its partial-volume weight)
    double m = 0;
    for (std::int32_t q = L_.offsets[i]; q < L_.offsets[i + 1]; ++q) m += L_.weight[q] * L_.length[q] * L_.length[q];
    m *= V;
    if (m > 0) {
      g_[i] = 3.0 * V / m;
      a_[i] = V * (3.0 * mat_.bulk - 5.0 * mat_.shear) / m;
      b_[i] = 15.0 * mat_.shear * V / m;
    }
  }
}

void PdSystem::fix(const std::vector<std::int32_t>& pts) {
  for (auto i : pts) {
    free_.at(i) = 0.0;
    bx_[i] = by_[i] = bz_[i] = 0;
  }
}

void PdSystem::add_load(const std::vector<std::int32_t>& pts, const Vec3& F) {
  std::vector<std::int32_t> loaded;
  for (auto i : pts)
    if (free_.at(i) != 0.0) loaded.push_back(i);
  if (loaded.empty()) return;
  // Force per point F/n, as a force density over the point volume.
  const Vec3 b = F / (static_cast<double>(loaded.size()) * L_.point_volume);
  for (auto i : loaded) {
    bx_[i] += b.x;
    by_[i] += b.y;
    bz_[i] += b.z;
  }
}

double PdSystem::stable_dt() const {
  // Linearised LPS operator: f_i = Σ_j w_ij [(a_i θ_i + a_j θ_j) r_ij + (b_i + b_j) e_ij] n_ij
  // with e_ij = n_ij·(u_j − u_i) and θ_i = g_i Σ_k w_ik r_ik e_ik. Row sums of the absolute
  // 3×3 blocks: the e-term gives 2 Σ_j w (b_i + b_j); ∂θ_i/∂u sums to at most 2 g_i S_i with
  // S_i = Σ_k w_ik r_ik, so the θ-terms give Σ_j w r (|a_i| 2 g_i S_i + |a_j| 2 g_j S_j).
  // Verlet is stable for dt < 2/ω_max and ω_max² <= max_i row_i / ρ (Gershgorin), the
  // argument of Silling & Askari (2005) for the bond-based model.
  const std::size_t n = size();
  std::vector<double> gs(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    double S = 0;
    for (std::int32_t q = L_.offsets[i]; q < L_.offsets[i + 1]; ++q) S += L_.weight[q] * L_.length[q];
    gs[i] = std::abs(a_[i]) * 2.0 * g_[i] * S;
  }
  double worst = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double row = 0;
    for (std::int32_t q = L_.offsets[i]; q < L_.offsets[i + 1]; ++q) {
      const std::int32_t j = L_.neighbours[q];
      row += L_.weight[q] * (2.0 * (b_[i] + b_[j]) + L_.length[q] * (gs[i] + gs[j]));
    }
    worst = std::max(worst, row);
  }
  if (!(worst > 0)) throw std::invalid_argument("peridynamics: lattice has no bonds");
  return 2.0 * std::sqrt(mat_.density / worst);
}

void PdSystem::compute_forces(int threads) {
  const std::int32_t n = static_cast<std::int32_t>(size());
  const std::int32_t* off = L_.offsets.data();
  const std::int32_t* nbr = L_.neighbours.data();
  const double* len = L_.length.data();
  threads = std::max(1, threads);
  if (threads == 1) {
    kernel::dilatation(0, n, off, nbr, len, alive_.data(), cur_.data(), pos_.data(), g_.data(), a_.data(), sc_);
    kernel::force(0, n, off, nbr, len, alive_.data(), cur_.data(), b_.data(), pos_.data(), fx_.data(), fy_.data(), fz_.data());
    return;
  }
  // Blocks of rows per thread; each row is computed exactly as in the serial call.
  const std::int32_t chunk = 64;
  const std::int32_t blocks = (n + chunk - 1) / chunk;
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(static)
    for (std::int32_t k = 0; k < blocks; ++k)
      kernel::dilatation(k * chunk, std::min(n, (k + 1) * chunk), off, nbr, len, alive_.data(), cur_.data(), pos_.data(), g_.data(),
                         a_.data(), sc_);
#pragma omp for schedule(static)
    for (std::int32_t k = 0; k < blocks; ++k)
      kernel::force(k * chunk, std::min(n, (k + 1) * chunk), off, nbr, len, alive_.data(), cur_.data(), b_.data(), pos_.data(),
                    fx_.data(), fy_.data(), fz_.data());
  }
}

void PdSystem::step(double dt, double lambda, double damping, int threads) {
  lambda_ = lambda;
  compute_forces(threads);
  const std::size_t n = size();
  const double inv_rho = 1.0 / mat_.density;
  const double c1 = 1.0 - 0.5 * damping * dt, c2 = 1.0 / (1.0 + 0.5 * damping * dt);
  for (std::size_t i = 0; i < n; ++i) {
    const double m = free_[i];
    vx_[i] = m * c2 * (c1 * vx_[i] + dt * (fx_[i] + lambda * bx_[i]) * inv_rho);
    vy_[i] = m * c2 * (c1 * vy_[i] + dt * (fy_[i] + lambda * by_[i]) * inv_rho);
    vz_[i] = m * c2 * (c1 * vz_[i] + dt * (fz_[i] + lambda * bz_[i]) * inv_rho);
    pos_[4 * i] += dt * vx_[i];
    pos_[4 * i + 1] += dt * vy_[i];
    pos_[4 * i + 2] += dt * vz_[i];
  }
}

void PdSystem::apply_operator(const Field3& u, Field3& out, int threads) const {
  // out = −f_lin(u) on free points, 0 on fixed ones: the stiffness operator (per unit
  // volume) of the small-displacement problem.
  const std::int32_t n = static_cast<std::int32_t>(size());
  const std::int32_t* off = L_.offsets.data();
  const std::int32_t* nbr = L_.neighbours.data();
  const double* len = L_.length.data();
  const double* w = alive_.data();
  std::vector<double> at(n);
  out.resize(n);
  const std::int32_t chunk = 64, blocks = (n + chunk - 1) / chunk;
#pragma omp parallel num_threads(std::max(1, threads)) if (threads > 1)
  {
#pragma omp for schedule(static)
    for (std::int32_t k = 0; k < blocks; ++k)
      kernel::linear_dilatation(k * chunk, std::min(n, (k + 1) * chunk), off, nbr, len, w, rx_.data(), ry_.data(),
                             rz_.data(), u.x.data(), u.y.data(), u.z.data(), g_.data(), a_.data(), at.data());
#pragma omp for schedule(static)
    for (std::int32_t k = 0; k < blocks; ++k)
      kernel::linear_force(k * chunk, std::min(n, (k + 1) * chunk), off, nbr, len, w, rx_.data(), ry_.data(), rz_.data(),
                        u.x.data(), u.y.data(), u.z.data(), at.data(), b_.data(), out.x.data(), out.y.data(),
                        out.z.data());
  }
  for (std::int32_t i = 0; i < n; ++i) {
    out.x[i] *= -free_[i];
    out.y[i] *= -free_[i];
    out.z[i] *= -free_[i];
  }
}

double PdSystem::Field3::dot(const Field3& o) const {
  double s = 0;
  for (std::size_t i = 0; i < x.size(); ++i) s += x[i] * o.x[i] + y[i] * o.y[i] + z[i] * o.z[i];
  return s;
}

void PdSystem::Field3::axpy(double a, const Field3& o) {
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] += a * o.x[i];
    y[i] += a * o.y[i];
    z[i] += a * o.z[i];
  }
}

std::vector<double> PdSystem::static_unit_solution(double tol, int max_iter, int* iterations, int threads) const {
  // Conjugate gradients on A u = b with A u = −f_lin(u): A is symmetric (the LPS derives
  // from an energy; every point has the same volume) and positive definite once the fixed
  // zone removes the rigid motions. Fixed points are held at u = 0.
  const std::size_t n = size();
  Field3 u, r, p, ap;
  u.resize(n);
  r.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    r.x[i] = free_[i] * bx_[i];
    r.y[i] = free_[i] * by_[i];
    r.z[i] = free_[i] * bz_[i];
  }
  p = r;
  const double bnorm = std::sqrt(r.dot(r));
  double rs = bnorm * bnorm;
  int it = 0;
  while (bnorm > 0 && it < max_iter && std::sqrt(rs) > tol * bnorm) {
    ++it;
    apply_operator(p, ap, threads);
    const double pap = p.dot(ap);
    if (!(pap > 0)) break;  // not positive definite along p (a load on an unconstrained piece)
    const double alpha = rs / pap;
    u.axpy(alpha, p);
    r.axpy(-alpha, ap);
    const double rs_new = r.dot(r);
    const double beta = rs_new / rs;
    rs = rs_new;
    for (std::size_t i = 0; i < n; ++i) {
      p.x[i] = r.x[i] + beta * p.x[i];
      p.y[i] = r.y[i] + beta * p.y[i];
      p.z[i] = r.z[i] + beta * p.z[i];
    }
  }
  if (iterations) *iterations = it;
  std::vector<double> out(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    out[3 * i] = u.x[i];
    out[3 * i + 1] = u.y[i];
    out[3 * i + 2] = u.z[i];
  }
  return out;
}

double PdSystem::spectral_dt(int iterations, int threads) const {
  // Power iteration for the largest eigenvalue ω² ρ of the operator, from a fixed
  // pseudo-random start (deterministic). The Rayleigh quotient approaches ω_max² from
  // below; it is taken with a 5 % margin on ω before the caller's safety factor.
  const std::size_t n = size();
  Field3 v, av;
  v.resize(n);
  std::uint64_t z = 0x9E3779B97F4A7C15ull;
  auto next = [&z] {
    z ^= z << 13;
    z ^= z >> 7;
    z ^= z << 17;
    return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0) - 0.5;
  };
  for (std::size_t i = 0; i < n; ++i) {
    v.x[i] = free_[i] * next();
    v.y[i] = free_[i] * next();
    v.z[i] = free_[i] * next();
  }
  double lambda = 0;
  for (int k = 0; k < iterations; ++k) {
    const double vv = v.dot(v);
    if (!(vv > 0)) break;
    apply_operator(v, av, threads);
    lambda = std::max(lambda, v.dot(av) / vv);
    const double s = 1.0 / std::sqrt(av.dot(av));
    for (std::size_t i = 0; i < n; ++i) {
      v.x[i] = av.x[i] * s;
      v.y[i] = av.y[i] * s;
      v.z[i] = av.z[i] * s;
    }
  }
  if (!(lambda > 0)) return stable_dt();
  const double omega = 1.05 * std::sqrt(lambda / mat_.density);
  return std::min(2.0 / omega, 3.0 * stable_dt());
}

double PdSystem::first_break_factor(const std::vector<double>& u) const {
  double lambda = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < size(); ++i)
    for (std::int32_t q = L_.offsets[i]; q < L_.offsets[i + 1]; ++q) {
      if (alive_[q] == 0.0) continue;
      const std::size_t j = static_cast<std::size_t>(L_.neighbours[q]);
      const double r = L_.length[q];
      const double e = ((rx_[j] - rx_[i]) * (u[3 * j] - u[3 * i]) + (ry_[j] - ry_[i]) * (u[3 * j + 1] - u[3 * i + 1]) +
                        (rz_[j] - rz_[i]) * (u[3 * j + 2] - u[3 * i + 2])) / r;
      if (e > 0) lambda = std::min(lambda, sc_ * r / e);
    }
  return lambda;
}

void PdSystem::set_state(const std::vector<double>& u, double scale, double vscale) {
  for (std::size_t i = 0; i < size(); ++i) {
    pos_[4 * i] = rx_[i] + scale * u[3 * i];
    pos_[4 * i + 1] = ry_[i] + scale * u[3 * i + 1];
    pos_[4 * i + 2] = rz_[i] + scale * u[3 * i + 2];
    vx_[i] = free_[i] * vscale * u[3 * i];
    vy_[i] = free_[i] * vscale * u[3 * i + 1];
    vz_[i] = free_[i] * vscale * u[3 * i + 2];
  }
}

double PdSystem::kinetic_energy() const {
  double s = 0;
  for (std::size_t i = 0; i < size(); ++i) s += vx_[i] * vx_[i] + vy_[i] * vy_[i] + vz_[i] * vz_[i];
  return 0.5 * mat_.density * L_.point_volume * s;
}

double PdSystem::external_work_at_rest() const {
  double s = 0;
  for (std::size_t i = 0; i < size(); ++i)
    s += bx_[i] * (pos_[4 * i] - rx_[i]) + by_[i] * (pos_[4 * i + 1] - ry_[i]) + bz_[i] * (pos_[4 * i + 2] - rz_[i]);
  return 0.5 * lambda_ * s * L_.point_volume;
}

long PdSystem::broken_bonds() const {
  long k = 0;
  for (std::size_t q = 0; q < alive_.size(); ++q) k += alive_[q] == 0.0;
  return k;
}

long PdSystem::broken_face_bonds() const {
  long k = 0;
  for (std::size_t i = 0; i < size(); ++i)
    for (auto q : L_.face_bond[i]) k += q >= 0 && alive_[q] == 0.0;
  return k;
}

double PdSystem::displacement(std::int32_t i, int axis) const {
  const double ref = axis == 0 ? rx_[i] : axis == 1 ? ry_[i] : rz_[i];
  return pos_[4 * static_cast<std::size_t>(i) + std::clamp(axis, 0, 2)] - ref;
}

double PdSystem::dilatation(std::int32_t i) const {
  double acc = 0;
  for (std::int32_t q = L_.offsets[i]; q < L_.offsets[i + 1]; ++q) {
    const Vec3 Y = current(L_.neighbours[q]) - current(i);
    acc += alive_[q] * L_.length[q] * (norm(Y) - L_.length[q]);
  }
  return g_[i] * acc;
}

Mat3 PdSystem::partial_stress(std::int32_t i) const {
  // θ_i from the current positions (eq. 4), then Σ_j w V t_ij M ⊗ ξ.
  const double ati = a_[i] * dilatation(i);
  Mat3 s = Mat3::zero();
  for (std::int32_t q = L_.offsets[i]; q < L_.offsets[i + 1]; ++q) {
    const std::int32_t j = L_.neighbours[q];
    const Vec3 Y = current(j) - current(i);
    const double l = norm(Y), r = L_.length[q];
    const double t = alive_[q] * (ati * r + b_[i] * (l - r));
    s += Mat3::outer(Y / l, L_.points[j] - L_.points[i]) * t;
  }
  return s;
}

}  // namespace crumble::pd
