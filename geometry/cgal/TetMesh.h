// Tetrahedral meshes of a solid given by its signed distance (Liu et al. 2019 §2.1: a grain
// discretised into tetrahedral blocks).
//
// Pure geometry (no core/ include). tetrahedralise() is implemented with CGAL's 3D mesh
// generator (Mesh_3) in TetMesh.cpp, which is compiled into the crumble_block_beam library
// only (CGAL compiles slowly; one translation unit per CGAL package). The adjacency and the
// checks below are plain C++ (TetMeshTopology.cpp, in the same library).
#pragma once
#include <array>
#include <functional>
#include <vector>

#include "geometry/Vec3.h"

namespace crumble {

struct TetMesh {
  std::vector<Vec3> vertices;
  // Each tetrahedron's four vertex indices, positively oriented (volume > 0).
  std::vector<std::array<int, 4>> tets;
  std::vector<char> on_boundary;  // per vertex: lies on the meshed surface
};

struct TetMeshOptions {
  double edge = 0;            // target edge length (facet and cell size), m, > 0
  double facet_distance = 0;  // surface approximation error, m; 0 = edge / 10
  double facet_angle = 25;    // degrees (Mesh_3 facet criterion)
  double radius_edge = 3;     // cell radius–edge ratio bound
  unsigned seed = 0;          // Mesh_3's random initial points: fixed, so a mesh is reproducible
};

// Tetrahedralises {x : sdf(x) < 0} inside the sphere of radius `bounding_radius` about the
// origin with CGAL Mesh_3 (implicit mesh domain, refinement only: no perturbation, no
// sliver exudation, no Lloyd/ODT smoothing). Deterministic and thread-safe: the random
// initial points come from a generator seeded with opt.seed, and the optimisers are off
// because CGAL 5.5's exuder gave a different mesh of the same sphere after other meshes
// had been made (820 vs 821 cells; tests/unit/block_beam). Without exudation a few slivers
// (flat but positive tetrahedra) remain; they are blocks like any other. Throws std::invalid_argument for bad options and std::runtime_error when
// the mesher returns no cell.
TetMesh tetrahedralise(const std::function<double(const Vec3&)>& sdf, double bounding_radius,
                       const TetMeshOptions& opt);

// Shared faces: for every pair of tetrahedra with three common vertices, one entry.
struct TetFace {
  int a = 0, b = 0;              // the two tetrahedra, a < b
  std::array<int, 3> vertices{};  // the shared vertices
};

double tet_volume(const TetMesh& m, int t);  // signed (positive for a positive orientation)
Vec3 tet_centroid(const TetMesh& m, int t);
// Interior faces (each once) and, per tetrahedron, the indices into that list of its faces.
std::vector<TetFace> shared_faces(const TetMesh& m, std::vector<std::vector<int>>* faces_of_tet = nullptr);

}  // namespace crumble
