// The LPS hot loops (Zhu & Zhao 2019 eqs. 1–4, influence function 1).
//
// The explicit passes run on a box layout that PdSystem builds from the lattice:
// positions, aθ, θ and forces as structures of arrays over the lattice's bounding box
// (padded by the horizon; cells outside the grain hold their reference position and take
// no part), the points in blocks of 4 consecutive cells along x, and each pair bond stored
// once (a half bond list), as a 4-lane group: the offset to the neighbour cells, the
// reference length, and per lane the bond factor `alive` (partial-volume weight, 0 once
// broken, 0 for a lane without a bond) and the current length. A block's 4 neighbours at one
// offset are 4 consecutive cells, so one load fetches them with no gather or transpose;
// each bond's length, stretch and force are computed once and added to both of its points.
// Versions: AVX2 and portable, chosen at run time from the CPU, and AVX-512 (two groups of a
// block per 8-lane register) on request (it was not faster where measured); all do the same
// additions in the same order into every cell, so they give bitwise the same results.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace crumble::pd::kernel {

// One box layout: the arrays are indexed by box cell, the groups by block.
struct BoxView {
  const double* x;   // current positions, m
  const double* y;
  const double* z;
  const double* at;  // a θ of the last dilatation pass (pass 2 reads it)
  const double* b;   // 15μV/m per cell (0 outside)
  double* th;        // pass 1 adds Σ alive r e here (zero it before)
  double* fx;        // pass 2 adds the force density here (zero it before)
  double* fy;
  double* fz;
  const std::int64_t* block_cell;  // first cell of each block
  const std::int32_t* block_group;  // groups of block k: [block_group[k], block_group[k+1])
  const std::int64_t* delta;        // per group: neighbour cell − own cell
  const double* len;                // per group: reference length, m
  double* alive;                    // 4 per group
  double* cur;                      // 4 per group: |Y| from pass 1
};

// Pass 1 over blocks [k0, k1): breaks the bonds whose stretch exceeds sc (alive ← 0),
// stores |Y| in cur, adds alive r e to th of both points of every bond (eq. 4 without the
// factor g). Returns true when a bond broke.
bool dilatation(const BoxView& v, std::int32_t k0, std::int32_t k1, double sc);
// Pass 2 over blocks [k0, k1): for every bond t = alive [(a_i θ_i + a_j θ_j) r + (b_i + b_j) e] / |Y|
// (eqs. 1–2), f_i += t Y and f_j −= t Y.
void force(const BoxView& v, std::int32_t k0, std::int32_t k1);

// The portable versions, whatever the CPU; tests compare them with the dispatched ones.
bool dilatation_portable(const BoxView& v, std::int32_t k0, std::int32_t k1, double sc);
void force_portable(const BoxView& v, std::int32_t k0, std::int32_t k1);

// The same two passes linearised about the reference positions for a small displacement
// (ux, uy, uz): e = n·(u_j − u_i), over the CSR lists; (xx, xy, xz) per CSR entry is the bond
// vector ξ = X_j − X_i. Used by the static solve and the spectral step estimate.
void linear_dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                       const double* len, const double* w, const double* xx, const double* xy, const double* xz,
                       const double* ux, const double* uy, const double* uz, const double* g, const double* a,
                       double* at);
void linear_force(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                  const double* len, const double* w, const double* xx, const double* xy, const double* xz,
                  const double* ux, const double* uy, const double* uz, const double* at, const double* b,
                  double* fx, double* fy, double* fz);

// "avx512", "avx2" or "generic": which version of dilatation/force runs (AVX2 when the CPU
// has it, else generic, unless select_isa() chose another). All versions give bitwise the same results.
const char* isa();
// The versions this CPU can run ("generic" always).
std::vector<std::string> available_isas();
// Runs `name` from now on, process-wide (benchmarks, tests); "" returns to the best one.
// std::invalid_argument for an unknown name or one this CPU cannot run.
void select_isa(const std::string& name);

}  // namespace crumble::pd::kernel
