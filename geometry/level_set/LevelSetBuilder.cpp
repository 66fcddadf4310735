#include "geometry/level_set/LevelSetBuilder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "geometry/LevelSetGrid.h"

namespace crumble {

LevelSetBuilder::LevelSetBuilder(LevelSetBuilderOptions opt) : opt_(opt) {
  if (!(opt_.spacing >= 0) || !std::isfinite(opt_.spacing) || !(opt_.min_thickness_cells >= 0) ||
      !(opt_.min_piece_volume_fraction >= 0) || !(opt_.min_piece_volume_fraction < 0.5))
    throw std::invalid_argument("LevelSetBuilder: need spacing >= 0, min_thickness_cells >= 0, "
                                "0 <= min_piece_volume_fraction < 0.5");
}

FragmentResult LevelSetBuilder::build(const Shape& parent, const Fracture& fracture) const {
  const LevelSetGrid& phi1 = parent.level_set();
  const double V = parent.volume();
  SplitOptions so;
  so.spacing = opt_.spacing;
  so.min_thickness_cells = opt_.min_thickness_cells;
  so.min_volume = opt_.min_piece_volume_fraction * V;
  FragmentResult out;
  const SplitResult sr = std::visit(
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
  if (sr.missed) {
    // Harmon et al. 2020 §3.4: grains of the size of the discretisation are unstable and are
    // removed. A grain under 3 cells thick (its deepest point less than 1.5 cells inside)
    // whose cut runs through it (parent surface nodes more than a quarter cell on both sides
    // of a plane) but that its grid cannot separate is such a grain: it is crushed, all of
    // it removed as fines (counted as removed mass). A cut that misses the grain stays a
    // no_split.
    const auto* cs = std::get_if<CuttingSurfaces>(&fracture);
    const double h = phi1.spacing();
    const double depth = -*std::min_element(phi1.values().begin(), phi1.values().end());
    bool through = false;
    if (cs && depth < 1.5 * std::max(1.0, opt_.min_thickness_cells) * h)
      for (const auto& p : cs->planes) {
        bool neg = false, pos = false;
        for (const auto& x : phi1.nodes()) {
          const double f = dot(p.normal, x) - p.offset;
          neg = neg || f < -0.25 * h;
          pos = pos || f > 0.25 * h;
        }
        through = through || (neg && pos);
      }
    if (through) {
      out.method = "level_set_unresolved";
      out.removed_volume = V;
      out.fallbacks = 1;
      return out;
    }
    out.method = "no_split";
    return out;
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
  out.fallbacks = static_cast<int>(sr.removed.size());  // pieces removed as fines
  return out;
}

// Config keys of "fragments" (type "level_set"), with defaults:
//   spacing                    0 m    children's grid spacing; 0 = the parent grid's
//   min_thickness_cells        1.0    pieces thinner than this many grid cells are fines
//   min_piece_volume_fraction  1e-4   pieces below this × V_parent are fines
std::unique_ptr<FragmentBuilder> make_level_set_builder(const Config& cfg, const EngineContext&) {
  cfg.string("type", "level_set");
  LevelSetBuilderOptions o;
  o.spacing = cfg.number("spacing", 0.0, 0.0, 1.0);
  o.min_thickness_cells = cfg.number("min_thickness_cells", 1.0, 0.0, 100.0);
  o.min_piece_volume_fraction = cfg.number("min_piece_volume_fraction", 1e-4, 0.0, 0.49);
  return std::make_unique<LevelSetBuilder>(o);
}

}  // namespace crumble
