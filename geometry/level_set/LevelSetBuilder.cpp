#include "geometry/level_set/LevelSetBuilder.h"

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

const OptionTable& level_set_options() {
  static const OptionTable t = [] {
    const LevelSetBuilderOptions d;
    return OptionTable{
        opt::number("spacing", d.spacing, 0, 1, "m",
                    "grid spacing of the children; 0 = the parent grid's (another value resamples the parent first)"),
        opt::number("min_thickness_cells", d.min_thickness_cells, 0, 100, "",
                    "a piece thinner than this many grid cells is removed (counted as removed mass and as a fragment "
                    "fallback)"),
        opt::number("min_piece_volume_fraction", d.min_piece_volume_fraction, 0, 0.49, "",
                    "a piece smaller than this × the parent's volume is removed (counted)"),
    };
  }();
  return t;
}

std::unique_ptr<FragmentBuilder> make_level_set_builder(const Config& cfg, const EngineContext&) {
  cfg.string("type", "level_set");
  const Options r(cfg, level_set_options());
  LevelSetBuilderOptions o;
  o.spacing = r.number("spacing");
  o.min_thickness_cells = r.number("min_thickness_cells");
  o.min_piece_volume_fraction = r.number("min_piece_volume_fraction");
  return std::make_unique<LevelSetBuilder>(o);
}

}  // namespace crumble
