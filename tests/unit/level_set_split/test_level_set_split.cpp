// Level-set splitting (Harmon et al. 2020 §3.2–3.3, eqs. 14–17) and the "level_set"
// fragment builder: volumes against closed forms, piece counts, mass budget, nodes,
// persistence of level-set grains, and an end-to-end run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "geometry/LevelSetGrid.h"
#include "geometry/LevelSetSplit.h"
#include "geometry/level_set/LevelSetBuilder.h"
#include "output/Checkpoint.h"
#include "core/ShapeSpec.h"
#include "tests/support/CliRunner.h"

namespace crumble {
namespace {

constexpr double kR = 1e-3;   // 1 mm radius
constexpr double kH = kR / 10;  // grid spacing: 20 cells across

std::shared_ptr<const LevelSetGrid> disk_grid(double h = kH) {
  return LevelSetGrid::sample(2, {{-kR, -kR, 0}, {kR, kR, 0}}, h,
                              [](const Vec3& p) { return std::hypot(p.x, p.y) - kR; });
}
std::shared_ptr<const LevelSetGrid> sphere_grid(double h = kH) {
  return LevelSetGrid::sample(3, {{-kR, -kR, -kR}, {kR, kR, kR}}, h, [](const Vec3& p) { return norm(p) - kR; });
}

// Relative error of the grid's own volume against the exact one: the yardstick for the
// children (the smoothed Heaviside of eqs. 24–30 biases volumes by O((ε/R)²), ε = 1.5 h).
double own_error(const LevelSetGrid& g, double exact) { return std::abs(g.mass_properties().volume - exact) / exact; }

double cap_volume(double R, double c) {  // sphere part beyond the plane x = c (|c| < R)
  const double t = R - c;
  return kPi * t * t * (3 * R - t) / 3;
}

// Every edge of a closed, consistently oriented triangle mesh is used once in each direction.
bool closed_mesh(const TriMesh& m) {
  std::map<std::pair<int, int>, int> e;
  for (const auto& t : m.triangles)
    for (int a = 0; a < 3; ++a) ++e[{t[a], t[(a + 1) % 3]}];
  for (const auto& [k, n] : e)
    if (n != 1 || e.count({k.second, k.first}) == 0) return false;
  return !m.triangles.empty();
}

double polygon_area(const std::vector<Vec3>& o) {
  double a = 0;
  for (std::size_t i = 0; i < o.size(); ++i) {
    const Vec3 &p = o[i], &q = o[(i + 1) % o.size()];
    a += p.x * q.y - q.x * p.y;
  }
  return 0.5 * a;
}

double budget_error(const FragmentResult& r, double parent_volume) {
  double s = r.removed_volume;
  for (const auto& c : r.children) s += c.shape->volume();
  return std::abs(s - parent_volume) / parent_volume;
}

// Halves of a disk (2D) and a sphere (3D) cut through the centre.
TEST(LevelSetSplit, DiskHalvesMatchExactAreaWithinGridError) {
  const auto g = disk_grid();
  const double A = kPi * kR * kR;
  const SplitResult r = split_by_planes(*g, {{{1, 0, 0}, 0.0}});
  ASSERT_FALSE(r.missed);
  ASSERT_EQ(r.children.size(), 2u);
  EXPECT_EQ(r.removed.size(), 0u);
  // Tolerance: twice the parent grid's own relative area error (1.1e-3 here) plus 1e-3:
  // the cut adds a straight edge with two corners whose smoothing is of the same order.
  const double tol = 2 * own_error(*g, A) + 1e-3;
  for (const auto& c : r.children) {
    EXPECT_NEAR(c.volume / (A / 2), 1.0, tol);
    const auto o = c.grid->outline();  // closed polygon (outline() follows the loop round)
    ASSERT_GT(o.size(), 10u);
    EXPECT_NEAR(polygon_area(o) / (A / 2), 1.0, 0.02);
    for (std::size_t i = 0; i < o.size(); ++i) EXPECT_LT(norm(o[(i + 1) % o.size()] - o[i]), 1.5 * kH);
    // New surface nodes on the cut, the parent's nodes kept on their side.
    double cut_len = 0;
    for (std::size_t i = 0; i < c.grid->nodes().size(); ++i) {
      const Vec3& x = c.grid->nodes()[i];
      EXPECT_GT(x.x * (c.centroid.x > 0 ? 1 : -1), -1e-12 * kR);  // right side
      // (a parent node may sit on the rim of the cut: it belongs to the arc, not the cut)
      if (std::abs(x.x) < 1e-3 * kH && norm(x) < kR - 0.1 * kH) cut_len += c.grid->node_weights()[i];
    }
    EXPECT_NEAR(cut_len / (2 * kR), 1.0, 0.03);  // the cut's length, carried by nodes on it
  }
  // Eq. 16 as a set identity: min(φ3, φ4) < 0 exactly where φ1 < 0 (away from the zero
  // level by a cell), and equal to φ1 pointwise where the cut is farther than the surface.
  for (double x = -1.3 * kR; x <= 1.3 * kR; x += 0.137 * kR)
    for (double y = -1.3 * kR; y <= 1.3 * kR; y += 0.129 * kR) {
      const Vec3 p{x, y, 0};
      const double f1 = g->value(p);
      const double m = std::min(r.children[0].grid->value(p), r.children[1].grid->value(p));
      if (f1 < -kH) {
        EXPECT_LT(m, 0) << x << " " << y;
      }
      if (f1 > kH) {
        EXPECT_GT(m, 0) << x << " " << y;
      }
      if (f1 < 0 && std::abs(x) > -f1 + kH) {
        EXPECT_NEAR(m, f1, 0.1 * kH) << x << " " << y;
      }
    }
}

TEST(LevelSetSplit, SphereHalvesMatchExactVolumeWithinGridError) {
  const auto g = sphere_grid();
  const double V = 4.0 / 3 * kPi * kR * kR * kR;
  const SplitResult r = split_by_planes(*g, {{{0, 0, 1}, 0.0}});
  ASSERT_EQ(r.children.size(), 2u);
  const double tol = 2 * own_error(*g, V) + 1e-3;  // see the disk test
  double cut_area = 0;
  for (const auto& c : r.children) {
    EXPECT_NEAR(c.volume / (V / 2), 1.0, tol);
    EXPECT_TRUE(closed_mesh(c.grid->to_mesh()));
    for (std::size_t i = 0; i < c.grid->nodes().size(); ++i)
      if (std::abs(c.grid->nodes()[i].z) < 1e-3 * kH && norm(c.grid->nodes()[i]) < kR - 0.1 * kH)
        cut_area += c.grid->node_weights()[i];
  }
  EXPECT_NEAR(cut_area / (2 * kPi * kR * kR), 1.0, 0.03);  // both faces of the cut
}

TEST(LevelSetSplit, OffCentreCutGivesTheCapVolume) {
  const auto g = sphere_grid();
  const double V = 4.0 / 3 * kPi * kR * kR * kR, c = 0.45 * kR;
  const SplitResult r = split_by_planes(*g, {{normalized(Vec3{1, 1, 0}), c}});
  ASSERT_EQ(r.children.size(), 2u);
  const double cap = std::min(r.children[0].volume, r.children[1].volume);
  // The cap is a sixth of the sphere: its edge and rim weigh more, hence the looser 1 %.
  EXPECT_NEAR(cap / cap_volume(kR, c), 1.0, 2 * own_error(*g, V) + 1e-2);

  LevelSetBuilder b;
  const auto parent = Shape::sphere(kR, {1, kH, 0});
  const FragmentResult fr = b.build(*parent, CuttingSurfaces{{{normalized(Vec3{1, 1, 0}), c}}});
  ASSERT_EQ(fr.children.size(), 2u);
  EXPECT_LT(budget_error(fr, parent->volume()), 1e-9);
  for (const auto& ch : fr.children) EXPECT_EQ(ch.shape->kind(), ShapeKind::LevelSet);
}

TEST(LevelSetSplit, PlaneMissingTheGrainIsNoSplit) {
  const auto g = sphere_grid();
  const SplitResult r = split_by_planes(*g, {{{0, 1, 0}, 1.5 * kR}});
  EXPECT_TRUE(r.missed);
  EXPECT_TRUE(r.children.empty());
  LevelSetBuilder b;
  const auto parent = Shape::sphere(kR, {1, kH, 0});
  const FragmentResult fr = b.build(*parent, CuttingSurfaces{{{{0, 1, 0}, 1.5 * kR}}});
  EXPECT_TRUE(fr.children.empty());
  EXPECT_EQ(fr.removed_volume, 0.0);
  EXPECT_EQ(fr.method, "no_split");
}

// A U (three boxes) cut across both arms: three pieces, one child each.
TEST(LevelSetSplit, CutThroughUShapeGivesThreePieces) {
  auto box = [](const Vec3& p, const Vec3& c, double hx, double hy) {
    const double qx = std::abs(p.x - c.x) - hx, qy = std::abs(p.y - c.y) - hy;
    return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
  };
  auto u = [&](const Vec3& p) {
    return std::min({box(p, {0, -0.8e-3, 0}, 1e-3, 0.2e-3), box(p, {-0.8e-3, 0.2e-3, 0}, 0.2e-3, 1e-3),
                     box(p, {0.8e-3, 0.2e-3, 0}, 0.2e-3, 1e-3)});
  };
  LevelSetOptions lo;
  lo.exact_distance = false;  // min of box distances is not a distance inside
  const auto g = LevelSetGrid::sample(2, {{-1e-3, -1e-3, 0}, {1e-3, 1.2e-3, 0}}, 0.05e-3, u, lo);
  const auto parent = Shape::from_level_set(g);
  LevelSetBuilder b;
  // The parent frame is centred on the U's centroid: cut at world y = 0.4 mm.
  const double y = 0.4e-3 + parent->recentring().y;
  const FragmentResult fr = b.build(*parent, CuttingSurfaces{{{{0, 1, 0}, y}}});
  EXPECT_EQ(fr.children.size(), 3u);
  EXPECT_LT(budget_error(fr, parent->volume()), 1e-9);
  // Two arm tips of 0.4 × 0.8 mm² each.
  int tips = 0;
  for (const auto& c : fr.children)
    if (std::abs(c.shape->volume() / (0.4e-3 * 0.8e-3) - 1) < 0.03) ++tips;
  EXPECT_EQ(tips, 2);
}

TEST(LevelSetSplit, SeveralPlanesGiveEveryArrangementCell) {
  const auto parent = Shape::sphere(kR, {1, kH, 0});
  LevelSetBuilder b;
  const FragmentResult fr = b.build(*parent, CuttingSurfaces{{{{1, 0, 0}, 0.0}, {{0, 1, 0}, 0.0}}});
  ASSERT_EQ(fr.children.size(), 4u);
  EXPECT_LT(budget_error(fr, parent->volume()), 1e-9);
  for (const auto& c : fr.children) EXPECT_NEAR(c.shape->volume() / (parent->volume() / 4), 1.0, 0.01);
}

TEST(LevelSetSplit, ChildThinnerThanACellIsRemovedVolume) {
  const auto parent = Shape::disk(kR, {1, kH, 0});
  const LevelSetGrid& g = parent->level_set();
  // The outermost grid node inside the disk along +x, and a line 0.2 h inside it: the cap
  // holds that node but is thinner than a cell.
  double xn = 0;
  for (int i = 0; i < g.counts()[0]; ++i) {
    const Vec3 p = g.origin() + Vec3{i * g.spacing(), 0, 0};
    if (std::abs(p.y) < 1e-12 && g.value(p) < 0) xn = std::max(xn, p.x);
  }
  for (int j = 0; j < g.counts()[1]; ++j) {  // the lattice row through y = 0 (or nearest)
    const double yy = g.origin().y + j * g.spacing();
    if (std::abs(yy) < 0.5 * g.spacing())
      for (int i = 0; i < g.counts()[0]; ++i) {
        const Vec3 p = g.origin() + Vec3{i * g.spacing(), j * g.spacing(), 0};
        if (g.value(p) < 0) xn = std::max(xn, p.x);
      }
  }
  ASSERT_GT(xn, 0.5 * kR);
  const CuttingSurfaces cut{{{{1, 0, 0}, xn - 0.2 * g.spacing()}}};
  LevelSetBuilderOptions o;  // the default: every unresolved piece removed
  FragmentResult fr;
  ASSERT_NO_THROW(fr = LevelSetBuilder(o).build(*parent, cut));
  EXPECT_EQ(fr.children.size(), 1u);
  EXPECT_GT(fr.removed_volume, 0.0);
  EXPECT_TRUE(std::isfinite(fr.removed_volume));
  EXPECT_EQ(fr.absorbed, 0);
  EXPECT_LT(budget_error(fr, parent->volume()), 1e-9);
  // absorb_cells 2 absorbs the cap (a node next to the kept child): nothing is removed, one
  // child with the parent's whole volume, which the simulation records as no_split.
  o.absorb_cells = 2;
  const FragmentResult kept = LevelSetBuilder(o).build(*parent, cut);
  EXPECT_EQ(kept.children.size(), 1u);
  EXPECT_EQ(kept.removed_volume, 0.0);
  EXPECT_EQ(kept.absorbed, 1);
  EXPECT_EQ(kept.fallbacks, 0);
  EXPECT_LT(budget_error(kept, parent->volume()), 1e-9);
}

// Pieces thinner than a cell that a cut leaves next to a kept child are lattice artefacts:
// split_by_planes reports them absorbed, not removed, when absorb_cells > 0 (Harmon et al.
// 2020 eqs. 14–15 take φ3 and φ4 whole, with no connectivity test).
TEST(LevelSetSplit, PiecesThinnerThanACellNextToAKeptChildAreAbsorbed) {
  // A square 2 mm wide on a 0.1 mm lattice: its outermost inside nodes lie at ±0.9 mm. Two
  // planes 0.3 cells inside them (x = 0.87 mm, y = 0.87 mm) leave a one-node corner and two
  // one-node-wide strips beyond them, all thinner than a cell, beside the big piece.
  const double h = 0.1e-3;
  const auto g = LevelSetGrid::sample(2, {{-1e-3, -1e-3, 0}, {1e-3, 1e-3, 0}}, h, [](const Vec3& p) {
    return std::max(std::abs(p.x), std::abs(p.y)) - 1e-3;
  });
  const std::vector<SplitPlane> planes{{{1, 0, 0}, 0.87e-3}, {{0, 1, 0}, 0.87e-3}};
  SplitOptions so;
  so.absorb_cells = 0;
  const SplitResult off = split_by_planes(*g, planes, so);
  so.absorb_cells = 2;
  const SplitResult on = split_by_planes(*g, planes, so);
  ASSERT_EQ(off.children.size(), 1u);
  ASSERT_EQ(off.removed.size(), 3u);
  EXPECT_EQ(on.children.size(), 1u);
  EXPECT_TRUE(on.removed.empty());
  EXPECT_EQ(on.removed_volume, 0.0);
  EXPECT_EQ(on.absorbed, 3);
  EXPECT_NEAR(on.absorbed_volume, off.removed_volume, 1e-12 * off.removed_volume);
  // The child took the strips in: it holds the square's whole grid volume (to the grid's own
  // error), not the cut piece's plus a rescaling.
  const double whole = g->mass_properties().volume;
  EXPECT_LT(off.children[0].volume, 0.9 * whole);
  EXPECT_NEAR(on.children[0].volume / whole, 1.0, 0.01);
}

// Harmon et al. 2020 §3.4, second method: the same sub-cell cap is kept when the split may be
// refined (resolve_diameter): the split is repeated on finer grids until the cap is resolved,
// and it becomes a child with the circular segment's area; nothing is removed.
TEST(LevelSetSplit, ThinCapIsKeptWhenTheSplitIsRefined) {
  const auto parent = Shape::disk(kR, {1, kH, 0});
  // A cap 1.2 cells thick whose only grid nodes (x = 0.9 R) lie 0.2 cells inside it: on the
  // parent's grid it is thinner than a cell (ChildThinnerThanACellIsRemovedVolume).
  const double c = kR - 1.2 * kH;
  LevelSetBuilderOptions o;
  o.cells_across = 20;
  o.resolve_diameter = 0.1e-3;
  const FragmentResult fr = LevelSetBuilder(o).build(*parent, CuttingSurfaces{{{{1, 0, 0}, c}}});
  ASSERT_EQ(fr.children.size(), 2u) << fr.method;
  EXPECT_EQ(fr.removed_volume, 0.0);
  EXPECT_GE(fr.refinements, 1);
  EXPECT_LT(budget_error(fr, parent->volume()), 1e-9);
  const double segment = kR * kR * std::acos(c / kR) - c * std::sqrt(kR * kR - c * c);
  const double cap = std::min(fr.children[0].shape->volume(), fr.children[1].shape->volume());
  EXPECT_NEAR(cap / segment, 1.0, 0.1);
  // Each child's grid follows its own thickness: ≈ 20 cells across twice its deepest inside
  // distance (the cap's spacing ≈ 1.2 h / 20, far finer than the parent's).
  for (const auto& ch : fr.children) {
    const LevelSetGrid& g = ch.shape->level_set();
    const double depth = -*std::min_element(g.values().begin(), g.values().end());
    EXPECT_NEAR(2 * depth / g.spacing(), 20.0, 2.0);
    if (ch.shape->volume() == cap) {
      EXPECT_LT(g.spacing(), 0.1 * kH);
    }
  }
  // Off (cells_across 0): the parent's lattice, the cap removed.
  o.cells_across = 0;
  const FragmentResult off = LevelSetBuilder(o).build(*parent, CuttingSurfaces{{{{1, 0, 0}, c}}});
  EXPECT_EQ(off.children.size(), 1u);
  EXPECT_GT(off.removed_volume, 0.0);
  EXPECT_EQ(off.refinements, 0);
}

// Each child is resampled at its own size: the halves of a disk 20 cells across have
// 2·(inscribed radius)/h ≈ 20 cells across their thickness again; max_grid_nodes caps it.
TEST(LevelSetSplit, ChildrenAreResampledAtTheirOwnSizeWithinTheNodeCap) {
  const auto parent = Shape::disk(kR, {1, kH, 0});
  LevelSetBuilderOptions o;
  o.cells_across = 20;
  const FragmentResult fr = LevelSetBuilder(o).build(*parent, CuttingSurfaces{{{{0, 1, 0}, 0.0}}});
  ASSERT_EQ(fr.children.size(), 2u);
  EXPECT_LT(budget_error(fr, parent->volume()), 1e-9);
  for (const auto& ch : fr.children) {
    const LevelSetGrid& g = ch.shape->level_set();
    const double depth = -*std::min_element(g.values().begin(), g.values().end());
    EXPECT_NEAR(2 * depth / g.spacing(), 20.0, 1.5);  // a half disk's inscribed diameter is R
    EXPECT_NEAR(ch.shape->volume() / (0.5 * kPi * kR * kR), 1.0, 0.01);
  }
  EXPECT_GT(fr.grid_nodes, 0);
  o.max_grid_nodes = 1000;
  const FragmentResult capped = LevelSetBuilder(o).build(*parent, CuttingSurfaces{{{{0, 1, 0}, 0.0}}});
  ASSERT_EQ(capped.children.size(), 2u);
  for (const auto& ch : capped.children) {
    const auto n = ch.shape->level_set().counts();
    EXPECT_LE(n[0] * n[1], 1000);
  }
}

// A child thinner than resolve_diameter (a cap, a long slab) is not resampled finer than
// resolve_diameter / cells_across, the finest grid a split is refined to: a 0.2 mm cap of a
// 1 mm disk (segment of 0.1635 mm², d = 0.456 mm, above resolve_diameter 0.4 mm) would get
// 2·depth / 20 ≈ 0.01 mm; it gets 0.4 mm / 20 = 0.02 mm, and its grid a quarter of the nodes.
// Its area stays the segment's; the other child follows its own thickness as before.
TEST(LevelSetSplit, ThinChildIsNotResampledFinerThanTheRefinementFloor) {
  const auto parent = Shape::disk(kR, {1, kH, 0});
  const double c = kR - 2 * kH;
  const CuttingSurfaces cut{{{{1, 0, 0}, c}}};
  const double segment = kR * kR * std::acos(c / kR) - c * std::sqrt(kR * kR - c * c);
  LevelSetBuilderOptions o;
  o.cells_across = 20;
  o.resolve_diameter = 0.4e-3;
  const FragmentResult fr = LevelSetBuilder(o).build(*parent, cut);
  ASSERT_EQ(fr.children.size(), 2u) << fr.method;
  EXPECT_EQ(fr.removed_volume, 0.0);
  EXPECT_LT(budget_error(fr, parent->volume()), 1e-9);
  auto cap_of = [](const FragmentResult& r) -> const LevelSetGrid& {
    const auto& a = r.children[0].shape, &b = r.children[1].shape;
    return (a->volume() < b->volume() ? a : b)->level_set();
  };
  const LevelSetGrid& cap = cap_of(fr);
  // (The children's grids are scaled by k^(1/2) ≈ 1 for the mass budget.)
  EXPECT_NEAR(cap.spacing() / (o.resolve_diameter / o.cells_across), 1.0, 0.01);
  // Cut on the parent's grid (2 cells across the cap, no refinement needed) and resampled
  // from it: the segment's area within the coarse cut's error.
  EXPECT_NEAR(cap.mass_properties().volume / segment, 1.0, 0.2);
  const auto n = cap.counts();
  for (const auto& ch : fr.children) {
    const LevelSetGrid& g = ch.shape->level_set();
    if (&g == &cap) continue;
    const double depth = -*std::min_element(g.values().begin(), g.values().end());
    EXPECT_NEAR(2 * depth / g.spacing(), 20.0, 2.0);
  }
  // Without the floor (resolve_diameter below the cap's own spacing × 20) the cap follows its
  // thickness: about half the spacing, about four times the nodes.
  o.resolve_diameter = 0.1e-3;
  const FragmentResult fine = LevelSetBuilder(o).build(*parent, cut);
  ASSERT_EQ(fine.children.size(), 2u);
  const LevelSetGrid& fine_cap = cap_of(fine);
  EXPECT_LT(fine_cap.spacing(), 0.7 * cap.spacing());
  EXPECT_NEAR(fine_cap.mass_properties().volume / cap.mass_properties().volume, 1.0, 0.02);
  const auto m = fine_cap.counts();
  EXPECT_GT(m[0] * m[1], 2 * n[0] * n[1]);
}

TEST(LevelSetSplit, ResampledGridKeepsTheZeroLevel) {
  const auto g = disk_grid();
  const auto fine = g->resampled(0.5 * kH, 0);
  EXPECT_NEAR(fine->spacing(), 0.5 * kH, 1e-15);
  EXPECT_NEAR(fine->mass_properties().volume / (kPi * kR * kR), 1.0, 2 * own_error(*g, kPi * kR * kR) + 1e-3);
  for (const auto& x : fine->nodes()) EXPECT_NEAR(std::hypot(x.x, x.y), kR, 0.05 * kH);
  EXPECT_THROW(g->resampled(0.0, 0), std::invalid_argument);
}

// Harmon et al. 2020 §3.4: a grain of the size of its discretisation. A slab 1.6 cells thick
// (one row of grid nodes inside) cut along its length: its grid cannot separate two pieces
// (split_by_planes finds one side empty), yet the plane runs through it. fines_policy "halt"
// (first method): no child and no removed volume, marked unresolved (the Simulation leaves the
// grain whole). "remove" (third method, the default): all of it is removed volume (outcome
// crushed), the budget exact. The same slab cut across its length splits in two; a plane
// beyond it misses it.
TEST(LevelSetSplit, UnresolvedThinGrainCutAlongItsLengthStaysWhole) {
  const double a = 10 * kH, b = 0.8 * kH;
  auto box = [&](const Vec3& p) {
    const double qx = std::abs(p.x) - a, qy = std::abs(p.y) - b;
    return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
  };
  // Bounds on whole cells about the origin: a lattice row runs along y = 0.
  const auto slab = Shape::from_level_set(LevelSetGrid::sample(2, {{-a - 2 * kH, -3 * kH, 0}, {a + 2 * kH, 3 * kH, 0}}, kH, box));
  LevelSetBuilderOptions halt;
  halt.fines_policy = "halt";
  const LevelSetBuilder lb(halt);
  const CuttingSurfaces along{{{{0, 1, 0}, 0.3 * kH}}};
  ASSERT_TRUE(split_by_planes(slab->level_set(), {{{0, 1, 0}, 0.3 * kH}}).missed);
  const FragmentResult fr = lb.build(*slab, along);
  EXPECT_EQ(fr.method, "level_set_unresolved");
  EXPECT_TRUE(fr.unresolved);
  EXPECT_TRUE(fr.children.empty());
  EXPECT_EQ(fr.removed_volume, 0.0);
  EXPECT_EQ(fr.fallbacks, 0);
  const FragmentResult crushed = LevelSetBuilder().build(*slab, along);
  EXPECT_EQ(crushed.method, "level_set_unresolved");
  EXPECT_FALSE(crushed.unresolved);
  EXPECT_TRUE(crushed.children.empty());
  EXPECT_NEAR(crushed.removed_volume, slab->volume(), 1e-12 * slab->volume());
  EXPECT_EQ(crushed.fallbacks, 1);
  const FragmentResult across = lb.build(*slab, CuttingSurfaces{{{{1, 0, 0}, 0.0}}});
  EXPECT_EQ(across.children.size(), 2u);
  EXPECT_FALSE(across.unresolved);
  const FragmentResult miss = lb.build(*slab, CuttingSurfaces{{{{0, 1, 0}, 3 * b}}});
  EXPECT_EQ(miss.method, "no_split");
  EXPECT_EQ(miss.removed_volume, 0.0);
}

// A split whose every piece is thinner than min_thickness_cells (here 25 cells: a 20-cell
// disk halved) resolves nothing either: with fines_policy "halt" unresolved, no child, no
// removed volume.
TEST(LevelSetSplit, SplitWithEveryPieceTooThinIsUnresolved) {
  const auto disk = Shape::from_level_set(disk_grid());
  LevelSetBuilderOptions o;
  o.min_thickness_cells = 25;
  o.fines_policy = "halt";
  const FragmentResult fr = LevelSetBuilder(o).build(*disk, CuttingSurfaces{{{{1, 0, 0}, 0.0}}});
  EXPECT_TRUE(fr.unresolved);
  EXPECT_EQ(fr.method, "level_set_unresolved");
  EXPECT_TRUE(fr.children.empty());
  EXPECT_EQ(fr.removed_volume, 0.0);
  const FragmentResult kept = LevelSetBuilder().build(*disk, CuttingSurfaces{{{{1, 0, 0}, 0.0}}});
  EXPECT_FALSE(kept.unresolved);
  EXPECT_EQ(kept.children.size(), 2u);
}

// fines_policy "halt" (Harmon et al. 2020 §3.4, first method): a split that would leave fines is
// not made. A 1 mm disk (20 cells across) cut at x = 0.7 R: the cap holds 0.2955 R² (closed
// form R²(acos 0.7 − 0.7·√0.51)), d = 0.613 mm. Below resolve_diameter 0.8 mm the split is
// unresolved; with 0.5 mm it is made. With the cap thinner than min_thickness_cells, "remove"
// removes it (one child and removed volume) and "halt" leaves the grain whole.
TEST(LevelSetSplit, FinesPolicyHaltLeavesTheGrainWholeInsteadOfRemovingFines) {
  const auto disk = Shape::from_level_set(disk_grid());
  const CuttingSurfaces at07{{{{1, 0, 0}, 0.7 * kR}}};
  const double cap = kR * kR * (std::acos(0.7) - 0.7 * std::sqrt(0.51));
  LevelSetBuilderOptions remove;
  remove.resolve_diameter = 0.8e-3;
  const FragmentResult made = LevelSetBuilder(remove).build(*disk, at07);
  ASSERT_EQ(made.children.size(), 2u);
  const double small = std::min(made.children[0].shape->volume(), made.children[1].shape->volume());
  EXPECT_NEAR(small, cap, 0.05 * cap);
  EXPECT_LT(std::sqrt(4 * small / kPi), 0.8e-3);
  LevelSetBuilderOptions halt = remove;
  halt.fines_policy = "halt";
  const FragmentResult held = LevelSetBuilder(halt).build(*disk, at07);
  EXPECT_TRUE(held.unresolved);
  EXPECT_TRUE(held.children.empty());
  EXPECT_EQ(held.removed_volume, 0.0);
  halt.resolve_diameter = 0.5e-3;
  EXPECT_EQ(LevelSetBuilder(halt).build(*disk, at07).children.size(), 2u);
  remove.min_thickness_cells = 5;  // the cap, 3 cells thick, is removed; the rest (17) is kept
  halt.min_thickness_cells = 5;
  const FragmentResult chip = LevelSetBuilder(remove).build(*disk, at07);
  ASSERT_EQ(chip.children.size(), 1u);
  EXPECT_GT(chip.removed_volume, 0.0);
  const FragmentResult no_chip = LevelSetBuilder(halt).build(*disk, at07);
  EXPECT_TRUE(no_chip.unresolved);
  EXPECT_EQ(no_chip.removed_volume, 0.0);
  LevelSetBuilderOptions bad;
  bad.fines_policy = "keep";
  EXPECT_THROW(LevelSetBuilder{bad}, std::exception);
}

// A slab 3.2 cells thick (grid rows at y = −h, 0, h inside) cut at y = −1.3 h, below its lowest
// row: the cut runs through the slab but leaves no grid node below it. The builder moves it
// to leave a cell of nodes on each side (y = 0) and gives two resolved halves, budget exact.
TEST(LevelSetSplit, CutBetweenTheSurfaceAndTheFirstGridRowIsMovedInside) {
  const double a = 10 * kH, b = 1.6 * kH;
  auto box = [&](const Vec3& p) {
    const double qx = std::abs(p.x) - a, qy = std::abs(p.y) - b;
    return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
  };
  const auto slab = Shape::from_level_set(LevelSetGrid::sample(2, {{-a - 2 * kH, -4 * kH, 0}, {a + 2 * kH, 4 * kH, 0}}, kH, box));
  ASSERT_TRUE(split_by_planes(slab->level_set(), {{{0, 1, 0}, -1.3 * kH}}).missed);
  LevelSetBuilder lb;
  const FragmentResult fr = lb.build(*slab, CuttingSurfaces{{{{0, 1, 0}, -1.3 * kH}}});
  EXPECT_EQ(fr.method, "level_set_planes_moved");
  ASSERT_EQ(fr.children.size(), 2u);
  EXPECT_GE(fr.fallbacks, 1);
  EXPECT_NEAR(fr.children[0].shape->volume() / fr.children[1].shape->volume(), 1.0, 0.1);
  EXPECT_LT(budget_error(fr, slab->volume()), 1e-9);
}

// Peridynamics output: two clusters of a lattice in a rotated frame.
TEST(LevelSetSplit, PointClustersPartitionASphere) {
  const auto parent = Shape::sphere(kR, {1, kH, 0});
  const Quat frame = Quat::from_axis_angle({0.3, -0.5, 0.8}, 0.7);
  PointClusters pc;
  pc.spacing = kR / 8;
  pc.frame = frame;
  pc.clusters = 2;
  // Lattice x = i·a, cluster 1 beyond x = 0.3 R: the bisector lies at 0.3125 R.
  for (int i = -8; i <= 8; ++i)
    for (int j = -8; j <= 8; ++j)
      for (int k = -8; k <= 8; ++k) {
        const Vec3 body{i * pc.spacing, j * pc.spacing, k * pc.spacing};
        if (norm(body) >= kR) continue;
        pc.points.push_back(frame.conjugate().rotate(body));  // given in the lattice frame
        pc.cluster.push_back(body.x > 0.3 * kR ? 1 : 0);
        pc.on_surface.push_back(0);
      }
  LevelSetBuilder b;
  const FragmentResult fr = b.build(*parent, pc);
  ASSERT_EQ(fr.children.size(), 2u);
  EXPECT_EQ(fr.method, "level_set_clusters");
  EXPECT_LT(budget_error(fr, parent->volume()), 1e-9);
  const double cap = cap_volume(kR, 0.3125 * kR);
  const Fragment& small = fr.children[0].shape->volume() < fr.children[1].shape->volume() ? fr.children[0]
                                                                                           : fr.children[1];
  EXPECT_NEAR(small.shape->volume() / cap, 1.0, 0.03);  // 3 %: grid error of a cap (see above) + rescale
  EXPECT_GT(small.offset.x, 0.5 * kR);  // the cap lies beyond the cut, in the body frame
}

// Persistence: a level-set grain survives shape_to_json → shape_from_config exactly.
TEST(LevelSetSplit, LevelSetShapeRoundTripsThroughJson) {
  const auto parent = Shape::sphere(kR, {1, kH, 0});
  const FragmentResult fr = LevelSetBuilder().build(*parent, CuttingSurfaces{{{{0, 0, 1}, 0.2 * kR}}});
  ASSERT_EQ(fr.children.size(), 2u);
  for (const auto& c : fr.children) {
    nlohmann::json j = nlohmann::json::parse(shape_to_json(*c.shape).dump());
    const auto back = shape_from_config(Config(j), 3);
    ASSERT_EQ(back->kind(), ShapeKind::LevelSet);
    EXPECT_DOUBLE_EQ(back->volume(), c.shape->volume());
    EXPECT_EQ(back->level_set().nodes().size(), c.shape->level_set().nodes().size());
    for (double t = -1.2; t <= 1.2; t += 0.11) {
      const Vec3 p{t * kR, 0.37 * t * kR, -0.5 * t * kR};
      EXPECT_DOUBLE_EQ(back->signed_distance(p), c.shape->signed_distance(p));
    }
  }
  // 2D and a bad value: ConfigError naming the path.
  const auto d = Shape::from_level_set(disk_grid());
  nlohmann::json j2 = shape_to_json(*d);
  EXPECT_DOUBLE_EQ(shape_from_config(Config(j2), 2)->volume(), d->volume());
  j2["values"][3] = "x";
  try {
    shape_from_config(Config(j2), 2);
    FAIL() << "accepted a non-number value";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("values/3"), std::string::npos) << e.what();
  }
  j2 = shape_to_json(*d);
  j2["counts"][0] = 3;
  EXPECT_THROW(shape_from_config(Config(j2), 2), ConfigError);
  j2 = shape_to_json(*d);
  EXPECT_THROW(shape_from_config(Config(j2), 3), ConfigError);  // dimension mismatch
}

TEST(LevelSetSplit, ScaledLevelSetShapeScalesVolumeExactly) {
  const auto d = Shape::from_level_set(sphere_grid());
  const auto s = d->scaled(1.1);
  EXPECT_NEAR(s->volume() / d->volume(), 1.1 * 1.1 * 1.1, 1e-12);
}

// lsdem + peridynamics + level_set on the single-grain scene (breakage checked every 1 MPa
// instead of 0.1 MPa so that the test runs in seconds: 173 N → 180 N crushing force).
TEST(LevelSetSplit, EndToEndPeridynamicsOnLsdemBreaksIntoLevelSetChildren) {
  namespace fs = std::filesystem;
  const fs::path out = fs::temp_directory_path() / ("crumble_ls_e2e_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const auto r = testing_support::run_cli(
      "run " + std::string(CRUMBLE_SOURCE_DIR) + "/scenarios/single_grain_pd.json --out " + out.string() +
      " --quiet --set engine.type=lsdem --set engine.kn=5e6 --set fragments.type=level_set --set output.checkpoint_every=1000000 --set schedule.every_stress=1e6");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto s = nlohmann::json::parse(testing_support::slurp(out / "summary.json"));
  EXPECT_GE(s["breakage_events"].get<int>(), 1) << s.dump(1);
  const double m0 = s["mass_initial_kg"], m1 = s["mass_final_kg"], mr = s["mass_removed_kg"];
  EXPECT_NEAR((m1 + mr) / m0, 1.0, 1e-9);
  EXPECT_GE(s["grains_final"].get<int>(), 2) << s.dump(1);
  // The children are saved as level sets in the final checkpoint and read back exactly
  // (packing.json is written before loading, so it holds the unbroken grain).
  const Checkpoint cp = read_checkpoint((out / "checkpoint.json").string(), "single_grain_pd", 3);
  int ls = 0;
  double v = 0;
  for (const auto& g : cp.grains) {
    ls += g.shape->kind() == ShapeKind::LevelSet;
    v += g.shape->volume();
  }
  EXPECT_GE(ls, 2);
  EXPECT_NEAR(v * 2650 / m1, 1.0, 1e-9);  // the grains' mass as summary.json reports it
  bool vtp = false;
  for (const auto& e : fs::directory_iterator(out / "vtk")) vtp |= fs::file_size(e.path()) > 1000;
  EXPECT_TRUE(vtp);
  fs::remove_all(out);
}

}  // namespace
}  // namespace crumble
