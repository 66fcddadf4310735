// Discrete level sets (Harmon et al. 2020 §2, Appendix; Kawamoto et al. 2016).
//
// Decisions of ours (Harmon et al. 2020 leave them open):
// - Interpolation: trilinear (2D bilinear) of the node values; outside the grid the value
//   at the nearest grid point plus the distance to it (an upper bound of the distance, so
//   a point outside the grid never reads as penetrating).
// - Reinitialisation: a sampled function that is not a distance (radial approximations of
//   ellipsoids/superellipsoids, CSG results) is replaced by the distance to its zero set:
//   closest points on the zero set for the nodes within 3 cells of it (projection along the
//   gradient, then tangential correction until x − q ∥ ∇f(q)), propagated to the other
//   nodes by fast sweeping of closest points. Every candidate is a point of the zero set,
//   so taking the nearest one is safe; no PDE (eq. 17) smearing of the zero level.
// - Surface nodes: the zero level of the interpolant is triangulated by marching
//   tetrahedra on a sub-lattice (2D: marching triangles), the triangles (segments) are
//   clustered by a lattice of spacing h_s, and each cluster gives one node (its
//   area-weighted centre projected onto the zero level) with the cluster's area (length)
//   as weight. The weights sum to the area of the triangulated zero level. h_s = h gives
//   about one node per crossed cell; a target count sets h_s from the surface area.
// - Mass properties: Harmon et al. 2020 eqs. 24–30 with ε = 1.5 grid spacings. The smoothing biases
//   the volume by ≈ 2·(1/6 − 1/π²)·ε²·∫H_mean dA (0.39·ε²/R² relative for a sphere), i.e.
//   second order in h.
#include "geometry/LevelSetGrid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace crumble {

namespace {

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::uint64_t edge_key(std::uint64_t a, std::uint64_t b) {
  return a < b ? (a << 32) | b : (b << 32) | a;
}

double det3(const Vec3& a, const Vec3& b, const Vec3& c) { return dot(a, cross(b, c)); }

// One tetrahedron of marching tetrahedra: emits 0, 1 or 2 triangles oriented with their
// normal towards increasing values (outward). The orientation is decided on the corners of
// the tetrahedron, never on the (possibly degenerate) cut triangle, so the surface is
// consistently oriented even where a corner value is exactly 0.
template <class Emit>
void march_tet(const Vec3* p, const double* v, const std::uint64_t* k, Emit& emit) {
  int neg[4], pos[4], nn = 0, np = 0;
  for (int i = 0; i < 4; ++i) (v[i] < 0 ? neg[nn++] : pos[np++]) = i;
  if (nn == 0 || np == 0) return;
  Vec3 x[4];
  std::uint64_t ks[4];
  auto cut = [&](int slot, int a, int b) {
    const double t = v[a] / (v[a] - v[b]);
    x[slot] = p[a] + (p[b] - p[a]) * t;
    ks[slot] = k ? edge_key(k[a], k[b]) : 0;
  };
  auto emit_tri = [&](int i0, int i1, int i2) {
    const Vec3 xs[3] = {x[i0], x[i1], x[i2]};
    const std::uint64_t kk[3] = {ks[i0], ks[i1], ks[i2]};
    emit(xs, kk, 3);
  };
  if (nn == 1 || np == 1) {
    const int s = nn == 1 ? neg[0] : pos[0];
    int o[3];
    for (int i = 0; i < 3; ++i) o[i] = (nn == 1 ? pos : neg)[i];
    // det(o0−s, o1−s, o2−s) has the sign of the cut triangle seen from s: > 0 means its
    // normal points away from s, which is right when s is the inside corner.
    const double d = det3(p[o[0]] - p[s], p[o[1]] - p[s], p[o[2]] - p[s]);
    if ((d > 0) != (nn == 1)) std::swap(o[1], o[2]);
    for (int i = 0; i < 3; ++i) cut(i, s, o[i]);
    emit_tri(0, 1, 2);
  } else {  // 2–2: the quad a-c, a-d, b-d, b-c; right as listed when det(b−a, c−a, d−a) > 0
    int a = neg[0], b = neg[1];
    const int c = pos[0], d = pos[1];
    if (det3(p[b] - p[a], p[c] - p[a], p[d] - p[a]) < 0) std::swap(a, b);
    cut(0, a, c);
    cut(1, a, d);
    cut(2, b, d);
    cut(3, b, c);
    emit_tri(0, 1, 2);
    emit_tri(0, 2, 3);
  }
}

// A cube split into the 6 tetrahedra around its main diagonal (corner bits x=1, y=2, z=4);
// neighbouring cubes split their shared faces the same way, so the surface is closed.
template <class Emit>
void march_cube(const Vec3* p, const double* v, const std::uint64_t* k, Emit& emit) {
  static constexpr int kTets[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                                      {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
  for (const auto& t : kTets) {
    const Vec3 tp[4] = {p[t[0]], p[t[1]], p[t[2]], p[t[3]]};
    const double tv[4] = {v[t[0]], v[t[1]], v[t[2]], v[t[3]]};
    if (k) {
      const std::uint64_t tk[4] = {k[t[0]], k[t[1]], k[t[2]], k[t[3]]};
      march_tet(tp, tv, tk, emit);
    } else {
      march_tet(tp, tv, nullptr, emit);
    }
  }
}

// One triangle of marching triangles: a segment with the inside (negative) on its left,
// oriented on the triangle's corners (see march_tet).
template <class Emit>
void march_tri2(const Vec3* p, const double* v, const std::uint64_t* k, Emit& emit) {
  int neg[3], pos[3], nn = 0, np = 0;
  for (int i = 0; i < 3; ++i) (v[i] < 0 ? neg[nn++] : pos[np++]) = i;
  if (nn == 0 || np == 0) return;
  const int s = nn == 1 ? neg[0] : pos[0];
  int o[2] = {(nn == 1 ? pos : neg)[0], (nn == 1 ? pos : neg)[1]};
  // s lies left of the segment (o0-side cut → o1-side cut) iff cross(o0−s, o1−s) > 0.
  const Vec3 a = p[o[0]] - p[s], b = p[o[1]] - p[s];
  if ((a.x * b.y - a.y * b.x > 0) != (nn == 1)) std::swap(o[0], o[1]);
  Vec3 x[2];
  std::uint64_t ks[2];
  for (int i = 0; i < 2; ++i) {
    const double t = v[s] / (v[s] - v[o[i]]);
    x[i] = p[s] + (p[o[i]] - p[s]) * t;
    ks[i] = k ? edge_key(k[s], k[o[i]]) : 0;
  }
  emit(x, ks, 2);
}

template <class Emit>
void march_square(const Vec3* p, const double* v, const std::uint64_t* k, Emit& emit) {
  static constexpr int kTris[2][3] = {{0, 1, 3}, {0, 3, 2}};
  for (const auto& t : kTris) {
    const Vec3 tp[3] = {p[t[0]], p[t[1]], p[t[2]]};
    const double tv[3] = {v[t[0]], v[t[1]], v[t[2]]};
    if (k) {
      const std::uint64_t tk[3] = {k[t[0]], k[t[1]], k[t[2]]};
      march_tri2(tp, tv, tk, emit);
    } else {
      march_tri2(tp, tv, nullptr, emit);
    }
  }
}

double heaviside(double x, double eps) {
  // Harmon et al. 2020 eq. 24: smoothed Heaviside of half width ε.
  if (x < -eps) return 0;
  if (x >= eps) return 1;
  return 0.5 * (1 + x / eps + std::sin(kPi * x / eps) / kPi);
}

}  // namespace

// Everything that needs the private members.
struct LevelSetGridBuilder {
  using Field = std::function<double(const Vec3&)>;

  static std::shared_ptr<LevelSetGrid> make() { return std::shared_ptr<LevelSetGrid>(new LevelSetGrid()); }

  static std::size_t idx(const LevelSetGrid& g, int i, int j, int k) {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(g.n_[0]) * (j + static_cast<std::size_t>(g.n_[1]) * k);
  }
  static Vec3 point(const LevelSetGrid& g, int i, int j, int k) {
    return {g.origin_.x + i * g.h_, g.origin_.y + j * g.h_, g.dim_ == 3 ? g.origin_.z + k * g.h_ : 0.0};
  }

  // Visits the zero level of the interpolant. r = 1: whole cells with welding keys (global
  // node indices); r > 1: each crossed cell subdivided r times per axis (no keys).
  template <class Emit>
  static void march(const LevelSetGrid& g, int r, Emit emit) {
    const int nz = g.dim_ == 3 ? g.n_[2] - 1 : 1;
    const double hs = g.h_ / r;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < g.n_[1] - 1; ++j)
        for (int i = 0; i < g.n_[0] - 1; ++i) {
          const int nc = g.dim_ == 3 ? 8 : 4;
          double c[8];
          std::uint64_t key[8];
          double lo = 1e300, hi = -1e300;
          for (int b = 0; b < nc; ++b) {
            const std::size_t id = idx(g, i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
            c[b] = g.phi_[id];
            key[b] = id;
            lo = std::min(lo, c[b]);
            hi = std::max(hi, c[b]);
          }
          if (!(lo < 0 && hi >= 0)) continue;  // trilinear = convex combination of corners
          const Vec3 base = point(g, i, j, k);
          if (r == 1) {
            Vec3 p[8];
            for (int b = 0; b < nc; ++b)
              p[b] = base + Vec3{(b & 1) * g.h_, ((b >> 1) & 1) * g.h_, ((b >> 2) & 1) * g.h_};
            if (g.dim_ == 3) march_cube(p, c, key, emit);
            else march_square(p, c, key, emit);
            continue;
          }
          // Sub-lattice values by trilinear interpolation of the corners.
          const int m = r + 1, mz = g.dim_ == 3 ? m : 1;
          std::vector<double> sv(static_cast<std::size_t>(m) * m * mz);
          for (int c3 = 0; c3 < mz; ++c3)
            for (int c2 = 0; c2 < m; ++c2)
              for (int c1 = 0; c1 < m; ++c1) {
                const double tx = double(c1) / r, ty = double(c2) / r, tz = g.dim_ == 3 ? double(c3) / r : 0;
                double v = 0;
                for (int b = 0; b < nc; ++b)
                  v += c[b] * ((b & 1) ? tx : 1 - tx) * ((b & 2) ? ty : 1 - ty) * ((b & 4) ? tz : 1 - tz);
                sv[c1 + m * (c2 + m * c3)] = v;
              }
          for (int c3 = 0; c3 < (g.dim_ == 3 ? r : 1); ++c3)
            for (int c2 = 0; c2 < r; ++c2)
              for (int c1 = 0; c1 < r; ++c1) {
                Vec3 p[8];
                double v[8];
                for (int b = 0; b < nc; ++b) {
                  const int a1 = c1 + (b & 1), a2 = c2 + ((b >> 1) & 1), a3 = c3 + ((b >> 2) & 1);
                  v[b] = sv[a1 + m * (a2 + m * a3)];
                  p[b] = base + Vec3{a1 * hs, a2 * hs, g.dim_ == 3 ? a3 * hs : 0.0};
                }
                if (g.dim_ == 3) march_cube(p, v, nullptr, emit);
                else march_square(p, v, nullptr, emit);
              }
        }
  }

  // Numerical gradient of a field (central differences).
  static Vec3 grad(const Field& f, const Vec3& x, double eta, int dim) {
    Vec3 g;
    for (int a = 0; a < dim; ++a) {
      Vec3 xp = x, xm = x;
      xp[a] += eta;
      xm[a] -= eta;
      g[a] = (f(xp) - f(xm)) / (2 * eta);
    }
    return g;
  }

  // Newton steps along the gradient onto the zero level of f.
  static Vec3 project(const Field& f, Vec3 x, double h, int dim) {
    for (int it = 0; it < 30; ++it) {
      const double v = f(x);
      if (std::abs(v) < 1e-10 * h) break;
      const Vec3 g = grad(f, x, 1e-4 * h, dim);
      const double gg = norm2(g);
      if (!(gg > 1e-20)) break;
      Vec3 step = g * (v / gg);
      const double sn = norm(step);
      if (sn > 2 * h) step *= 2 * h / sn;  // far from the zero level the gradient may mislead
      x -= step;
    }
    return x;
  }

  // Closest point of the zero level of f to x0 (local minimum of |x0 − q| on the zero set,
  // from the projection of x0 by tangential correction with backtracking).
  static Vec3 foot_point(const Field& f, const Vec3& x0, double h, int dim) {
    Vec3 q = project(f, x0, h, dim);
    double best = norm(x0 - q);
    double beta = 1.0;
    for (int it = 0; it < 40; ++it) {
      const Vec3 n = normalized(grad(f, q, 1e-4 * h, dim));
      const Vec3 d = x0 - q;
      const Vec3 t = d - n * dot(d, n);
      if (norm(t) < 1e-9 * h) break;
      const Vec3 q2 = project(f, q + t * beta, h, dim);
      const double d2 = norm(x0 - q2);
      if (d2 < best) {
        best = d2;
        q = q2;
        beta = std::min(1.0, beta * 2);
      } else {
        beta *= 0.5;
        if (beta < 1e-3) break;
      }
    }
    return q;
  }

  // Replaces g.phi_ by the signed distance to the zero set of `f` (sign from g.phi_).
  static void redistance(LevelSetGrid& g, const Field& f) {
    const std::size_t N = g.phi_.size();
    const int nz = g.dim_ == 3 ? g.n_[2] : 1;
    std::vector<Vec3> cp(N);
    std::vector<char> has(N, 0);
    std::vector<double> dist(N, 1e300);
    const double band = 3 * g.h_;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < g.n_[1]; ++j)
        for (int i = 0; i < g.n_[0]; ++i) {
          const std::size_t id = idx(g, i, j, k);
          bool near = std::abs(g.phi_[id]) < band;
          if (!near) {  // a sign change to a neighbour also puts a node in the band
            const int di[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
            for (int d = 0; d < 2 * g.dim_ && !near; ++d) {
              const int a = i + di[d][0], b = j + di[d][1], c = k + di[d][2];
              if (a < 0 || b < 0 || c < 0 || a >= g.n_[0] || b >= g.n_[1] || c >= nz) continue;
              near = (g.phi_[idx(g, a, b, c)] < 0) != (g.phi_[id] < 0);
            }
          }
          if (!near) continue;
          const Vec3 x = point(g, i, j, k);
          cp[id] = foot_point(f, x, g.h_, g.dim_);
          has[id] = 1;
          dist[id] = norm(x - cp[id]);
        }
    // Fast sweeping of closest points (every direction combination, twice).
    const int ns = g.dim_ == 3 ? 8 : 4;
    for (int round = 0; round < 2; ++round)
      for (int s = 0; s < ns; ++s) {
        const int sx = (s & 1) ? -1 : 1, sy = (s & 2) ? -1 : 1, sz = (s & 4) ? -1 : 1;
        for (int kk = 0; kk < nz; ++kk)
          for (int jj = 0; jj < g.n_[1]; ++jj)
            for (int ii = 0; ii < g.n_[0]; ++ii) {
              const int i = sx > 0 ? ii : g.n_[0] - 1 - ii;
              const int j = sy > 0 ? jj : g.n_[1] - 1 - jj;
              const int k = sz > 0 ? kk : nz - 1 - kk;
              const std::size_t id = idx(g, i, j, k);
              const Vec3 x = point(g, i, j, k);
              const int nb[3][3] = {{i - sx, j, k}, {i, j - sy, k}, {i, j, k - sz}};
              for (int d = 0; d < g.dim_; ++d) {
                const int a = nb[d][0], b = nb[d][1], c = nb[d][2];
                if (a < 0 || b < 0 || c < 0 || a >= g.n_[0] || b >= g.n_[1] || c >= nz) continue;
                const std::size_t o = idx(g, a, b, c);
                if (!has[o]) continue;
                const double dd = norm(x - cp[o]);
                if (dd < dist[id]) {
                  dist[id] = dd;
                  cp[id] = cp[o];
                  has[id] = 1;
                }
              }
            }
      }
    for (std::size_t id = 0; id < N; ++id)
      if (has[id]) g.phi_[id] = g.phi_[id] < 0 ? -dist[id] : dist[id];
  }

  // Surface nodes by clustering the triangulated zero level (see the file comment).
  static void build_nodes(LevelSetGrid& g, const Field* exact, int target, double hs_fixed) {
    struct Piece {
      Vec3 c;
      double w;
    };
    auto soup = [&](int r) {
      std::vector<Piece> out;
      march(g, r, [&](const Vec3* x, const std::uint64_t*, int nv) {
        if (nv == 3) {
          const double a = 0.5 * norm(cross(x[1] - x[0], x[2] - x[0]));
          if (a > 0) out.push_back({(x[0] + x[1] + x[2]) / 3.0, a});
        } else {
          const double l = norm(x[1] - x[0]);
          if (l > 0) out.push_back({(x[0] + x[1]) * 0.5, l});
        }
      });
      return out;
    };
    const double dimf = g.dim_;
    auto area_of = [](const std::vector<Piece>& s) {
      double a = 0;
      for (const auto& p : s) a += p.w;
      return a;
    };
    // Expected nodes per unit area (length) of a lattice of spacing hs: mean L1 norm of the
    // unit normal (3/2 over a sphere, 4/π over a circle) per cell face.
    const double l1 = g.dim_ == 3 ? 1.5 : 4.0 / kPi;
    double hs = hs_fixed > 0 ? hs_fixed : g.h_;
    std::vector<Piece> pieces = soup(2);
    const double area = area_of(pieces);
    if (hs_fixed <= 0 && target > 0 && area > 0)
      hs = g.dim_ == 3 ? std::sqrt(l1 * area / target) : l1 * area / target;
    int r = std::max(2, static_cast<int>(std::ceil(2 * g.h_ / hs - 1e-9)));
    if (r > 2) pieces = soup(r);

    const Vec3 off{0.3183, 0.4721, 0.2236};  // cluster lattice shifted off the sub-lattice
    auto cluster = [&](double s, std::vector<Vec3>& nodes, std::vector<double>& w) {
      std::map<std::array<long, 3>, std::size_t> at;
      nodes.clear();
      w.clear();
      for (const auto& p : pieces) {
        const Vec3 q = (p.c - g.origin_) / s + off;
        const std::array<long, 3> key{static_cast<long>(std::floor(q.x)), static_cast<long>(std::floor(q.y)),
                                      g.dim_ == 3 ? static_cast<long>(std::floor(q.z)) : 0L};
        auto [it, fresh] = at.emplace(key, nodes.size());
        if (fresh) {
          nodes.push_back({});
          w.push_back(0);
        }
        nodes[it->second] += p.c * p.w;
        w[it->second] += p.w;
      }
      // Order by lattice key (deterministic, spatially coherent).
      std::vector<Vec3> n2;
      std::vector<double> w2;
      for (const auto& [key, i] : at) {
        n2.push_back(nodes[i] / w[i]);
        w2.push_back(w[i]);
      }
      nodes = std::move(n2);
      w = std::move(w2);
    };
    std::vector<Vec3> nodes;
    std::vector<double> w;
    cluster(hs, nodes, w);
    if (hs_fixed <= 0 && target > 0) {
      for (int it = 0; it < 4 && !nodes.empty(); ++it) {
        const double ratio = double(nodes.size()) / target;
        if (std::abs(ratio - 1) < 0.05) break;
        hs *= std::pow(ratio, 1.0 / (dimf - 1));
        cluster(hs, nodes, w);
      }
    }
    // Onto the zero level: of the exact function when given, else of the interpolant.
    const Field interp = [&g](const Vec3& x) { return g.value(x); };
    const Field& f = exact ? *exact : interp;
    for (auto& x : nodes) {
      x = project(f, x, g.h_, g.dim_);
      if (g.dim_ == 2) x.z = 0;
    }
    g.nodes_ = std::move(nodes);
    g.node_w_ = std::move(w);
    g.node_h_ = hs;
  }

  static void check_nodes(const LevelSetGrid& g) {
    if (g.nodes_.empty())
      throw std::invalid_argument(g.name_ + ": the level set has no zero level inside the grid (no surface node)");
  }
};

std::shared_ptr<const LevelSetGrid> LevelSetGrid::sample(int dimension, const Aabb& bounds, double h, const Sdf& sdf,
                                                         int target_nodes, int pad) {
  LevelSetOptions o;
  o.target_nodes = target_nodes;
  o.pad = pad;
  return sample(dimension, bounds, h, sdf, o);
}

std::shared_ptr<const LevelSetGrid> LevelSetGrid::sample(int dim, const Aabb& b, double h, const Sdf& sdf,
                                                         const LevelSetOptions& opt) {
  const std::string& who = opt.name;
  if (dim != 2 && dim != 3) throw std::invalid_argument(who + ": level-set dimension must be 2 or 3");
  if (!(h > 0) || !std::isfinite(h))
    throw std::invalid_argument(who + ": level-set spacing must be a finite number > 0 (got " + num(h) + ")");
  if (!sdf) throw std::invalid_argument(who + ": no signed-distance function to sample");
  if (b.empty() || !is_finite(b.lo) || !is_finite(b.hi))
    throw std::invalid_argument(who + ": empty or non-finite bounds");
  if (opt.pad < 2) throw std::invalid_argument(who + ": level-set padding must be >= 2 cells");
  if (opt.target_nodes < 0) throw std::invalid_argument(who + ": negative surface-node target");
  const Vec3 ext = b.size();
  const double thin = dim == 2 ? std::min(ext.x, ext.y) : std::min({ext.x, ext.y, ext.z});
  if (thin < 2 * h)
    throw std::invalid_argument(who + " is thinner (" + num(thin) + " m) than two level-set cells (2 x " + num(h) +
                                " m)");
  auto g = LevelSetGridBuilder::make();
  g->dim_ = dim;
  g->h_ = h;
  g->inv_h_ = 1.0 / h;
  g->name_ = who;
  g->origin_ = b.lo - Vec3{1, 1, 1} * (opt.pad * h);
  if (dim == 2) g->origin_.z = 0;
  double total = 1;
  for (int a = 0; a < 3; ++a) {
    if (a == 2 && dim == 2) {
      g->n_[a] = 1;
      continue;
    }
    const double cells = std::ceil(ext[a] / h - 1e-9);
    g->n_[a] = static_cast<int>(std::min(cells, 1e9)) + 1 + 2 * opt.pad;
    total *= g->n_[a];
  }
  // 2e7 nodes (≈ 270³) = 160 MB of values and a minute of sampling: far beyond any grain's
  // need; larger requests (fuzzing found them) ran out of memory.
  if (total > 2e7)
    throw std::invalid_argument(who + ": level-set grid of " + num(total) + " nodes is too large (spacing " + num(h) +
                                " m; at most 2e7 nodes): raise resolution.level_set_spacing");
  g->phi_.resize(static_cast<std::size_t>(total));
  for (int k = 0; k < g->n_[2]; ++k)
    for (int j = 0; j < g->n_[1]; ++j)
      for (int i = 0; i < g->n_[0]; ++i) {
        const double v = sdf(LevelSetGridBuilder::point(*g, i, j, k));
        if (!std::isfinite(v))
          throw std::invalid_argument(who + ": signed-distance function is not finite at a grid node");
        g->phi_[LevelSetGridBuilder::idx(*g, i, j, k)] = v;
      }
  if (!opt.exact_distance) LevelSetGridBuilder::redistance(*g, sdf);
  LevelSetGridBuilder::build_nodes(*g, &sdf, opt.target_nodes, 0);
  LevelSetGridBuilder::check_nodes(*g);
  return g;
}

double LevelSetGrid::value_gradient(const Vec3& p, Vec3& grad) const {
  const double inv = 1.0 / h_;
  double f[3] = {(p.x - origin_.x) * inv, (p.y - origin_.y) * inv, dim_ == 3 ? (p.z - origin_.z) * inv : 0.0};
  double extra2 = 0;
  Vec3 outdir;
  for (int a = 0; a < dim_; ++a) {
    const double m = n_[a] - 1;
    double d = 0;
    if (f[a] < 0) d = f[a], f[a] = 0;
    else if (f[a] > m) d = f[a] - m, f[a] = m;
    if (d != 0) {
      extra2 += d * d;
      outdir[a] = d;
    }
  }
  int i = std::min(static_cast<int>(f[0]), n_[0] - 2);
  int j = std::min(static_cast<int>(f[1]), n_[1] - 2);
  const double tx = f[0] - i, ty = f[1] - j;
  const std::size_t sx = 1, sy = static_cast<std::size_t>(n_[0]);
  double v;
  if (dim_ == 3) {
    const int k = std::min(static_cast<int>(f[2]), n_[2] - 2);
    const double tz = f[2] - k;
    const std::size_t sz = sy * n_[1];
    const double* c = &phi_[i + sy * j + sz * k];
    const double c000 = c[0], c100 = c[sx], c010 = c[sy], c110 = c[sx + sy];
    const double c001 = c[sz], c101 = c[sx + sz], c011 = c[sy + sz], c111 = c[sx + sy + sz];
    const double c00 = c000 + (c100 - c000) * tx, c10 = c010 + (c110 - c010) * tx;
    const double c01 = c001 + (c101 - c001) * tx, c11 = c011 + (c111 - c011) * tx;
    const double c0 = c00 + (c10 - c00) * ty, c1 = c01 + (c11 - c01) * ty;
    v = c0 + (c1 - c0) * tz;
    const double dx0 = (c100 - c000) + ((c110 - c010) - (c100 - c000)) * ty;
    const double dx1 = (c101 - c001) + ((c111 - c011) - (c101 - c001)) * ty;
    grad.x = (dx0 + (dx1 - dx0) * tz) * inv;
    grad.y = ((c10 - c00) + ((c11 - c01) - (c10 - c00)) * tz) * inv;
    grad.z = (c1 - c0) * inv;
  } else {
    const double* c = &phi_[i + sy * j];
    const double c00 = c[0], c10 = c[sx], c01 = c[sy], c11 = c[sx + sy];
    const double a0 = c00 + (c10 - c00) * tx, a1 = c01 + (c11 - c01) * tx;
    v = a0 + (a1 - a0) * ty;
    grad.x = ((c10 - c00) + ((c11 - c01) - (c10 - c00)) * ty) * inv;
    grad.y = (a1 - a0) * inv;
    grad.z = 0;
  }
  if (extra2 > 0) {
    // Outside: value at the nearest grid point plus the distance to it (never penetrating:
    // the border values are >= pad·h > 0), gradient pointing away from the grid.
    const double e = std::sqrt(extra2);
    grad = outdir / e;
    return v + e * h_;
  }
  return v;
}

double LevelSetGrid::value(const Vec3& p) const {
  Vec3 g;
  return value_gradient(p, g);
}

Vec3 LevelSetGrid::gradient(const Vec3& p) const {
  Vec3 g;
  value_gradient(p, g);
  return g;
}

bool LevelSetGrid::inside_grid(const Vec3& p) const {
  for (int a = 0; a < dim_; ++a) {
    const double f = (p[a] - origin_[a]) / h_;
    if (!(f >= 0 && f <= n_[a] - 1)) return false;
  }
  return true;
}

Aabb LevelSetGrid::bounds() const {
  Aabb b;
  b.lo = origin_;
  b.hi = origin_ + Vec3{(n_[0] - 1) * h_, (n_[1] - 1) * h_, dim_ == 3 ? (n_[2] - 1) * h_ : 0.0};
  return b;
}

MassProperties LevelSetGrid::mass_properties() const {
  // Harmon et al. 2020 eqs. 24–30, per unit density, ε = 1.5 h (the paper's 1.5 in grid units).
  const double eps = heaviside_width();
  const double dv = dim_ == 3 ? h_ * h_ * h_ : h_ * h_;
  const int nz = dim_ == 3 ? n_[2] : 1;
  double V = 0;
  Vec3 s1;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i) {
        const double w = heaviside(-phi_[LevelSetGridBuilder::idx(*this, i, j, k)], eps);
        if (w == 0) continue;
        V += w;
        s1 += LevelSetGridBuilder::point(*this, i, j, k) * w;
      }
  MassProperties mp;
  if (!(V > 0)) return mp;
  const Vec3 c = s1 / V;
  Mat3 S;  // central second moments Σ w (x_i − c_i)(x_j − c_j)
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i) {
        const double w = heaviside(-phi_[LevelSetGridBuilder::idx(*this, i, j, k)], eps);
        if (w == 0) continue;
        const Vec3 d = LevelSetGridBuilder::point(*this, i, j, k) - c;
        S += Mat3::outer(d, d) * w;
      }
  S = S * dv;
  mp.volume = V * dv;
  mp.centroid = c;
  if (dim_ == 2) {
    mp.centroid.z = 0;
    Mat3 I;
    I(0, 0) = S(1, 1);
    I(1, 1) = S(0, 0);
    I(2, 2) = S(0, 0) + S(1, 1);
    I(0, 1) = I(1, 0) = -S(0, 1);
    mp.inertia = I;
  } else {
    mp.inertia = Mat3::identity() * S.trace() - S;  // eq. 29
  }
  return mp;
}

TriMesh LevelSetGrid::to_mesh() const {
  if (dim_ != 3) throw std::logic_error(name_ + ": to_mesh() asked of a 2D level set; use outline()");
  TriMesh m;
  std::unordered_map<std::uint64_t, int> at;
  LevelSetGridBuilder::march(*this, 1, [&](const Vec3* x, const std::uint64_t* k, int) {
    std::array<int, 3> t;
    for (int a = 0; a < 3; ++a) {
      auto [it, fresh] = at.emplace(k[a], static_cast<int>(m.vertices.size()));
      if (fresh) m.vertices.push_back(x[a]);
      t[a] = it->second;
    }
    m.triangles.push_back(t);
  });
  return m;
}

std::vector<Vec3> LevelSetGrid::outline() const {
  if (dim_ != 2) throw std::logic_error(name_ + ": outline() asked of a 3D level set; use to_mesh()");
  std::unordered_map<std::uint64_t, std::pair<std::uint64_t, Vec3>> next;  // start key -> (end key, start point)
  std::vector<std::uint64_t> order;
  LevelSetGridBuilder::march(*this, 1, [&](const Vec3* x, const std::uint64_t* k, int) {
    if (next.emplace(k[0], std::make_pair(k[1], x[0])).second) order.push_back(k[0]);
  });
  std::vector<Vec3> best;
  double best_area = 0;
  std::unordered_map<std::uint64_t, char> used;
  for (std::uint64_t start : order) {
    if (used.count(start)) continue;
    std::vector<Vec3> loop;
    std::uint64_t k = start;
    while (!used.count(k)) {
      auto it = next.find(k);
      if (it == next.end()) break;
      used[k] = 1;
      loop.push_back(it->second.second);
      k = it->second.first;
    }
    double a = 0;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec3& p = loop[i];
      const Vec3& q = loop[(i + 1) % loop.size()];
      a += p.x * q.y - q.x * p.y;
    }
    if (a > best_area) {
      best_area = a;
      best = std::move(loop);
    }
  }
  return best;
}

std::shared_ptr<const LevelSetGrid> LevelSetGrid::with_values(std::vector<double> phi) const {
  if (phi.size() != phi_.size())
    throw std::invalid_argument(name_ + ": with_values got " + std::to_string(phi.size()) + " values for a grid of " +
                                std::to_string(phi_.size()));
  for (double v : phi)
    if (!std::isfinite(v)) throw std::invalid_argument(name_ + ": with_values got a non-finite value");
  auto g = LevelSetGridBuilder::make();
  g->dim_ = dim_;
  g->h_ = h_;
  g->inv_h_ = inv_h_;
  g->origin_ = origin_;
  g->n_ = n_;
  g->name_ = name_;
  g->phi_ = std::move(phi);
  LevelSetGridBuilder::build_nodes(*g, nullptr, 0, node_h_ > 0 ? node_h_ : h_);
  LevelSetGridBuilder::check_nodes(*g);
  return g;
}

std::shared_ptr<const LevelSetGrid> LevelSetGrid::from_values(int dim, const Vec3& origin, double h,
                                                              const std::array<int, 3>& counts,
                                                              std::vector<double> values, double node_spacing,
                                                              bool surface_nodes, const std::string& name) {
  if (dim != 2 && dim != 3) throw std::invalid_argument(name + ": level-set dimension must be 2 or 3");
  if (!(h > 0) || !std::isfinite(h))
    throw std::invalid_argument(name + ": level-set spacing must be a finite number > 0 (got " + num(h) + ")");
  if (!(node_spacing >= 0) || !std::isfinite(node_spacing))
    throw std::invalid_argument(name + ": node spacing must be a finite number >= 0 (got " + num(node_spacing) + ")");
  if (!is_finite(origin)) throw std::invalid_argument(name + ": level-set origin is not finite");
  double total = 1;
  for (int a = 0; a < 3; ++a) {
    const int need = (a == 2 && dim == 2) ? 1 : 2;
    if (a == 2 && dim == 2 ? counts[a] != 1 : counts[a] < need)
      throw std::invalid_argument(name + ": level-set node count along axis " + std::to_string(a) + " must be " +
                                  (a == 2 && dim == 2 ? std::string("1 in 2D") : std::string(">= 2")) + " (got " +
                                  std::to_string(counts[a]) + ")");
    total *= counts[a];
  }
  if (total > 2e8) throw std::invalid_argument(name + ": level-set grid of " + num(total) + " nodes is too large");
  if (static_cast<double>(values.size()) != total)
    throw std::invalid_argument(name + ": " + std::to_string(values.size()) + " level-set values for " + num(total) +
                                " grid nodes");
  for (double v : values)
    if (!std::isfinite(v)) throw std::invalid_argument(name + ": a level-set value is not finite");
  auto g = LevelSetGridBuilder::make();
  g->dim_ = dim;
  g->h_ = h;
  g->inv_h_ = 1.0 / h;
  g->origin_ = origin;
  if (dim == 2) g->origin_.z = 0;
  g->n_ = counts;
  g->name_ = name;
  g->phi_ = std::move(values);
  g->node_h_ = node_spacing > 0 ? node_spacing : h;
  if (surface_nodes) {
    LevelSetGridBuilder::build_nodes(*g, nullptr, 0, g->node_h_);
    LevelSetGridBuilder::check_nodes(*g);
  }
  return g;
}

std::shared_ptr<const LevelSetGrid> LevelSetGrid::with_nodes(std::vector<Vec3> nodes,
                                                             std::vector<double> weights) const {
  if (nodes.size() != weights.size())
    throw std::invalid_argument(name_ + ": " + std::to_string(nodes.size()) + " surface nodes but " +
                                std::to_string(weights.size()) + " weights");
  if (nodes.empty()) throw std::invalid_argument(name_ + ": no surface node");
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (!is_finite(nodes[i])) throw std::invalid_argument(name_ + ": surface node " + std::to_string(i) + " is not finite");
    if (!(weights[i] > 0) || !std::isfinite(weights[i]))
      throw std::invalid_argument(name_ + ": surface node weight " + std::to_string(i) + " must be a finite number > 0");
    if (dim_ == 2) nodes[i].z = 0;
  }
  auto g = LevelSetGridBuilder::make();
  *g = *this;
  g->nodes_ = std::move(nodes);
  g->node_w_ = std::move(weights);
  return g;
}

std::shared_ptr<const LevelSetGrid> LevelSetGrid::translated(const Vec3& d) const {
  if (!is_finite(d)) throw std::invalid_argument(name_ + ": non-finite translation");
  auto g = LevelSetGridBuilder::make();
  *g = *this;
  Vec3 dd = d;
  if (dim_ == 2) dd.z = 0;
  g->origin_ += dd;
  for (auto& x : g->nodes_) x += dd;
  return g;
}

std::shared_ptr<const LevelSetGrid> LevelSetGrid::scaled(double f) const {
  if (!(f > 0) || !std::isfinite(f)) throw std::invalid_argument(name_ + ": scale factor must be a finite number > 0");
  auto g = LevelSetGridBuilder::make();
  *g = *this;
  g->h_ = h_ * f;
  g->inv_h_ = 1.0 / g->h_;
  g->origin_ = origin_ * f;
  g->node_h_ = node_h_ * f;
  for (auto& v : g->phi_) v *= f;
  for (auto& x : g->nodes_) x *= f;
  const double wf = dim_ == 3 ? f * f : f;  // node weights are areas (2D: lengths)
  for (auto& w : g->node_w_) w *= wf;
  return g;
}

std::shared_ptr<const LevelSetGrid> LevelSetGrid::resampled(double h, double node_spacing, int pad) const {
  if (!(h > 0) || !std::isfinite(h) || pad < 2)
    throw std::invalid_argument(name_ + ": resampling needs a finite spacing > 0 and a margin of >= 2 cells");
  if (nodes_.empty()) throw std::invalid_argument(name_ + ": resampling needs the surface nodes");
  Aabb box;
  for (const auto& x : nodes_) box.extend(x);
  const Vec3 origin = box.lo - Vec3{1, 1, dim_ == 3 ? 1.0 : 0.0} * (pad * h);
  std::array<int, 3> n{1, 1, 1};
  double total = 1;
  for (int a = 0; a < dim_; ++a) {
    n[a] = static_cast<int>(std::min(std::ceil(box.size()[a] / h - 1e-9), 1e9)) + 1 + 2 * pad;
    total *= n[a];
  }
  if (total > 2e8) throw std::invalid_argument(name_ + ": resampled grid of " + num(total) + " nodes is too large");
  std::vector<double> v(static_cast<std::size_t>(total));
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        v[i + static_cast<std::size_t>(n[0]) * (j + static_cast<std::size_t>(n[1]) * k)] =
            value(origin + Vec3{i * h, j * h, dim_ == 3 ? k * h : 0.0});
  return from_values(dim_, origin, h, n, std::move(v), node_spacing, true, name_);
}

std::shared_ptr<const LevelSetGrid> LevelSetGrid::reinitialised() const {
  auto g = LevelSetGridBuilder::make();
  *g = *this;
  const LevelSetGrid& self = *this;
  LevelSetGridBuilder::redistance(*g, [&self](const Vec3& x) { return self.value(x); });
  return g;
}

}  // namespace crumble
