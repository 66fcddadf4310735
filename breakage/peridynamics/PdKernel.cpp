// Compiled with -fno-math-errno (sqrt vectorises) and -ffp-contract=off (no FMA
// contraction: both directed copies of a bond see bitwise the same length in every code
// path, so a bond breaks in both lists at the same step).
#include "breakage/peridynamics/PdKernel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

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
// Pass-2 bond scale: alive [(a_i θ_i + a_j θ_j) r + kb e] / |Y| (|Y| bounded away from 0), kb = b_i + b_j.
CRUMBLE_PD_INLINE double force_scale(double alive, double ati, double atj, double r, double kb, double l) {
  return alive * ((ati + atj) * r + kb * (l - r)) / std::max(l, 1e-3 * r);
}

// The summation order every version follows, so that all of them give the same bits: the
// bonds of a row are dealt to 8 lanes (bond q0 + 8m + k to lane k), each lane adds its
// bonds in order of m, and the lanes are added as ((l0 + l4) + (l2 + l6)) + ((l1 + l5) + (l3 + l7))
// (what _mm512_reduce_add_pd and the AVX2 two-register reduction compute). Additions are
// commutative in IEEE arithmetic, so only the grouping matters.
constexpr int kLanes = 8;
CRUMBLE_PD_INLINE double reduce8(const double* l) {
  return ((l[0] + l[4]) + (l[2] + l[6])) + ((l[1] + l[5]) + (l[3] + l[7]));
}

// ---- portable versions (scalar code in the 8-lane order; the full blocks of 8 bonds are
// element-wise, so the compiler may vectorise them without reordering any sum) ----

CRUMBLE_PD_CLONES
void dilatation_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                        const std::int32_t* __restrict nbr, const double* __restrict len, double* __restrict alive,
                        double* __restrict cur, double* __restrict pos, const double* __restrict g,
                        const double* __restrict a, double sc) {
  for (std::int32_t i = i0; i < i1; ++i) {
    const double xi = pos[4 * i], yi = pos[4 * i + 1], zi = pos[4 * i + 2];
    double acc[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0};
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q = off[i]; q < q1; q += kLanes) {
      const int m = std::min<std::int32_t>(kLanes, q1 - q);
      for (int k = 0; k < m; ++k) {
        const double r = len[q + k];
        const double l = bond(pos, nbr[q + k], xi, yi, zi).l;
        cur[q + k] = l;
        const double e = l - r;
        const double w = keep(e, r, sc, alive[q + k]);
        alive[q + k] = w;
        acc[k] += w * r * e;
      }
    }
    pos[4 * i + 3] = a[i] * g[i] * reduce8(acc);
  }
}

CRUMBLE_PD_CLONES
void force_portable(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                   const std::int32_t* __restrict nbr, const double* __restrict len, const double* __restrict alive,
                   const double* __restrict cur, const double* __restrict b, const double* __restrict pos,
                   double* __restrict fx,
                   double* __restrict fy, double* __restrict fz) {
  for (std::int32_t i = i0; i < i1; ++i) {
    const double xi = pos[4 * i], yi = pos[4 * i + 1], zi = pos[4 * i + 2], ati = pos[4 * i + 3], bi = b[i];
    double sx[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0}, sy[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0},
           sz[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0};
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q = off[i]; q < q1; q += kLanes) {
      const int m = std::min<std::int32_t>(kLanes, q1 - q);
      for (int k = 0; k < m; ++k) {
        const std::int32_t j = nbr[q + k];
        const double dx = pos[4 * j] - xi, dy = pos[4 * j + 1] - yi, dz = pos[4 * j + 2] - zi;
        const double f = force_scale(alive[q + k], ati, pos[4 * j + 3], len[q + k], bi + b[j], cur[q + k]);
        sx[k] += f * dx;
        sy[k] += f * dy;
        sz[k] += f * dz;
      }
    }
    fx[i] = reduce8(sx);
    fy[i] = reduce8(sy);
    fz[i] = reduce8(sz);
  }
}

namespace {

#ifdef CRUMBLE_PD_HAVE_AVX512
// ---- AVX2: the 8 lanes as two 4-wide registers (bonds q..q+3 and q+4..q+7); the four
// neighbours' (x, y, z, aθ) come in as four 32-byte loads and one 4×4 transpose
// (gathers are slow on many cores). Same arithmetic, in the same order, as the scalar code.

__attribute__((target("avx2"), always_inline)) inline void load4(const double* pos, const std::int32_t* j,
                                                                 __m256d& X, __m256d& Y, __m256d& Z, __m256d& W) {
  const __m256d a0 = _mm256_loadu_pd(pos + 4 * j[0]);
  const __m256d a1 = _mm256_loadu_pd(pos + 4 * j[1]);
  const __m256d a2 = _mm256_loadu_pd(pos + 4 * j[2]);
  const __m256d a3 = _mm256_loadu_pd(pos + 4 * j[3]);
  const __m256d t0 = _mm256_unpacklo_pd(a0, a1);  // x0 x1 z0 z1
  const __m256d t1 = _mm256_unpackhi_pd(a0, a1);  // y0 y1 w0 w1
  const __m256d t2 = _mm256_unpacklo_pd(a2, a3);  // x2 x3 z2 z3
  const __m256d t3 = _mm256_unpackhi_pd(a2, a3);  // y2 y3 w2 w3
  X = _mm256_permute2f128_pd(t0, t2, 0x20);
  Z = _mm256_permute2f128_pd(t0, t2, 0x31);
  Y = _mm256_permute2f128_pd(t1, t3, 0x20);
  W = _mm256_permute2f128_pd(t1, t3, 0x31);
}

// Up to four bonds [q, q + n) of one point (n = 1..4): Y = x_j − x_i, |Y|, reference length
// r (0 in lanes ≥ n), extension e = |Y| − r, the neighbours' aθ, and the lane mask. Lanes
// ≥ n repeat the last neighbour, so |Y| > 0 there too.
// With `pb`, also the neighbours' b_j (pass 2).
struct Bond4 {
  __m256d dx, dy, dz, l, r, e, at, m, bj;
};
__attribute__((target("avx2"), always_inline)) inline Bond4 bond4(const double* pos, const std::int32_t* nbr,
                                                                  const double* len, std::int32_t q, int n,
                                                                  __m256d vx, __m256d vy, __m256d vz,
                                                                  const double* pb = nullptr,
                                                                  const double* cur = nullptr) {
  Bond4 b;
  const std::int32_t* j = nbr + q;
  std::int32_t pad[4];
  if (n >= 4) {
    b.m = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    b.r = _mm256_loadu_pd(len + q);
  } else {
    for (int k = 0; k < 4; ++k) pad[k] = nbr[q + std::min(k, n - 1)];
    j = pad;
    b.m = _mm256_castsi256_pd(_mm256_cmpgt_epi64(_mm256_set1_epi64x(n), _mm256_setr_epi64x(0, 1, 2, 3)));
    b.r = _mm256_maskload_pd(len + q, _mm256_castpd_si256(b.m));
  }
  __m256d X, Y, Z, W;
  load4(pos, j, X, Y, Z, W);
  b.dx = _mm256_sub_pd(X, vx);
  b.dy = _mm256_sub_pd(Y, vy);
  b.dz = _mm256_sub_pd(Z, vz);
  if (cur)  // |Y| stored by pass 1 (1 in lanes >= n, so that no lane divides by 0)
    b.l = n >= 4 ? _mm256_loadu_pd(cur + q)
                 : _mm256_blendv_pd(_mm256_set1_pd(1.0), _mm256_maskload_pd(cur + q, _mm256_castpd_si256(b.m)), b.m);
  else
    b.l = _mm256_sqrt_pd(_mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(b.dx, b.dx), _mm256_mul_pd(b.dy, b.dy)),
                                       _mm256_mul_pd(b.dz, b.dz)));
  b.e = _mm256_sub_pd(b.l, b.r);
  b.at = W;
  if (pb) b.bj = _mm256_setr_pd(pb[j[0]], pb[j[1]], pb[j[2]], pb[j[3]]);
  return b;
}
__attribute__((target("avx2"), always_inline)) inline __m256d load_lanes(const double* p, int n, __m256d m) {
  return n >= 4 ? _mm256_loadu_pd(p) : _mm256_maskload_pd(p, _mm256_castpd_si256(m));
}
// ((l0 + l4) + (l2 + l6)) + ((l1 + l5) + (l3 + l7)) for lanes 0–3 in lo, 4–7 in hi.
__attribute__((target("avx2"), always_inline)) inline double reduce8_avx2(__m256d lo, __m256d hi) {
  const __m256d s = _mm256_add_pd(hi, lo);
  const __m128d t = _mm_add_pd(_mm256_extractf128_pd(s, 1), _mm256_castpd256_pd128(s));
  return _mm_cvtsd_f64(t) + _mm_cvtsd_f64(_mm_unpackhi_pd(t, t));
}

// Pass 1 on four bonds [q, q + n): break, store alive, acc += (w r) e.
__attribute__((target("avx2"), always_inline)) inline __m256d dilatation4(
    const double* pos, const std::int32_t* nbr, const double* len, double* alive, double* cur, std::int32_t q, int n,
    __m256d vx, __m256d vy, __m256d vz, __m256d vsc, __m256d acc) {
  const Bond4 b = bond4(pos, nbr, len, q, n, vx, vy, vz);
  if (n >= 4)
    _mm256_storeu_pd(cur + q, b.l);
  else
    _mm256_maskstore_pd(cur + q, _mm256_castpd_si256(b.m), b.l);
  const __m256d ok = _mm256_cmp_pd(b.e, _mm256_mul_pd(vsc, b.r), _CMP_LE_OQ);
  const __m256d w = _mm256_and_pd(ok, load_lanes(alive + q, n, b.m));
  if (n >= 4)
    _mm256_storeu_pd(alive + q, w);
  else
    _mm256_maskstore_pd(alive + q, _mm256_castpd_si256(b.m), w);
  return _mm256_add_pd(acc, _mm256_mul_pd(_mm256_mul_pd(w, b.r), b.e));
}

__attribute__((target("avx2"))) void dilatation_avx2(std::int32_t i0, std::int32_t i1,
                                                     const std::int32_t* __restrict off,
                                                     const std::int32_t* __restrict nbr, const double* __restrict len,
                                                     double* __restrict alive, double* __restrict cur,
                                                     double* __restrict pos, const double* __restrict g,
                                                     const double* __restrict a, double sc) {
  const __m256d vsc = _mm256_set1_pd(sc);
  for (std::int32_t i = i0; i < i1; ++i) {
    const __m256d vx = _mm256_set1_pd(pos[4 * i]), vy = _mm256_set1_pd(pos[4 * i + 1]),
                  vz = _mm256_set1_pd(pos[4 * i + 2]);
    __m256d lo = _mm256_setzero_pd(), hi = _mm256_setzero_pd();
    const std::int32_t q1 = off[i + 1];
    std::int32_t q = off[i];
    for (; q + 8 <= q1; q += 8) {
      lo = dilatation4(pos, nbr, len, alive, cur, q, 4, vx, vy, vz, vsc, lo);
      hi = dilatation4(pos, nbr, len, alive, cur, q + 4, 4, vx, vy, vz, vsc, hi);
    }
    const int rest = q1 - q;
    if (rest > 0) lo = dilatation4(pos, nbr, len, alive, cur, q, std::min(rest, 4), vx, vy, vz, vsc, lo);
    if (rest > 4) hi = dilatation4(pos, nbr, len, alive, cur, q + 4, rest - 4, vx, vy, vz, vsc, hi);
    pos[4 * i + 3] = a[i] * g[i] * reduce8_avx2(lo, hi);
  }
}

// Pass 2 on four bonds [q, q + n): s = alive t / max(|Y|, 1e-3 r), f += s Y.
__attribute__((target("avx2"), always_inline)) inline void force4(const double* pos, const std::int32_t* nbr,
                                                                  const double* len, const double* alive,
                                                                  const double* cur, const double* pb,
                                                                  std::int32_t q, int n,
                                                                  __m256d vx, __m256d vy, __m256d vz, __m256d vat,
                                                                  __m256d vbi, __m256d& ax, __m256d& ay,
                                                                  __m256d& az) {
  const Bond4 b = bond4(pos, nbr, len, q, n, vx, vy, vz, pb, cur);
  const __m256d tiny = _mm256_set1_pd(1e-3);
  const __m256d t =
      _mm256_add_pd(_mm256_mul_pd(_mm256_add_pd(vat, b.at), b.r), _mm256_mul_pd(_mm256_add_pd(vbi, b.bj), b.e));
  const __m256d s = _mm256_div_pd(_mm256_mul_pd(load_lanes(alive + q, n, b.m), t),
                                  _mm256_max_pd(b.l, _mm256_mul_pd(tiny, b.r)));
  ax = _mm256_add_pd(ax, _mm256_mul_pd(s, b.dx));
  ay = _mm256_add_pd(ay, _mm256_mul_pd(s, b.dy));
  az = _mm256_add_pd(az, _mm256_mul_pd(s, b.dz));
}

__attribute__((target("avx2"))) void force_avx2(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                                                const std::int32_t* __restrict nbr, const double* __restrict len,
                                                const double* __restrict alive, const double* __restrict cur,
                                                const double* __restrict pb, const double* __restrict pos,
                                                double* __restrict fx,
                                                double* __restrict fy, double* __restrict fz) {
  for (std::int32_t i = i0; i < i1; ++i) {
    const __m256d vx = _mm256_set1_pd(pos[4 * i]), vy = _mm256_set1_pd(pos[4 * i + 1]),
                  vz = _mm256_set1_pd(pos[4 * i + 2]), vat = _mm256_set1_pd(pos[4 * i + 3]),
                  vbi = _mm256_set1_pd(pb[i]);
    __m256d xlo = _mm256_setzero_pd(), ylo = xlo, zlo = xlo, xhi = xlo, yhi = xlo, zhi = xlo;
    const std::int32_t q1 = off[i + 1];
    std::int32_t q = off[i];
    for (; q + 8 <= q1; q += 8) {
      force4(pos, nbr, len, alive, cur, pb, q, 4, vx, vy, vz, vat, vbi, xlo, ylo, zlo);
      force4(pos, nbr, len, alive, cur, pb, q + 4, 4, vx, vy, vz, vat, vbi, xhi, yhi, zhi);
    }
    const int rest = q1 - q;
    if (rest > 0) force4(pos, nbr, len, alive, cur, pb, q, std::min(rest, 4), vx, vy, vz, vat, vbi, xlo, ylo, zlo);
    if (rest > 4) force4(pos, nbr, len, alive, cur, pb, q + 4, rest - 4, vx, vy, vz, vat, vbi, xhi, yhi, zhi);
    fx[i] = reduce8_avx2(xlo, xhi);
    fy[i] = reduce8_avx2(ylo, yhi);
    fz[i] = reduce8_avx2(zlo, zhi);
  }
}

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
  __m512d dx, dy, dz, l, r, e, at, bj;
  __mmask8 m;
};
__attribute__((target("avx512f"), always_inline)) inline Bond8 bond8(const double* pos, const std::int32_t* nbr,
                                                                      const double* len, std::int32_t q,
                                                                      std::int32_t q1, __m512d vx, __m512d vy,
                                                                      __m512d vz, const double* pb = nullptr,
                                                                      const double* cur = nullptr) {
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
  if (cur)  // |Y| stored by pass 1 (1 in lanes past q1, so that no lane divides by 0)
    b.l = _mm512_mask_loadu_pd(_mm512_set1_pd(1.0), b.m, cur + q);
  else
    b.l = _mm512_sqrt_pd(_mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(b.dx, b.dx), _mm512_mul_pd(b.dy, b.dy)),
                                       _mm512_mul_pd(b.dz, b.dz)));
  b.r = _mm512_maskz_loadu_pd(b.m, len + q);
  b.e = _mm512_sub_pd(b.l, b.r);
  b.at = W;
  if (pb) b.bj = _mm512_i32gather_pd(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(j)), pb, 8);
  return b;
}

__attribute__((target("avx512f"))) void dilatation_avx512(std::int32_t i0, std::int32_t i1,
                                                          const std::int32_t* __restrict off,
                                                          const std::int32_t* __restrict nbr,
                                                          const double* __restrict len, double* __restrict alive,
                                                          double* __restrict cur, double* __restrict pos,
                                                          const double* __restrict g,
                                                          const double* __restrict a, double sc) {
  const __m512d vsc = _mm512_set1_pd(sc);
  for (std::int32_t i = i0; i < i1; ++i) {
    const double xi = pos[4 * i], yi = pos[4 * i + 1], zi = pos[4 * i + 2];
    const __m512d vx = _mm512_set1_pd(xi), vy = _mm512_set1_pd(yi), vz = _mm512_set1_pd(zi);
    __m512d vacc = _mm512_setzero_pd();
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q = off[i]; q < q1; q += 8) {
      const Bond8 b = bond8(pos, nbr, len, q, q1, vx, vy, vz);
      _mm512_mask_storeu_pd(cur + q, b.m, b.l);
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
                                                     const double* __restrict alive, const double* __restrict cur,
                                                     const double* __restrict pb, const double* __restrict pos,
                                                     double* __restrict fx,
                                                     double* __restrict fy, double* __restrict fz) {
  const __m512d tiny = _mm512_set1_pd(1e-3);
  for (std::int32_t i = i0; i < i1; ++i) {
    const double xi = pos[4 * i], yi = pos[4 * i + 1], zi = pos[4 * i + 2], ati = pos[4 * i + 3];
    const __m512d vx = _mm512_set1_pd(xi), vy = _mm512_set1_pd(yi), vz = _mm512_set1_pd(zi),
                  vat = _mm512_set1_pd(ati), vbi = _mm512_set1_pd(pb[i]);
    __m512d ax = _mm512_setzero_pd(), ay = _mm512_setzero_pd(), az = _mm512_setzero_pd();
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q = off[i]; q < q1; q += 8) {
      const Bond8 b = bond8(pos, nbr, len, q, q1, vx, vy, vz, pb, cur);
      const __m512d t = _mm512_add_pd(_mm512_mul_pd(_mm512_add_pd(vat, b.at), b.r),
                                      _mm512_mul_pd(_mm512_add_pd(vbi, b.bj), b.e));
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
bool cpu_has_avx2() {
  static const bool ok = __builtin_cpu_supports("avx2");
  return ok;
}
#else
bool cpu_has_avx512() { return false; }
bool cpu_has_avx2() { return false; }
#endif

enum Isa : int { kGeneric = 0, kAvx2 = 1, kAvx512 = 2 };
int best_isa() { return cpu_has_avx512() ? kAvx512 : cpu_has_avx2() ? kAvx2 : kGeneric; }
// -1: the best this CPU has; else the version select_isa() chose.
std::atomic<int> g_selected{-1};
int current_isa() {
  const int s = g_selected.load(std::memory_order_relaxed);
  return s >= 0 ? s : best_isa();
}
const char* isa_name(int k) { return k == kAvx512 ? "avx512" : k == kAvx2 ? "avx2" : "generic"; }

}  // namespace

void dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr, const double* len,
                double* alive, double* cur, double* pos, const double* g, const double* a, double sc) {
#ifdef CRUMBLE_PD_HAVE_AVX512
  switch (current_isa()) {
    case kAvx512: return dilatation_avx512(i0, i1, off, nbr, len, alive, cur, pos, g, a, sc);
    case kAvx2: return dilatation_avx2(i0, i1, off, nbr, len, alive, cur, pos, g, a, sc);
    default: break;
  }
#endif
  dilatation_portable(i0, i1, off, nbr, len, alive, cur, pos, g, a, sc);
}

void force(std::int32_t i0, std::int32_t i1, const std::int32_t* off, const std::int32_t* nbr, const double* len,
           const double* alive, const double* cur, const double* b, const double* pos, double* fx, double* fy,
           double* fz) {
#ifdef CRUMBLE_PD_HAVE_AVX512
  switch (current_isa()) {
    case kAvx512: return force_avx512(i0, i1, off, nbr, len, alive, cur, b, pos, fx, fy, fz);
    case kAvx2: return force_avx2(i0, i1, off, nbr, len, alive, cur, b, pos, fx, fy, fz);
    default: break;
  }
#endif
  force_portable(i0, i1, off, nbr, len, alive, cur, b, pos, fx, fy, fz);
}

const char* isa() { return isa_name(current_isa()); }

std::vector<std::string> available_isas() {
  std::vector<std::string> v{"generic"};
  if (cpu_has_avx2()) v.emplace_back("avx2");
  if (cpu_has_avx512()) v.emplace_back("avx512");
  return v;
}

void select_isa(const std::string& name) {
  if (name.empty()) {
    g_selected.store(-1);
    return;
  }
  for (int k : {kGeneric, kAvx2, kAvx512})
    if (name == isa_name(k)) {
      const auto av = available_isas();
      if (std::find(av.begin(), av.end(), name) == av.end())
        throw std::invalid_argument("peridynamics kernel: this CPU cannot run the " + name + " version");
      g_selected.store(k);
      return;
    }
  throw std::invalid_argument("peridynamics kernel: unknown version '" + name + "' (known: generic, avx2, avx512)");
}

// The linearised passes follow the same 8-lane order, so the static solve and the step
// estimate are bitwise the same in every clone.
CRUMBLE_PD_CLONES
void linear_dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                       const std::int32_t* __restrict nbr, const double* __restrict len, const double* __restrict w,
                       const double* __restrict rx, const double* __restrict ry, const double* __restrict rz,
                       const double* __restrict ux, const double* __restrict uy, const double* __restrict uz,
                       const double* __restrict g, const double* __restrict a, double* __restrict at) {
  for (std::int32_t i = i0; i < i1; ++i) {
    double acc[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0};
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q0 = off[i]; q0 < q1; q0 += kLanes) {
      const int m = std::min<std::int32_t>(kLanes, q1 - q0);
      for (int k = 0; k < m; ++k) {
        const std::int32_t q = q0 + k, j = nbr[q];
        const double e = ((rx[j] - rx[i]) * (ux[j] - ux[i]) + (ry[j] - ry[i]) * (uy[j] - uy[i]) +
                          (rz[j] - rz[i]) * (uz[j] - uz[i])) / len[q];
        acc[k] += w[q] * len[q] * e;
      }
    }
    at[i] = a[i] * g[i] * reduce8(acc);
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
    double sx[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0}, sy[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0},
           sz[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0};
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q0 = off[i]; q0 < q1; q0 += kLanes) {
      const int m = std::min<std::int32_t>(kLanes, q1 - q0);
      for (int k = 0; k < m; ++k) {
        const std::int32_t q = q0 + k, j = nbr[q];
        const double dx = rx[j] - rx[i], dy = ry[j] - ry[i], dz = rz[j] - rz[i];
        const double r = len[q];
        const double e = (dx * (ux[j] - ux[i]) + dy * (uy[j] - uy[i]) + dz * (uz[j] - uz[i])) / r;
        const double s = w[q] * ((at[i] + at[j]) * r + (b[i] + b[j]) * e) / r;  // s dx = w (...) n
        sx[k] += s * dx;
        sy[k] += s * dy;
        sz[k] += s * dz;
      }
    }
    fx[i] = reduce8(sx);
    fy[i] = reduce8(sy);
    fz[i] = reduce8(sz);
  }
}

}  // namespace crumble::pd::kernel
