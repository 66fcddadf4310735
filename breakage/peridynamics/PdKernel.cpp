// Compiled with -fno-math-errno (sqrt vectorises) and -ffp-contract=off (no FMA
// contraction: both directed copies of a bond see bitwise the same length in every code
// path, so a bond breaks in both lists at the same step).
#include "breakage/peridynamics/PdKernel.h"

#include <algorithm>
#include <cmath>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define CRUMBLE_PD_HAVE_AVX512 1
// GCC 12's own avx512fintrin.h trips -Wmaybe-uninitialized in _mm512_insertf64x4 (GCC PR 105593).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

// The bond helpers below must be inlined into every clone to be compiled for its ISA.
#if defined(__GNUC__)
#define CRUMBLE_PD_INLINE inline __attribute__((always_inline))
#else
#define CRUMBLE_PD_INLINE inline
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CRUMBLE_PD_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define CRUMBLE_PD_CLONES
#endif

namespace crumble::pd::kernel {

// One bond, shared by the portable loops and the scalar tails of the AVX-512 ones.
struct Bond {
  double dx, dy, dz, l;
};
CRUMBLE_PD_INLINE Bond bond(const double* pos, std::int32_t j, double xi, double yi, double zi) {
  const double dx = pos[4 * j] - xi, dy = pos[4 * j + 1] - yi, dz = pos[4 * j + 2] - zi;
  return {dx, dy, dz, std::sqrt(dx * dx + dy * dy + dz * dz)};
}
// Critical stretch (Zhu & Zhao 2019 §2.1): a bond stretched beyond sc is broken for good.
CRUMBLE_PD_INLINE double keep(double e, double r, double sc, double alive) { return e <= sc * r ? alive : 0.0; }
// Pass-2 bond scale: alive [(a_i θ_i + a_j θ_j) r + kb e] / |Y| (|Y| bounded away from 0).
CRUMBLE_PD_INLINE double force_scale(double alive, double ati, double atj, double r, double kb, double l) {
  return alive * ((ati + atj) * r + kb * (l - r)) / std::max(l, 1e-3 * r);
}

// Bonds [q, q1) of point i (position xi, yi, zi): pass 1 returns Σ alive r e after the
// breakage check; pass 2 adds Σ scale·Y to s[0..2].
CRUMBLE_PD_INLINE double dilatation_bonds(std::int32_t q, std::int32_t q1, const std::int32_t* __restrict nbr,
                               const double* __restrict len, double* __restrict alive, const double* __restrict pos,
                               double xi, double yi, double zi, double sc) {
  double acc = 0;
#pragma omp simd reduction(+ : acc)
  for (std::int32_t k = q; k < q1; ++k) {
    const double r = len[k];
    const double e = bond(pos, nbr[k], xi, yi, zi).l - r;
    const double w = keep(e, r, sc, alive[k]);
    alive[k] = w;
    acc += w * r * e;
  }
  return acc;
}

CRUMBLE_PD_INLINE void force_bonds(std::int32_t q, std::int32_t q1, const std::int32_t* __restrict nbr,
                        const double* __restrict len, const double* __restrict alive, const double* __restrict kb,
                        const double* __restrict pos, double xi, double yi, double zi, double ati, double* s) {
  double sx = 0, sy = 0, sz = 0;
#pragma omp simd reduction(+ : sx, sy, sz)
  for (std::int32_t k = q; k < q1; ++k) {
    const std::int32_t j = nbr[k];
    const Bond y = bond(pos, j, xi, yi, zi);
    const double f = force_scale(alive[k], ati, pos[4 * j + 3], len[k], kb[k], y.l);
    sx += f * y.dx;
    sy += f * y.dy;
    sz += f * y.dz;
  }
  s[0] += sx;
  s[1] += sy;
  s[2] += sz;
}

// ---- portable versions (auto-vectorised; AVX2 and baseline clones) ----

CRUMBLE_PD_CLONES
void dilatation_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                        const std::int32_t* __restrict nbr, const double* __restrict len, double* __restrict alive,
                        double* __restrict pos, const double* __restrict g, const double* __restrict a, double sc) {
  for (std::int32_t i = i0; i < i1; ++i) {
    const double acc = dilatation_bonds(off[i], off[i + 1], nbr, len, alive, pos, pos[4 * i], pos[4 * i + 1],
                                        pos[4 * i + 2], sc);
    pos[4 * i + 3] = a[i] * g[i] * acc;
  }
}

CRUMBLE_PD_CLONES
void force_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                   const std::int32_t* __restrict nbr, const double* __restrict len, const double* __restrict alive,
                   const double* __restrict kb, const double* __restrict pos, double* __restrict fx,
                   double* __restrict fy, double* __restrict fz) {
  for (std::int32_t i = i0; i < i1; ++i) {
    double f[3] = {0, 0, 0};
    force_bonds(off[i], off[i + 1], nbr, len, alive, kb, pos, pos[4 * i], pos[4 * i + 1], pos[4 * i + 2],
                pos[4 * i + 3], f);
    fx[i] = f[0];
    fy[i] = f[1];
    fz[i] = f[2];
  }
}

namespace {

#ifdef CRUMBLE_PD_HAVE_AVX512
// ---- AVX-512: 8 bonds at a time; the 8 neighbours' (x, y, z, aθ) come in as eight
// 32-byte loads and a 4×4 transpose per 256-bit half (gathers are slow on many cores).
// The arithmetic is written in the same order as the scalar tail.

__attribute__((target("avx512f"))) inline void load8(const double* pos, const std::int32_t* j, __m512d& X,
                                                     __m512d& Y, __m512d& Z, __m512d& W) {
  const __m512d a0 = _mm512_insertf64x4(_mm512_zextpd256_pd512(_mm256_loadu_pd(pos + 4 * j[0])),
                                        _mm256_loadu_pd(pos + 4 * j[4]), 1);
  const __m512d a1 = _mm512_insertf64x4(_mm512_zextpd256_pd512(_mm256_loadu_pd(pos + 4 * j[1])),
                                        _mm256_loadu_pd(pos + 4 * j[5]), 1);
  const __m512d a2 = _mm512_insertf64x4(_mm512_zextpd256_pd512(_mm256_loadu_pd(pos + 4 * j[2])),
                                        _mm256_loadu_pd(pos + 4 * j[6]), 1);
  const __m512d a3 = _mm512_insertf64x4(_mm512_zextpd256_pd512(_mm256_loadu_pd(pos + 4 * j[3])),
                                        _mm256_loadu_pd(pos + 4 * j[7]), 1);
  const __m512d t0 = _mm512_unpacklo_pd(a0, a1);  // x0 x1 z0 z1 | x4 x5 z4 z5
  const __m512d t1 = _mm512_unpackhi_pd(a0, a1);  // y0 y1 w0 w1 | y4 y5 w4 w5
  const __m512d t2 = _mm512_unpacklo_pd(a2, a3);
  const __m512d t3 = _mm512_unpackhi_pd(a2, a3);
  const __m512i lo = _mm512_setr_epi64(0, 1, 8, 9, 4, 5, 12, 13);
  const __m512i hi = _mm512_setr_epi64(2, 3, 10, 11, 6, 7, 14, 15);
  X = _mm512_permutex2var_pd(t0, lo, t2);
  Z = _mm512_permutex2var_pd(t0, hi, t2);
  Y = _mm512_permutex2var_pd(t1, lo, t3);
  W = _mm512_permutex2var_pd(t1, hi, t3);
}

// Up to eight bonds [q, q1) of one point: Y = x_j − x_i, |Y|, reference length r
// (0 in lanes past q1), extension e = |Y| − r, the neighbours' aθ, and the lane mask.
// Lanes past q1 repeat the last neighbour, so |Y| > 0 there too.
struct Bond8 {
  __m512d dx, dy, dz, l, r, e, at;
  __mmask8 m;
};
__attribute__((target("avx512f"), always_inline)) inline Bond8 bond8(const double* pos, const std::int32_t* nbr,
                                                                      const double* len, std::int32_t q,
                                                                      std::int32_t q1, __m512d vx, __m512d vy,
                                                                      __m512d vz) {
  Bond8 b;
  const std::int32_t* j = nbr + q;
  std::int32_t pad[8];
  if (q1 - q >= 8) {
    b.m = 0xFF;
  } else {
    b.m = static_cast<__mmask8>((1u << (q1 - q)) - 1u);
    for (int k = 0; k < 8; ++k) pad[k] = nbr[std::min(q + k, q1 - 1)];
    j = pad;
  }
  __m512d X, Y, Z, W;
  load8(pos, j, X, Y, Z, W);
  b.dx = _mm512_sub_pd(X, vx);
  b.dy = _mm512_sub_pd(Y, vy);
  b.dz = _mm512_sub_pd(Z, vz);
  b.l = _mm512_sqrt_pd(
      _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(b.dx, b.dx), _mm512_mul_pd(b.dy, b.dy)), _mm512_mul_pd(b.dz, b.dz)));
  b.r = _mm512_maskz_loadu_pd(b.m, len + q);
  b.e = _mm512_sub_pd(b.l, b.r);
  b.at = W;
  return b;
}

__attribute__((target("avx512f"))) void dilatation_avx512(std::int32_t i0, std::int32_t i1,
                                                          const std::int32_t* __restrict off,
                                                          const std::int32_t* __restrict nbr,
                                                          const double* __restrict len, double* __restrict alive,
                                                          double* __restrict pos, const double* __restrict g,
                                                          const double* __restrict a, double sc) {
  const __m512d vsc = _mm512_set1_pd(sc);
  for (std::int32_t i = i0; i < i1; ++i) {
    const double xi = pos[4 * i], yi = pos[4 * i + 1], zi = pos[4 * i + 2];
    const __m512d vx = _mm512_set1_pd(xi), vy = _mm512_set1_pd(yi), vz = _mm512_set1_pd(zi);
    __m512d vacc = _mm512_setzero_pd();
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q = off[i]; q < q1; q += 8) {
      const Bond8 b = bond8(pos, nbr, len, q, q1, vx, vy, vz);
      const __mmask8 ok = _mm512_mask_cmp_pd_mask(b.m, b.e, _mm512_mul_pd(vsc, b.r), _CMP_LE_OQ);
      const __m512d w = _mm512_maskz_loadu_pd(ok, alive + q);
      _mm512_mask_storeu_pd(alive + q, b.m, w);
      vacc = _mm512_add_pd(vacc, _mm512_mul_pd(_mm512_mul_pd(w, b.r), b.e));
    }
    pos[4 * i + 3] = a[i] * g[i] * _mm512_reduce_add_pd(vacc);
  }
}

__attribute__((target("avx512f"))) void force_avx512(std::int32_t i0, std::int32_t i1,
                                                     const std::int32_t* __restrict off,
                                                     const std::int32_t* __restrict nbr, const double* __restrict len,
                                                     const double* __restrict alive, const double* __restrict kb,
                                                     const double* __restrict pos, double* __restrict fx,
                                                     double* __restrict fy, double* __restrict fz) {
  const __m512d tiny = _mm512_set1_pd(1e-3);
  for (std::int32_t i = i0; i < i1; ++i) {
    const double xi = pos[4 * i], yi = pos[4 * i + 1], zi = pos[4 * i + 2], ati = pos[4 * i + 3];
    const __m512d vx = _mm512_set1_pd(xi), vy = _mm512_set1_pd(yi), vz = _mm512_set1_pd(zi),
                  vat = _mm512_set1_pd(ati);
    __m512d ax = _mm512_setzero_pd(), ay = _mm512_setzero_pd(), az = _mm512_setzero_pd();
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q = off[i]; q < q1; q += 8) {
      const Bond8 b = bond8(pos, nbr, len, q, q1, vx, vy, vz);
      const __m512d t = _mm512_add_pd(_mm512_mul_pd(_mm512_add_pd(vat, b.at), b.r),
                                      _mm512_mul_pd(_mm512_maskz_loadu_pd(b.m, kb + q), b.e));
      const __m512d s = _mm512_div_pd(_mm512_mul_pd(_mm512_maskz_loadu_pd(b.m, alive + q), t),
                                      _mm512_max_pd(b.l, _mm512_mul_pd(tiny, b.r)));
      ax = _mm512_add_pd(ax, _mm512_mul_pd(s, b.dx));
      ay = _mm512_add_pd(ay, _mm512_mul_pd(s, b.dy));
      az = _mm512_add_pd(az, _mm512_mul_pd(s, b.dz));
    }
    fx[i] = _mm512_reduce_add_pd(ax);
    fy[i] = _mm512_reduce_add_pd(ay);
    fz[i] = _mm512_reduce_add_pd(az);
  }
}

bool cpu_has_avx512() {
  static const bool ok = __builtin_cpu_supports("avx512f");
  return ok;
}
#else
bool cpu_has_avx512() { return false; }
#endif

}  // namespace

void dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr, const double* len,
                double* alive, double* pos, const double* g, const double* a, double sc) {
#ifdef CRUMBLE_PD_HAVE_AVX512
  if (cpu_has_avx512()) return dilatation_avx512(i0, i1, off, nbr, len, alive, pos, g, a, sc);
#endif
  dilatation_portable(i0, i1, off, nbr, len, alive, pos, g, a, sc);
}

void force(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr, const double* len,
           const double* alive, const double* kb, const double* pos, double* fx, double* fy, double* fz) {
#ifdef CRUMBLE_PD_HAVE_AVX512
  if (cpu_has_avx512()) return force_avx512(i0, i1, off, nbr, len, alive, kb, pos, fx, fy, fz);
#endif
  force_portable(i0, i1, off, nbr, len, alive, kb, pos, fx, fy, fz);
}

const char* isa() { return cpu_has_avx512() ? "avx512" : "generic"; }

CRUMBLE_PD_CLONES
void linear_dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                       const std::int32_t* __restrict nbr, const double* __restrict len, const double* __restrict w,
                       const double* __restrict rx, const double* __restrict ry, const double* __restrict rz,
                       const double* __restrict ux, const double* __restrict uy, const double* __restrict uz,
                       const double* __restrict g, const double* __restrict a, double* __restrict at) {
  for (std::int32_t i = i0; i < i1; ++i) {
    double acc = 0;
    const std::int32_t q1 = off[i + 1];
#pragma omp simd reduction(+ : acc)
    for (std::int32_t q = off[i]; q < q1; ++q) {
      const std::int32_t j = nbr[q];
      const double e = ((rx[j] - rx[i]) * (ux[j] - ux[i]) + (ry[j] - ry[i]) * (uy[j] - uy[i]) +
                        (rz[j] - rz[i]) * (uz[j] - uz[i])) / len[q];
      acc += w[q] * len[q] * e;
    }
    at[i] = a[i] * g[i] * acc;
  }
}

CRUMBLE_PD_CLONES
void linear_force(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                  const std::int32_t* __restrict nbr, const double* __restrict len, const double* __restrict w,
                  const double* __restrict rx, const double* __restrict ry, const double* __restrict rz,
                  const double* __restrict ux, const double* __restrict uy, const double* __restrict uz,
                  const double* __restrict at, const double* __restrict b, double* __restrict fx,
                  double* __restrict fy, double* __restrict fz) {
  for (std::int32_t i = i0; i < i1; ++i) {
    double sx = 0, sy = 0, sz = 0;
    const std::int32_t q1 = off[i + 1];
#pragma omp simd reduction(+ : sx, sy, sz)
    for (std::int32_t q = off[i]; q < q1; ++q) {
      const std::int32_t j = nbr[q];
      const double dx = rx[j] - rx[i], dy = ry[j] - ry[i], dz = rz[j] - rz[i];
      const double r = len[q];
      const double e = (dx * (ux[j] - ux[i]) + dy * (uy[j] - uy[i]) + dz * (uz[j] - uz[i])) / r;
      const double s = w[q] * ((at[i] + at[j]) * r + (b[i] + b[j]) * e) / r;  // s dx = w (...) n
      sx += s * dx;
      sy += s * dy;
      sz += s * dz;
    }
    fx[i] = sx;
    fy[i] = sy;
    fz[i] = sz;
  }
}

}  // namespace crumble::pd::kernel
