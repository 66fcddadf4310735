// Synthetic peridynamic outcomes for the alpha-shape tests: a cubic lattice of a parent
// shape (spacing 0.062·d, Zhu & Zhao 2019 §2.1), split into clusters by a rule, with surface
// flags (fewer than 6 lattice neighbours inside) and fracture points at the midpoints of
// cut nearest-neighbour bonds (Zhu & Zhao 2019 §3.2).
#pragma once
#include <cmath>
#include <functional>
#include <map>
#include <tuple>

#include "core/Fracture.h"
#include "geometry/Shape.h"

namespace crumble::test {

inline PointClusters lattice_clusters(const Shape& parent, double spacing, int clusters,
                                      const std::function<int(const Vec3&)>& cluster_of) {
  PointClusters pc;
  pc.spacing = spacing;
  pc.clusters = clusters;
  pc.fracture_points.resize(clusters);
  const Aabb b = parent.bounds();
  const int n = static_cast<int>(std::ceil(std::max({-b.lo.x, -b.lo.y, -b.lo.z, b.hi.x, b.hi.y, b.hi.z}) / spacing)) + 1;
  std::map<std::tuple<int, int, int>, int> index;
  std::vector<std::tuple<int, int, int>> ijk;
  for (int i = -n; i < n; ++i)
    for (int j = -n; j < n; ++j)
      for (int k = -n; k < n; ++k) {
        const Vec3 p{(i + 0.5) * spacing, (j + 0.5) * spacing, (k + 0.5) * spacing};
        if (!parent.contains(p)) continue;
        index[{i, j, k}] = static_cast<int>(pc.points.size());
        ijk.push_back({i, j, k});
        pc.points.push_back(p);
        pc.cluster.push_back(cluster_of(p));
      }
  pc.on_surface.assign(pc.points.size(), 0);
  const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (std::size_t a = 0; a < pc.points.size(); ++a) {
    const auto [i, j, k] = ijk[a];
    int neighbours = 0;
    for (int q = 0; q < 6; ++q) {
      auto it = index.find({i + d[q][0], j + d[q][1], k + d[q][2]});
      if (it == index.end()) continue;
      ++neighbours;
      const int bidx = it->second;
      if (q % 2 == 0 && pc.cluster[bidx] != pc.cluster[a]) {  // each cut bond once
        const Vec3 mid = (pc.points[a] + pc.points[bidx]) * 0.5;
        pc.fracture_points[pc.cluster[a]].push_back(mid);
        pc.fracture_points[pc.cluster[bidx]].push_back(mid);
      }
    }
    pc.on_surface[a] = neighbours < 6;
  }
  return pc;
}

}  // namespace crumble::test
