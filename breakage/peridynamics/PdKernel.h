// The LPS hot loops over CSR rows [i0, i1) (Zhu & Zhao 2019 eqs. 1–4, influence function 1).
//
// Positions are stored per point as 4 doubles (x, y, z, aθ): one 32-byte load fetches all
// a neighbour contributes to the force pass. Bond factors `alive` (partial-volume weight,
// 0 once broken) multiply the bond terms instead of a branch. An AVX-512 version
// (explicit 4×4 transposes instead of gathers) is chosen at run time when the CPU has
// it, else auto-vectorised loops. Each row is summed by one call in a fixed order, so a
// split of the rows between threads does not change any bit of the result.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace crumble::pd::kernel {

// Pass 1: breaks bonds whose stretch exceeds sc (alive ← 0) and stores
// pos[4i+3] = a_i θ_i with θ_i = g_i Σ_j alive r e (eq. 4).
void dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                const double* len, double* alive, double* pos, const double* g, const double* a, double sc);

// Pass 2: f_i = Σ_j alive [(a_i θ_i + a_j θ_j) r + (b_i + b_j) e] Y/|Y| (eqs. 1–2), b per point.
void force(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr, const double* len,
           const double* alive, const double* b, const double* pos, double* fx, double* fy, double* fz);

// The portable (auto-vectorised) versions, whatever the CPU; tests compare them with the
// dispatched ones.
void dilatation_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                         const double* len, double* alive, double* pos, const double* g, const double* a, double sc);
void force_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr,
                    const double* len, const double* alive, const double* b, const double* pos, double* fx,
                    double* fy, double* fz);

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
