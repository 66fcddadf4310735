// Block–beam breakage (Liu et al. 2019): the tetrahedral mesh, the beam element against
// its closed forms, and the model on a diametrally loaded concrete sphere.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "breakage/block_beam/BbSystem.h"
#include "breakage/block_beam/BlockBeam.h"
#include "geometry/Shape.h"
#include "geometry/cgal/TetMesh.h"

using namespace crumble;

namespace {

constexpr double kR = 0.02;  // the 4 cm concrete spheres of Liu et al. 2019 §4

Material concrete() {
  Material m;
  m.density = 2400;
  m.young = 30e9;
  m.poisson = 0.2;
  return m;
}

// Two opposite contact forces of magnitude F along z on a grain at rest at the origin.
std::vector<Contact> diametral(double F) {
  Contact top, bottom;
  top.point = {0, 0, kR};
  top.force = {0, 0, -F};
  bottom.point = {0, 0, -kR};
  bottom.force = {0, 0, F};
  return {top, bottom};
}

Grain sphere_grain(const BlockBeamModel& model) {
  Grain g;
  g.id = 1;
  g.shape = Shape::sphere(kR);
  Rng rng(1);
  model.assign_strength(g, concrete(), rng);
  return g;
}

}  // namespace

// The mesh of a sphere: volume close to 4/3 π r³ (the meshed surface lies inside the
// sphere within facet_distance = 5 % of the edge, edge = d/5: the deficit must stay
// below 4 %), every block positive, the shared faces symmetric and consistent.
TEST(BlockBeamMesh, SphereVolumeAndAdjacency) {
  const auto s = Shape::sphere(kR);
  const TetMesh m = bb_mesh(*s, BbOptions{});
  ASSERT_GT(m.tets.size(), 100u);
  double V = 0;
  for (int t = 0; t < static_cast<int>(m.tets.size()); ++t) {
    const double v = tet_volume(m, t);
    EXPECT_GT(v, 0) << "tet " << t;
    V += v;
  }
  const double exact = 4.0 / 3.0 * M_PI * kR * kR * kR;
  EXPECT_NEAR(V / exact, 1.0, 0.04) << "mesh volume " << V << " vs " << exact;
  EXPECT_LE(V, exact * 1.001);  // the mesh vertices lie on the sphere: an inscribed solid
  std::vector<std::vector<int>> faces_of;
  const auto faces = shared_faces(m, &faces_of);
  std::size_t listed = 0;
  for (int t = 0; t < static_cast<int>(m.tets.size()); ++t) {
    EXPECT_LE(faces_of[t].size(), 4u);
    listed += faces_of[t].size();
    for (int f : faces_of[t]) {
      const TetFace& F = faces[f];
      EXPECT_TRUE(F.a == t || F.b == t);
      const int other = F.a == t ? F.b : F.a;
      // Symmetric: the neighbour lists the same face.
      EXPECT_NE(std::find(faces_of[other].begin(), faces_of[other].end(), f), faces_of[other].end());
      // The face's three vertices belong to both tetrahedra.
      for (int v : F.vertices) {
        EXPECT_NE(std::find(m.tets[F.a].begin(), m.tets[F.a].end(), v), m.tets[F.a].end());
        EXPECT_NE(std::find(m.tets[F.b].begin(), m.tets[F.b].end(), v), m.tets[F.b].end());
      }
    }
  }
  EXPECT_EQ(listed, 2 * faces.size());
  // Surface vertices lie on the sphere (Mesh_3 puts them on the zero level within its
  // relative error bound); interior ones inside.
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    if (m.on_boundary[i])
      EXPECT_NEAR(norm(m.vertices[i]), kR, 1e-5 * kR);
    else
      EXPECT_LT(norm(m.vertices[i]), kR);
  }
}

// Section of an equilateral triangle of side a: A = √3 a²/4, J = √3 a⁴/48, I = J/2.
TEST(BlockBeamBeam, TriangleSection) {
  const double a = 0.01;
  double A, I, J, c;
  Vec3 cen;
  bb::triangle_section({0, 0, 0}, {a, 0, 0}, {a / 2, a * std::sqrt(3.0) / 2, 0}, &A, &I, &J, &c, &cen);
  EXPECT_NEAR(A, std::sqrt(3.0) / 4 * a * a, 1e-15);
  EXPECT_NEAR(J, std::sqrt(3.0) * std::pow(a, 4) / 48, 1e-20);
  EXPECT_NEAR(I, std::sqrt(3.0) * std::pow(a, 4) / 96, 1e-20);
  EXPECT_NEAR(c, a / std::sqrt(3.0), 1e-15);
}

// The frame element against Euler–Bernoulli closed forms, on a beam along a generic axis.
TEST(BlockBeamBeam, StiffnessClosedForms) {
  bb::Beam b;
  b.axis = normalized(Vec3{1, 2, 2});
  b.length = 0.01;
  b.area = 2e-5;
  b.inertia = 4e-11;
  b.polar = 8e-11;
  b.x_face = 0.005;
  b.c_max = 3e-3;
  const bb::BeamMaterial m{30e9, 12.5e9, 3e6, 6e6};
  const double L = b.length, EI = m.young * b.inertia;
  const Vec3 z{};
  const Vec3 t = normalized(cross(b.axis, Vec3{0, 0, 1}));  // a transverse direction
  const double d = 1e-7;
  // Axial: F = EA δ / L, pulling a towards b.
  auto l = bb::beam_loads(b, m, z, z, b.axis * d, z);
  EXPECT_NEAR(dot(l.force_a, b.axis), m.young * b.area * d / L, 1e-9 * m.young * b.area * d / L);
  EXPECT_NEAR(l.axial, m.young * b.area * d / L, 1e-6);
  EXPECT_NEAR(norm(l.force_a + l.force_b), 0, 1e-9);
  // Transverse end displacement with both ends clamped against rotation: F = 12 EI δ / L³.
  l = bb::beam_loads(b, m, z, z, t * d, z);
  EXPECT_NEAR(dot(l.force_a, t), 12 * EI * d / std::pow(L, 3), 1e-9 * 12 * EI * d / std::pow(L, 3));
  // Cantilever (a clamped, b free to rotate): the tip rotation that frees end b's moment is
  // 3δ/(2L), and the tip force is then 3 EI δ / L³.
  const Vec3 tip_rotation = cross(b.axis, t) * (1.5 * d / L);
  l = bb::beam_loads(b, m, z, z, t * d, tip_rotation);
  EXPECT_NEAR(norm(l.moment_b), 0, 1e-12 * EI * d / (L * L));
  EXPECT_NEAR(-dot(l.force_b, t), 3 * EI * d / std::pow(L, 3), 1e-9 * 3 * EI * d / std::pow(L, 3));
  // Torsion: T = GJ φ / L.
  l = bb::beam_loads(b, m, z, z, z, b.axis * 1e-5);
  EXPECT_NEAR(dot(l.moment_a, b.axis), m.shear * b.polar * 1e-5 / L, 1e-9 * m.shear * b.polar * 1e-5 / L);
  // A rigid rotation of both blocks about a loads nothing.
  const Vec3 w = Vec3{0.3, -0.2, 0.5} * 1e-5;
  l = bb::beam_loads(b, m, z, w, cross(w, b.axis * L), w);
  EXPECT_NEAR(norm(l.force_a) + norm(l.moment_a) + norm(l.moment_b), 0, 1e-9);
  // Failure ratio: pure tension σ = N/A.
  l = bb::beam_loads(b, m, z, z, b.axis * d, z);
  EXPECT_NEAR(bb::beam_failure_ratio(b, m, l), (m.young * d / L) / m.tensile, 1e-9);
}

// Diametral compression of a 4 cm concrete sphere: a probe at 10 kN measures the force at
// which it splits (force_at_split_N: the load factor is ramped, so this is above the
// quasi-static splitting force: with the defaults 1.5 kN holds, 2 kN splits); 30 % of it leaves the grain
// intact with no beam broken, and twice it splits the grain into two or more pieces.
TEST(BlockBeamModel, BelowHoldsAboveSplits) {
  BbOptions o;
  const BlockBeamModel model(o);
  const Grain g = sphere_grain(model);
  const auto probe = model.analyse(g, concrete(), diametral(1e4));
  ASSERT_TRUE(probe.broken) << probe.outcome;
  const double f_split = probe.figure("force_at_split_N");
  std::printf("diametral split of a 4 cm sphere: %.0f N (blocks %.0f, beams %.0f, steps %.0f, broken %.0f, %.0f ms)\n",
              f_split, probe.figure("blocks"), probe.figure("beams"), probe.figure("steps"),
              probe.figure("broken_beams"), probe.wall_ms);
  ASSERT_GT(f_split, 0);
  const auto below = model.analyse(g, concrete(), diametral(0.3 * f_split));
  EXPECT_FALSE(below.broken) << below.outcome;
  EXPECT_EQ(below.outcome, "intact");
  EXPECT_EQ(below.figure("broken_beams"), 0) << "no beam reaches its strength at 30 % of the splitting force";
  const auto above = model.analyse(g, concrete(), diametral(2 * f_split));
  ASSERT_TRUE(above.broken) << above.outcome;
  const auto& pc = std::get<PointClusters>(*above.fracture);
  EXPECT_GE(pc.clusters, 2);
  EXPECT_EQ(pc.points.size(), pc.cluster.size());
  EXPECT_GT(pc.spacing, 0);
  for (int c = 0; c < pc.clusters; ++c) EXPECT_FALSE(pc.fracture_points[c].empty()) << "piece " << c;
}

TEST(BlockBeamModel, Deterministic) {
  const BlockBeamModel model(BbOptions{});
  const Grain g = sphere_grain(model);
  const auto a = model.analyse(g, concrete(), diametral(3e4));
  const auto b = model.analyse(g, concrete(), diametral(3e4));
  ASSERT_EQ(a.outcome, b.outcome);
  EXPECT_EQ(a.figures, b.figures);
  ASSERT_EQ(a.broken, b.broken);
  if (a.broken) {
    const auto& pa = std::get<PointClusters>(*a.fracture);
    const auto& pb = std::get<PointClusters>(*b.fracture);
    EXPECT_EQ(pa.cluster, pb.cluster);
    ASSERT_EQ(pa.points.size(), pb.points.size());
    for (std::size_t i = 0; i < pa.points.size(); ++i) EXPECT_EQ(norm(pa.points[i] - pb.points[i]), 0.0);
  }
}

// The same shape meshes to the same blocks, whatever was meshed before on this thread or
// allocated in between.
TEST(BlockBeamMesh, Reproducible) {
  const auto s = Shape::sphere(kR);
  const TetMesh first = bb_mesh(*s, BbOptions{});
  for (int k = 0; k < 4; ++k) {
    std::vector<std::unique_ptr<double[]>> noise;
    for (int j = 0; j < 50 * (k + 1); ++j) noise.emplace_back(new double[37 * j + 1]);
    (void)bb_mesh(*Shape::sphere(kR * (1.5 + k)), BbOptions{});
    const TetMesh again = bb_mesh(*s, BbOptions{});
    ASSERT_EQ(again.tets.size(), first.tets.size()) << "attempt " << k;
    ASSERT_EQ(again.tets, first.tets);
    for (std::size_t i = 0; i < first.vertices.size(); ++i) ASSERT_EQ(norm(again.vertices[i] - first.vertices[i]), 0.0);
  }
}
