#include "geometry/level_set/LevelSetBuilder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "geometry/LevelSetGrid.h"

namespace crumble {

LevelSetBuilder::LevelSetBuilder(LevelSetBuilderOptions opt) : opt_(opt) {
  // Every option in its declared range (level_set_options).
  check_options(level_set_options(), opt_, "LevelSetBuilder");
}

namespace {

// The split the fracture asks for, on the parent's grid or at so.spacing; `method` names it.
SplitResult split_once(const LevelSetGrid& phi1, const Fracture& fracture, const SplitOptions& so,
                       std::string& method) {
  return std::visit(
      [&](const auto& f) -> SplitResult {
        using T = std::decay_t<decltype(f)>;
        if constexpr (std::is_same_v<T, CuttingSurfaces>) {
          method = "level_set_planes";
          std::vector<SplitPlane> planes;
          for (const auto& p : f.planes) planes.push_back({p.normal, p.offset});
          return split_by_planes(phi1, planes, so);
        } else {
          method = "level_set_clusters";
          const Quat& q = f.frame;
          const double qn = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
          if (!std::isfinite(qn) || std::abs(qn - 1) > 1e-9)
            throw std::invalid_argument("PointClusters: frame must be a unit quaternion");
          std::vector<Vec3> pts(f.points.size());
          for (std::size_t i = 0; i < pts.size(); ++i) pts[i] = q.rotate(f.points[i]);  // lattice → body frame
          return split_by_clusters(phi1, pts, f.cluster, f.clusters, so);
        }
      },
      fracture);
}

// True when a cutting plane runs through the grain: parent surface nodes more than a quarter
// cell on both sides of it.
bool cut_through(const LevelSetGrid& phi1, const CuttingSurfaces* cs) {
  if (!cs) return false;
  const double h = phi1.spacing();
  for (const auto& p : cs->planes) {
    bool neg = false, pos = false;
    for (const auto& x : phi1.nodes()) {
      const double f = p.signed_distance(x);
      neg = neg || f < -0.25 * h;
      pos = pos || f > 0.25 * h;
    }
    if (neg && pos) return true;
  }
  return false;
}

// One plane through the grain that leaves no grid node on one side: moved along its normal
// to leave at least one row of nodes on each side. Missed when the grain has a single row of
// nodes along the normal.
SplitResult moved_cut(const LevelSetGrid& phi1, const CutPlane& p, const SplitOptions& so) {
  const double h = phi1.spacing();
  const auto c = phi1.counts();
  const auto& v = phi1.values();
  double hmin = 1e300, hmax = -1e300;
  for (int k = 0; k < c[2]; ++k)
    for (int j = 0; j < c[1]; ++j)
      for (int i = 0; i < c[0]; ++i) {
        const std::size_t id = static_cast<std::size_t>(i) + static_cast<std::size_t>(c[0]) * (j + static_cast<std::size_t>(c[1]) * k);
        if (!(v[id] < 0)) continue;
        const double t = dot(p.normal, phi1.origin() + Vec3{i * h, j * h, phi1.dimension() == 3 ? k * h : 0.0});
        hmin = std::min(hmin, t);
        hmax = std::max(hmax, t);
      }
  SplitResult none;
  none.missed = true;
  if (hmax - hmin < 0.999 * h) return none;  // a single row of nodes: nothing to cut between
  const double m = std::min(h, 0.5 * (hmax - hmin));  // a cell from the outer rows, or the middle
  return split_by_planes(phi1, {{p.normal, std::clamp(p.offset, hmin + m, hmax - m)}}, so);
}

// A split that is not made (fines_policy "halt"): no child, no removed volume, unresolved.
FragmentResult left_whole(int refinements) {
  FragmentResult whole;
  whole.method = "level_set_unresolved";
  whole.unresolved = true;
  whole.refinements = refinements;
  return whole;
}

// The spacing that keeps a grid over `box` (plus 3 cells each side) at most `max_nodes` nodes.
double capped_spacing(double h, const Aabb& box, int dim, long max_nodes) {
  for (int it = 0; it < 60; ++it) {
    double total = 1;
    for (int a = 0; a < dim; ++a) total *= std::ceil(box.size()[a] / h) + 7;
    if (total <= static_cast<double>(max_nodes)) return h;
    h *= 1.1;
  }
  return h;
}

}  // namespace

// The split on the parent's grid, repeated on grids refined by halves while it removes a piece
// the grid cannot resolve or cannot resolve the cut at all (Harmon et al. 2020 §3.4, second
// method), down to resolve_diameter / cells_across and the max_grid_nodes cap.
SplitResult LevelSetBuilder::refined_split(const LevelSetGrid& phi1, const Fracture& fracture, SplitOptions& so,
                                           bool through, FragmentResult& out) const {
  so.spacing = opt_.spacing > 0 ? opt_.spacing : phi1.spacing();
  SplitResult sr = split_once(phi1, fracture, so, out.method);
  if (!(opt_.cells_across > 0) || !(opt_.resolve_diameter > 0)) return sr;
  Aabb box;
  for (const auto& x : phi1.nodes()) box.extend(x);
  const double floor = capped_spacing(opt_.resolve_diameter / opt_.cells_across, box, phi1.dimension(),
                                      opt_.max_grid_nodes);
  while (((sr.missed && through) || !sr.removed.empty() || sr.absorbed > 0) && so.spacing > floor * (1 + 1e-9)) {
    so.spacing = std::max(0.5 * so.spacing, floor);
    sr = split_once(phi1, fracture, so, out.method);
    ++out.refinements;
  }
  return sr;
}

// A child's grid at its own spacing: its thickness (twice its deepest inside distance) /
// cells_across, never finer than resolve_diameter / cells_across (the finest grid a split is
// refined to: a sliver thinner than resolve_diameter, e.g. a long slab, would otherwise get a
// grid of hundreds of thousands of nodes along its length) and never coarser than
// `coarsest`, within the max_grid_nodes cap; surface nodes at `node_ratio` × the spacing.
std::shared_ptr<const LevelSetGrid> LevelSetBuilder::own_resolution(const std::shared_ptr<const LevelSetGrid>& g,
                                                                    double coarsest, double node_ratio) const {
  if (!(opt_.cells_across > 0)) return g;
  const double depth = -*std::min_element(g->values().begin(), g->values().end());
  Aabb box;
  for (const auto& x : g->nodes()) box.extend(x);
  const double finest = opt_.resolve_diameter / opt_.cells_across;  // 0 when resolve_diameter is 0
  const double own = std::max(2 * depth / opt_.cells_across, finest);
  const double h = capped_spacing(std::min(coarsest, own), box, g->dimension(), opt_.max_grid_nodes);
  if (std::abs(h - g->spacing()) <= 1e-9 * h) return g;
  try {
    return g->resampled(h, node_ratio * h);
  } catch (const std::invalid_argument&) {  // no zero level at the new spacing: keep the piece as cut
    return g;
  }
}

FragmentResult LevelSetBuilder::build(const Shape& parent, const Fracture& fracture) const {
  const LevelSetGrid& phi1 = parent.level_set();
  const double V = parent.volume();
  SplitOptions so;
  so.min_thickness_cells = opt_.min_thickness_cells;
  so.min_volume = opt_.min_piece_volume_fraction * V;
  so.absorb_cells = opt_.absorb_cells;
  FragmentResult out;
  const auto* cs = std::get_if<CuttingSurfaces>(&fracture);
  const bool through = cut_through(phi1, cs);
  SplitResult sr = refined_split(phi1, fracture, so, through, out);
  if (sr.missed) {
    // The cut runs through the grain but no grid node lies on one side of it, even on the
    // finest grid allowed: one plane is moved along its normal to leave at least one row of
    // grid nodes on each side (counted as a fallback). A cut that misses the grain stays a
    // no_split.
    if (!through) {
      out.method = "no_split";
      return out;
    }
    if (cs->planes.size() == 1) {
      sr = moved_cut(phi1, cs->planes.front(), so);
      if (!sr.missed && !sr.children.empty()) out.method = "level_set_planes_moved";
    }
    if (!sr.missed && !sr.children.empty()) ++out.fallbacks;
  }
  if (sr.missed || sr.children.empty()) {
    // No piece the grid can resolve: a grain with a single row of nodes along the normal, a
    // moved cut that still fails, or a split whose every piece is thinner than
    // min_thickness_cells. Such a grain is of the size of its discretisation (Harmon et al.
    // 2020 §3.4). fines_policy "remove" (third method): all of it is removed volume (no child;
    // events.csv outcome crushed). "halt" (first method): it does not break — no child, no
    // removed volume, unresolved; the simulation leaves it whole and counts it.
    out.method = "level_set_unresolved";
    if (opt_.fines_policy == "halt") {
      out.unresolved = true;
    } else {
      out.removed_volume = parent.volume();
      out.fallbacks = 1;
    }
    return out;
  }
  // fines_policy "halt" (Harmon et al. 2020 §3.4, first method): a split that would leave
  // fines is not made. A removed piece is known before the children are resampled (the
  // costly part, and a halted grain is analysed again at the next check).
  if (opt_.fines_policy == "halt" && sr.removed_volume > 0) return left_whole(out.refinements);
  finish_children(parent, sr, out);
  if (leaves_fines(out)) return left_whole(out.refinements);
  return out;
}

// With fines_policy "halt": true when the split removes a piece or gives a child finer than
// resolve_diameter (which the run removes as fines).
bool LevelSetBuilder::leaves_fines(const FragmentResult& out) const {
  if (opt_.fines_policy != "halt") return false;
  if (out.removed_volume > 0) return true;
  for (const auto& c : out.children)
    if (c.shape->equivalent_diameter() < opt_.resolve_diameter) return true;
  return false;
}

// Each child at its own resolution, then the mass bookkeeping (see the header): grid volumes
// × k with k = V_parent / Σ grid volumes, realised by scaling each child's grid about the
// parent's centroid by k^(1/dim).
void LevelSetBuilder::finish_children(const Shape& parent, SplitResult& sr, FragmentResult& out) const {
  const LevelSetGrid& phi1 = parent.level_set();
  const double coarsest = opt_.spacing > 0 ? opt_.spacing : phi1.spacing();
  const double node_ratio = (phi1.node_spacing() > 0 ? phi1.node_spacing() : phi1.spacing()) / phi1.spacing();
  const int dim = phi1.dimension();
  double sum = sr.removed_volume;
  for (auto& c : sr.children) {
    const double d = dim == 3 ? std::cbrt(6 * c.volume / kPi) : std::sqrt(4 * c.volume / kPi);
    auto g = d < opt_.resolve_diameter ? c.grid : own_resolution(c.grid, coarsest, node_ratio);
    if (g != c.grid) {
      c.grid = std::move(g);
      c.volume = c.grid->mass_properties().volume;
    }
    sum += c.volume;
  }
  if (!(sum > 0)) throw std::runtime_error("fragment builder 'level_set': the pieces have no volume");
  const double k = parent.volume() / sum;
  const double s = dim == 3 ? std::cbrt(k) : std::sqrt(k);
  for (const auto& c : sr.children) {
    Fragment fr;
    fr.shape = Shape::from_level_set(c.grid->scaled(s));
    fr.offset = -fr.shape->recentring();  // the child's centroid in the parent frame
    const auto n = c.grid->counts();
    out.grid_nodes += static_cast<long>(n[0]) * n[1] * n[2];
    out.children.push_back(std::move(fr));
  }
  out.removed_volume = k * sr.removed_volume;
  out.fallbacks += static_cast<int>(sr.removed.size());  // pieces removed as fines
  out.absorbed += sr.absorbed;
}

const OptionTable& level_set_options() {
  using S = LevelSetBuilderOptions;
  static const OptionTable t = [] {
    return OptionTable{
        opt::number("spacing", &S::spacing, 0, 1, "m",
                    "grid spacing of the children; 0 = the parent grid's (another value resamples the parent first)"),
        opt::number("min_thickness_cells", &S::min_thickness_cells, 0, 100, "",
                    "a piece thinner than this many grid cells is removed (counted as removed mass and as a fragment "
                    "fallback)"),
        opt::number("min_piece_volume_fraction", &S::min_piece_volume_fraction, 0, 0.49, "",
                    "a piece smaller than this × the parent's volume is removed (counted)"),
        opt::number("cells_across", &S::cells_across, 0, 1000, "",
                    "grid cells across a child's thickness (twice its deepest inside distance): each child is "
                    "resampled at its own spacing, never coarser than its parent's nor finer than resolve_diameter / "
                    "cells_across (Harmon et al. 2020 §3.4, second method; the count is ours; measured in "
                    "docs/validation.md); 0 = off: children keep the parent's lattice and no split is refined"),
        opt::number("resolve_diameter", &S::resolve_diameter, 0, 1, "m",
                    "a split that removes a piece its grid cannot resolve is repeated on grids of half the spacing, "
                    "down to this / cells_across; 0 = simulation.fines_diameter (no refinement when that is 0 too)"),
        opt::integer("absorb_cells", &S::absorb_cells, 0, 10,
                     "a piece the grid cannot resolve (thinner than min_thickness_cells, no zero level) within this "
                     "many grid cells of a kept child is a lattice artefact of the cut: the child is rebuilt as the "
                     "union of the two instead of removing it as fines (Harmon et al. 2020 eqs. 14-15 keep such nodes in the child; "
                     "ours); 0 = every such piece is removed"),
        opt::choice("fines_policy", &S::fines_policy, {"remove", "halt"},
                    "a split that leaves a piece the grid cannot resolve (thinner than min_thickness_cells, after "
                    "absorb_cells), a child finer than resolve_diameter, or no resolved piece at all: remove = those "
                    "pieces (or the whole grain: outcome crushed) leave as fines (Harmon et al. 2020 §3.4, third "
                    "method); halt = the split is not made and the grain stays whole (outcome unresolved, "
                    "summary.json fragment_unresolved; §3.4, first method: breakage halted at a minimum size)"),
        opt::integer("max_grid_nodes", &S::max_grid_nodes, 1000, 100000000,
                     "nodes of one grid (a refined split's or a child's) at most: the spacing is raised to meet it "
                     "(ours)"),
    };
  }();
  return t;
}

std::unique_ptr<FragmentBuilder> make_level_set_builder(const Config& cfg, const EngineContext& ctx) {
  cfg.string("type", "level_set");
  LevelSetBuilderOptions o;
  read_options(cfg, level_set_options(), o);
  if (o.resolve_diameter == 0) o.resolve_diameter = ctx.fines_diameter;
  return std::make_unique<LevelSetBuilder>(o);
}

}  // namespace crumble
