// FragmentBuilder "alpha_shape" (Zhu & Zhao 2019 §3.2) and its geometry
// (geometry/cgal/AlphaShape.h, geometry/cgal/MeshClip.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <cmath>
#include <iostream>
#include <random>

#include <nlohmann/json.hpp>

#include "Lattice.h"
#include "geometry/cgal/AlphaShape.h"
#include "geometry/ConvexHull.h"
#include "geometry/cgal/MeshClip.h"
#include "geometry/alpha_shape/AlphaShapeBuilder.h"
#include "scenarios/Registry.h"

using namespace crumble;

namespace {

constexpr double kD = 2e-3;              // 2 mm grain (Zhu & Zhao 2019 reference)
constexpr double kSpacing = 0.062 * kD;  // Zhu & Zhao 2019 §2.1

double hull_volume(const TriMesh& m) { return polyhedron_mass_properties(convex_hull(m.vertices)).volume; }

// Every structural property the Simulation and the engines rely on.
void expect_valid_child(const Fragment& f) {
  const TriMesh& m = f.shape->mesh();
  std::string why;
  EXPECT_TRUE(is_closed_oriented_manifold(m, &why)) << why;
  EXPECT_EQ(euler_characteristic(m), 2);
  EXPECT_FALSE(mesh_self_intersects(m));
  EXPECT_GT(f.shape->volume(), 0);
  EXPECT_NEAR(norm(polyhedron_mass_properties(m).centroid), 0, 1e-12 * kD);  // re-centred
}

double volume_sum(const FragmentResult& r) {
  double v = 0;
  for (const auto& c : r.children) v += c.shape->volume();
  return v;
}

AlphaShapeBuilderOptions alpha_only() {  // Zhu's hull simplification off
  AlphaShapeBuilderOptions o;
  o.hull_diameter = 0;
  o.hull_convexity = 2;
  return o;
}

}  // namespace

// A 2 mm sphere split by a plane through the centre into two lattice clusters.
TEST(AlphaShapeBuilder, HalfSpheresAreClosedGenusZeroAndConserveVolume) {
  const auto parent = Shape::sphere(kD / 2);
  const Vec3 n = normalized(Vec3{1, 0.3, -0.2});
  const auto pc = test::lattice_clusters(*parent, kSpacing, 2, [&](const Vec3& p) { return dot(p, n) < 0 ? 0 : 1; });
  ASSERT_GT(pc.fracture_points[0].size(), 100u);
  const AlphaShapeBuilder b(alpha_only());
  std::vector<ChildReport> rep;
  const FragmentResult r = b.build(*parent, pc, &rep);
  ASSERT_EQ(r.children.size(), 2u);
  EXPECT_EQ(r.method, "alpha_shape");
  EXPECT_EQ(r.fallbacks, 0);
  for (std::size_t i = 0; i < 2; ++i) {
    SCOPED_TRACE(i);
    expect_valid_child(r.children[i]);
    EXPECT_EQ(rep[i].method, "alpha_shape");
    // Alpha shapes through lattice points are smaller than the parent: the rescaling grows them.
    EXPECT_GT(rep[i].scale, 1.0);
    EXPECT_LT(rep[i].scale, 1.15);
    // Each half: volume V/2 within the lattice's asymmetry, centroid on its own side at ≈ 3r/8.
    EXPECT_NEAR(r.children[i].shape->volume(), parent->volume() / 2, 0.03 * parent->volume());
    const double along = dot(r.children[i].offset, n);
    EXPECT_EQ(along < 0, i == 0);
    EXPECT_NEAR(std::abs(along), 3.0 / 8.0 * kD / 2, 0.05 * kD / 2);
    std::cout << "  half sphere child " << i << ": " << rep[i].boundary_points << " boundary points, "
              << rep[i].cluster_points << " cluster points, sqrt(alpha)/spacing " << std::sqrt(rep[i].alpha) / kSpacing
              << ", " << rep[i].alpha_steps << " alpha step(s), convexity " << rep[i].convexity << ", scale "
              << rep[i].scale << ", " << rep[i].seconds << " s\n";
  }
  EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-9 * parent->volume());
}

TEST(AlphaShapeBuilder, ThreeClustersByTwoPlanes) {
  const auto parent = Shape::sphere(kD / 2);
  auto cluster_of = [](const Vec3& p) { return p.z > 0.2e-3 ? 2 : (p.x < 0 ? 0 : 1); };
  const auto pc = test::lattice_clusters(*parent, kSpacing, 3, cluster_of);
  for (const bool about_parent : {true, false}) {
    SCOPED_TRACE(about_parent);
    AlphaShapeBuilderOptions o = alpha_only();
    o.scale_about_parent = about_parent;
    const FragmentResult r = AlphaShapeBuilder(o).build(*parent, pc);
    ASSERT_EQ(r.children.size(), 3u);
    EXPECT_EQ(r.fallbacks, 0);
    for (const auto& c : r.children) expect_valid_child(c);
    EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-9 * parent->volume());
    // Centroids on the correct sides of both cuts.
    EXPECT_LT(r.children[0].offset.x, 0);
    EXPECT_LT(r.children[0].offset.z, 0.2e-3);
    EXPECT_GT(r.children[1].offset.x, 0);
    EXPECT_LT(r.children[1].offset.z, 0.2e-3);
    EXPECT_GT(r.children[2].offset.z, 0.2e-3);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(cluster_of(r.children[k].offset), k);
  }
}

// Robustness: random cuts (1 or 2 planes, off-centre) of spheres and ellipsoids of 1.6–2.4
// mm on the 2 mm grain's lattice; every child must come out as a valid alpha shape.
TEST(AlphaShapeBuilder, RandomCutsAlwaysGiveValidAlphaShapes) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  int children = 0;
  double worst_alpha = 0;
  for (int trial = 0; trial < 30; ++trial) {
    SCOPED_TRACE(trial);
    const double d = kD * (0.8 + 0.2 * (u(rng) + 1));
    const Shape::Ptr parent = trial % 3 == 2 ? Shape::ellipsoid({d / 2, d / 2.5, d / 3.2}) : Shape::sphere(d / 2);
    const int nplanes = 1 + trial % 2;
    std::vector<Vec3> ns;
    std::vector<double> os;
    for (int k = 0; k < nplanes; ++k) {
      ns.push_back(normalized(Vec3{u(rng), u(rng), u(rng)}));
      os.push_back(0.3 * u(rng) * d / 2);
    }
    // Clusters = sign vectors; empty ones give no child.
    const auto pc = test::lattice_clusters(*parent, kSpacing, 1 << nplanes, [&](const Vec3& p) {
      int c = 0;
      for (int k = 0; k < nplanes; ++k) c |= (dot(ns[k], p) > os[k] ? 1 : 0) << k;
      return c;
    });
    std::vector<ChildReport> rep;
    const FragmentResult r = AlphaShapeBuilder(alpha_only()).build(*parent, pc, &rep);
    EXPECT_EQ(r.fallbacks, 0);
    for (std::size_t i = 0; i < r.children.size(); ++i) {
      EXPECT_EQ(rep[i].method, "alpha_shape") << rep[i].note;
      expect_valid_child(r.children[i]);
      worst_alpha = std::max(worst_alpha, std::sqrt(rep[i].alpha) / kSpacing);
      ++children;
    }
    EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-9 * parent->volume());
  }
  std::cout << "  " << children << " children, largest sqrt(alpha)/spacing " << worst_alpha << "\n";
  EXPECT_GT(children, 80);
}

// Scaling the whole assembly about the parent's centroid is a similarity: the union of
// the children fills the parent again, with little overlap between them.
TEST(AlphaShapeBuilder, RescaledChildrenTileTheParent) {
  const auto parent = Shape::sphere(kD / 2);
  const auto pc = test::lattice_clusters(*parent, kSpacing, 2, [](const Vec3& p) { return p.y < 0.1e-3 ? 0 : 1; });
  for (const bool about_parent : {true, false}) {
    AlphaShapeBuilderOptions o = alpha_only();
    o.scale_about_parent = about_parent;
    const FragmentResult r = AlphaShapeBuilder(o).build(*parent, pc);
    ASSERT_EQ(r.children.size(), 2u);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-kD / 2, kD / 2);
    int in_parent = 0, covered = 0, overlap = 0, outside_covered = 0, outside = 0;
    for (int i = 0; i < 40000; ++i) {
      const Vec3 p{u(rng), u(rng), u(rng)};
      int k = 0;
      for (const auto& c : r.children) k += c.shape->contains(p - c.offset);
      if (parent->contains(p)) {
        ++in_parent;
        covered += k >= 1;
        overlap += k >= 2;
      } else {
        ++outside;
        outside_covered += k >= 1;
      }
    }
    const double miss = 1.0 - static_cast<double>(covered) / in_parent;
    const double twice = static_cast<double>(overlap) / in_parent;
    const double spill = static_cast<double>(outside_covered) / outside;
    std::cout << "  scale about " << (about_parent ? "parent" : "child") << " centroid: parent points not covered "
              << miss << ", covered twice " << twice << ", bounding-cube points outside the parent covered " << spill
              << "\n";
    if (about_parent) {
      EXPECT_LT(miss, 0.03);
      EXPECT_LT(twice, 0.002);
      EXPECT_LT(spill, 0.03);
    } else {
      EXPECT_GT(twice, 0.002);  // children grown about their own centroids overlap at the crack
    }
  }
}

// Zhu & Zhao's simplification: convex pieces (V/V_hull >= 0.85) become convex hulls.
TEST(AlphaShapeBuilder, DefaultRulesTurnConvexPiecesIntoHulls) {
  const auto parent = Shape::sphere(kD / 2);
  const auto pc = test::lattice_clusters(*parent, kSpacing, 2, [](const Vec3& p) { return p.x < 0 ? 0 : 1; });
  std::vector<ChildReport> rep;
  const FragmentResult r = AlphaShapeBuilder().build(*parent, pc, &rep);
  ASSERT_EQ(r.children.size(), 2u);
  EXPECT_EQ(r.method, "convex_hull");
  EXPECT_EQ(r.fallbacks, 0);
  for (std::size_t i = 0; i < 2; ++i) {
    expect_valid_child(r.children[i]);
    EXPECT_EQ(rep[i].method, "convex_hull");
    EXPECT_GE(rep[i].convexity, 0.85);
    const TriMesh& m = r.children[i].shape->mesh();
    EXPECT_NEAR(polyhedron_mass_properties(m).volume / hull_volume(m), 1.0, 1e-9);
  }
  EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-9 * parent->volume());
}

// The size rule: children with d_e < 0.7 mm are hulls even when concave shapes are allowed.
TEST(AlphaShapeBuilder, SmallChildrenBecomeHulls) {
  for (const double d : {0.8e-3, 1.0e-3}) {
    SCOPED_TRACE(d);
    const auto parent = Shape::sphere(d / 2);
    const auto pc = test::lattice_clusters(*parent, 0.062 * d, 2, [](const Vec3& p) { return p.x < 0 ? 0 : 1; });
    AlphaShapeBuilderOptions o;
    o.hull_convexity = 2;  // only the size rule
    std::vector<ChildReport> rep;
    const FragmentResult r = AlphaShapeBuilder(o).build(*parent, pc, &rep);
    ASSERT_EQ(r.children.size(), 2u);
    const double de = r.children[0].shape->equivalent_diameter();
    EXPECT_NEAR(de, d / std::cbrt(2.0), 0.02 * d);  // half of the parent's volume
    for (std::size_t i = 0; i < 2; ++i) {
      expect_valid_child(r.children[i]);
      EXPECT_EQ(rep[i].method, de < 0.7e-3 ? "convex_hull" : "alpha_shape");
    }
    EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-9 * parent->volume());
  }
}

// A concave piece keeps its concavity: a 2×2×1 mm box split into a U (the box minus a
// 1.4×0.8 mm slot, convexity 2.88/4 = 0.72) and the block filling the slot.
TEST(AlphaShapeBuilder, ConcaveClusterKeepsItsConcavity) {
  const auto parent = Shape::box({1e-3, 1e-3, 0.5e-3});
  const double s = 0.062 * parent->equivalent_diameter();
  auto in_slot = [](const Vec3& p) { return p.x > -0.4e-3 && std::abs(p.y) < 0.4e-3; };
  const auto pc = test::lattice_clusters(*parent, s, 2, [&](const Vec3& p) { return in_slot(p) ? 1 : 0; });
  std::vector<ChildReport> rep;
  const FragmentResult r = AlphaShapeBuilder().build(*parent, pc, &rep);  // default rules
  ASSERT_EQ(r.children.size(), 2u);
  EXPECT_EQ(r.method, "alpha_shape+convex_hull");
  EXPECT_EQ(rep[0].method, "alpha_shape");  // the U
  EXPECT_EQ(rep[1].method, "convex_hull");  // the block: convex
  EXPECT_EQ(r.fallbacks, 0);
  for (const auto& c : r.children) expect_valid_child(c);
  const Fragment& U = r.children[0];
  const double convexity = U.shape->volume() / hull_volume(U.shape->mesh());
  std::cout << "  U piece: convexity " << convexity << ", sqrt(alpha)/spacing " << std::sqrt(rep[0].alpha) / s << ", "
            << rep[0].seconds << " s; block convexity " << rep[1].convexity << "\n";
  EXPECT_NEAR(convexity, 0.72, 0.04);
  // The slot is empty, the arms and the base are solid (positions in the parent frame).
  EXPECT_FALSE(U.shape->contains(Vec3{0.3e-3, 0, 0} - U.offset));
  EXPECT_FALSE(U.shape->contains(Vec3{-0.2e-3, 0, 0} - U.offset));
  EXPECT_TRUE(U.shape->contains(Vec3{0.3e-3, 0.7e-3, 0} - U.offset));
  EXPECT_TRUE(U.shape->contains(Vec3{0.3e-3, -0.7e-3, 0} - U.offset));
  EXPECT_TRUE(U.shape->contains(Vec3{-0.7e-3, 0, 0} - U.offset));
  EXPECT_GE(rep[1].convexity, 0.85);
  EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-9 * parent->volume());
  EXPECT_NEAR(U.shape->volume() / parent->volume(), 0.72, 0.02);
}

// No alpha accepted -> documented, counted fallback to the hull; no child is lost.
TEST(AlphaShapeBuilder, FailedAlphaFallsBackToHull) {
  const auto parent = Shape::sphere(kD / 2);
  const auto pc = test::lattice_clusters(*parent, kSpacing, 2, [](const Vec3& p) { return p.x < 0 ? 0 : 1; });
  AlphaShapeBuilderOptions o = alpha_only();
  o.alpha.start_spacings = 0.5;  // cells of a cubic lattice: sqrt(alpha) ≈ 0.87 spacing
  o.alpha.max_spacings = 0.6;    // nothing in [0.5, 0.6] spacings
  std::vector<ChildReport> rep;
  const FragmentResult r = AlphaShapeBuilder(o).build(*parent, pc, &rep);
  ASSERT_EQ(r.children.size(), 2u);
  EXPECT_EQ(r.fallbacks, 2);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(rep[i].method, "hull_fallback");
    EXPECT_FALSE(rep[i].note.empty());
    expect_valid_child(r.children[i]);
  }
  EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-9 * parent->volume());

  // A flat cluster (one lattice layer) has no hull: the hull of its points' lattice cells.
  PointClusters flat = pc;
  flat.clusters = 3;
  flat.fracture_points.push_back({});
  int moved = 0;
  for (std::size_t i = 0; i < flat.points.size(); ++i)
    if (std::abs(flat.points[i].z - 0.5 * kSpacing) < 1e-3 * kSpacing && flat.points[i].x > 0 && moved < 12) {
      flat.cluster[i] = 2;
      ++moved;
    }
  ASSERT_EQ(moved, 12);
  const FragmentResult rf = AlphaShapeBuilder(alpha_only()).build(*parent, flat, &rep);
  ASSERT_EQ(rf.children.size(), 3u);
  EXPECT_GE(rf.fallbacks, 1);
  EXPECT_EQ(rep[2].method, "hull_fallback");
  for (const auto& c : rf.children) expect_valid_child(c);
  EXPECT_NEAR(volume_sum(rf), parent->volume(), 1e-9 * parent->volume());
}

// CuttingSurfaces: a sphere (level-3 icosphere mesh) cut through the centre.
TEST(AlphaShapeBuilder, SphereCutThroughCentre) {
  ShapeResolution res;
  res.mesh_subdivisions = 3;
  const double r0 = kD / 2;
  const auto parent = Shape::sphere(r0, res);
  const double mesh_volume = polyhedron_mass_properties(parent->mesh()).volume;
  ASSERT_LT(mesh_volume, parent->volume());  // inscribed mesh: the rescale must use parent.volume()
  const Vec3 n = normalized(Vec3{1, 2, 3});
  CuttingSurfaces cs;
  cs.planes.push_back({n, 0.0});
  for (const bool about_parent : {true, false}) {
    SCOPED_TRACE(about_parent);
    AlphaShapeBuilderOptions o;
    o.scale_about_parent = about_parent;
    std::vector<ChildReport> rep;
    const auto t0 = std::chrono::steady_clock::now();
    const FragmentResult r = AlphaShapeBuilder(o).build(*parent, cs, &rep);
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_EQ(r.children.size(), 2u);
    std::cout << "  sphere cut (" << parent->mesh().triangles.size() << " triangles, scale about "
              << (about_parent ? "parent" : "child") << " centroid): " << t << " s; |centroid|/r = "
              << norm(r.children[0].offset) / r0 << " (3/8 = 0.375)\n";
    EXPECT_EQ(r.method, "plane_cut");
    EXPECT_EQ(r.fallbacks, 0);
    EXPECT_NEAR(rep[0].scale, std::cbrt(parent->volume() / mesh_volume), 1e-12);
    for (std::size_t i = 0; i < 2; ++i) {
      expect_valid_child(r.children[i]);
      // The icosphere is centrally symmetric: both halves are congruent.
      EXPECT_NEAR(r.children[i].shape->volume(), parent->volume() / 2, 1e-9 * parent->volume());
      // Centroid at ∓3r/8 along n; the level-3 mesh's radial chord error is 0.3 % of r
      // (0.8 % in volume), so 3r/8 is met within 0.5 % of r, 0.1 % after the rescaling
      // about the parent's centroid (which restores the sphere's volume).
      const double along = dot(r.children[i].offset, n);
      EXPECT_NEAR(std::abs(along), 3.0 / 8.0 * r0, (about_parent ? 0.001 : 0.005) * r0);
      EXPECT_NEAR(norm(r.children[i].offset - n * along), 0, 0.002 * r0);
      EXPECT_EQ(along < 0, i == 0);  // negative side first
    }
    EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-9 * parent->volume());
  }
}

TEST(AlphaShapeBuilder, BoxCutByTwoPlanesGivesFourExactPieces) {
  const Vec3 h{1e-3, 0.8e-3, 0.5e-3};
  const auto parent = Shape::box(h);
  const double x0 = 0.2e-3, y0 = -0.3e-3;
  CuttingSurfaces cs;
  cs.planes.push_back({{1, 0, 0}, x0});
  cs.planes.push_back({{0, 1, 0}, y0});
  std::vector<ChildReport> rep;
  const FragmentResult r = AlphaShapeBuilder().build(*parent, cs, &rep);
  ASSERT_EQ(r.children.size(), 4u);
  EXPECT_NEAR(rep[0].scale, 1.0, 1e-12);  // the box mesh is exact
  // Order: (x<x0, y<y0), (x<x0, y>y0), (x>x0, y<y0), (x>x0, y>y0).
  const double xs[2][2] = {{-h.x, x0}, {x0, h.x}}, ys[2][2] = {{-h.y, y0}, {y0, h.y}};
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const Fragment& f = r.children[2 * i + j];
      expect_valid_child(f);
      const double lx = xs[i][1] - xs[i][0], ly = ys[j][1] - ys[j][0];
      EXPECT_NEAR(f.shape->volume(), lx * ly * 2 * h.z, 1e-12 * parent->volume());
      EXPECT_NEAR(norm(f.offset - Vec3{(xs[i][0] + xs[i][1]) / 2, (ys[j][0] + ys[j][1]) / 2, 0}), 0, 1e-12);
      // Box inertia about the centroid (per unit density).
      const double V = f.shape->volume();
      EXPECT_NEAR(f.shape->mass_properties().inertia(2, 2), V / 12 * (lx * lx + ly * ly), 1e-9 * V * lx * lx);
    }
  EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-12 * parent->volume());
  // A plane that misses the grain leaves one child (no breakage).
  CuttingSurfaces miss;
  miss.planes.push_back({{0, 0, 1}, 2e-3});
  EXPECT_EQ(AlphaShapeBuilder().build(*parent, miss).children.size(), 1u);
}

// A plane grazing a face leaves a sliver thinner than min_piece_thickness_fraction × d:
// removed as fines (Bullet could not inset its hull by a collision margin), the other
// piece is the child, and children + removed = parent exactly.
TEST(AlphaShapeBuilder, ThinSliverOfAPlaneCutIsRemovedVolume) {
  const Vec3 h{1e-3, 0.8e-3, 0.5e-3};
  const auto parent = Shape::box(h);
  const double t = 10e-6;  // 10 µm sliver; 0.02 × d_parent = 37 µm
  ASSERT_LT(t, 0.02 * parent->equivalent_diameter());
  CuttingSurfaces cs;
  cs.planes.push_back({{1, 0, 0}, h.x - t});
  const FragmentResult r = AlphaShapeBuilder().build(*parent, cs);
  ASSERT_EQ(r.children.size(), 1u);
  EXPECT_EQ(r.fallbacks, 1);
  EXPECT_NEAR(r.removed_volume, t * 2 * h.y * 2 * h.z, 1e-9 * parent->volume());
  EXPECT_NEAR(r.children[0].shape->volume(), (2 * h.x - t) * 2 * h.y * 2 * h.z, 1e-9 * parent->volume());
  EXPECT_NEAR(volume_sum(r) + r.removed_volume, parent->volume(), 1e-12 * parent->volume());
  // A thicker slab (60 µm > 37 µm) stays a child.
  cs.planes[0].offset = h.x - 60e-6;
  const FragmentResult k = AlphaShapeBuilder().build(*parent, cs);
  EXPECT_EQ(k.children.size(), 2u);
  EXPECT_EQ(k.removed_volume, 0.0);
  // Switched off: the 10 µm sliver is a child again.
  AlphaShapeBuilderOptions o;
  o.min_piece_thickness_fraction = 0;
  cs.planes[0].offset = h.x - t;
  EXPECT_EQ(AlphaShapeBuilder(o).build(*parent, cs).children.size(), 2u);
}

// A closed, manifold but self-intersecting parent mesh (two interpenetrating boxes in one
// mesh) cannot be cut by CGAL: the builder cuts its convex hull instead and counts a
// fallback, never an error that stops the run.
TEST(AlphaShapeBuilder, SelfIntersectingParentFallsBackToItsHull) {
  TriMesh m;
  for (const Vec3 shift : {Vec3{-0.4e-3, 0, 0}, Vec3{0.4e-3, 0.1e-3, 0.05e-3}}) {
    TriMesh b = Shape::box({0.6e-3, 0.5e-3, 0.5e-3})->mesh();
    b.translate(shift);
    const int base = static_cast<int>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
    for (auto tr : b.triangles) m.triangles.push_back({tr[0] + base, tr[1] + base, tr[2] + base});
  }
  const auto parent = Shape::polyhedron(m);
  ASSERT_THROW(split_by_planes(parent->mesh(), {{{1, 0, 0}, 0.0}}), std::invalid_argument);
  CuttingSurfaces cs;
  cs.planes.push_back({{1, 0, 0}, 0.0});
  const FragmentResult r = AlphaShapeBuilder().build(*parent, cs);
  EXPECT_EQ(r.method, "plane_cut_hull");
  EXPECT_EQ(r.fallbacks, 1);
  ASSERT_EQ(r.children.size(), 2u);
  for (const auto& c : r.children) expect_valid_child(c);
  EXPECT_EQ(r.removed_volume, 0.0);
  EXPECT_NEAR(volume_sum(r), parent->volume(), 1e-12 * parent->volume());
}

// A non-convex parent: one plane through both arms of an L-prism gives three pieces.
TEST(AlphaShapeBuilder, NonConvexParentSplitsIntoConnectedPieces) {
  // L-prism from three unit voxels (1 mm), surface triangulated voxel face by voxel face.
  const double a = 1e-3;
  const int vox[3][2] = {{-1, -1}, {0, -1}, {-1, 0}};
  auto filled = [&](int i, int j, int k) {
    if (k != 0) return false;
    for (const auto& v : vox)
      if (v[0] == i && v[1] == j) return true;
    return false;
  };
  TriMesh m;
  std::map<std::tuple<int, int, int>, int> vid;
  auto vertex = [&](int i, int j, int k) {
    auto [it, fresh] = vid.try_emplace({i, j, k}, static_cast<int>(m.vertices.size()));
    if (fresh) m.vertices.push_back({i * a, j * a, (k - 0.5) * a});
    return it->second;
  };
  for (const auto& v : vox)
    for (int axis = 0; axis < 3; ++axis)
      for (int dir : {-1, 1}) {
        int c[3] = {v[0], v[1], 0};
        c[axis] += dir;
        if (filled(c[0], c[1], c[2])) continue;
        // Face of voxel v normal to `axis` on side `dir`: 4 corners, counter-clockwise from outside.
        const int u = (axis + 1) % 3, w = (axis + 2) % 3;
        int base[3] = {v[0], v[1], 0};
        base[axis] += dir > 0 ? 1 : 0;
        int q[4];
        const int du[4] = {0, 1, 1, 0}, dw[4] = {0, 0, 1, 1};
        for (int t = 0; t < 4; ++t) {
          int p[3] = {base[0], base[1], base[2]};
          p[u] += du[t];
          p[w] += dw[t];
          q[t] = vertex(p[0], p[1], p[2]);
        }
        if (dir > 0) {
          m.triangles.push_back({q[0], q[1], q[2]});
          m.triangles.push_back({q[0], q[2], q[3]});
        } else {
          m.triangles.push_back({q[0], q[2], q[1]});
          m.triangles.push_back({q[0], q[3], q[2]});
        }
      }
  const auto parent = Shape::polyhedron(m);
  ASSERT_NEAR(parent->volume(), 3 * a * a * a, 1e-12 * a * a * a);
  const Vec3 c0 = -parent->recentring();  // (−a/6, −a/6, 0)
  // x + y = a/2 in the voxel frame: two corner prisms (a³/8 each) and the rest.
  CuttingSurfaces cs;
  cs.planes.push_back({normalized(Vec3{1, 1, 0}), (0.5 * a - c0.x - c0.y) / std::sqrt(2.0)});
  const FragmentResult r = AlphaShapeBuilder().build(*parent, cs);
  ASSERT_EQ(r.children.size(), 3u);
  std::vector<double> v;
  for (const auto& c : r.children) {
    expect_valid_child(c);
    v.push_back(c.shape->volume() / (a * a * a));
  }
  std::sort(v.begin(), v.end());
  EXPECT_NEAR(v[0], 0.125, 1e-9);
  EXPECT_NEAR(v[1], 0.125, 1e-9);
  EXPECT_NEAR(v[2], 2.75, 1e-9);
}

// build() is const and called from several OpenMP threads at once.
TEST(AlphaShapeBuilder, ConcurrentBuildsAgreeWithSerial) {
  const auto parent = Shape::sphere(kD / 2);
  const auto pc = test::lattice_clusters(*parent, kSpacing, 2, [](const Vec3& p) { return p.z < 0.3e-3 ? 0 : 1; });
  CuttingSurfaces cs;
  cs.planes.push_back({{0, 0, 1}, 0.1e-3});
  const AlphaShapeBuilder b(alpha_only());
  const FragmentResult ref = b.build(*parent, pc), ref_cut = b.build(*parent, cs);
  constexpr int kRuns = 6;
  std::vector<FragmentResult> out(kRuns);
#pragma omp parallel for num_threads(3) schedule(dynamic)
  for (int i = 0; i < kRuns; ++i) out[i] = i % 2 ? b.build(*parent, cs) : b.build(*parent, pc);
  for (int i = 0; i < kRuns; ++i) {
    const FragmentResult& e = i % 2 ? ref_cut : ref;
    ASSERT_EQ(out[i].children.size(), e.children.size());
    for (std::size_t k = 0; k < e.children.size(); ++k) {
      EXPECT_EQ(out[i].children[k].shape->volume(), e.children[k].shape->volume());
      EXPECT_EQ(out[i].children[k].offset, e.children[k].offset);
    }
  }
}

TEST(AlphaShapeBuilder, RejectsBadInput) {
  const auto parent = Shape::sphere(kD / 2);
  const AlphaShapeBuilder b;
  PointClusters pc = test::lattice_clusters(*parent, kSpacing, 2, [](const Vec3& p) { return p.x < 0 ? 0 : 1; });
  PointClusters bad = pc;
  bad.cluster.pop_back();
  EXPECT_THROW(b.build(*parent, bad), std::invalid_argument);
  bad = pc;
  bad.cluster[0] = 5;
  EXPECT_THROW(b.build(*parent, bad), std::invalid_argument);
  bad = pc;
  bad.spacing = 0;
  EXPECT_THROW(b.build(*parent, bad), std::invalid_argument);
  bad = pc;
  bad.fracture_points.pop_back();
  EXPECT_THROW(b.build(*parent, bad), std::invalid_argument);
  EXPECT_THROW(b.build(*Shape::disk(1e-3), pc), std::invalid_argument);
  CuttingSurfaces cs;
  cs.planes.push_back({{0, 0, 0}, 0.0});
  EXPECT_THROW(b.build(*parent, cs), std::invalid_argument);
  EXPECT_THROW(alpha_shape_polyhedron({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, AlphaShapeOptions{1.0}), std::invalid_argument);
  EXPECT_THROW(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}), std::invalid_argument);
}

TEST(AlphaShapeBuilder, RegistryAndConfig) {
  nlohmann::json j = {{"type", "alpha_shape"}, {"convex_hull_convexity", 0.9}, {"scale_about", "child_centroid"}};
  Config cfg(j);
  const auto builder = fragment_builders().find("alpha_shape", "/fragments").make(cfg, EngineContext{});
  EXPECT_EQ(builder->name(), "alpha_shape");
  EXPECT_NO_THROW(cfg.check_unknown());
  const auto& o = dynamic_cast<const AlphaShapeBuilder&>(*builder).options();
  EXPECT_DOUBLE_EQ(o.hull_convexity, 0.9);
  EXPECT_FALSE(o.scale_about_parent);
  EXPECT_DOUBLE_EQ(j["convex_hull_diameter"].get<double>(), 0.7e-3);  // defaults written back
  EXPECT_EQ(j["max_alpha_steps"].get<long>(), 400);

  nlohmann::json typo = {{"type", "alpha_shape"}, {"convex_hull_diamter", 1e-3}};
  Config ct(typo);
  fragment_builders().find("alpha_shape", "/fragments").make(ct, EngineContext{});
  EXPECT_THROW(ct.check_unknown(), ConfigError);

  nlohmann::json range = {{"type", "alpha_shape"}, {"alpha_start_spacings", 3.0}, {"alpha_max_spacings", 2.0}};
  Config cr(range);
  EXPECT_THROW(fragment_builders().find("alpha_shape", "/fragments").make(cr, EngineContext{}), ConfigError);
  nlohmann::json bad_choice = {{"type", "alpha_shape"}, {"scale_about", "origin"}};
  Config cb(bad_choice);
  EXPECT_THROW(fragment_builders().find("alpha_shape", "/fragments").make(cb, EngineContext{}), ConfigError);
}

// Time per child for the reference case (half sphere of a 2 mm grain);
// reported, bounded loosely (the machine is shared).
TEST(AlphaShapeBuilder, TimePerChild) {
  const auto parent = Shape::sphere(kD / 2);
  const auto pc = test::lattice_clusters(*parent, kSpacing, 2, [](const Vec3& p) { return p.x < 0 ? 0 : 1; });
  for (const bool boundary_only : {false, true}) {
    AlphaShapeBuilderOptions o = alpha_only();
    o.alpha_boundary_only = boundary_only;
    std::vector<ChildReport> rep;
    const auto t0 = std::chrono::steady_clock::now();
    const FragmentResult r = AlphaShapeBuilder(o).build(*parent, pc, &rep);
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << "  alpha input " << (boundary_only ? "boundary points" : "all points") << ": " << t / 2
              << " s per child (build() total " << t << " s);";
    for (const auto& x : rep)
      std::cout << " [" << x.method << ", " << x.boundary_points << " boundary pts, sqrt(alpha)/s "
                << std::sqrt(x.alpha) / kSpacing << ", steps " << x.alpha_steps << ", convexity " << x.convexity << ", "
                << x.seconds << " s]";
    std::cout << "\n";
    EXPECT_EQ(r.children.size(), 2u);
    EXPECT_LT(t / 2, 5.0);
  }
}
