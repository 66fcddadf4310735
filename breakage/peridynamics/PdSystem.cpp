#include "breakage/peridynamics/PdSystem.h"
#include "base/Format.h"

#include "breakage/peridynamics/PdKernel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
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
  build_box();
}

namespace {

using HalfOffsets = std::vector<std::pair<std::array<int, 3>, double>>;

// The bond offsets in use (from the CSR: whatever stencil built the lattice), and the
// positive half of them: dz > 0, or dz = 0 and dy > 0, or dz = dy = 0 and dx > 0, each with
// its reference length. Sets H, the largest reach of a bond in cells along an axis.
HalfOffsets half_bond_offsets(const Lattice& L, int& H) {
  std::map<std::array<int, 3>, double> offsets;  // offset → reference length
  H = 0;
  for (std::size_t i = 0; i < L.size(); ++i)
    for (std::int32_t q = L.offsets[i]; q < L.offsets[i + 1]; ++q) {
      const auto& ci = L.cell[i];
      const auto& cj = L.cell[static_cast<std::size_t>(L.neighbours[q])];
      const std::array<int, 3> d{cj[0] - ci[0], cj[1] - ci[1], cj[2] - ci[2]};
      offsets.emplace(d, L.length[q]);
      H = std::max({H, std::abs(d[0]), std::abs(d[1]), std::abs(d[2])});
    }
  HalfOffsets half;
  for (const auto& [d, len] : offsets)
    if (d[2] > 0 || (d[2] == 0 && (d[1] > 0 || (d[1] == 0 && d[0] > 0)))) half.emplace_back(d, len);
  // Ordered by dx first: consecutive bonds of a block then add into cells a row or more
  // apart, not into overlapping runs of 4 (a store still in flight would stall the next load).
  std::stable_sort(half.begin(), half.end(), [](const auto& a, const auto& b) {
    return std::array<int, 3>{a.first[0], a.first[2], a.first[1]} < std::array<int, 3>{b.first[0], b.first[2], b.first[1]};
  });
  return half;
}

// The CSR entry of the bond i → j, or -1 (rows are sorted by neighbour).
std::int32_t csr_entry(const Lattice& L, std::int32_t i, std::int32_t j) {
  const auto* b = L.neighbours.data() + L.offsets[i];
  const auto* e = L.neighbours.data() + L.offsets[i + 1];
  const auto* it = std::lower_bound(b, e, j);
  return it != e && *it == j ? static_cast<std::int32_t>(it - L.neighbours.data()) : -1;
}

}  // namespace

PdSystem::BoxExtent PdSystem::box_extent(int H) const {
  // The box: the lattice's bounding box, padded by the reach H of a bond on every side and by
  // 3 more cells in +x (a block's last lanes may pass the end of its row).
  BoxExtent e;
  e.lo = {INT32_MAX, INT32_MAX, INT32_MAX};
  std::array<int, 3> hi{INT32_MIN, INT32_MIN, INT32_MIN};
  for (const auto& c : L_.cell)
    for (int a = 0; a < 3; ++a) e.lo[a] = std::min(e.lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
  e.org = {e.lo[0] - H, e.lo[1] - H, e.lo[2] - H};
  e.nx = hi[0] - e.lo[0] + 1 + 2 * H + 3;
  e.ny = hi[1] - e.lo[1] + 1 + 2 * H;
  e.nz = hi[2] - e.lo[2] + 1 + 2 * H;
  if (e.nx * e.ny * e.nz > 200'000'000) throw std::invalid_argument("peridynamics: lattice too large for its box layout");
  return e;
}

std::vector<std::int32_t> PdSystem::fill_box_cells(const BoxExtent& e) {
  const std::size_t n = size();
  const auto cell_index = [&](int x, int y, int z) {
    return ((static_cast<std::int64_t>(z) - e.org[2]) * e.ny + (y - e.org[1])) * e.nx + (x - e.org[0]);
  };
  Box& B = box_;
  const std::size_t nbox = static_cast<std::size_t>(e.nx * e.ny * e.nz);
  for (auto* v : {&B.x, &B.y, &B.z, &B.at, &B.b, &B.th, &B.fx, &B.fy, &B.fz}) v->assign(nbox, 0.0);
  for (std::int64_t z = 0; z < e.nz; ++z)  // cells without a point keep their reference position
    for (std::int64_t y = 0; y < e.ny; ++y)
      for (std::int64_t x = 0; x < e.nx; ++x) {
        const std::size_t c = static_cast<std::size_t>((z * e.ny + y) * e.nx + x);
        B.x[c] = static_cast<double>(x + e.org[0]) * L_.spacing;
        B.y[c] = static_cast<double>(y + e.org[1]) * L_.spacing;
        B.z[c] = static_cast<double>(z + e.org[2]) * L_.spacing;
      }
  std::vector<std::int32_t> who(nbox, -1);
  B.cell.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    B.cell[i] = cell_index(L_.cell[i][0], L_.cell[i][1], L_.cell[i][2]);
    who[static_cast<std::size_t>(B.cell[i])] = static_cast<std::int32_t>(i);
    B.b[static_cast<std::size_t>(B.cell[i])] = b_[i];
  }
  return who;
}

void PdSystem::build_box_blocks(const BoxExtent& e, int H, const HalfOffsets& half, const std::vector<std::int32_t>& who) {
  // Blocks: runs of 4 cells along x from the start of each row segment (points are sorted
  // z, y, x). Slabs of T >= H cells in z, so a slab's additions reach only itself and the next.
  const std::size_t n = size();
  const int T = std::max(H, 1);
  Box& B = box_;
  B.block_cell.clear();
  B.block_group.assign(1, 0);
  B.delta.clear();
  B.len.clear();
  B.alive.clear();
  B.csr.clear();
  B.slab_blocks.assign(1, 0);
  int slab = 0;
  for (std::size_t i = 0; i < n;) {
    std::size_t j = i;
    while (j + 1 < n && L_.cell[j + 1][1] == L_.cell[i][1] && L_.cell[j + 1][2] == L_.cell[i][2] &&
           L_.cell[j + 1][0] == L_.cell[j][0] + 1)
      ++j;
    const int s = (L_.cell[i][2] - e.lo[2]) / T;
    while (slab < s) B.slab_blocks.push_back(static_cast<std::int32_t>(B.block_cell.size())), ++slab;
    for (std::size_t p0 = i; p0 <= j; p0 += 4) {
      const int lanes = static_cast<int>(std::min<std::size_t>(4, j - p0 + 1));
      for (const auto& [d, len] : half) add_bond_group(e, d, len, p0, lanes, who);
      B.block_cell.push_back(B.cell[p0]);
      B.block_group.push_back(static_cast<std::int32_t>(B.delta.size()));
    }
    i = j + 1;
  }
  B.slab_blocks.push_back(static_cast<std::int32_t>(B.block_cell.size()));
}

void PdSystem::add_bond_group(const BoxExtent& e, const std::array<int, 3>& d, double len, std::size_t p0, int lanes,
                              const std::vector<std::int32_t>& who) {
  Box& B = box_;
  const std::int64_t c = B.cell[p0];
  const std::int64_t dc = (static_cast<std::int64_t>(d[2]) * e.ny + d[1]) * e.nx + d[0];
  double al[4] = {0, 0, 0, 0};
  std::int32_t qq[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
  bool any = false;
  for (int l = 0; l < lanes; ++l) {
    const auto pi = static_cast<std::int32_t>(p0 + l);
    const std::int32_t pj = who[static_cast<std::size_t>(c + l + dc)];
    if (pj < 0) continue;
    const std::int32_t qij = csr_entry(L_, pi, pj), qji = csr_entry(L_, pj, pi);
    if (qij < 0 || qji < 0) continue;
    al[l] = alive_[qij];
    qq[2 * l] = qij;
    qq[2 * l + 1] = qji;
    any = true;
  }
  if (!any) return;
  B.delta.push_back(dc);
  B.len.push_back(len);
  B.alive.insert(B.alive.end(), al, al + 4);
  B.csr.insert(B.csr.end(), qq, qq + 8);
}

void PdSystem::order_box_slabs() {
  Box& B = box_;
  const auto slab_groups = [&B](std::int32_t s) {
    return B.block_group[static_cast<std::size_t>(B.slab_blocks[static_cast<std::size_t>(s) + 1])] -
           B.block_group[static_cast<std::size_t>(B.slab_blocks[static_cast<std::size_t>(s)])];
  };
  for (int parity = 0; parity < 2; ++parity) {
    auto& order = B.slab_order[parity];
    order.clear();
    for (auto s = static_cast<std::int32_t>(parity); s + 1 < static_cast<std::int32_t>(B.slab_blocks.size()); s += 2)
      order.push_back(s);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::int32_t a, std::int32_t b) { return slab_groups(a) > slab_groups(b); });
  }
}

void PdSystem::count_box_lanes() {
  // The broken-bond counts read the box's lanes, so a check needs no sync_alive(): per lane its
  // number of CSR entries, per directed face bond its lane, and the entries outside the box
  // (they never change) counted once here.
  Box& B = box_;
  std::vector<std::int32_t> lane_of(alive_.size(), -1);
  B.lane_entries.assign(B.alive.size(), 0);
  for (std::size_t k = 0; k < B.alive.size(); ++k)
    for (int e = 0; e < 2; ++e)
      if (const std::int32_t q = B.csr[2 * k + e]; q >= 0) {
        lane_of[static_cast<std::size_t>(q)] = static_cast<std::int32_t>(k);
        ++B.lane_entries[k];
      }
  B.broken_outside = 0;
  for (std::size_t q = 0; q < alive_.size(); ++q) B.broken_outside += lane_of[q] < 0 && alive_[q] == 0.0;
  B.face_lane.clear();
  B.face_broken_outside = 0;
  for (std::size_t i = 0; i < size(); ++i)
    for (auto q : L_.face_bond[i]) {
      if (q < 0) continue;
      if (const std::int32_t l = lane_of[static_cast<std::size_t>(q)]; l >= 0)
        B.face_lane.push_back(l);
      else
        B.face_broken_outside += alive_[static_cast<std::size_t>(q)] == 0.0;
    }
}

void PdSystem::build_box() {
  int H = 0;
  const HalfOffsets half = half_bond_offsets(L_, H);
  const BoxExtent e = box_extent(H);
  const std::vector<std::int32_t> who = fill_box_cells(e);
  build_box_blocks(e, H, half, who);
  order_box_slabs();
  if (box_.delta.size() > static_cast<std::size_t>(INT32_MAX / 8))
    throw std::invalid_argument("peridynamics: too many bonds for the box layout");
  box_.cur.assign(box_.alive.size(), 0.0);
  count_box_lanes();
}

void PdSystem::sync_alive() const {
  if (!box_broke_) return;
  for (std::size_t k = 0; k < box_.alive.size(); ++k)
    if (box_.alive[k] == 0.0)
      for (int e = 0; e < 2; ++e)
        if (const std::int32_t q = box_.csr[2 * k + e]; q >= 0) alive_[static_cast<std::size_t>(q)] = 0.0;
  box_broke_ = false;
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

void PdSystem::compute_forces(int threads) { forces_and_update(threads, nullptr); }

void PdSystem::forces_and_update(int threads, const Update* up) {
  threads = std::max(1, threads);
  const std::size_t n = size();
  Box& B = box_;
  const kernel::BoxView v{B.x.data(), B.y.data(), B.z.data(), B.at.data(), B.b.data(), B.th.data(),
                          B.fx.data(), B.fy.data(), B.fz.data(), B.block_cell.data(), B.block_group.data(),
                          B.delta.data(), B.len.data(), B.alive.data(), B.cur.data()};
  const std::int32_t* sb = B.slab_blocks.data();
  const auto points = static_cast<std::int64_t>(n);
  bool broke = false;
  // Even slabs, then odd ones: the same order of additions into every cell for any thread count
  // (slabs of one colour touch disjoint cells, so which thread takes which does not matter).
  // Everything else is per point, so the whole step runs in one parallel region.
  const std::int32_t* order[2] = {B.slab_order[0].data(), B.slab_order[1].data()};
  const int n_colour[2] = {static_cast<int>(B.slab_order[0].size()), static_cast<int>(B.slab_order[1].size())};
#pragma omp parallel num_threads(threads) if (threads > 1) reduction(|| : broke)
  {
#pragma omp for schedule(static)
    for (std::int64_t ii = 0; ii < points; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const auto c = static_cast<std::size_t>(B.cell[i]);
      B.x[c] = pos_[4 * i];
      B.y[c] = pos_[4 * i + 1];
      B.z[c] = pos_[4 * i + 2];
      B.th[c] = B.fx[c] = B.fy[c] = B.fz[c] = 0.0;
    }
    for (int parity = 0; parity < 2; ++parity) {
#pragma omp for schedule(dynamic, 1)
      for (int k = 0; k < n_colour[parity]; ++k) {
        const std::int32_t s = order[parity][k];
        broke = kernel::dilatation(v, sb[s], sb[s + 1], sc_) || broke;
      }
    }
#pragma omp for schedule(static)
    for (std::int64_t i = 0; i < points; ++i) {  // Zhu & Zhao 2019 eq. 4: θ_i = g_i Σ; stored as a_i θ_i
      const auto c = static_cast<std::size_t>(B.cell[static_cast<std::size_t>(i)]);
      B.at[c] = a_[static_cast<std::size_t>(i)] * g_[static_cast<std::size_t>(i)] * B.th[c];
    }
    for (int parity = 0; parity < 2; ++parity) {
#pragma omp for schedule(dynamic, 1)
      for (int k = 0; k < n_colour[parity]; ++k) {
        const std::int32_t s = order[parity][k];
        kernel::force(v, sb[s], sb[s + 1]);
      }
    }
#pragma omp for schedule(static)
    for (std::int64_t ii = 0; ii < points; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const auto c = static_cast<std::size_t>(B.cell[i]);
      fx_[i] = B.fx[c];
      fy_[i] = B.fy[c];
      fz_[i] = B.fz[c];
      if (up) {  // velocity Verlet, leapfrog form (step())
        const double m = free_[i], dt = up->dt, c1 = up->c1, c2 = up->c2, lambda = lambda_;
        vx_[i] = m * c2 * (c1 * vx_[i] + dt * (fx_[i] + lambda * bx_[i]) * up->inv_rho);
        vy_[i] = m * c2 * (c1 * vy_[i] + dt * (fy_[i] + lambda * by_[i]) * up->inv_rho);
        vz_[i] = m * c2 * (c1 * vz_[i] + dt * (fz_[i] + lambda * bz_[i]) * up->inv_rho);
        pos_[4 * i] += dt * vx_[i];
        pos_[4 * i + 1] += dt * vy_[i];
        pos_[4 * i + 2] += dt * vz_[i];
      }
    }
  }
  if (broke) box_broke_ = true;
}

void PdSystem::step(double dt, double lambda, double damping, int threads) {
  lambda_ = lambda;
  const Update up{dt, 1.0 - 0.5 * damping * dt, 1.0 / (1.0 + 0.5 * damping * dt), 1.0 / mat_.density};
  forces_and_update(threads, &up);
}

void PdSystem::apply_operator(const Field3& u, Field3& out, int threads) const {
  // out = −f_lin(u) on free points, 0 on fixed ones: the stiffness operator (per unit
  // volume) of the small-displacement problem.
  sync_alive();
  const std::int32_t n = static_cast<std::int32_t>(size());
  const std::int32_t* off = L_.offsets.data();
  const std::int32_t* nbr = L_.neighbours.data();
  const double* len = L_.length.data();
  const double* w = alive_.data();
  if (xi_x_.size() != L_.neighbours.size()) {  // bond vectors ξ = X_j − X_i per CSR entry, once
    xi_x_.resize(L_.neighbours.size());
    xi_y_.resize(L_.neighbours.size());
    xi_z_.resize(L_.neighbours.size());
    for (std::int32_t i = 0; i < n; ++i)
      for (std::int32_t q = off[i]; q < off[i + 1]; ++q) {
        const auto j = static_cast<std::size_t>(nbr[q]);
        xi_x_[static_cast<std::size_t>(q)] = rx_[j] - rx_[static_cast<std::size_t>(i)];
        xi_y_[static_cast<std::size_t>(q)] = ry_[j] - ry_[static_cast<std::size_t>(i)];
        xi_z_[static_cast<std::size_t>(q)] = rz_[j] - rz_[static_cast<std::size_t>(i)];
      }
  }
  std::vector<double> at(n);
  out.resize(n);
  const std::int32_t chunk = 64, blocks = (n + chunk - 1) / chunk;
#pragma omp parallel num_threads(std::max(1, threads)) if (threads > 1)
  {
#pragma omp for schedule(static)
    for (std::int32_t k = 0; k < blocks; ++k)
      kernel::linear_dilatation(k * chunk, std::min(n, (k + 1) * chunk), off, nbr, len, w, xi_x_.data(),
                                xi_y_.data(), xi_z_.data(), u.x.data(), u.y.data(), u.z.data(), g_.data(), a_.data(),
                                at.data());
#pragma omp for schedule(static)
    for (std::int32_t k = 0; k < blocks; ++k)
      kernel::linear_force(k * chunk, std::min(n, (k + 1) * chunk), off, nbr, len, w, xi_x_.data(), xi_y_.data(),
                           xi_z_.data(),
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
  sync_alive();
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
  long k = box_.broken_outside;
  for (std::size_t l = 0; l < box_.alive.size(); ++l) k += box_.alive[l] == 0.0 ? box_.lane_entries[l] : 0;
  return k;
}

long PdSystem::broken_face_bonds() const {
  long k = box_.face_broken_outside;
  for (const auto l : box_.face_lane) k += box_.alive[static_cast<std::size_t>(l)] == 0.0;
  return k;
}

double PdSystem::displacement(std::int32_t i, int axis) const {
  const double ref = axis == 0 ? rx_[i] : axis == 1 ? ry_[i] : rz_[i];
  return pos_[4 * static_cast<std::size_t>(i) + std::clamp(axis, 0, 2)] - ref;
}

double PdSystem::dilatation(std::int32_t i) const {
  sync_alive();
  double acc = 0;
  for (std::int32_t q = L_.offsets[i]; q < L_.offsets[i + 1]; ++q) {
    const Vec3 Y = current(L_.neighbours[q]) - current(i);
    acc += alive_[q] * L_.length[q] * (norm(Y) - L_.length[q]);
  }
  return g_[i] * acc;
}

Mat3 PdSystem::partial_stress(std::int32_t i) const {
  sync_alive();
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
