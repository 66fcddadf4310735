// The linear peridynamic solid (LPS, Zhu & Zhao 2019 eqs. 1–4, influence function 1) on a
// Lattice, with critical-stretch bond breakage and explicit time integration.
//
// Bonds are stored twice. The explicit passes run on a box layout with a half bond list
// (PdKernel.h): every pair bond once, with a factor `alive` = (partial-volume weight) × (0 once
// broken), so the hot loops multiply instead of branching on broken bonds. The lattice's
// CSR lists (each point's full family) carry the same factors for everything else (clusters,
// damage, the linearised passes); they are brought up to date from the box when read.
// A pass adds each bond to both of its points, so blocks are dealt to threads by slabs of
// cells in z, thick enough that two slabs of one colour never touch the same cell; the even
// slabs run first, then the odd ones, whatever the thread count, so every cell receives its
// additions in the same order and results are bitwise independent of the thread count.
#pragma once
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "breakage/peridynamics/PdLattice.h"

namespace crumble::pd {

struct LpsMaterial {
  double bulk = 0;     // K, Pa
  double shear = 0;    // μ, Pa
  double density = 0;  // ρ used in the equation of motion, kg/m³ (may be mass-scaled)
  static LpsMaterial from_young(double young, double poisson, double density);
};

// Zhu & Zhao 2019 eq. 5 (Madenci & Oterkus): critical stretch of the LPS for G_c and horizon δ.
double critical_stretch(double gc, double bulk, double shear, double horizon);

class PdSystem {
 public:
  PdSystem(const Lattice& lattice, const LpsMaterial& mat, double critical_stretch);

  const Lattice& lattice() const { return L_; }
  std::size_t size() const { return L_.size(); }

  // Boundary conditions. Fixed points keep zero displacement and velocity. A load adds
  // `total_force` (N, at load factor 1), spread uniformly over `points`; fixed points get
  // no share (Zhu & Zhao 2019 §3.1: "no force will be applied to material points within the
  // fixed zone").
  void fix(const std::vector<std::int32_t>& points);
  void add_load(const std::vector<std::int32_t>& points, const Vec3& total_force);
  bool is_fixed(std::int32_t i) const { return free_[i] == 0.0; }

  // Largest stable step of the explicit scheme: the Silling–Askari bound (2005) extended
  // to the LPS — a Gershgorin bound on the linearised force operator, so
  // dt <= 2 / ω_max is guaranteed — without any safety factor.
  double stable_dt() const;

  // The same limit estimated from the spectrum: power iteration on the linearised
  // operator gives ω_max (taken 5 % high), dt = 2/ω_max. About 2.2× the Gershgorin bound on
  // the cubic lattice; never more than 3× it.
  double spectral_dt(int iterations = 60, int threads = 1) const;

  // Internal force density f(x) (N/m³) from the current positions; breaks the bonds whose
  // stretch exceeds the critical stretch (Zhu & Zhao 2019 §2.1). `threads` > 1 splits the points.
  void compute_forces(int threads = 1);
  // One step of velocity Verlet in leapfrog form with mass-proportional damping
  // (rate `damping`, 1/s): v ← ((1 − c dt/2) v + dt a) / (1 + c dt/2); x ← x + dt v,
  // a = (f + λ b) / ρ, forces computed at the current positions.
  void step(double dt, double load_factor, double damping, int threads = 1);

  double kinetic_energy() const;              // J (with the density given)
  double external_work_at_rest() const;       // ½ Σ λ b·u V: the elastic energy at equilibrium, J
  long broken_bonds() const;                  // directed CSR entries broken
  long broken_face_bonds() const;
  double displacement(std::int32_t i, int axis) const;
  Vec3 force_density(std::int32_t i) const { return {fx_[i], fy_[i], fz_[i]}; }
  // Apply a displacement field (tests): positions ← reference + u(X).
  template <class F>
  void set_displacement(F&& u) {
    for (std::size_t i = 0; i < size(); ++i) {
      const Vec3 d = u(L_.points[i]);
      pos_[4 * i] = L_.points[i].x + d.x;
      pos_[4 * i + 1] = L_.points[i].y + d.y;
      pos_[4 * i + 2] = L_.points[i].z + d.z;
    }
  }
  // Dilation θ_i (Zhu & Zhao 2019 eq. 4) from the current positions.
  double dilatation(std::int32_t i) const;
  Vec3 current(std::int32_t i) const { return {pos_[4 * i], pos_[4 * i + 1], pos_[4 * i + 2]}; }
  // Partial stress Σ_j t_ij M_ij ⊗ ξ_ij V_j at point i (equals the Cauchy stress for a
  // homogeneous deformation in the bulk), from the current positions.
  Mat3 partial_stress(std::int32_t i) const;

  // Static small-displacement solution for the loads at load factor 1 (conjugate
  // gradients on the linearised LPS operator, fixed points held): the elastic state a
  // slow ramp passes through before the first bond breaks. Returns the displacement
  // (3 per point, x y z interleaved) and sets *iterations.
  std::vector<double> static_unit_solution(double tolerance, int max_iterations, int* iterations,
                                           int threads = 1) const;
  // Smallest load factor at which an intact bond of the static unit solution `u1`
  // reaches the critical stretch (infinity when no bond is stretched).
  double first_break_factor(const std::vector<double>& u1) const;
  // Positions X + scale·u, velocities vscale·u (the quasi-static state of a linear ramp).
  void set_state(const std::vector<double>& u, double scale, double vscale);

  // Per CSR bond: weight, or 0 once broken.
  const std::vector<double>& alive() const {
    sync_alive();
    return alive_;
  }
  double load_factor() const { return lambda_; }

 private:
  struct Field3 {
    std::vector<double> x, y, z;
    void resize(std::size_t n) {
      x.assign(n, 0.0);
      y.assign(n, 0.0);
      z.assign(n, 0.0);
    }
    double dot(const Field3& o) const;
    void axpy(double a, const Field3& o);
  };
  void apply_operator(const Field3& u, Field3& out, int threads) const;
  struct Update {  // one leapfrog step after the forces (step())
    double dt, c1, c2, inv_rho;
  };
  void forces_and_update(int threads, const Update* up);
  // The box layout (box_ below) from the lattice, in steps: the box's extent (its lowest
  // lattice cell lo, origin cell org and nx × ny × nz cells, padded by the bond reach H);
  // the cells' reference positions and the point in each cell (-1: none); the blocks with
  // their bond groups (one group per half-stencil offset d of length len with a bond in one
  // of the block's `lanes` points from p0) and slabs; the slabs' order; the lane counts.
  struct BoxExtent {
    std::array<int, 3> lo, org;
    std::int64_t nx = 0, ny = 0, nz = 0;
  };
  void build_box();
  BoxExtent box_extent(int H) const;
  std::vector<std::int32_t> fill_box_cells(const BoxExtent& e);
  void build_box_blocks(const BoxExtent& e, int H, const std::vector<std::pair<std::array<int, 3>, double>>& half,
                        const std::vector<std::int32_t>& who);
  void add_bond_group(const BoxExtent& e, const std::array<int, 3>& d, double len, std::size_t p0, int lanes,
                      const std::vector<std::int32_t>& who);
  void order_box_slabs();
  void count_box_lanes();
  void sync_alive() const;

  const Lattice& L_;
  LpsMaterial mat_;
  double sc_;
  double lambda_ = 0;
  std::vector<double> rx_, ry_, rz_;  // reference positions
  std::vector<double> pos_;  // per point x, y, z (current, m) and a spare slot (a θ lives in box_.at)
  std::vector<double> vx_, vy_, vz_, fx_, fy_, fz_;
  std::vector<double> bx_, by_, bz_;  // body force density at load factor 1, N/m³
  std::vector<double> free_;          // 1 free, 0 fixed
  std::vector<double> g_;             // 3V/m_i (eq. 4)
  std::vector<double> a_;             // V(3K − 5μ)/m_i
  std::vector<double> b_;             // 15μV/m_i
  mutable std::vector<double> xi_x_, xi_y_, xi_z_;  // per CSR entry: X_j − X_i (the linearised passes)
  mutable std::vector<double> alive_;  // per CSR bond: weight, or 0 once broken (see sync_alive)

  // The box layout of the explicit passes (PdKernel.h BoxView).
  struct Box {
    std::vector<std::int64_t> cell;  // per point: its box cell
    std::vector<double> x, y, z, at, b, th, fx, fy, fz;  // per box cell
    std::vector<std::int64_t> block_cell;
    std::vector<std::int32_t> block_group;
    std::vector<std::int64_t> delta;
    std::vector<double> len;
    std::vector<double> alive, cur;         // 4 per group
    std::vector<std::int32_t> csr;          // 8 per group: the two CSR entries of each lane's bond, or -1
    std::vector<std::int32_t> slab_blocks;  // blocks of slab s: [slab_blocks[s], slab_blocks[s + 1])
    // The even slabs, then the odd ones, each colour heaviest first (most bond groups), handed
    // out one at a time: the threads finish a colour nearly together. (The 2 mm reference
    // sphere's 6 slabs hold 1–29 % of the bond groups each; dealt in z order, one of two
    // threads took 98 % of the odd colour.)
    std::vector<std::int32_t> slab_order[2];
    std::vector<std::uint8_t> lane_entries;  // per lane: its CSR entries (0–2)
    std::vector<std::int32_t> face_lane;     // per directed face bond in the box: its lane
    long broken_outside = 0, face_broken_outside = 0;  // broken CSR entries without a lane
  } box_;
  mutable bool box_broke_ = false;  // a bond broke in the box since alive_ was last brought up to date
};

}  // namespace crumble::pd
