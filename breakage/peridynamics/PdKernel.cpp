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

__attribute__((target("avx2"))) bool dilatation_avx2(const BoxView& v, std::int32_t k0, std::int32_t k1, double sc) {
  const __m256d vsc = _mm256_set1_pd(sc);
  const double *X = v.x, *Y = v.y, *Z = v.z;
  double* T = v.th;
  __m256d broke = _mm256_setzero_pd();
  for (std::int32_t k = k0; k < k1; ++k) {
    const std::int64_t c = v.block_cell[k];
    const __m256d xi = _mm256_loadu_pd(X + c), yi = _mm256_loadu_pd(Y + c), zi = _mm256_loadu_pd(Z + c);
    __m256d acc = _mm256_setzero_pd();
    for (std::int32_t q = v.block_group[k]; q < v.block_group[k + 1]; ++q) {
      const std::int64_t cj = c + v.delta[q];
      const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(X + cj), xi);
      const __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(Y + cj), yi);
      const __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(Z + cj), zi);
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
      _mm256_storeu_pd(T + cj, _mm256_add_pd(_mm256_loadu_pd(T + cj), t));
    }
    _mm256_storeu_pd(T + c, _mm256_add_pd(_mm256_loadu_pd(T + c), acc));
  }
  return _mm256_movemask_pd(broke) != 0;
}

__attribute__((target("avx2"))) void force_avx2(const BoxView& v, std::int32_t k0, std::int32_t k1) {
  const __m256d tiny = _mm256_set1_pd(1e-3);
  const double *X = v.x, *Y = v.y, *Z = v.z, *AT = v.at, *B = v.b;
  double *FX = v.fx, *FY = v.fy, *FZ = v.fz;
  for (std::int32_t k = k0; k < k1; ++k) {
    const std::int64_t c = v.block_cell[k];
    const __m256d xi = _mm256_loadu_pd(X + c), yi = _mm256_loadu_pd(Y + c), zi = _mm256_loadu_pd(Z + c);
    const __m256d ati = _mm256_loadu_pd(AT + c), bi = _mm256_loadu_pd(B + c);
    __m256d sx = _mm256_setzero_pd(), sy = sx, sz = sx;
    for (std::int32_t q = v.block_group[k]; q < v.block_group[k + 1]; ++q) {
      const std::int64_t cj = c + v.delta[q];
      const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(X + cj), xi);
      const __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(Y + cj), yi);
      const __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(Z + cj), zi);
      const __m256d l = _mm256_loadu_pd(v.cur + 4 * q);
      const __m256d r = _mm256_set1_pd(v.len[q]);
      const __m256d t = _mm256_add_pd(_mm256_mul_pd(_mm256_add_pd(ati, _mm256_loadu_pd(AT + cj)), r),
                                      _mm256_mul_pd(_mm256_add_pd(bi, _mm256_loadu_pd(B + cj)), _mm256_sub_pd(l, r)));
      const __m256d s = _mm256_div_pd(_mm256_mul_pd(_mm256_loadu_pd(v.alive + 4 * q), t),
                                      _mm256_max_pd(l, _mm256_mul_pd(tiny, r)));
      const __m256d gx = _mm256_mul_pd(s, dx), gy = _mm256_mul_pd(s, dy), gz = _mm256_mul_pd(s, dz);
      sx = _mm256_add_pd(sx, gx);
      sy = _mm256_add_pd(sy, gy);
      sz = _mm256_add_pd(sz, gz);
      _mm256_storeu_pd(FX + cj, _mm256_sub_pd(_mm256_loadu_pd(FX + cj), gx));
      _mm256_storeu_pd(FY + cj, _mm256_sub_pd(_mm256_loadu_pd(FY + cj), gy));
      _mm256_storeu_pd(FZ + cj, _mm256_sub_pd(_mm256_loadu_pd(FZ + cj), gz));
    }
    _mm256_storeu_pd(FX + c, _mm256_add_pd(_mm256_loadu_pd(FX + c), sx));
    _mm256_storeu_pd(FY + c, _mm256_add_pd(_mm256_loadu_pd(FY + c), sy));
    _mm256_storeu_pd(FZ + c, _mm256_add_pd(_mm256_loadu_pd(FZ + c), sz));
  }
}

bool cpu_has_avx2() {
  static const bool ok = __builtin_cpu_supports("avx2");
  return ok;
}
#else
bool cpu_has_avx2() { return false; }
#endif

enum Isa : int { kGeneric = 0, kAvx2 = 1 };
int best_isa() { return cpu_has_avx2() ? kAvx2 : kGeneric; }
// -1: the best this CPU has; else the version select_isa() chose.
std::atomic<int> g_selected{-1};
int current_isa() {
  const int s = g_selected.load(std::memory_order_relaxed);
  return s >= 0 ? s : best_isa();
}
const char* isa_name(int k) { return k == kAvx2 ? "avx2" : "generic"; }

}  // namespace

bool dilatation(const BoxView& v, std::int32_t k0, std::int32_t k1, double sc) {
#ifdef CRUMBLE_PD_HAVE_AVX2
  if (current_isa() == kAvx2) return dilatation_avx2(v, k0, k1, sc);
#endif
  return dilatation_portable(v, k0, k1, sc);
}

void force(const BoxView& v, std::int32_t k0, std::int32_t k1) {
#ifdef CRUMBLE_PD_HAVE_AVX2
  if (current_isa() == kAvx2) return force_avx2(v, k0, k1);
#endif
  force_portable(v, k0, k1);
}

const char* isa() { return isa_name(current_isa()); }

std::vector<std::string> available_isas() {
  std::vector<std::string> v{"generic"};
  if (cpu_has_avx2()) v.emplace_back("avx2");
  return v;
}

void select_isa(const std::string& name) {
  if (name.empty()) {
    g_selected.store(-1);
    return;
  }
  for (int k : {kGeneric, kAvx2})
    if (name == isa_name(k)) {
      const auto av = available_isas();
      if (std::find(av.begin(), av.end(), name) == av.end())
        throw std::invalid_argument("peridynamics kernel: this CPU cannot run the " + name + " version");
      g_selected.store(k);
      return;
    }
  throw std::invalid_argument("peridynamics kernel: unknown version '" + name + "' (known: generic, avx2)");
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
