// Conformance of the fragment-builder seam (core/FragmentBuilder.h): every registered
// builder, in every dimension it declares, cuts a sphere and a cube (2D: a disk and a
// square) by a plane (CuttingSurfaces, what the stress criteria give) and by two point
// clusters (PointClusters, what peridynamics gives), and must return
//   - at least two children whose volumes plus the removed volume equal the parent's to
//     1e-9 (the mass budget the Simulation checks; both builders rescale to it exactly);
//   - children centred where the parent's mass was (Σ v_i·c_i = 0 within 2 % of the radius,
//     the grid/alpha-shape resolution), every child a closed surface (3D: closed oriented
//     manifold mesh; 2D: a counter-clockwise outline);
//   - the same children in the same order, bit for bit, for the same input (canonical order).
// The builders come from the registration table (tests/support/Registered.h).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <tuple>

#include "core/Config.h"
#include "geometry/TriMesh.h"
#include "scenarios/Registry.h"
#include "tests/support/Registered.h"

using namespace crumble;
using namespace crumble::testing_support;
using nlohmann::json;

namespace {

constexpr double kR = 1e-3;

// A cubic (2D: square) lattice of the parent at `spacing` (Zhu & Zhao 2019 §2.1), split by
// the plane n·x = 0 into two clusters, with surface flags (a missing lattice neighbour) and
// fracture points at the midpoints of the cut nearest-neighbour bonds (§3.2).
PointClusters split_lattice(const Shape& parent, int dim, double spacing, Vec3 n) {
  PointClusters pc;
  pc.spacing = spacing;
  pc.clusters = 2;
  pc.fracture_points.resize(2);
  const int m = static_cast<int>(std::ceil(1.5 * kR / spacing));
  std::map<std::tuple<int, int, int>, int> index;
  std::vector<std::tuple<int, int, int>> ijk;
  const int kmax = dim == 3 ? m : 0, kmin = dim == 3 ? -m : 0;
  for (int i = -m; i <= m; ++i)
    for (int j = -m; j <= m; ++j)
      for (int k = kmin; k <= kmax; ++k) {
        const Vec3 p{(i + 0.5) * spacing, (j + 0.5) * spacing, dim == 3 ? (k + 0.5) * spacing : 0.0};
        if (!parent.contains(p)) continue;
        index[{i, j, k}] = static_cast<int>(pc.points.size());
        ijk.push_back({i, j, k});
        pc.points.push_back(p);
        pc.cluster.push_back(dot(n, p) > 0 ? 1 : 0);
      }
  pc.on_surface.assign(pc.points.size(), 0);
  const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const int dirs = dim == 3 ? 6 : 4;
  for (std::size_t a = 0; a < pc.points.size(); ++a) {
    const auto [i, j, k] = ijk[a];
    int neighbours = 0;
    for (int q = 0; q < dirs; ++q) {
      const auto it = index.find({i + d[q][0], j + d[q][1], k + d[q][2]});
      if (it == index.end()) continue;
      ++neighbours;
      const int b = it->second;
      if (q % 2 == 0 && pc.cluster[b] != pc.cluster[a]) {
        const Vec3 mid = (pc.points[a] + pc.points[b]) * 0.5;
        pc.fracture_points[pc.cluster[a]].push_back(mid);
        pc.fracture_points[pc.cluster[b]].push_back(mid);
      }
    }
    pc.on_surface[a] = neighbours < dirs;
  }
  return pc;
}

class BuilderConformance : public ::testing::TestWithParam<Registered> {
 protected:
  int dim() const { return GetParam().dimension; }

  std::unique_ptr<FragmentBuilder> make() const {
    json opts = {{"type", GetParam().name}};
    Config cfg(opts);
    EngineContext ctx;
    ctx.dimension = dim();
    auto b = fragment_builders().find(GetParam().name, "/fragments/type").make(cfg, ctx);
    cfg.accept("type");  // read by the scenario factory, not the builder
    cfg.check_unknown();
    return b;
  }

  std::vector<std::pair<std::string, Shape::Ptr>> parents() const {
    if (dim() == 3) return {{"sphere", Shape::sphere(kR)}, {"cube", Shape::box({0.8 * kR, 0.8 * kR, 0.8 * kR})}};
    const double h = 0.8 * kR;
    return {{"disk", Shape::disk(kR)}, {"square", Shape::polygon({{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}})}};
  }
  // A plane through the centroid, turned off the lattice axes; 2D: in the plane.
  Vec3 normal() const { return dim() == 3 ? normalized(Vec3{0.3, -0.2, 1}) : normalized(Vec3{0.3, 1, 0}); }

  std::vector<std::pair<std::string, Fracture>> fractures(const Shape& parent) const {
    CuttingSurfaces cut;
    cut.planes.push_back({normal(), 0.1 * kR});
    return {{"plane", cut}, {"clusters", split_lattice(parent, dim(), 0.1 * parent.equivalent_diameter(), normal())}};
  }

  void expect_conforming(const Shape& parent, const FragmentResult& r, const std::string& what) const {
    ASSERT_GE(r.children.size(), 2u) << what << " (" << r.method << ")";
    EXPECT_FALSE(r.method.empty()) << what;
    const double V = parent.volume();
    double sum = r.removed_volume;
    Vec3 moment{0, 0, 0};
    for (const auto& c : r.children) {
      ASSERT_TRUE(c.shape) << what;
      const double v = c.shape->volume();
      EXPECT_GT(v, 0) << what;
      sum += v;
      moment = moment + c.offset * v;
      if (dim() == 3) {
        std::string why;
        EXPECT_TRUE(is_closed_oriented_manifold(c.shape->mesh(), &why)) << what << ": " << why;
      } else {
        const auto& o = c.shape->outline();
        ASSERT_GE(o.size(), 3u) << what;
        double area2 = 0;  // shoelace: positive for counter-clockwise
        for (std::size_t i = 0; i < o.size(); ++i) {
          const Vec3& p = o[i];
          const Vec3& q = o[(i + 1) % o.size()];
          area2 += p.x * q.y - q.x * p.y;
        }
        EXPECT_GT(area2, 0) << what << ": the outline is closed and counter-clockwise";
      }
    }
    EXPECT_NEAR(sum, V, 1e-9 * V) << what << ": children + removed = parent";
    if (r.removed_volume == 0) EXPECT_LT(norm(moment) / V, 0.02 * kR) << what << ": children centred on the parent";
  }
};

TEST_P(BuilderConformance, ChildrenConserveTheParentAndAreClosed) {
  const auto b = make();
  for (const auto& [pname, parent] : parents())
    for (const auto& [fname, f] : fractures(*parent)) expect_conforming(*parent, b->build(*parent, f), pname + " by " + fname);
}

TEST_P(BuilderConformance, SameInputGivesTheSameChildrenInTheSameOrder) {
  const auto b = make();
  for (const auto& [pname, parent] : parents())
    for (const auto& [fname, f] : fractures(*parent)) {
      const FragmentResult r1 = b->build(*parent, f), r2 = b->build(*parent, f);
      const std::string what = pname + " by " + fname;
      ASSERT_EQ(r1.children.size(), r2.children.size()) << what;
      EXPECT_EQ(r1.method, r2.method) << what;
      EXPECT_EQ(std::memcmp(&r1.removed_volume, &r2.removed_volume, sizeof(double)), 0) << what;
      for (std::size_t i = 0; i < r1.children.size(); ++i) {
        const double v1 = r1.children[i].shape->volume(), v2 = r2.children[i].shape->volume();
        EXPECT_EQ(std::memcmp(&v1, &v2, sizeof(double)), 0) << what << " child " << i;
        EXPECT_EQ(std::memcmp(&r1.children[i].offset, &r2.children[i].offset, sizeof(Vec3)), 0) << what << " child " << i;
      }
    }
}

INSTANTIATE_TEST_SUITE_P(Registry, BuilderConformance, ::testing::ValuesIn(registered_builders()),
                         [](const auto& info) { return param_name(info.param); });

}  // namespace
