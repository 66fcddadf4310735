#include <algorithm>
#include <map>

#include "geometry/cgal/TetMesh.h"

namespace crumble {

double tet_volume(const TetMesh& m, int t) {
  const auto& v = m.tets[t];
  const Vec3 a = m.vertices[v[0]];
  return dot(cross(m.vertices[v[1]] - a, m.vertices[v[2]] - a), m.vertices[v[3]] - a) / 6.0;
}

Vec3 tet_centroid(const TetMesh& m, int t) {
  const auto& v = m.tets[t];
  return (m.vertices[v[0]] + m.vertices[v[1]] + m.vertices[v[2]] + m.vertices[v[3]]) * 0.25;
}

std::vector<TetFace> shared_faces(const TetMesh& m, std::vector<std::vector<int>>* faces_of_tet) {
  std::map<std::array<int, 3>, int> first;  // sorted face → tetrahedron that has it
  std::vector<TetFace> faces;
  if (faces_of_tet) faces_of_tet->assign(m.tets.size(), {});
  for (int t = 0; t < static_cast<int>(m.tets.size()); ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> f{};
      for (int j = 0, n = 0; j < 4; ++j)
        if (j != k) f[n++] = m.tets[t][j];
      std::array<int, 3> key = f;
      std::sort(key.begin(), key.end());
      auto [it, fresh] = first.emplace(key, t);
      if (fresh) continue;
      TetFace face{std::min(it->second, t), std::max(it->second, t), f};
      if (faces_of_tet) {
        (*faces_of_tet)[face.a].push_back(static_cast<int>(faces.size()));
        (*faces_of_tet)[face.b].push_back(static_cast<int>(faces.size()));
      }
      faces.push_back(face);
    }
  return faces;
}

}  // namespace crumble
