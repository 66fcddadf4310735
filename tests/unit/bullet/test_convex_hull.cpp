// geometry/ConvexHull: closed, outward, extreme points only; exact volume on a cube.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "geometry/ConvexHull.h"
#include "geometry/Shape.h"
#include "geometry/TriMesh.h"

using namespace crumble;

namespace {
// Largest signed distance of p above any face plane of the hull (negative: strictly inside).
double max_plane_distance(const TriMesh& h, const Vec3& p) {
  double worst = -1e300;
  for (const auto& t : h.triangles) {
    const Vec3 n = normalized(cross(h.vertices[t[1]] - h.vertices[t[0]], h.vertices[t[2]] - h.vertices[t[0]]));
    worst = std::max(worst, dot(n, p - h.vertices[t[0]]));
  }
  return worst;
}

void expect_valid(const TriMesh& h) {
  std::string why;
  EXPECT_TRUE(is_closed_oriented_manifold(h, &why)) << why;
  EXPECT_EQ(euler_characteristic(h), 2);
  EXPECT_GT(polyhedron_mass_properties(h).volume, 0);  // outward orientation
}
}  // namespace

TEST(ConvexHull, CubeCornersWithInteriorAndFacePointsGiveEightVertices) {
  std::vector<Vec3> pts;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.999, 0.999);
  for (int i = 0; i < 200; ++i) pts.push_back({u(rng), u(rng), u(rng)});
  // Points on faces and edges (not extreme) and the 8 corners of [-1,1]^3 (+ offset).
  for (int i = 0; i < 30; ++i) {
    pts.push_back({1, u(rng), u(rng)});
    pts.push_back({u(rng), -1, 1});
    pts.push_back({0, 0, -1});
  }
  for (int x : {-1, 1})
    for (int y : {-1, 1})
      for (int z : {-1, 1}) pts.push_back({double(x), double(y), double(z)});
  for (int i = 0; i < 8; ++i) pts.push_back({0.5, 1, 0});  // duplicates on a face
  for (auto& p : pts) p += Vec3{10, -3, 2};
  const TriMesh h = convex_hull(pts);
  EXPECT_EQ(h.vertices.size(), 8u);
  EXPECT_EQ(h.triangles.size(), 12u);
  expect_valid(h);
  const auto mp = polyhedron_mass_properties(h);
  EXPECT_NEAR(mp.volume, 8.0, 1e-12);
  EXPECT_NEAR(mp.centroid.x, 10.0, 1e-12);
  for (const auto& v : h.vertices) {
    EXPECT_DOUBLE_EQ(std::abs(v.x - 10), 1.0);
    EXPECT_DOUBLE_EQ(std::abs(v.y + 3), 1.0);
    EXPECT_DOUBLE_EQ(std::abs(v.z - 2), 1.0);
  }
}

TEST(ConvexHull, RandomPointsOnSphereAreAllOnOrInsideAndHullIsClosed) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> g;
  std::vector<Vec3> pts;
  for (int i = 0; i < 2000; ++i) pts.push_back(normalized(Vec3{g(rng), g(rng), g(rng)}) * 1e-3);
  const TriMesh h = convex_hull(pts);
  expect_valid(h);
  // Every point of a sphere sample is extreme.
  EXPECT_EQ(h.vertices.size(), pts.size());
  for (const auto& p : pts) EXPECT_LE(max_plane_distance(h, p), 1e-15);
  // Volume approaches the ball's from below.
  const double vball = 4.0 / 3.0 * kPi * 1e-9;
  const double v = polyhedron_mass_properties(h).volume;
  EXPECT_LT(v, vball);
  EXPECT_GT(v, 0.99 * vball);
}

TEST(ConvexHull, InteriorPointsOfARandomCloudAreInside) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> pts;
  for (int i = 0; i < 3000; ++i) pts.push_back({u(rng), 0.3 * u(rng), 2 * u(rng)});
  const TriMesh h = convex_hull(pts);
  expect_valid(h);
  for (const auto& p : pts) EXPECT_LE(max_plane_distance(h, p), 1e-12);
  EXPECT_LT(h.vertices.size(), pts.size());
}

TEST(ConvexHull, IcosphereLevelOneHullHas42Vertices) {
  const TriMesh ico = icosphere(1);
  const TriMesh h = convex_hull(ico.vertices);
  EXPECT_EQ(h.vertices.size(), 42u);
  EXPECT_EQ(h.triangles.size(), 80u);
  expect_valid(h);
  EXPECT_NEAR(polyhedron_mass_properties(h).volume, polyhedron_mass_properties(ico).volume, 1e-12);
  // Through Shape: the lazily built hull of a sphere grain.
  const auto s = Shape::sphere(1e-3);
  EXPECT_EQ(s->convex_hull().vertices.size(), 42u);
}

TEST(ConvexHull, RejectsTooFewAndFlatClouds) {
  EXPECT_THROW(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), std::invalid_argument);
  std::vector<Vec3> flat;
  for (int i = 0; i < 20; ++i) flat.push_back({std::cos(i * 0.3), std::sin(i * 0.7), 0.0});
  EXPECT_THROW(convex_hull(flat), std::invalid_argument);
  std::vector<Vec3> line;
  for (int i = 0; i < 20; ++i) line.push_back({i * 1.0, 2.0 * i, -1.0 * i});
  EXPECT_THROW(convex_hull(line), std::invalid_argument);
  std::vector<Vec3> same(10, Vec3{1, 2, 3});
  EXPECT_THROW(convex_hull(same), std::invalid_argument);
  EXPECT_THROW(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, NAN}}), std::invalid_argument);
}

TEST(ConvexHull, LatticeWithManyCoplanarPointsGivesTheBox) {
  // 7x5x9 lattice: every face holds many coplanar and collinear points.
  std::vector<Vec3> pts;
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 9; ++k) pts.push_back({0.1 * i, 0.3 * j - 7.0, 1e3 + 0.05 * k});
  const TriMesh h = convex_hull(pts);
  EXPECT_EQ(h.vertices.size(), 8u);
  expect_valid(h);
  EXPECT_NEAR(polyhedron_mass_properties(h).volume, 0.6 * 1.2 * 0.4, 1e-9);
  // A box shape's hull and a rotated lattice, too.
  EXPECT_EQ(Shape::box({1e-3, 2e-3, 0.5e-3})->convex_hull().vertices.size(), 8u);
  const Quat q = Quat::from_axis_angle({1, 2, 3}, 0.7);
  for (auto& p : pts) p = q.rotate(p);
  const TriMesh hr = convex_hull(pts);
  EXPECT_EQ(hr.vertices.size(), 8u);
  expect_valid(hr);
}

TEST(ConvexHull, InsetMovesEveryFacePlaneInwardsByTheDistance) {
  // Largest shift of each original face plane after the inset, over all faces (min, max).
  auto plane_shifts = [](const TriMesh& h, const std::vector<Vec3>& moved) {
    double lo = 1e300, hi = -1e300;
    for (const auto& t : h.triangles) {
      const Vec3 n = normalized(cross(h.vertices[t[1]] - h.vertices[t[0]], h.vertices[t[2]] - h.vertices[t[0]]));
      double top = -1e300;
      for (const auto& p : moved) top = std::max(top, dot(n, p - h.vertices[t[0]]));
      lo = std::min(lo, top);
      hi = std::max(hi, top);
    }
    return std::pair{lo, hi};
  };
  // Box: three faces per corner, exact.
  const TriMesh box = Shape::box({1.0, 2.0, 0.5})->convex_hull();
  const auto in = inset_convex_vertices(box, 0.1);
  ASSERT_EQ(in.size(), 8u);
  EXPECT_NEAR(polyhedron_mass_properties(convex_hull(in)).volume, 8 * 0.9 * 1.9 * 0.4, 1e-10);
  auto [blo, bhi] = plane_shifts(box, in);
  EXPECT_NEAR(blo, -0.1, 1e-12);
  EXPECT_NEAR(bhi, -0.1, 1e-12);
  // Icosphere grain (5 or 6 faces per vertex): every face plane moves in by the distance
  // within 2 % of it, and the vertex count stays 42.
  const TriMesh ico = Shape::sphere(1e-3)->convex_hull();
  const double d = 2e-5;
  const auto ii = inset_convex_vertices(ico, d);
  ASSERT_EQ(ii.size(), 42u);
  auto [ilo, ihi] = plane_shifts(ico, ii);
  EXPECT_NEAR(ilo, -d, 0.02 * d);
  EXPECT_NEAR(ihi, -d, 0.02 * d);
  EXPECT_NEAR(convex_inradius_about_centroid(box), 0.5, 1e-15);
  EXPECT_THROW(inset_convex_vertices(box, 0.5), std::invalid_argument);
  EXPECT_THROW(inset_convex_vertices(box, -0.1), std::invalid_argument);
}

TEST(ConvexHull, InsetOfAThinFragmentStaysInsideEveryFace) {
  // The convex hull of a stress-model fragment (Bullet + stress + alpha_shape on
  // oedometer_zhu_zhao_quick): d_e 0.52 mm, 0.09 mm thick, cut at a shallow angle. The
  // per-vertex least-squares inset moved one acute vertex 916 margins (4.8 mm) outside
  // the solid, and Bullet then reported a floor contact 30 diameters deep.
  const std::vector<Vec3> pts = {
      {-0.00084135038216666142, -0.00039789298952101618, 4.4639953768088464e-05},
      {-0.0008408294580250379, -0.0003934629200361044, 4.325504945076105e-05},
      {-0.00083956749838172287, -0.00039789298952101618, 5.0915966813035564e-05},
      {-0.00083716964661249631, -0.00038388140936565556, 4.9176748708668216e-05},
      {-0.00083707135654497507, -0.00041216189641390358, 4.9335785378673935e-05},
      {-0.00083406084570392342, -0.00042004351611927719, 5.420689424299579e-05},
      {-0.00083065741849693063, -0.00042895380422542056, 5.4916337059299959e-05},
      {-0.00082994575093643262, -0.00043081697408749512, 5.5891192414726958e-05},
      {-0.0006899196804409166, 1.6240069138121826e-06, -7.6131365090038124e-05},
      {-0.0006899196804409166, 1.6240069138121826e-06, 6.0583305754087236e-06},
      {-0.00059971067149482138, 0.00011328457275528387, -0.0001079951923749058},
      {-0.0005126622800441928, 0.00022103293135631067, -1.3040117038831409e-05},
      {-0.00048354195767539719, -0.00046823605871419607, 8.1082172555196688e-05},
      {-0.00043895456303601345, 0.00027707798408393351, -1.6262913068025143e-05},
      {-0.00038190614549639379, 0.00026611818493353537, -0.00014788428165592857},
      {-0.00016626143029672475, 0.00032526260399221713, -0.00015813511259049249},
      {-7.4160477163066934e-05, 0.0003821841234250789, -9.1126400239729713e-06},
      {-1.4845575007115084e-05, 0.00038343925770044943, -5.8266558306079754e-06},
      {7.4056569527281208e-05, 0.0003284947107054367, -0.0001496733473600168},
      {0.00030640531131873397, 0.00026832257157383463, -0.00012141076854573917},
      {0.00037222860083336847, 0.00028096814639627204, 3.045587078491506e-05},
      {0.00038413259551775021, 0.00027246900252261022, 3.228879632933132e-05},
      {0.00048389998615678805, 0.00014897708723132371, -7.6540556359930805e-05},
      {0.00060294447818872896, 1.6240069138121826e-06, -2.5092218908869709e-05},
      {0.00060294447818872896, 1.6240069138121826e-06, 8.1350151414238852e-05},
      {0.00068107553768510126, -0.00058751166997279803, 0.00016489943557463737},
      {0.00070459635126351799, -0.00026450405181607616, 0.00012295601316145713},
      {0.00072668066946370686, -0.00039789298952101618, 0.00014212870223882963},
      {0.00072855212052663407, -0.00032722106997356404, 8.4194764267085315e-05},
      {0.0007366779820176737, -0.00039789298952101618, 0.00010693669223057642},
  };
  const TriMesh h = convex_hull(pts);
  expect_valid(h);
  const double d = 0.000520108;  // equivalent diameter of the fragment
  const double inradius = convex_inradius_about_centroid(h);
  EXPECT_NEAR(2 * inradius, 9.19e-5, 1e-7);
  const double margin = std::min(0.01 * d, 0.5 * inradius);  // BulletEngine's rule
  const auto in = inset_convex_vertices(h, margin);
  ASSERT_GE(in.size(), 4u);
  // Every inset vertex lies at least `margin` inside every face plane (rounding: 1e-9 d),
  // so the inset hull inflated by the margin stays inside the fragment.
  double worst = -1e300;
  for (const auto& p : in) worst = std::max(worst, max_plane_distance(h, p));
  EXPECT_LE(worst, -margin + 1e-9 * d);
  // And it is the inset, not a shrunken copy: the nearest face plane is reached exactly.
  EXPECT_NEAR(worst, -margin, 1e-9 * d);
  // The inflated inset loses only the edges' rounding: volume of the inset hull close to
  // that of the exact erosion's lower bound V − A·margin (A the surface area).
  const TriMesh hi = convex_hull(in);
  double area = 0;
  for (const auto& t : h.triangles)
    area += 0.5 * norm(cross(h.vertices[t[1]] - h.vertices[t[0]], h.vertices[t[2]] - h.vertices[t[0]]));
  EXPECT_GE(polyhedron_mass_properties(hi).volume, polyhedron_mass_properties(h).volume - area * margin);
}

// A convex piece of an alpha-shape fragment (geometry/ConvexPieces, from a Zhu & Zhao run on
// ode, 2026-12-01): 72 points, most of them on its cut planes. With a few ulps as the on-face
// tolerance the quickhull folded over itself (two faces facing inwards, 47 points outside the
// hull by up to 0.14 mm, 0.2 of the piece's size); ode's dConvex then had planes behind its
// origin. The hull must enclose every point and face outwards.
TEST(ConvexHull, NearlyCoplanarPiecePointsGiveAConvexOutwardHull) {
  const std::vector<Vec3> pts = {
      {8.10066731333042e-05, -3.3765091162243335e-06, 0.00066657466318117021},
      {2.5541418703346427e-05, 3.3155580308568631e-05, 0.00056697834750915556},
      {-2.9923835726611238e-05, 6.9687669733361514e-05, 0.00046738203183714112},
      {-8.538909015656901e-05, 0.00010621975915815453, 0.00036778571616512647},
      {-0.00014085434458652678, 0.00014275184858294744, 0.00026818940049311182},
      {-0.00019631959901648445, 0.00017928393800774035, 0.00016859308482109728},
      {-0.00025178485344644222, 0.00021581602743253326, 6.899676914908271e-05},
      {-0.00014034763983990938, 0.00032054283558247799, 0.00033312123742565203},
      {-0.0001958128942698671, 0.0003570749250072709, 0.00023352492175363746},
      {-0.00025127814869982482, 0.00039360701443206381, 0.00013392860608162289},
      {-0.00041767391198969803, 0.00050320328270644248, -0.00016486034093442082},
      {-0.00033998623848537638, 0.00053088101941687325, 8.9797544839566036e-05},
      {-0.00039545149291533415, 0.00056741310884166627, -9.7987708324486693e-06},
      {-0.00045091674734529187, 0.00060394519826645907, -0.00010939508650446316},
      {-0.00037486066785811606, 0.0003760665031374193, -0.00020407376472548333},
      {-0.00038452109419888727, 0.00037087628372863457, -0.00023186092412651725},
      {-0.0004359811227173255, 0.00042372523165353941, -0.00031745243800120521},
      {0.00012633190128730632, -4.8222890864412838e-06, 0.00073333092402536699},
      {0.00010844375770727902, 9.0840683928038424e-06, 0.00070011582613279527},
      {-0.00037568345539332415, 0.00038544766703501899, -0.00019882221646815268},
      {-0.00038213749183241768, 0.00039046507633210892, -0.00021080621308399315},
      {9.204792309424489e-05, 2.1830295315647342e-05, 0.00066967168030704306},
      {4.4524127283198903e-05, 0.00013889528494380324, 0.00064356371325127726},
      {2.58972964514321e-05, 0.00015802485873098757, 0.00061258241192907958},
      {1.1100058569013414e-05, 0.00017322147787005767, 0.00058797072732680051},
      {-2.9509901823195095e-05, 0.00021492751153910888, 0.00052042572029061495},
      {-3.8611403867025177e-05, 0.00022427466546422677, 0.00050528753710469122},
      {-8.4917100097822406e-05, 0.00027183016434723019, 0.00042826902865215015},
      {-8.8322866303063843e-05, 0.00027532785305839596, 0.00042260434688258183},
      {-0.00011804784365028309, 0.00030585511519019446, 0.00037316391934516416},
      {-0.00039184471379092841, 0.00042492828371525337, -0.00020795603462275984},
      {-0.00043784108386779103, 0.00044493192189742122, -0.00030558099449913572},
      {-0.00044036645520559287, 0.00044603019583583392, -0.00031094096692987032},
      {-0.00043156725971906987, 0.00056595383602662164, -0.00019629293004828587},
      {-0.00042395812369354932, 0.00057702681329964607, -0.00016898912119790792},
      {-0.0001381972859624463, 0.00032151942079836434, 0.00033574999229985105},
      {-0.00013948229299150301, 0.00032251839349944206, 0.00033336396302454844},
      {-0.00018831406438330842, 0.00036048052558325605, 0.00024269205736870045},
      {-0.00019279521012165396, 0.0003639641970036715, 0.00023437136753835862},
      {-0.00026519528348928833, 0.00049020862261833168, 0.0001541935474580013},
      {-0.00041843128508683579, 0.00062115056605393907, -0.00012117530535015941},
      {-0.00029884335641416904, 0.00053531227261335575, 0.00010640781966605385},
      {-0.00031769959194709985, 0.00058176068817900701, 9.6048841228243734e-05},
      {-0.00033472155121130941, 0.00059499366841903295, 6.4442093398057467e-05},
      {-0.00037101250907725089, 0.0006232064916832364, -2.9437542579462545e-06},
      {-0.00038483832963217163, 0.00063395477320392466, -2.8615841533093274e-05},
      {-0.00035044391904637018, 0.00030872593498477307, -0.00016261086844496637},
      {-0.00038460653297487898, 0.00034089779149425664, -0.00024280950257864762},
      {-0.00042120381984327707, 0.00036609785554066296, -0.00030813182266008557},
      {-0.00042146233871691698, 0.00037217970543648737, -0.00032171535952686198},
      {0.00012779434150318549, -3.1823212203609919e-05, 0.00071598808424277408},
      {9.8910280990484583e-05, -3.104006749514502e-05, 0.00070689829685120808},
      {7.5964234375732966e-05, -1.4888228176242695e-05, 0.00066516028353723431},
      {6.8001156143159751e-05, -9.2829767681990963e-06, 0.00065067573764261883},
      {2.1339386405370395e-05, 2.3562481091886627e-05, 0.00056579969780587555},
      {1.4703487878226017e-05, 2.8233523931922972e-05, 0.00055372924289369603},
      {-3.3285461564992069e-05, 6.2013190360015935e-05, 0.00046643911207451717},
      {-3.8594180386707555e-05, 6.5750024632045006e-05, 0.00045678274814477354},
      {-8.7910309535354668e-05, 0.00010046389962814527, 0.00036707852634315847},
      {-9.189184865164133e-05, 0.00010326652533216711, 0.00035983625339585068},
      {-0.00014253515750571719, 0.00013891460889627467, 0.00026771794061179982},
      {-0.00014518951691657494, 0.00014078302603228918, 0.00026288975864692803},
      {-0.00019716000547607965, 0.000177365318164404, 0.00016835735488044131},
      {-0.00019848718518150849, 0.00017829952673241125, 0.00016594326389800541},
      {-0.00030927274458198562, 0.00025628204739637755, -3.5571586607025069e-05},
      {-0.00036382447850455077, 0.00029468129131311966, -0.00013479918057942669},
      {-0.00030673333817891717, 0.00025365231129397545, -2.9080515120428388e-05},
      {-0.00030743774634109058, 0.00025394462460671068, -2.9909448916518936e-05},
      {-0.00030829865520560286, 0.00025473015319704483, -3.1874441900131383e-05},
      {-0.00030775857912597199, 0.0002541644317609977, -3.0479632346949909e-05},
      {0.00013264919295761778, -3.5394173145794448e-05, 0.00072516029143602221},
      {-0.00043890145442973761, 0.00038500695703444607, -0.00035466285217135621}};
  const TriMesh h = convex_hull(pts);
  expect_valid(h);
  const double size = norm(h.bounds().size());
  for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_LE(max_plane_distance(h, pts[i]), 1e-9 * size) << "point " << i;
  Vec3 mean;
  for (const auto& v : h.vertices) mean += v;
  mean = mean / static_cast<double>(h.vertices.size());
  EXPECT_LT(max_plane_distance(h, mean), 0);  // every face has the inside behind it
}
