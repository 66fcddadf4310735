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

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CRUMBLE_PD_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define CRUMBLE_PD_CLONES
#endif

namespace crumble::pd::kernel {

// ---- portable versions (auto-vectorised; AVX2 and baseline clones) ----

CRUMBLE_PD_CLONES
void dilatation_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                        const std::int32_t* __restrict nbr, const double* __restrict len, double* __restrict alive,
                        double* __restrict pos, const double* __restrict g, const double* __restrict a, double sc) {
  for (std::int32_t i = i0; i < i1; ++i) {
    const double xi = pos[4 * i], yi = pos[4 * i + 1], zi = pos[4 * i + 2];
    double acc = 0;
    const std::int32_t q1 = off[i + 1];
#pragma omp simd reduction(+ : acc)
    for (std::int32_t q = off[i]; q < q1; ++q) {
      const std::int32_t j = nbr[q];
      const double dx = pos[4 * j] - xi, dy = pos[4 * j + 1] - yi, dz = pos[4 * j + 2] - zi;
      const double r = len[q];
      const double e = std::sqrt(dx * dx + dy * dy + dz * dz) - r;
      const double w = e <= sc * r ? alive[q] : 0.0;  // critical stretch: broken for good
      alive[q] = w;
      acc += w * r * e;
    }
    pos[4 * i + 3] = a[i] * g[i] * acc;
  }
}

CRUMBLE_PD_CLONES
void force_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                   const std::int32_t* __restrict nbr, const double* __restrict len, const double* __restrict alive,
                   const double* __restrict kb, const double* __restrict pos, double* __restrict fx,
                   double* __restrict fy, double* __restrict fz) {
  for (std::int32_t i = i0; i < i1; ++i) {
    const double xi = pos[4 * i], yi = pos[4 * i + 1], zi = pos[4 * i + 2], ati = pos[4 * i + 3];
    double sx = 0, sy = 0, sz = 0;
    const std::int32_t q1 = off[i + 1];
#pragma omp simd reduction(+ : sx, sy, sz)
    for (std::int32_t q = off[i]; q < q1; ++q) {
      const std::int32_t j = nbr[q];
      const double dx = pos[4 * j] - xi, dy = pos[4 * j + 1] - yi, dz = pos[4 * j + 2] - zi;
      const double r = len[q];
      const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
      const double e = l - r;
      const double s = alive[q] * ((ati + pos[4 * j + 3]) * r + kb[q] * e) / std::max(l, 1e-3 * r);
      sx += s * dx;
      sy += s * dy;
      sz += s * dz;
    }
    fx[i] = sx;
    fy[i] = sy;
    fz[i] = sz;
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
    std::int32_t q = off[i];
    const std::int32_t q1 = off[i + 1];
    for (; q + 8 <= q1; q += 8) {
      __m512d X, Y, Z, W;
      load8(pos, nbr + q, X, Y, Z, W);
      const __m512d dx = _mm512_sub_pd(X, vx), dy = _mm512_sub_pd(Y, vy), dz = _mm512_sub_pd(Z, vz);
      const __m512d l = _mm512_sqrt_pd(
          _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz)));
      const __m512d r = _mm512_loadu_pd(len + q);
      const __m512d e = _mm512_sub_pd(l, r);
      const __mmask8 ok = _mm512_cmp_pd_mask(e, _mm512_mul_pd(vsc, r), _CMP_LE_OQ);
      const __m512d w = _mm512_maskz_loadu_pd(ok, alive + q);
      _mm512_storeu_pd(alive + q, w);
      vacc = _mm512_add_pd(vacc, _mm512_mul_pd(_mm512_mul_pd(w, r), e));
    }
    double acc = _mm512_reduce_add_pd(vacc);
    for (; q < q1; ++q) {
      const std::int32_t j = nbr[q];
      const double dx = pos[4 * j] - xi, dy = pos[4 * j + 1] - yi, dz = pos[4 * j + 2] - zi;
      const double r = len[q];
      const double e = std::sqrt(dx * dx + dy * dy + dz * dz) - r;
      const double w = e <= sc * r ? alive[q] : 0.0;
      alive[q] = w;
      acc += w * r * e;
    }
    pos[4 * i + 3] = a[i] * g[i] * acc;
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
    std::int32_t q = off[i];
    const std::int32_t q1 = off[i + 1];
    for (; q + 8 <= q1; q += 8) {
      __m512d X, Y, Z, W;
      load8(pos, nbr + q, X, Y, Z, W);
      const __m512d dx = _mm512_sub_pd(X, vx), dy = _mm512_sub_pd(Y, vy), dz = _mm512_sub_pd(Z, vz);
      const __m512d l = _mm512_sqrt_pd(
          _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz)));
      const __m512d r = _mm512_loadu_pd(len + q);
      const __m512d e = _mm512_sub_pd(l, r);
      const __m512d t = _mm512_add_pd(_mm512_mul_pd(_mm512_add_pd(vat, W), r), _mm512_mul_pd(_mm512_loadu_pd(kb + q), e));
      const __m512d s = _mm512_div_pd(_mm512_mul_pd(_mm512_loadu_pd(alive + q), t),
                                      _mm512_max_pd(l, _mm512_mul_pd(tiny, r)));
      ax = _mm512_add_pd(ax, _mm512_mul_pd(s, dx));
      ay = _mm512_add_pd(ay, _mm512_mul_pd(s, dy));
      az = _mm512_add_pd(az, _mm512_mul_pd(s, dz));
    }
    double sx = _mm512_reduce_add_pd(ax), sy = _mm512_reduce_add_pd(ay), sz = _mm512_reduce_add_pd(az);
    for (; q < q1; ++q) {
      const std::int32_t j = nbr[q];
      const double dx = pos[4 * j] - xi, dy = pos[4 * j + 1] - yi, dz = pos[4 * j + 2] - zi;
      const double r = len[q];
      const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
      const double e = l - r;
      const double s = alive[q] * ((ati + pos[4 * j + 3]) * r + kb[q] * e) / std::max(l, 1e-3 * r);
      sx += s * dx;
      sy += s * dy;
      sz += s * dz;
    }
    fx[i] = sx;
    fy[i] = sy;
    fz[i] = sz;
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
