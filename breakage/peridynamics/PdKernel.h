// The LPS hot loops over CSR rows [i0, i1) (Zhu & Zhao 2019 eqs. 1–4, influence function 1).
//
// Positions are stored per point as 4 doubles (x, y, z, aθ): one 32-byte load fetches all
// a neighbour contributes to the force pass. Bond factors `alive` (partial-volume weight,
// 0 once broken) multiply the bond terms instead of a branch. Pass 1 stores each bond's
// current length |Y| in `cur`, so pass 2 takes no square root. Versions: AVX-512 (8 bonds,
// 4×4 transposes instead of gathers), AVX2 (2 × 4 bonds, the same transposes) and portable
// code, chosen at run time from the CPU. Every version sums each row in one fixed 8-lane
// order (PdKernel.cpp), so all of them, and any split of the rows between threads, give
// bitwise the same results.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace crumble::pd::kernel {

// Pass 1: breaks bonds whose stretch exceeds sc (alive ← 0), stores cur[q] = |Y| per bond and
// pos[4i+3] = a_i θ_i with θ_i = g_i Σ_j alive r e (eq. 4).
void dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                const double* len, double* alive, double* cur, double* pos, const double* g, const double* a,
                double sc);

// Pass 2: f_i = Σ_j alive [(a_i θ_i + a_j θ_j) r + (b_i + b_j) e] Y/|Y| (eqs. 1–2), b per point,
// |Y| = cur from pass 1 at the same positions.
void force(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr, const double* len,
           const double* alive, const double* cur, const double* b, const double* pos, double* fx, double* fy,
           double* fz);

// The portable versions, whatever the CPU; tests compare them with the dispatched ones.
void dilatation_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                         const double* len, double* alive, double* cur, double* pos, const double* g,
                         const double* a, double sc);
void force_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                    const double* len, const double* alive, const double* cur, const double* b, const double* pos,
                    double* fx, double* fy, double* fz);

// The same two passes linearised about the reference positions (rx, ry, rz) for a small
// displacement (ux, uy, uz): e = n·(u_j − u_i). Used by the static solve and the
// spectral step estimate.
void linear_dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                       const double* len, const double* w, const double* rx, const double* ry, const double* rz,
                       const double* ux, const double* uy, const double* uz, const double* g, const double* a,
                       double* at);
void linear_force(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                  const double* len, const double* w, const double* rx, const double* ry, const double* rz,
                  const double* ux, const double* uy, const double* uz, const double* at, const double* b,
                  double* fx, double* fy, double* fz);

// "avx512", "avx2" or "generic": which version of dilatation/force runs (the best this CPU
// has, unless select_isa() chose another). All versions give bitwise the same results.
const char* isa();
// The versions this CPU can run ("generic" always).
std::vector<std::string> available_isas();
// Runs `name` from now on, process-wide (benchmarks, tests); "" returns to the best one.
// std::invalid_argument for an unknown name or one this CPU cannot run.
void select_isa(const std::string& name);

}  // namespace crumble::pd::kernel
