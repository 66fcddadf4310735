// Compiled with -fno-math-errno (sqrt vectorises) and -ffp-contract=off (no FMA
// contraction: the portable and the AVX2 versions round every operation alike).
#include "breakage/peridynamics/PdKernel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define CRUMBLE_PD_HAVE_AVX2 1
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CRUMBLE_PD_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define CRUMBLE_PD_CLONES
#endif

namespace crumble::pd::kernel {

// The order every version follows, so that all of them give the same bits. Blocks are
// taken in the caller's order; within a block its groups (bonds) in order; for each group
// lanes 0..3 (4 different cells, so their order does not matter), and for each lane: the
// bond's value is added to the neighbour cell's sum at once and to a running sum of the
// block's own point, which is added to the point's cell after the block's last group.

// ---- portable versions ----

// Critical stretch (Zhu & Zhao 2019 §2.1): a bond stretched beyond sc is broken for good.
CRUMBLE_PD_CLONES
bool dilatation_portable(const BoxView& v, std::int32_t k0, std::int32_t k1, double sc) {
  bool broke = false;
  for (std::int32_t k = k0; k < k1; ++k) {
    const std::int64_t c = v.block_cell[k];
    double acc[4] = {0, 0, 0, 0};
    for (std::int32_t q = v.block_group[k]; q < v.block_group[k + 1]; ++q) {
      const std::int64_t cj = c + v.delta[q];
      const double r = v.len[q];
      for (int l = 0; l < 4; ++l) {
        const double dx = v.x[cj + l] - v.x[c + l], dy = v.y[cj + l] - v.y[c + l], dz = v.z[cj + l] - v.z[c + l];
        const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
        v.cur[4 * q + l] = len;
        const double e = len - r;
        const double old = v.alive[4 * q + l];
        const double w = e <= sc * r ? old : 0.0;
        broke |= w != old;
        v.alive[4 * q + l] = w;
        const double t = w * r * e;  // eq. 4: ω r e V_j (ω = 1; V_j and g applied later)
        acc[l] += t;
        v.th[cj + l] += t;
      }
    }
    for (int l = 0; l < 4; ++l) v.th[c + l] += acc[l];
  }
  return broke;
}

CRUMBLE_PD_CLONES
void force_portable(const BoxView& v, std::int32_t k0, std::int32_t k1) {
  for (std::int32_t k = k0; k < k1; ++k) {
    const std::int64_t c = v.block_cell[k];
    double sx[4] = {0, 0, 0, 0}, sy[4] = {0, 0, 0, 0}, sz[4] = {0, 0, 0, 0};
    for (std::int32_t q = v.block_group[k]; q < v.block_group[k + 1]; ++q) {
      const std::int64_t cj = c + v.delta[q];
      const double r = v.len[q];
      for (int l = 0; l < 4; ++l) {
        const double dx = v.x[cj + l] - v.x[c + l], dy = v.y[cj + l] - v.y[c + l], dz = v.z[cj + l] - v.z[c + l];
        const double len = v.cur[4 * q + l];
        // eqs. 1–2: t = alive [(a_i θ_i + a_j θ_j) r + (b_i + b_j) e], along Y/|Y| (|Y| bounded away from 0)
        const double t = (v.at[c + l] + v.at[cj + l]) * r + (v.b[c + l] + v.b[cj + l]) * (len - r);
        const double s = v.alive[4 * q + l] * t / std::max(len, 1e-3 * r);
        const double gx = s * dx, gy = s * dy, gz = s * dz;
        sx[l] += gx;
        sy[l] += gy;
        sz[l] += gz;
        v.fx[cj + l] -= gx;
        v.fy[cj + l] -= gy;
        v.fz[cj + l] -= gz;
      }
    }
    for (int l = 0; l < 4; ++l) {
      v.fx[c + l] += sx[l];
      v.fy[c + l] += sy[l];
      v.fz[c + l] += sz[l];
    }
  }
}

namespace {

#ifdef CRUMBLE_PD_HAVE_AVX2
// ---- AVX2: a block's 4 lanes in one register; the same operations in the same order. ----

// One group (4 lanes) of each pass, shared by the AVX2 and the AVX-512 versions.
#define CRUMBLE_PD_AVX2_INLINE __attribute__((target("avx2"), always_inline)) inline

CRUMBLE_PD_AVX2_INLINE void add4(double* p, __m256d s) { _mm256_storeu_pd(p, _mm256_add_pd(_mm256_loadu_pd(p), s)); }
CRUMBLE_PD_AVX2_INLINE void sub4(double* p, __m256d s) { _mm256_storeu_pd(p, _mm256_sub_pd(_mm256_loadu_pd(p), s)); }
// A bond's force g on the block's own sums (s += g) and on its neighbour cells (f −= g)
CRUMBLE_PD_AVX2_INLINE void push_force(const BoxView& v, std::int64_t cj, __m256d gx, __m256d gy, __m256d gz, __m256d& sx,
                                       __m256d& sy, __m256d& sz) {
  sx = _mm256_add_pd(sx, gx);
  sy = _mm256_add_pd(sy, gy);
  sz = _mm256_add_pd(sz, gz);
  sub4(v.fx + cj, gx);
  sub4(v.fy + cj, gy);
  sub4(v.fz + cj, gz);
}

CRUMBLE_PD_AVX2_INLINE void dilatation_group4(const BoxView& v, std::int32_t q, std::int64_t c, __m256d xi, __m256d yi,
                                              __m256d zi, __m256d vsc, __m256d& acc, __m256d& broke) {
  const std::int64_t cj = c + v.delta[q];
  const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(v.x + cj), xi);
  const __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(v.y + cj), yi);
  const __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(v.z + cj), zi);
  const __m256d l = _mm256_sqrt_pd(
      _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz)));
  _mm256_storeu_pd(v.cur + 4 * q, l);
  const __m256d r = _mm256_set1_pd(v.len[q]);
  const __m256d e = _mm256_sub_pd(l, r);
  const __m256d old = _mm256_loadu_pd(v.alive + 4 * q);
  const __m256d w = _mm256_and_pd(_mm256_cmp_pd(e, _mm256_mul_pd(vsc, r), _CMP_LE_OQ), old);
  broke = _mm256_or_pd(broke, _mm256_cmp_pd(w, old, _CMP_NEQ_UQ));
  _mm256_storeu_pd(v.alive + 4 * q, w);
  const __m256d t = _mm256_mul_pd(_mm256_mul_pd(w, r), e);
  acc = _mm256_add_pd(acc, t);
  add4(v.th + cj, t);
}

struct Own4 {  // a block's own 4 points: position, aθ, b
  __m256d x, y, z, at, b;
};

CRUMBLE_PD_AVX2_INLINE void force_group4(const BoxView& v, std::int32_t q, std::int64_t c, const Own4& o, __m256d& sx,
                                         __m256d& sy, __m256d& sz) {
  const __m256d tiny = _mm256_set1_pd(1e-3);
  const std::int64_t cj = c + v.delta[q];
  const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(v.x + cj), o.x);
  const __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(v.y + cj), o.y);
  const __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(v.z + cj), o.z);
  const __m256d l = _mm256_loadu_pd(v.cur + 4 * q);
  const __m256d r = _mm256_set1_pd(v.len[q]);
  const __m256d t = _mm256_add_pd(_mm256_mul_pd(_mm256_add_pd(o.at, _mm256_loadu_pd(v.at + cj)), r),
                                  _mm256_mul_pd(_mm256_add_pd(o.b, _mm256_loadu_pd(v.b + cj)), _mm256_sub_pd(l, r)));
  const __m256d s =
      _mm256_div_pd(_mm256_mul_pd(_mm256_loadu_pd(v.alive + 4 * q), t), _mm256_max_pd(l, _mm256_mul_pd(tiny, r)));
  push_force(v, cj, _mm256_mul_pd(s, dx), _mm256_mul_pd(s, dy), _mm256_mul_pd(s, dz), sx, sy, sz);
}

CRUMBLE_PD_AVX2_INLINE Own4 own4(const BoxView& v, std::int64_t c) {
  return {_mm256_loadu_pd(v.x + c), _mm256_loadu_pd(v.y + c), _mm256_loadu_pd(v.z + c), _mm256_loadu_pd(v.at + c),
          _mm256_loadu_pd(v.b + c)};
}


__attribute__((target("avx2"))) bool dilatation_avx2(const BoxView& view, std::int32_t k0, std::int32_t k1, double sc) {
  const BoxView v = view;  // a local copy: the may-alias stores of the intrinsics would force reloads of view's pointers
  const __m256d vsc = _mm256_set1_pd(sc);
  __m256d broke = _mm256_setzero_pd();
  for (std::int32_t k = k0; k < k1; ++k) {
    const std::int64_t c = v.block_cell[k];
    const __m256d xi = _mm256_loadu_pd(v.x + c), yi = _mm256_loadu_pd(v.y + c), zi = _mm256_loadu_pd(v.z + c);
    __m256d acc = _mm256_setzero_pd();
    for (std::int32_t q = v.block_group[k]; q < v.block_group[k + 1]; ++q)
      dilatation_group4(v, q, c, xi, yi, zi, vsc, acc, broke);
    add4(v.th + c, acc);
  }
  return _mm256_movemask_pd(broke) != 0;
}

__attribute__((target("avx2"))) void force_avx2(const BoxView& view, std::int32_t k0, std::int32_t k1) {
  const BoxView v = view;  // a local copy: the may-alias stores of the intrinsics would force reloads of view's pointers
  for (std::int32_t k = k0; k < k1; ++k) {
    const std::int64_t c = v.block_cell[k];
    const Own4 o = own4(v, c);
    __m256d sx = _mm256_setzero_pd(), sy = sx, sz = sx;
    for (std::int32_t q = v.block_group[k]; q < v.block_group[k + 1]; ++q) force_group4(v, q, c, o, sx, sy, sz);
    add4(v.fx + c, sx);
    add4(v.fy + c, sy);
    add4(v.fz + c, sz);
  }
}

// ---- AVX-512: two groups of a block in one 8-lane register (their cells are 4 + 4 separate
// loads; group q in the low half, q + 1 in the high half). The block's own sums add the low
// half, then the high half, and the neighbour cells take group q's values before q + 1's:
// the order of the 4-lane versions. Two groups whose neighbour runs overlap (offsets less
// than 4 cells apart) go one at a time, as in the AVX2 version. ----
#define CRUMBLE_PD_AVX512 __attribute__((target("avx512f,avx512dq,avx512vl,avx2")))
// GCC 12's AVX-512 intrinsics pass an undefined vector as the unused merge source of their
// masked builtins, which -Wmaybe-uninitialized reports (GCC bug 105593, fixed in GCC 13).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

CRUMBLE_PD_AVX512 inline __m512d load_pair(const double* p, std::int64_t a, std::int64_t b) {
  return _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_loadu_pd(p + a)), _mm256_loadu_pd(p + b), 1);
}
CRUMBLE_PD_AVX512 inline __m512d twice(__m256d x) { return _mm512_insertf64x4(_mm512_castpd256_pd512(x), x, 1); }
CRUMBLE_PD_AVX512 inline __m512d len_pair(const BoxView& v, std::int32_t q) {
  return _mm512_insertf64x4(_mm512_set1_pd(v.len[q]), _mm256_set1_pd(v.len[q + 1]), 1);
}
// true when groups q and q + 1 (< q1) can go together: their neighbour runs of 4 cells are disjoint
inline bool pairable(const BoxView& v, std::int32_t q, std::int32_t q1) {
  if (q + 1 >= q1) return false;
  const std::int64_t d = v.delta[q + 1] - v.delta[q];
  return d >= 4 || d <= -4;
}
// The bond vectors Y of groups q (low half) and q + 1 (high half) from the block's points (twice)
struct Pair8 {
  std::int64_t cj0, cj1;
  __m512d dx, dy, dz;
};
CRUMBLE_PD_AVX512 inline Pair8 bond_pair(const BoxView& v, std::int32_t q, std::int64_t c, __m512d xi8, __m512d yi8,
                                         __m512d zi8) {
  const std::int64_t cj0 = c + v.delta[q], cj1 = c + v.delta[q + 1];
  return {cj0, cj1, _mm512_sub_pd(load_pair(v.x, cj0, cj1), xi8), _mm512_sub_pd(load_pair(v.y, cj0, cj1), yi8),
          _mm512_sub_pd(load_pair(v.z, cj0, cj1), zi8)};
}

CRUMBLE_PD_AVX512 bool dilatation_avx512(const BoxView& view, std::int32_t k0, std::int32_t k1, double sc) {
  const BoxView v = view;  // a local copy: the may-alias stores of the intrinsics would force reloads of view's pointers
  const __m256d vsc = _mm256_set1_pd(sc);
  const __m512d vsc8 = _mm512_set1_pd(sc);
  __m256d broke = _mm256_setzero_pd();
  __mmask8 broke8 = 0;
  for (std::int32_t k = k0; k < k1; ++k) {
    const std::int64_t c = v.block_cell[k];
    const __m256d xi = _mm256_loadu_pd(v.x + c), yi = _mm256_loadu_pd(v.y + c), zi = _mm256_loadu_pd(v.z + c);
    const __m512d xi8 = twice(xi), yi8 = twice(yi), zi8 = twice(zi);
    __m256d acc = _mm256_setzero_pd();
    for (std::int32_t q = v.block_group[k], q1 = v.block_group[k + 1]; q < q1; q += 2) {
      if (!pairable(v, q, q1)) {
        dilatation_group4(v, q, c, xi, yi, zi, vsc, acc, broke);
        --q;  // one group, not two
        continue;
      }
      const auto [cj0, cj1, dx, dy, dz] = bond_pair(v, q, c, xi8, yi8, zi8);
      const __m512d l = _mm512_sqrt_pd(
          _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz)));
      _mm512_storeu_pd(v.cur + 4 * q, l);
      const __m512d r = len_pair(v, q);
      const __m512d e = _mm512_sub_pd(l, r);
      const __m512d old = _mm512_loadu_pd(v.alive + 4 * q);
      const __m512d w = _mm512_maskz_mov_pd(_mm512_cmp_pd_mask(e, _mm512_mul_pd(vsc8, r), _CMP_LE_OQ), old);
      broke8 |= _mm512_cmp_pd_mask(w, old, _CMP_NEQ_UQ);
      _mm512_storeu_pd(v.alive + 4 * q, w);
      const __m512d t = _mm512_mul_pd(_mm512_mul_pd(w, r), e);
      const __m256d t0 = _mm512_castpd512_pd256(t), t1 = _mm512_extractf64x4_pd(t, 1);
      acc = _mm256_add_pd(acc, t0);
      add4(v.th + cj0, t0);
      acc = _mm256_add_pd(acc, t1);
      add4(v.th + cj1, t1);
    }
    add4(v.th + c, acc);
  }
  return broke8 != 0 || _mm256_movemask_pd(broke) != 0;
}

CRUMBLE_PD_AVX512 void force_avx512(const BoxView& view, std::int32_t k0, std::int32_t k1) {
  const BoxView v = view;  // a local copy: the may-alias stores of the intrinsics would force reloads of view's pointers
  const __m512d tiny = _mm512_set1_pd(1e-3);
  for (std::int32_t k = k0; k < k1; ++k) {
    const std::int64_t c = v.block_cell[k];
    const Own4 o = own4(v, c);
    const __m512d xi8 = twice(o.x), yi8 = twice(o.y), zi8 = twice(o.z), ati8 = twice(o.at), bi8 = twice(o.b);
    __m256d sx = _mm256_setzero_pd(), sy = sx, sz = sx;
    for (std::int32_t q = v.block_group[k], q1 = v.block_group[k + 1]; q < q1; q += 2) {
      if (!pairable(v, q, q1)) {
        force_group4(v, q, c, o, sx, sy, sz);
        --q;  // one group, not two
        continue;
      }
      const auto [cj0, cj1, dx, dy, dz] = bond_pair(v, q, c, xi8, yi8, zi8);
      const __m512d l = _mm512_loadu_pd(v.cur + 4 * q);
      const __m512d r = len_pair(v, q);
      const __m512d t = _mm512_add_pd(_mm512_mul_pd(_mm512_add_pd(ati8, load_pair(v.at, cj0, cj1)), r),
                                      _mm512_mul_pd(_mm512_add_pd(bi8, load_pair(v.b, cj0, cj1)), _mm512_sub_pd(l, r)));
      const __m512d s = _mm512_div_pd(_mm512_mul_pd(_mm512_loadu_pd(v.alive + 4 * q), t),
                                      _mm512_max_pd(l, _mm512_mul_pd(tiny, r)));
      const __m512d gx = _mm512_mul_pd(s, dx), gy = _mm512_mul_pd(s, dy), gz = _mm512_mul_pd(s, dz);
      push_force(v, cj0, _mm512_castpd512_pd256(gx), _mm512_castpd512_pd256(gy), _mm512_castpd512_pd256(gz), sx, sy, sz);
      push_force(v, cj1, _mm512_extractf64x4_pd(gx, 1), _mm512_extractf64x4_pd(gy, 1), _mm512_extractf64x4_pd(gz, 1), sx,
                 sy, sz);
    }
    add4(v.fx + c, sx);
    add4(v.fy + c, sy);
    add4(v.fz + c, sz);
  }
}

#pragma GCC diagnostic pop

bool cpu_has_avx2() {
  static const bool ok = __builtin_cpu_supports("avx2");
  return ok;
}
bool cpu_has_avx512() {
  static const bool ok = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                         __builtin_cpu_supports("avx512vl") && cpu_has_avx2();
  return ok;
}
#else
bool cpu_has_avx2() { return false; }
bool cpu_has_avx512() { return false; }
#endif

enum Isa : int { kGeneric = 0, kAvx2 = 1, kAvx512 = 2 };
// AVX2 where the CPU has it, also when it has AVX-512: on the one AVX-512 CPU measured (AMD
// Zen 5, docs/performance.md) the AVX-512 version was 2-3 % slower on one thread and 13 % on
// two. The kernel is bound by its 4-cell loads and stores, not by arithmetic; the AVX-512
// version runs when select_isa("avx512") asks for it (`crumble bench pd-kernel` times it).
int best_isa() { return cpu_has_avx2() ? kAvx2 : kGeneric; }
// -1: the best this CPU has; else the version select_isa() chose.
std::atomic<int> g_selected{-1};
int current_isa() {
  const int s = g_selected.load(std::memory_order_relaxed);
  return s >= 0 ? s : best_isa();
}
const char* isa_name(int k) { return k == kAvx512 ? "avx512" : k == kAvx2 ? "avx2" : "generic"; }

}  // namespace

bool dilatation(const BoxView& v, std::int32_t k0, std::int32_t k1, double sc) {
#ifdef CRUMBLE_PD_HAVE_AVX2
  switch (current_isa()) {
    case kAvx512: return dilatation_avx512(v, k0, k1, sc);
    case kAvx2: return dilatation_avx2(v, k0, k1, sc);
    default: break;
  }
#endif
  return dilatation_portable(v, k0, k1, sc);
}

void force(const BoxView& v, std::int32_t k0, std::int32_t k1) {
#ifdef CRUMBLE_PD_HAVE_AVX2
  switch (current_isa()) {
    case kAvx512: return force_avx512(v, k0, k1);
    case kAvx2: return force_avx2(v, k0, k1);
    default: break;
  }
#endif
  force_portable(v, k0, k1);
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

// The linearised passes (CSR, full bond lists) sum each row in one fixed 8-lane order (bonds
// q0 + 8m + k to lane k, lanes added as ((l0 + l4) + (l2 + l6)) + ((l1 + l5) + (l3 + l7))), so
// the static solve and the step estimate are bitwise the same in every clone.
constexpr int kLanes = 8;
inline double reduce8(const double* l) {
  return ((l[0] + l[4]) + (l[2] + l[6])) + ((l[1] + l[5]) + (l[3] + l[7]));
}

CRUMBLE_PD_CLONES
void linear_dilatation(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                       const std::int32_t* __restrict nbr, const double* __restrict len, const double* __restrict w,
                       const double* __restrict xx, const double* __restrict xy, const double* __restrict xz,
                       const double* __restrict ux, const double* __restrict uy, const double* __restrict uz,
                       const double* __restrict g, const double* __restrict a, double* __restrict at) {
  for (std::int32_t i = i0; i < i1; ++i) {
    double acc[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0};
    const std::int32_t q1 = off[i + 1];
    for (std::int32_t q0 = off[i]; q0 < q1; q0 += kLanes) {
      const int m = std::min<std::int32_t>(kLanes, q1 - q0);
      for (int k = 0; k < m; ++k) {
        const std::int32_t q = q0 + k, j = nbr[q];
        const double e = (xx[q] * (ux[j] - ux[i]) + xy[q] * (uy[j] - uy[i]) + xz[q] * (uz[j] - uz[i])) / len[q];
        acc[k] += w[q] * len[q] * e;
      }
    }
    at[i] = a[i] * g[i] * reduce8(acc);
  }
}

CRUMBLE_PD_CLONES
void linear_force(std::int32_t i0, std::int32_t i1, const std::int32_t* __restrict off,
                  const std::int32_t* __restrict nbr, const double* __restrict len, const double* __restrict w,
                  const double* __restrict xx, const double* __restrict xy, const double* __restrict xz,
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
        const double dx = xx[q], dy = xy[q], dz = xz[q];
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
