#include "geometry/level_set/LevelSetBuilder.h"

#include <algorithm>
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

FragmentResult LevelSetBuilder::build(const Shape& parent, const Fracture& fracture) const {
  const LevelSetGrid& phi1 = parent.level_set();
  const double V = parent.volume();
  SplitOptions so;
  so.spacing = opt_.spacing;
  so.min_thickness_cells = opt_.min_thickness_cells;
  so.min_volume = opt_.min_piece_volume_fraction * V;
  FragmentResult out;
  const SplitResult first = std::visit(
      [&](const auto& f) -> SplitResult {
        using T = std::decay_t<decltype(f)>;
        if constexpr (std::is_same_v<T, CuttingSurfaces>) {
          out.method = "level_set_planes";
          std::vector<SplitPlane> planes;
          for (const auto& p : f.planes) planes.push_back({p.normal, p.offset});
          return split_by_planes(phi1, planes, so);
        } else {
          out.method = "level_set_clusters";
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
  SplitResult sr = first;
  if (sr.missed) {
    // The cut runs through the grain (parent surface nodes more than a quarter cell on both
    // sides of a plane) but no grid node lies on one side of it: the grid cannot resolve
    // the piece. One plane: it is moved along its normal to leave at least one row of grid
    // nodes on each side (counted as a fallback). A grain with a single row of nodes along
    // the normal, or whose moved cut still fails, is of the size of its discretisation: Harmon et
    // al. 2020 §3.4 remove such grains, so it is crushed — all of it removed volume (no
    // child; events.csv outcome crushed). A cut that misses the grain stays a no_split.
    const auto* cs = std::get_if<CuttingSurfaces>(&fracture);
    const double h = phi1.spacing();
    bool through = false;
    if (cs)
      for (const auto& p : cs->planes) {
        bool neg = false, pos = false;
        for (const auto& x : phi1.nodes()) {
          const double f = p.signed_distance(x);
          neg = neg || f < -0.25 * h;
          pos = pos || f > 0.25 * h;
        }
        through = through || (neg && pos);
      }
    if (!through) {
      out.method = "no_split";
      return out;
    }
    if (cs->planes.size() == 1) {
      const CutPlane& p = cs->planes.front();
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
      if (hmax - hmin >= 0.999 * h) {  // two rows of nodes or more: a cut between them
        const double m = std::min(h, 0.5 * (hmax - hmin));  // a cell from the outer rows, or the middle
        sr = split_by_planes(phi1, {{p.normal, std::clamp(p.offset, hmin + m, hmax - m)}}, so);
        if (!sr.missed && !sr.children.empty()) out.method = "level_set_planes_moved";
      }
    }
    if (sr.missed || sr.children.empty()) {
      out.method = "level_set_unresolved";
      out.removed_volume = V;
      out.fallbacks = 1;
      return out;
    }
    ++out.fallbacks;
  }
  double sum = sr.removed_volume;
  for (const auto& c : sr.children) sum += c.volume;
  if (!(sum > 0)) throw std::runtime_error("fragment builder 'level_set': the pieces have no volume");
  // Mass bookkeeping (see the header): grid volumes × k with k = V_parent / Σ grid volumes,
  // realised by scaling each child's grid about the parent's centroid by k^(1/dim).
  const double k = V / sum;
  const double s = phi1.dimension() == 3 ? std::cbrt(k) : std::sqrt(k);
  for (const auto& c : sr.children) {
    Fragment fr;
    fr.shape = Shape::from_level_set(c.grid->scaled(s));
    fr.offset = -fr.shape->recentring();  // the child's centroid in the parent frame
    out.children.push_back(std::move(fr));
  }
  out.removed_volume = k * sr.removed_volume;
  out.fallbacks += static_cast<int>(sr.removed.size());  // pieces removed as fines
  return out;
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
    };
  }();
  return t;
}

std::unique_ptr<FragmentBuilder> make_level_set_builder(const Config& cfg, const EngineContext&) {
  cfg.string("type", "level_set");
  LevelSetBuilderOptions o;
  read_options(cfg, level_set_options(), o);
  return std::make_unique<LevelSetBuilder>(o);
}

}  // namespace crumble
