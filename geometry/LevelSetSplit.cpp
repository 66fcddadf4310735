#include "geometry/LevelSetSplit.h"

#include "base/BuildCounters.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace crumble {

namespace {

// The lattice φ1 is read on: the parent's own grid, or the parent resampled at the
// requested child spacing.
const LevelSetGrid& working_grid(const LevelSetGrid& parent, const SplitOptions& o,
                                 std::shared_ptr<const LevelSetGrid>& hold) {
  if (!(o.spacing >= 0) || !std::isfinite(o.spacing))
    throw std::invalid_argument("level-set split: spacing must be a finite number >= 0");
  if (o.pad < 3) throw std::invalid_argument("level-set split: pad must be >= 3 cells");
  if (!(o.min_thickness_cells >= 0) || !(o.min_volume >= 0))
    throw std::invalid_argument("level-set split: min_thickness_cells and min_volume must be >= 0");
  if (o.spacing == 0 || std::abs(o.spacing - parent.spacing()) <= 1e-12 * parent.spacing()) return parent;
  LevelSetOptions lo;
  lo.name = "parent level set resampled at the child spacing";
  hold = LevelSetGrid::sample(parent.dimension(), parent.bounds(), o.spacing,
                              [&parent](const Vec3& x) { return parent.value(x); }, lo);
  return *hold;
}

struct Lattice {
  int dim;
  std::array<int, 3> n;
  Vec3 origin;
  double h;
  std::size_t size() const { return static_cast<std::size_t>(n[0]) * n[1] * n[2]; }
  std::size_t id(int i, int j, int k) const {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(n[0]) * (j + static_cast<std::size_t>(n[1]) * k);
  }
  Vec3 point(int i, int j, int k) const { return origin + Vec3{i * h, j * h, dim == 3 ? k * h : 0.0}; }
  Vec3 point(std::size_t id) const {
    const int i = static_cast<int>(id % n[0]);
    const int j = static_cast<int>((id / n[0]) % n[1]);
    const int k = static_cast<int>(id / (static_cast<std::size_t>(n[0]) * n[1]));
    return point(i, j, k);
  }
};

Lattice lattice_of(const LevelSetGrid& g) { return {g.dimension(), g.counts(), g.origin(), g.spacing()}; }

// Custom surface nodes of a child (plane cuts); empty = rebuild from the zero level.
using NodeFn = std::function<void(int region, const LevelSetGrid& child, std::vector<Vec3>& nodes,
                                  std::vector<double>& weights)>;
// Values max(φ1, ψ_r) of region r on the working lattice.
using RegionFill = std::function<void(int region, std::vector<double>& values)>;
// ψ_r at a point beyond the working lattice (positive is always safe there).
using RegionFn = std::function<double(int region, const Vec3& x)>;

SplitPiece measure(std::shared_ptr<const LevelSetGrid> g) {
  SplitPiece p;
  const MassProperties mp = g->mass_properties();
  p.volume = mp.volume;
  p.centroid = mp.centroid;
  p.grid = std::move(g);
  return p;
}

// A connected set of one region's inside nodes, with its index box.
struct Component {
  int region;
  std::vector<std::size_t> nodes;
  std::array<int, 3> lo, hi;
};

// A region with inside nodes: its values on the working lattice and the component of each
// inside node (-1 elsewhere).
struct RegionLabels {
  int region;
  std::vector<double> vals;
  std::vector<int> label;
};

// Grows component `ci` of `region` from node s over face neighbours with vals < 0.
Component flood(const Lattice& L, const std::vector<double>& vals, std::vector<int>& label, std::size_t s, int ci,
                int region, std::vector<std::size_t>& stack) {
  const int nz = L.n[2];
  Component c;
  c.region = region;
  c.lo = {L.n[0], L.n[1], nz};
  c.hi = {-1, -1, -1};
  stack.assign(1, s);
  label[s] = ci;
  while (!stack.empty()) {
    const std::size_t q = stack.back();
    stack.pop_back();
    c.nodes.push_back(q);
    const int i = static_cast<int>(q % L.n[0]);
    const int j = static_cast<int>((q / L.n[0]) % L.n[1]);
    const int k = static_cast<int>(q / (static_cast<std::size_t>(L.n[0]) * L.n[1]));
    const int ijk[3] = {i, j, k};
    for (int a = 0; a < 3; ++a) {
      c.lo[a] = std::min(c.lo[a], ijk[a]);
      c.hi[a] = std::max(c.hi[a], ijk[a]);
    }
    const int nb[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int d = 0; d < 2 * L.dim; ++d) {
      const int a = i + nb[d][0], b = j + nb[d][1], e = k + nb[d][2];
      if (a < 0 || b < 0 || e < 0 || a >= L.n[0] || b >= L.n[1] || e >= nz) continue;
      const std::size_t t = L.id(a, b, e);
      if (label[t] >= 0 || !(vals[t] < 0)) continue;
      label[t] = ci;
      stack.push_back(t);
    }
  }
  return c;
}

// Pass 1: the connected components of every region's inside nodes (face neighbours), and
// the values and labels of the regions that have any.
std::vector<Component> components(const Lattice& L, int regions, const RegionFill& fill,
                                  std::vector<RegionLabels>& stored) {
  const std::size_t N = L.size();
  std::vector<Component> comps;
  std::vector<double> vals;
  std::vector<std::size_t> stack;
  for (int r = 0; r < regions; ++r) {
    vals.assign(N, 0.0);
    fill(r, vals);
    std::vector<int> label(N, -1);
    bool any = false;
    for (std::size_t s = 0; s < N; ++s) {
      if (!(vals[s] < 0) || label[s] >= 0) continue;
      any = true;
      comps.push_back(flood(L, vals, label, s, static_cast<int>(comps.size()), r, stack));
    }
    if (any) stored.push_back({r, vals, std::move(label)});
  }
  return comps;
}

// The values of component ci's child on its lattice box (the component's box padded by
// `pad` nodes; its lowest node is `lo`, its counts `cnt`).
std::vector<double> child_values(const Lattice& L, const LevelSetGrid& W, const RegionFn& beyond, const Component& c,
                                 int ci, const RegionLabels& rl, const std::array<int, 3>& lo,
                                 const std::array<int, 3>& cnt) {
  std::vector<double> v(static_cast<std::size_t>(cnt[0]) * cnt[1] * cnt[2]);
  for (int k = 0; k < cnt[2]; ++k)
    for (int j = 0; j < cnt[1]; ++j)
      for (int i = 0; i < cnt[0]; ++i) {
        const int I = lo[0] + i, J = lo[1] + j, K = lo[2] + k;
        double x;
        if (I >= 0 && J >= 0 && K >= 0 && I < L.n[0] && J < L.n[1] && K < L.n[2]) {
          const std::size_t id = L.id(I, J, K);
          x = rl.vals[id];
          // Inside nodes of another piece of the same region are outside this child.
          if (x < 0 && rl.label[id] != ci) x = L.h;
        } else {
          const Vec3 p = L.point(I, J, K);
          x = std::max(W.value(p), beyond(c.region, p));
        }
        v[static_cast<std::size_t>(i) + static_cast<std::size_t>(cnt[0]) * (j + static_cast<std::size_t>(cnt[1]) * k)] = x;
      }
  return v;
}

// The piece of grid g: a signed distance again before use (Eq. 17's purpose: closest points,
// no PDE). True when it is a child; false when it is to be removed: thin, empty, below
// min_volume or without a resolved zero level.
bool make_piece(std::shared_ptr<const LevelSetGrid> g, int region, const SplitOptions& o, const NodeFn* custom_nodes,
                SplitPiece& piece) {
  const double h = g->spacing();
  g = g->reinitialised();
  const double vmin = *std::min_element(g->values().begin(), g->values().end());
  piece = measure(g);
  const bool thin = -vmin < 0.5 * o.min_thickness_cells * h;
  if (thin || !(piece.volume > 0) || piece.volume < o.min_volume) return false;
  try {
    std::vector<Vec3> nodes;
    std::vector<double> w;
    if (custom_nodes) (*custom_nodes)(region, *g, nodes, w);
    piece.grid = nodes.empty() ? g->with_values(g->values()) : g->with_nodes(std::move(nodes), std::move(w));
  } catch (const std::invalid_argument&) {  // no zero level resolved: too small to be a grain
    return false;
  }
  return true;
}

// The kept component (any region) with an inside node within `cells` lattice cells (each
// axis) of a node of component c, or -1.
int kept_neighbour(const Lattice& L, const Component& c, const std::vector<RegionLabels>& stored,
                   const std::vector<char>& kept, int cells) {
  const int kz = L.dim == 3 ? cells : 0;
  for (const std::size_t q : c.nodes) {
    const int i = static_cast<int>(q % L.n[0]);
    const int j = static_cast<int>((q / L.n[0]) % L.n[1]);
    const int k = static_cast<int>(q / (static_cast<std::size_t>(L.n[0]) * L.n[1]));
    for (int dk = -kz; dk <= kz; ++dk)
      for (int dj = -cells; dj <= cells; ++dj)
        for (int di = -cells; di <= cells; ++di) {
          const int a = i + di, b = j + dj, e = k + dk;
          if (a < 0 || b < 0 || e < 0 || a >= L.n[0] || b >= L.n[1] || e >= L.n[2]) continue;
          const std::size_t t = L.id(a, b, e);
          for (const auto& rl : stored)
            if (rl.label[t] >= 0 && kept[static_cast<std::size_t>(rl.label[t])]) return rl.label[t];
        }
  }
  return -1;
}

// The grid of the union of components `members` (the first one's region gives the surface
// nodes): on the box of all of them padded by `pad` cells, the minimum of each member's
// child values (eqs. 14–15 per member; across a cut plane the minimum is φ1 again).
std::shared_ptr<const LevelSetGrid> union_grid(const Lattice& L, const LevelSetGrid& W, const RegionFn& beyond,
                                               const std::vector<Component>& comps,
                                               const std::vector<RegionLabels>& stored,
                                               const std::vector<int>& members, int pad, double node_spacing) {
  std::array<int, 3> lo{}, cnt{1, 1, 1};
  for (int a = 0; a < L.dim; ++a) {
    int l = comps[members[0]].lo[a], h = comps[members[0]].hi[a];
    for (const int m : members) {
      l = std::min(l, comps[m].lo[a]);
      h = std::max(h, comps[m].hi[a]);
    }
    lo[a] = l - pad;
    cnt[a] = h - l + 1 + 2 * pad;
  }
  std::vector<double> v;
  for (const int m : members) {
    std::size_t slot = 0;
    while (stored[slot].region != comps[m].region) ++slot;
    std::vector<double> w = child_values(L, W, beyond, comps[m], m, stored[slot], lo, cnt);
    if (v.empty()) v = std::move(w);
    else
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = std::min(v[i], w[i]);
  }
  return LevelSetGrid::from_values(L.dim, L.point(lo[0], lo[1], lo[2]), L.h, cnt, std::move(v), node_spacing, false,
                                   "level-set child");
}

SplitResult split_regions(const LevelSetGrid& W, double node_spacing, int regions, const RegionFill& fill,
                          const RegionFn& beyond, const SplitOptions& o, const NodeFn* custom_nodes) {
  count_built(Representation::LevelSetSplit);
  const Lattice L = lattice_of(W);
  std::vector<RegionLabels> stored;
  const std::vector<Component> comps = components(L, regions, fill, stored);
  SplitResult out;
  if (comps.size() <= 1) {  // the surfaces missed the grain (or it has no inside node)
    out.missed = true;
    return out;
  }
  // Pass 2: one cropped, reinitialised grid per component.
  std::vector<SplitPiece> pieces(comps.size());
  std::vector<char> kept(comps.size(), 0);
  for (std::size_t ci = 0; ci < comps.size(); ++ci)
    kept[ci] = make_piece(union_grid(L, W, beyond, comps, stored, {static_cast<int>(ci)}, o.pad, node_spacing),
                          comps[ci].region, o, custom_nodes, pieces[ci]);
  // Pass 3: a dropped piece next to a kept child is a lattice artefact of the cut: the child
  // is rebuilt as the union of the two (absorbed); other dropped pieces are removed.
  std::vector<std::vector<int>> members(comps.size());
  for (std::size_t ci = 0; ci < comps.size(); ++ci) {
    if (kept[ci]) {
      members[ci].push_back(static_cast<int>(ci));
      continue;
    }
    const double v = std::max(0.0, pieces[ci].volume);
    const int to = o.absorb_cells > 0 ? kept_neighbour(L, comps[ci], stored, kept, o.absorb_cells) : -1;
    if (to >= 0) {
      members[static_cast<std::size_t>(to)].push_back(static_cast<int>(ci));
      ++out.absorbed;
      out.absorbed_volume += v;
    } else {
      out.removed_volume += v;
      out.removed.push_back(std::move(pieces[ci]));
    }
  }
  for (std::size_t ci = 0; ci < comps.size(); ++ci) {
    if (!kept[ci]) continue;
    SplitPiece merged;
    if (members[ci].size() > 1 &&
        make_piece(union_grid(L, W, beyond, comps, stored, members[ci], o.pad, node_spacing), comps[ci].region, o,
                   custom_nodes, merged))
      pieces[ci] = std::move(merged);  // (a union with a kept child is always kept)
    out.children.push_back(std::move(pieces[ci]));
  }
  return out;
}

// Orthonormal tangents of a plane (2D: one tangent in the x–y plane).
void tangents(const Vec3& n, int dim, Vec3& t1, Vec3& t2) {
  if (dim == 2) {
    t1 = {-n.y, n.x, 0};
    t2 = {};
    return;
  }
  const Vec3 e = std::abs(n.x) <= std::abs(n.y) && std::abs(n.x) <= std::abs(n.z)
                     ? Vec3{1, 0, 0}
                     : (std::abs(n.y) <= std::abs(n.z) ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
  t1 = normalized(cross(n, e));
  t2 = cross(n, t1);
}

}  // namespace

SplitResult split_by_planes(const LevelSetGrid& parent, const std::vector<SplitPlane>& planes,
                            const SplitOptions& o) {
  const int m = static_cast<int>(planes.size());
  if (m == 0) throw std::invalid_argument("level-set split: no cutting plane");
  if (m > 12) throw std::invalid_argument("level-set split: at most 12 planes (got " + std::to_string(m) + ")");
  const int dim = parent.dimension();
  for (int j = 0; j < m; ++j) {
    const Vec3& n = planes[j].normal;
    if (!is_finite(n) || !std::isfinite(planes[j].offset) || std::abs(norm(n) - 1) > 1e-9 ||
        (dim == 2 && std::abs(n.z) > 1e-12))
      throw std::invalid_argument("level-set split: plane " + std::to_string(j) +
                                  " needs a finite unit normal (in the x-y plane in 2D) and a finite offset");
  }
  std::shared_ptr<const LevelSetGrid> hold;
  const LevelSetGrid& W = working_grid(parent, o, hold);
  const Lattice L = lattice_of(W);
  const double big = 10 * norm(W.bounds().size()) + 1.0;
  // Region `mask`: bit j set = the side φ2_j > 0 (eq. 14, φ3 = max(φ1, −φ2)), unset = the
  // side φ2_j < 0 (eq. 15, φ4 = max(φ1, φ2)).
  auto psi = [&](int mask, const Vec3& x) {
    double s = -big;
    for (int j = 0; j < m; ++j) {
      const double f = planes[j].value(x);
      s = std::max(s, (mask >> j) & 1 ? -f : f);
    }
    return s;
  };
  const std::vector<double>& phi1 = W.values();
  RegionFill fill = [&](int mask, std::vector<double>& v) {
    for (std::size_t id = 0; id < v.size(); ++id) v[id] = std::max(phi1[id], psi(mask, L.point(id)));
  };
  RegionFn beyond = [&](int mask, const Vec3& x) { return psi(mask, x); };
  const double hs = parent.node_spacing() > 0 ? parent.node_spacing() : parent.spacing();
  // Harmon et al. 2020 §3.3: the parent's surface nodes go to the side of the cut they lie
  // on; new nodes are placed at equal spacing along the cut's tangent directions and kept
  // where they are inside the parent.
  NodeFn nodes = [&](int mask, const LevelSetGrid& child, std::vector<Vec3>& nv, std::vector<double>& wv) {
    const double tol = 0.5 * child.spacing();
    const auto& pn = parent.nodes();
    const auto& pw = parent.node_weights();
    for (std::size_t i = 0; i < pn.size(); ++i)
      if (psi(mask, pn[i]) < 0 && child.value(pn[i]) < tol) {
        nv.push_back(pn[i]);
        wv.push_back(pw[i]);
      }
    const Aabb cb = child.bounds();
    const int sub = 4, sub2 = dim == 3 ? sub : 1;
    for (int j = 0; j < m; ++j) {
      const Vec3 n = planes[j].normal;
      Vec3 t1, t2;
      tangents(n, dim, t1, t2);
      const Vec3 p0 = n * planes[j].offset;
      double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
      for (int c = 0; c < 8; ++c) {
        const Vec3 q{(c & 1) ? cb.hi.x : cb.lo.x, (c & 2) ? cb.hi.y : cb.lo.y, (c & 4) ? cb.hi.z : cb.lo.z};
        a0 = std::min(a0, dot(q - p0, t1));
        a1 = std::max(a1, dot(q - p0, t1));
        b0 = std::min(b0, dot(q - p0, t2));
        b1 = std::max(b1, dot(q - p0, t2));
      }
      const long ia0 = static_cast<long>(std::floor(a0 / hs)), ia1 = static_cast<long>(std::ceil(a1 / hs));
      const long ib0 = dim == 3 ? static_cast<long>(std::floor(b0 / hs)) : 0;
      const long ib1 = dim == 3 ? static_cast<long>(std::ceil(b1 / hs)) : 1;
      if ((ia1 - ia0) * (ib1 - ib0) > 4000000L) continue;  // cannot happen for a cropped child
      for (long b = ib0; b < ib1; ++b)
        for (long a = ia0; a < ia1; ++a) {
          int cnt = 0;
          Vec3 sum;
          for (int v = 0; v < sub2; ++v)
            for (int u = 0; u < sub; ++u) {
              const Vec3 x = p0 + t1 * ((a + (u + 0.5) / sub) * hs) +
                             (dim == 3 ? t2 * ((b + (v + 0.5) / sub) * hs) : Vec3{});
              if (!(W.value(x) < 0) || !(child.value(x) < tol)) continue;
              bool ok = true;
              for (int k = 0; k < m && ok; ++k)
                if (k != j) {
                  const double f = planes[k].value(x);
                  ok = ((mask >> k) & 1) ? f > 0 : f < 0;
                }
              if (!ok) continue;
              ++cnt;
              sum += x;
            }
          if (cnt == 0) continue;
          nv.push_back(sum / static_cast<double>(cnt));
          wv.push_back((dim == 3 ? hs * hs : hs) * cnt / static_cast<double>(sub * sub2));
        }
    }
  };
  return split_regions(W, hs, 1 << m, fill, beyond, o, &nodes);
}

SplitResult split_by_surface(const LevelSetGrid& parent, const std::function<double(const Vec3&)>& phi2,
                             const SplitOptions& o) {
  if (!phi2) throw std::invalid_argument("level-set split: no fracture surface function");
  std::shared_ptr<const LevelSetGrid> hold;
  const LevelSetGrid& W = working_grid(parent, o, hold);
  const Lattice L = lattice_of(W);
  const double big = 10 * norm(W.bounds().size()) + 1.0;
  auto psi = [&](int r, const Vec3& x) {
    const double f = phi2(x);
    if (!std::isfinite(f)) throw std::invalid_argument("level-set split: fracture surface value is not finite");
    return std::clamp(r == 0 ? -f : f, -big, big);  // r 0: eq. 14, r 1: eq. 15
  };
  const std::vector<double>& phi1 = W.values();
  RegionFill fill = [&](int r, std::vector<double>& v) {
    for (std::size_t id = 0; id < v.size(); ++id) v[id] = std::max(phi1[id], psi(r, L.point(id)));
  };
  RegionFn beyond = [&](int r, const Vec3& x) { return psi(r, x); };
  const double hs = parent.node_spacing() > 0 ? parent.node_spacing() : parent.spacing();
  return split_regions(W, hs, 2, fill, beyond, o, nullptr);
}

SplitResult split_by_clusters(const LevelSetGrid& parent, const std::vector<Vec3>& points,
                              const std::vector<int>& cluster, int clusters, const SplitOptions& o) {
  if (clusters < 1) throw std::invalid_argument("level-set split: clusters must be >= 1");
  if (cluster.size() != points.size())
    throw std::invalid_argument("level-set split: " + std::to_string(cluster.size()) + " cluster ids for " +
                                std::to_string(points.size()) + " points");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!is_finite(points[i])) throw std::invalid_argument("level-set split: cluster point is not finite");
    if (cluster[i] < 0 || cluster[i] >= clusters)
      throw std::invalid_argument("level-set split: point " + std::to_string(i) + " has cluster " +
                                  std::to_string(cluster[i]) + " outside [0, " + std::to_string(clusters) + ")");
  }
  std::shared_ptr<const LevelSetGrid> hold;
  const LevelSetGrid& W = working_grid(parent, o, hold);
  const Lattice L = lattice_of(W);
  const std::size_t N = L.size();
  const double big = 10 * norm(W.bounds().size()) + 1.0;
  const std::vector<double>& phi1 = W.values();
  // Nearest distance to each cluster, only where the child's zero level can be: a node with
  // φ1 >= 2h is at least that far from every child, and reinitialisation recomputes it.
  const double band = 2 * L.h;
  std::vector<double> D(N * static_cast<std::size_t>(clusters), big);
  for (std::size_t id = 0; id < N; ++id) {
    if (phi1[id] >= band) continue;
    const Vec3 x = L.point(id);
    double* d = &D[id * clusters];
    for (std::size_t p = 0; p < points.size(); ++p) {
      const double q = norm2(points[p] - x);
      double& t = d[cluster[p]];
      if (q < t * t) t = std::sqrt(q);
    }
  }
  RegionFill fill = [&](int r, std::vector<double>& v) {
    for (std::size_t id = 0; id < N; ++id) {
      if (phi1[id] >= band) {
        v[id] = phi1[id];
        continue;
      }
      const double* d = &D[id * clusters];
      double other = big;
      for (int c = 0; c < clusters; ++c)
        if (c != r) other = std::min(other, d[c]);
      v[id] = std::max(phi1[id], std::clamp(0.5 * (d[r] - other), -big, big));
    }
  };
  RegionFn beyond = [&](int, const Vec3&) { return big; };
  const double hs = parent.node_spacing() > 0 ? parent.node_spacing() : parent.spacing();
  return split_regions(W, hs, clusters, fill, beyond, o, nullptr);
}

}  // namespace crumble
