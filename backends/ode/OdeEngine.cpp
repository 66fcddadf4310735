// ODE adapter: ODE's bodies, geoms, contact joints and force read-out under the shared rules
// of backends/rigid/RigidWorld.h (units: ODE sees lengths × scale, seconds and kilograms;
// libccd's tolerances are absolute lengths too). Each body's origin is its centre of mass
// (dBodySetMass needs it there); the geometry is the shape's convex hull in that frame, or
// for a concave polyhedron a few convex pieces that cover it (one dConvex geom each on the
// body; the near callback skips two pieces of one grain).
#include "backends/ode/OdeEngine.h"
#include "backends/rigid/RigidWorld.h"

#include <ode/ode.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

#include "core/Platen.h"
#include "base/Format.h"

// ode/precision.h picks dDOUBLE unless dIDESINGLE is set; the build states dIDEDOUBLE and
// configure checks that ode.pc was built with dDOUBLE.
#if !defined(dDOUBLE) || defined(dSINGLE)
#error "crumble_ode must be compiled with ODE's double precision (dDOUBLE)"
#endif
static_assert(sizeof(dReal) == sizeof(double), "dReal must be double");

namespace crumble {

namespace {

constexpr unsigned long kGrainBit = 1, kWallBit = 2, kPlatenBit = 4;

// ODE's error and debug handlers abort the process by default (e.g. "bSafeNormalize4Fault"
// when a body's quaternion stops being finite after a diverged contact solve under an
// extreme load). Throwing instead turns that into a run that stops with exit 1 and a
// message naming what to change, never a crash.
[[noreturn]] void throw_ode_error(int errnum, const char* msg, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof text, msg ? msg : "", ap);
  throw std::runtime_error("ode: internal error " + std::to_string(errnum) + " (" + text +
                           "): the contact solve diverged and the state is no longer finite. Reduce the time "
                           "step (time_step), raise engine.solver_iterations, or lower loading.max_stress");
}

void init_ode_for_this_thread() {
  static std::once_flag once;
  std::call_once(once, [] {
    dInitODE2(0);
    dSetErrorHandler(&throw_ode_error);
    dSetDebugHandler(&throw_ode_error);
  });
  thread_local bool allocated = false;
  if (!allocated) {
    dAllocateODEDataForThread(dAllocateMaskAll);
    allocated = true;
  }
}

Vec3 vec(const dReal* p) { return {p[0], p[1], p[2]}; }

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// A convex polyhedron in ODE's format, in the body frame (centre of mass at the origin),
// internal units. ODE keeps pointers to these arrays: the entry outlives its geoms.
struct ConvexData {
  std::vector<dReal> planes;        // a, b, c, d per face (outward normal, d = n·p)
  std::vector<dReal> points;        // x, y, z per vertex
  std::vector<unsigned> polygons;   // count, then the vertex indices (counter-clockwise seen from outside)
  unsigned plane_count = 0, point_count = 0;
};

// Faces of a closed convex triangle mesh merged into polygons (coplanar triangles share a
// face), so that ODE's convex colliders and our contact clipping see whole faces.
void fill_convex(const TriMesh& hull, const Vec3& origin, double scale, ConvexData& out) {
  const double size = std::max(norm(hull.bounds().size()), 1e-300);
  struct Face {
    Vec3 n;
    double d;
    std::vector<int> verts;
  };
  std::vector<Face> faces;
  for (const auto& t : hull.triangles) {
    const Vec3 a = hull.vertices[t[0]], b = hull.vertices[t[1]], c = hull.vertices[t[2]];
    const Vec3 cr = cross(b - a, c - a);
    if (!(norm(cr) > 0)) continue;
    const Vec3 n = cr / norm(cr);
    const double d = dot(n, a);
    Face* f = nullptr;
    for (auto& g : faces)
      if (dot(g.n, n) > 1 - 1e-9 && std::abs(g.d - d) < 1e-9 * size) f = &g;
    if (!f) {
      faces.push_back({n, d, {}});
      f = &faces.back();
    }
    for (int k : t)
      if (std::find(f->verts.begin(), f->verts.end(), k) == f->verts.end()) f->verts.push_back(k);
  }
  for (const auto& v : hull.vertices) {
    const Vec3 p = (v - origin) * scale;
    out.points.insert(out.points.end(), {p.x, p.y, p.z});
  }
  out.point_count = static_cast<unsigned>(hull.vertices.size());
  for (auto& f : faces) {
    Vec3 c;
    for (int k : f.verts) c = c + hull.vertices[k];
    c = c / static_cast<double>(f.verts.size());
    const Vec3 e1 = normalized(hull.vertices[f.verts[0]] - c);
    const Vec3 e2 = cross(f.n, e1);
    std::vector<std::pair<double, int>> order;
    for (int k : f.verts) {
      const Vec3 r = hull.vertices[k] - c;
      order.push_back({std::atan2(dot(r, e2), dot(r, e1)), k});
    }
    std::sort(order.begin(), order.end());
    out.polygons.push_back(static_cast<unsigned>(order.size()));
    for (const auto& [ang, k] : order) out.polygons.push_back(static_cast<unsigned>(k));
    const double d = (f.d - dot(f.n, origin)) * scale;
    out.planes.insert(out.planes.end(), {f.n.x, f.n.y, f.n.z, d});
  }
  out.plane_count = static_cast<unsigned>(faces.size());
}

// ODE data shared by every grain of one Shape (its inertia about the centroid).
struct ShapeEntry : RigidShapeEntry {
  bool sphere = false;  // exact dSphere
  double radius = 0;    // internal, exact sphere
  double size = 0;      // equivalent diameter, internal
  ConvexData convex;    // the hull, when the shape collides as one dConvex
  // A concave polyhedron's convex pieces (engine.concave_shapes = "convex_pieces"), one
  // dConvex each, in its own frame: origin at the piece's centroid, which sits at
  // piece_offsets[k] (internal) in the body frame. libccd's MPR starts from the geom's
  // origin and needs it inside the solid; the grain's centre of mass may lie outside a piece.
  // Empty when the hull is used. Built once: geoms point into it.
  std::vector<ConvexData> pieces;
  std::vector<Vec3> piece_offsets;
};

// What the near callback and the force read-out need to know about a geom.
struct GeomTag {
  GrainId id = -1;  // grain id, -1 for walls and the platen
  int wall = -1;    // WallId for walls and the platen
  int material = 0;
  double size = 1;  // internal, for the contact tolerance
  const ConvexData* convex = nullptr;  // dConvex geoms (grains and the platen)
};

struct GrainBody {
  std::shared_ptr<ShapeEntry> entry;
  dBodyID body = nullptr;
  // One geom (the hull or the exact sphere), or one per convex piece; tags[k] is geoms[k]'s
  // (sized before the geoms point into it).
  std::vector<dGeomID> geoms;
  std::vector<GeomTag> tags;
  double mass = 0;  // kg, physical
};

// One contact point of the last step: geom 1 is always a grain (`a_id`), the normal points
// into it (ODE's convention) and the joint force on it is fb.f1.
struct PointRec {
  dContact contact;
  GrainId a_id = -1, b_id = -1;
  int wall = -1;
  bool live = true;
  dJointFeedback fb;
};

// World-frame planes and vertices of a convex geom.
struct WorldConvex {
  std::vector<Vec3> pts;
  std::vector<Vec3> n;
  std::vector<double> d;
};

WorldConvex world_convex(dGeomID g, const ConvexData& c) {
  const dReal* p = dGeomGetPosition(g);
  const dReal* R = dGeomGetRotation(g);  // 3x4, row-major
  auto rot = [R](double x, double y, double z) {
    return Vec3{R[0] * x + R[1] * y + R[2] * z, R[4] * x + R[5] * y + R[6] * z, R[8] * x + R[9] * y + R[10] * z};
  };
  const Vec3 pos = vec(p);
  WorldConvex w;
  for (unsigned i = 0; i < c.point_count; ++i)
    w.pts.push_back(pos + rot(c.points[3 * i], c.points[3 * i + 1], c.points[3 * i + 2]));
  for (unsigned i = 0; i < c.plane_count; ++i) {
    const Vec3 n = rot(c.planes[4 * i], c.planes[4 * i + 1], c.planes[4 * i + 2]);
    w.n.push_back(n);
    w.d.push_back(c.planes[4 * i + 3] + dot(n, pos));
  }
  return w;
}

// 2D convex hull (Andrew's monotone chain), counter-clockwise, collinear points dropped.
using P2 = std::array<double, 2>;
double cross2(const P2& o, const P2& a, const P2& b) { return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]); }
std::vector<P2> hull2(std::vector<P2> p, double eps) {
  std::sort(p.begin(), p.end());
  p.erase(std::unique(p.begin(), p.end(),
                      [eps](const P2& a, const P2& b) { return std::abs(a[0] - b[0]) <= eps && std::abs(a[1] - b[1]) <= eps; }),
          p.end());
  if (p.size() < 3) return p;
  std::vector<P2> h(2 * p.size());
  std::size_t k = 0;
  const double area_eps = eps * eps;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross2(h[k - 2], h[k - 1], p[i]) <= area_eps) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross2(h[k - 2], h[k - 1], p[i]) <= area_eps) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

// Sutherland–Hodgman: the part of `subject` (polygon or segment) inside the convex CCW `clip`.
std::vector<P2> clip_polygon(std::vector<P2> subject, const std::vector<P2>& clip) {
  for (std::size_t e = 0; e < clip.size() && !subject.empty(); ++e) {
    const P2 a = clip[e], b = clip[(e + 1) % clip.size()];
    std::vector<P2> out;
    const std::size_t n = subject.size();
    for (std::size_t i = 0; i < n; ++i) {
      const P2 p = subject[i], q = subject[(i + 1) % n];
      const double sp = cross2(a, b, p), sq = cross2(a, b, q);
      if (sp >= 0) out.push_back(p);
      if ((sp >= 0) != (sq >= 0)) {
        const double t = sp / (sp - sq);
        out.push_back({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])});
      }
    }
    subject = std::move(out);
  }
  return subject;
}

struct OdeWorld final : RigidWorld {
  using Options = OdeEngine::Options;
  Options opt;

  dWorldID world = nullptr;
  dSpaceID space = nullptr;
  dJointGroupID contact_group = nullptr;

  std::vector<dGeomID> walls;
  std::vector<GeomTag> wall_tags;  // one per wall (reserved: geoms point into it)
  GeomTag platen_tag;
  ConvexData platen_convex;
  dBodyID platen_body = nullptr;
  dGeomID platen_geom = nullptr;
  dJointID platen_slider = nullptr;

  std::map<GrainId, std::unique_ptr<GrainBody>> grains;
  ShapeCache<ShapeEntry> shapes;
  long concave_as_hull = 0;  // concave polyhedral shapes collided as their convex hull
  std::uint64_t step_count = 0;
  std::vector<PointRec> recs;

  OdeWorld(const Options& o, const EngineContext& c) : RigidWorld("ode", o, c), opt(o) {
    init_ode_for_this_thread();
    std::string why;
    if (!ode_double_precision_ok(&why)) throw std::runtime_error("ode: " + why);
    world = dWorldCreate();
    // Sweep and prune, not ODE's hash space: on a settled packing the hash space left 2 of
    // about 300 pairs with overlapping bounding boxes untested at every step (grains in a
    // corner of the box sank 0.75 mm into each other with no contact; test
    // OdeEngine.EveryOverlappingPairOfASettledPackingIsInContact). Same cost per step.
    space = dSweepAndPruneSpaceCreate(nullptr, dSAP_AXES_XYZ);
    contact_group = dJointGroupCreate(0);
    dWorldSetQuickStepNumIterations(world, opt.solver_iterations);
    dWorldSetQuickStepW(world, opt.sor_w);
    dWorldSetAutoDisableFlag(world, 0);
    dWorldSetContactSurfaceLayer(world, 0);
    wall_tags.reserve(8);
  }

  ~OdeWorld() override {
    dJointGroupDestroy(contact_group);
    for (auto& [id, g] : grains) {
      for (dGeomID geom : g->geoms) dGeomDestroy(geom);
      dBodyDestroy(g->body);
    }
    remove_container_bodies();
    dSpaceDestroy(space);
    dWorldDestroy(world);
  }

  void attach_thread() override { init_ode_for_this_thread(); }

  // "concave_shapes_as_hull" besides the shared figures: concave polyhedra (hull > 1.02 ×
  // volume) collided as their hull.
  std::map<std::string, double> summary_figures() const override {
    auto figures = RigidWorld::summary_figures();
    figures["concave_shapes_as_hull"] = static_cast<double>(concave_as_hull);
    return figures;
  }

  // ---------------------------------------------------------------- units
  void scale_fixed() override {
    // Mass scaling slows the dynamics; the weight stays m·g (the platen has no gravity).
    const Vec3 g = ctx.gravity * (scale / opt.mass_scale);
    dWorldSetGravity(world, g.x, g.y, g.z);
    dWorldSetContactMaxCorrectingVel(world, opt.max_correcting_velocity > 0 ? opt.max_correcting_velocity * scale
                                                                             : dInfinity);
  }

  // ---------------------------------------------------------------- container
  void remove_container_bodies() {
    for (dGeomID w : walls) dGeomDestroy(w);
    walls.clear();
    wall_tags.clear();
    if (platen_slider) dJointDestroy(platen_slider);
    if (platen_geom) dGeomDestroy(platen_geom);
    if (platen_body) dBodyDestroy(platen_body);
    platen_slider = nullptr;
    platen_geom = nullptr;
    platen_body = nullptr;
  }

  void build_container() override {
    remove_container_bodies();
    for (const WallPlane& w : fixed_walls()) {
      dGeomID g = dCreatePlane(space, w.normal.x, w.normal.y, w.normal.z, to_int(w.offset()));
      GeomTag t;
      t.wall = w.id;
      wall_tags.push_back(t);
      dGeomSetData(g, &wall_tags.back());
      dGeomSetCategoryBits(g, kWallBit);
      dGeomSetCollideBits(g, kGrainBit);
      walls.push_back(g);
    }
    build_platen();
  }

  // The platen box as a dConvex (so flat faces on it get several points) on a body with a
  // slider along z, enabled while the platen is force-driven.
  void build_platen() {
    const PlatenBox box = platen_box();
    const double hx = box.half_extents.x, hy = box.half_extents.y, hz = box.half_extents.z;
    platen_convex = ConvexData{};
    TriMesh mesh;
    for (int k = 0; k < 8; ++k) mesh.vertices.push_back({(k & 1) ? hx : -hx, (k & 2) ? hy : -hy, (k & 4) ? hz : -hz});
    mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                      {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    fill_convex(mesh, {}, 1.0, platen_convex);
    platen_body = dBodyCreate(world);
    platen_geom = dCreateConvex(space, platen_convex.planes.data(), platen_convex.plane_count,
                                platen_convex.points.data(), platen_convex.point_count, platen_convex.polygons.data());
    dGeomSetBody(platen_geom, platen_body);
    platen_tag = GeomTag{};
    platen_tag.wall = kPlaten;
    platen_tag.size = 2 * hz;
    platen_tag.convex = &platen_convex;
    dGeomSetData(platen_geom, &platen_tag);
    dGeomSetCategoryBits(platen_geom, kPlatenBit);
    dGeomSetCollideBits(platen_geom, kGrainBit);
    dBodySetPosition(platen_body, box.centre.x, box.centre.y, box.centre.z);
    dBodySetGravityMode(platen_body, 0);
    platen_slider = dJointCreateSlider(world, nullptr);
    dJointAttach(platen_slider, platen_body, nullptr);
    dJointSetSliderAxis(platen_slider, 0, 0, 1);
    configure_platen_body();
  }

  bool has_platen() const override { return platen_body != nullptr; }

  void set_platen_mass() override {
    dMass m;
    dMassSetZero(&m);
    const double M = platen_mass();
    // A box-like inertia; rotation is held by the slider anyway.
    const double I = M * platen_half_thickness * platen_half_thickness;
    dMassSetParameters(&m, M, 0, 0, 0, I, I, I, 0, 0, 0);
    dBodySetMass(platen_body, &m);
  }

  // Kinematic body for velocity control; dynamic body on a slider along z for force control.
  void configure_platen_body() override {
    const bool dynamic = driver.force_driven();
    const double vz = dBodyGetLinearVel(platen_body)[2];
    if (dynamic) {
      dBodySetDynamic(platen_body);
      set_platen_mass();
      dJointEnable(platen_slider);
      dBodySetLinearVel(platen_body, 0, 0, vz);
    } else {
      dJointDisable(platen_slider);
      dBodySetKinematic(platen_body);
      dBodySetLinearVel(platen_body, 0, 0, 0);
    }
    dBodySetAngularVel(platen_body, 0, 0, 0);
    platen_dynamic = dynamic;
  }

  double platen_body_z() const override { return dBodyGetPosition(platen_body)[2]; }

  // ---------------------------------------------------------------- grains
  std::shared_ptr<ShapeEntry> shape_entry(const Shape::Ptr& shape) {
    return shapes.get(shape, engine, [&](ShapeEntry& e) {
      e.size = shape->equivalent_diameter() * scale;
      if (exact_sphere(*shape)) {
        e.sphere = true;
        e.radius = shape->parameters().at(0) * scale;
      } else if (auto pieces = convex_pieces(*shape); !pieces.empty()) {
        // A concave polyhedron (Zhu & Zhao 2019 §3.2 keep children with V/V_hull < 0.85
        // concave in the engine) collides as convex pieces whose hulls cover it, as in bullet;
        // a convex one (within concavity_tolerance of its hull) as its hull, as below.
        e.pieces.resize(pieces.size());
        for (std::size_t k = 0; k < pieces.size(); ++k) {
          const Vec3 c = polyhedron_mass_properties(pieces[k]).centroid;
          fill_convex(pieces[k], c, scale, e.pieces[k]);
          e.piece_offsets.push_back((c - e.centroid) * scale);
        }
      } else {
        fill_convex(shape->convex_hull(), e.centroid, scale, e.convex);
        note_concave_hull(*shape);
      }
    });
  }

  // engine.concave_shapes = "convex_hull" (or a shape that could not be cut): a concave
  // grain collides as its hull, with more solid than the grain has. Said once, and counted.
  void note_concave_hull(const Shape& shape) {
    if (shape.kind() != ShapeKind::Polyhedron) return;
    const double ratio = polyhedron_mass_properties(shape.convex_hull()).volume / shape.mass_properties().volume;
    if (ratio > 1.02 && concave_as_hull++ == 0)
      std::cerr << "crumble: note: ode collides concave grains as their convex hulls (the first: hull " << ratio
                << " × its volume; engine.concave_shapes). Counted in summary.json: "
                   "engine_concave_shapes_as_hull\n";
  }

  bool has_grain(GrainId id) const override { return grains.count(id) != 0; }
  std::size_t grain_count() const override { return grains.size(); }

  // The grain's geoms (its hull or exact sphere, or one per convex piece) on its body.
  void add_geoms(GrainBody& gb, const Grain& g) {
    const ShapeEntry& e = *gb.entry;
    GeomTag tag;
    tag.id = g.id;
    tag.material = g.material;
    tag.size = e.size;
    gb.tags.assign(std::max<std::size_t>(1, e.pieces.size()), tag);
    auto add_convex = [&](const ConvexData& c) {
      gb.tags[gb.geoms.size()].convex = &c;
      gb.geoms.push_back(
          dCreateConvex(space, c.planes.data(), c.plane_count, c.points.data(), c.point_count, c.polygons.data()));
    };
    if (e.sphere) {
      gb.geoms.push_back(dCreateSphere(space, e.radius));
    } else if (e.pieces.empty()) {
      add_convex(e.convex);
    } else {
      for (const ConvexData& c : e.pieces) add_convex(c);
    }
    for (std::size_t k = 0; k < gb.geoms.size(); ++k) {
      dGeomID geom = gb.geoms[k];
      dGeomSetBody(geom, gb.body);
      if (!e.piece_offsets.empty())
        dGeomSetOffsetPosition(geom, e.piece_offsets[k].x, e.piece_offsets[k].y, e.piece_offsets[k].z);
      dGeomSetData(geom, &gb.tags[k]);
      dGeomSetCategoryBits(geom, kGrainBit);
      dGeomSetCollideBits(geom, kGrainBit | kWallBit | kPlatenBit);
    }
  }

  double add_body(const Grain& g, const Material& mat) override {
    auto gb = std::make_unique<GrainBody>();
    gb->entry = shape_entry(g.shape);
    const ShapeEntry& e = *gb->entry;
    gb->mass = mat.density * g.shape->volume();
    gb->body = dBodyCreate(world);
    dMass m;
    dMassSetZero(&m);
    const Mat3 I = e.inertia * (mat.density * opt.mass_scale * scale * scale);
    dMassSetParameters(&m, gb->mass * opt.mass_scale, 0, 0, 0, I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2));
    dBodySetMass(gb->body, &m);
    add_geoms(*gb, g);
    const BodyMotion start = initial_motion(g, e.centroid);
    const Quat& q = start.orientation;
    dBodySetPosition(gb->body, start.com.x, start.com.y, start.com.z);
    const dQuaternion dq = {q.w, q.x, q.y, q.z};
    dBodySetQuaternion(gb->body, dq);
    dBodySetLinearVel(gb->body, start.velocity.x, start.velocity.y, start.velocity.z);
    dBodySetAngularVel(gb->body, g.angular_velocity.x, g.angular_velocity.y, g.angular_velocity.z);
    const double mass = gb->mass;
    grains.emplace(g.id, std::move(gb));
    return mass;
  }

  double remove_body(GrainId id) override {
    auto it = grains.find(id);
    // Its contact joints go to limbo with the body; their records no longer count.
    for (auto& r : recs)
      if (r.a_id == id || r.b_id == id) r.live = false;
    for (dGeomID geom : it->second->geoms) dGeomDestroy(geom);
    dBodyDestroy(it->second->body);
    const double mass = it->second->mass;
    grains.erase(it);
    return mass;
  }

  // ---------------------------------------------------------------- contacts
  dSurfaceParameters surface(const GeomTag& a, const GeomTag* b_grain) const {
    const Material& ma = ctx.materials[a.material];
    dSurfaceParameters s{};
    double mu = 0, rho = 0;
    if (!b_grain) {
      mu = ma.wall_friction;
      rho = ma.rolling_friction;
    } else {
      const Material& mb = ctx.materials[b_grain->material];
      mu = a.material == b_grain->material ? ma.friction : std::sqrt(ma.friction * mb.friction);
      rho = a.material == b_grain->material ? ma.rolling_friction : std::sqrt(ma.rolling_friction * mb.rolling_friction);
    }
    mu *= friction_scale;
    rho *= friction_scale;
    // dContactApprox1: friction (and rolling) limits proportional to the normal force, so
    // μ is a Coulomb coefficient (otherwise ODE reads it as a force bound).
    s.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactMu2;
    s.mu = mu;
    s.mu2 = mu;
    if (rho > 0) {
      // Rolling resistance: a lever arm rho in the internal length unit (Bullet convention).
      s.mode |= dContactRolling;
      s.rho = rho;
      s.rho2 = rho;
      s.rhoN = 0;
    }
    s.soft_erp = opt.erp;
    s.soft_cfm = opt.cfm;
    return s;
  }

  // Several points for two polyhedra touching face to face: libccd gives one contact (its
  // normal n and depth); the faces of each hull within a tolerance of the contact plane are
  // projected on it and clipped against each other, and each corner of the overlap becomes a
  // point with the exact gap between the two hulls along n there (points with a gap are
  // dropped). Falls back to the libccd point when the overlap is a point or an edge crossing.
  int manifold(dGeomID g1, dGeomID g2, const GeomTag& t1, const GeomTag& t2, const dContactGeom& c0,
               dContactGeom* out, int max_points) const {
    const Vec3 n = normalized(vec(c0.normal));  // points into g1, from g2 towards g1
    const WorldConvex w1 = world_convex(g1, *t1.convex), w2 = world_convex(g2, *t2.convex);
    const double L = std::min(t1.size, t2.size);
    const double tol = 0.02 * L;
    double s1 = std::numeric_limits<double>::infinity(), s2 = -s1;
    for (const auto& p : w1.pts) s1 = std::min(s1, dot(n, p));
    for (const auto& p : w2.pts) s2 = std::max(s2, dot(n, p));
    const Vec3 u = normalized(std::abs(n.x) < 0.6 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0}));
    const Vec3 v = cross(n, u);
    std::vector<P2> f1, f2;
    for (const auto& p : w1.pts)
      if (dot(n, p) <= s1 + tol) f1.push_back({dot(u, p), dot(v, p)});
    for (const auto& p : w2.pts)
      if (dot(n, p) >= s2 - tol) f2.push_back({dot(u, p), dot(v, p)});
    if (f1.size() < 2 || f2.size() < 2) return 0;
    const double eps = 1e-9 * L;
    std::vector<P2> h1 = hull2(f1, eps), h2 = hull2(f2, eps);
    std::vector<P2> region;
    if (h2.size() >= 3) {
      region = clip_polygon(h1, h2);
    } else if (h1.size() >= 3) {
      region = clip_polygon(h2, h1);
    } else {
      return 0;  // edge across edge: one point
    }
    region = hull2(region, 1e-6 * L);
    if (region.size() < 2) return 0;
    // At most max_points corners: farthest-point sampling from the first corner.
    std::vector<P2> pick;
    if (static_cast<int>(region.size()) <= max_points) {
      pick = region;
    } else {
      std::vector<double> dmin(region.size(), std::numeric_limits<double>::infinity());
      std::size_t next = 0;
      for (int k = 0; k < max_points; ++k) {
        pick.push_back(region[next]);
        std::size_t best = 0;
        double bd = -1;
        for (std::size_t i = 0; i < region.size(); ++i) {
          const double dx = region[i][0] - region[next][0], dy = region[i][1] - region[next][1];
          dmin[i] = std::min(dmin[i], dx * dx + dy * dy);
          if (dmin[i] > bd) {
            bd = dmin[i];
            best = i;
          }
        }
        next = best;
      }
    }
    int count = 0;
    for (const auto& r : pick) {
      const Vec3 x0 = u * r[0] + v * r[1];  // on the line x0 + t·n
      // g1's surface facing g2 (its lower side along n) and g2's upper side.
      double t1lo = -std::numeric_limits<double>::infinity(), t2hi = std::numeric_limits<double>::infinity();
      for (std::size_t k = 0; k < w1.n.size(); ++k) {
        const double nn = dot(w1.n[k], n);
        if (nn < -1e-12) t1lo = std::max(t1lo, (w1.d[k] - dot(w1.n[k], x0)) / nn);
      }
      for (std::size_t k = 0; k < w2.n.size(); ++k) {
        const double nn = dot(w2.n[k], n);
        if (nn > 1e-12) t2hi = std::min(t2hi, (w2.d[k] - dot(w2.n[k], x0)) / nn);
      }
      const double depth = t2hi - t1lo;
      if (!std::isfinite(depth) || depth < 0) continue;
      dContactGeom& o = out[count++];
      o = c0;
      const Vec3 p = x0 + n * (0.5 * (t1lo + t2hi));
      o.pos[0] = p.x;
      o.pos[1] = p.y;
      o.pos[2] = p.z;
      o.depth = depth;
    }
    return count >= 2 ? count : 0;
  }

  static void near_callback(void* data, dGeomID o1, dGeomID o2) { static_cast<OdeWorld*>(data)->near(o1, o2); }

  void near(dGeomID o1, dGeomID o2) {
    const auto* t1 = static_cast<const GeomTag*>(dGeomGetData(o1));
    const auto* t2 = static_cast<const GeomTag*>(dGeomGetData(o2));
    if (!t1 || !t2) return;
    if (t1->id < 0 && t2->id < 0) return;
    if (t1->id == t2->id) return;  // two convex pieces of one grain
    if (t1->id < 0) {  // the grain first: the normal points into it and f1 is the force on it
      std::swap(o1, o2);
      std::swap(t1, t2);
    }
    constexpr int kMax = 16;
    std::array<dContactGeom, kMax> cg{};
    const int max_pts = opt.contacts_per_pair;
    int n = dCollide(o1, o2, max_pts, cg.data(), sizeof(dContactGeom));
    // ODE's contact is "move body 1 along the unit normal by depth" (dContactGeom): a
    // point without a finite unit normal fixes no direction. libccd returns a zero normal
    // with depth ~1e-16 for two fragments of one grain born face to face on their cut;
    // as a joint it turns the solver's velocities into NaN and ODE aborts the process
    // (dNormalize4 assertion). Such points are dropped.
    int valid = 0;
    for (int k = 0; k < n; ++k) {
      const dContactGeom& q = cg[k];
      const double nl = std::sqrt(q.normal[0] * q.normal[0] + q.normal[1] * q.normal[1] + q.normal[2] * q.normal[2]);
      if (!std::isfinite(q.depth) || !std::isfinite(q.pos[0]) || !std::isfinite(q.pos[1]) || !std::isfinite(q.pos[2]) ||
          !(std::abs(nl - 1) <= 1e-6))
        continue;
      cg[valid++] = q;
    }
    n = valid;
    if (n <= 0) return;
    if (n == 1 && max_pts > 1 && t1->convex && t2->convex) {
      std::array<dContactGeom, kMax> more{};
      const int m = manifold(o1, o2, *t1, *t2, cg[0], more.data(), max_pts);
      if (m >= 2) {
        cg = more;
        n = m;
      }
    }
    const GeomTag* partner_grain = t2->id >= 0 ? t2 : nullptr;
    const dSurfaceParameters s = surface(*t1, partner_grain);
    for (int k = 0; k < n; ++k) {
      PointRec r;
      r.contact.surface = s;
      r.contact.geom = cg[k];
      r.contact.geom.g1 = o1;
      r.contact.geom.g2 = o2;
      r.a_id = t1->id;
      r.b_id = t2->id;
      r.wall = t2->id >= 0 ? -1 : t2->wall;
      recs.push_back(r);
    }
  }

  // ---------------------------------------------------------------- stepping
  void advance(double dt) override {
    dJointGroupEmpty(contact_group);
    recs.clear();
    if (platen_dynamic) {
      dBodyAddForce(platen_body, 0, 0, driver.applied_force() * scale);
    } else {
      // Kinematic: starts the step where the driver has it, moving at the command.
      const dReal* p = dBodyGetPosition(platen_body);
      dBodySetPosition(platen_body, p[0], p[1], platen_centre_z());
      dBodySetLinearVel(platen_body, 0, 0, driver.command().value * scale);
    }
    dSpaceCollide(space, this, &OdeWorld::near_callback);
    for (auto& r : recs) {
      dJointID j = dJointCreateContact(world, contact_group, &r.contact);
      dBodyID b1 = dGeomGetBody(r.contact.geom.g1), b2 = dGeomGetBody(r.contact.geom.g2);
      dJointAttach(j, b1, b2);
      dJointSetFeedback(j, &r.fb);
    }
    // QuickStep reorders constraints with ODE's global generator: reseed it so a run
    // depends only on the scenario seed and the step.
    dRandSetSeed(static_cast<unsigned long>(splitmix64(ctx.seed ^ splitmix64(step_count))));
    dWorldQuickStep(world, dt);
    ++step_count;
    if (platen_dynamic) {
      sync_platen(dBodyGetLinearVel(platen_body)[2]);
    } else {
      driver.advance(dt, 0, 0);
      const dReal* p = dBodyGetPosition(platen_body);
      dBodySetPosition(platen_body, p[0], p[1], platen_centre_z());
    }
  }

  // Force of the wall on the grains (SI), summed over the wall's contact points.
  Vec3 wall_force_on_grains(int wall) const {
    Vec3 f;
    for (const auto& r : recs)
      if (r.live && r.wall == wall) f += Vec3{r.fb.f1[0], r.fb.f1[1], r.fb.f1[2]};
    return f / scale;
  }
  double wall_force_z(int wall) const { return wall_force_on_grains(wall).z; }

  double platen_force() const override { return -wall_force_z(kPlaten); }  // up on the platen
  double floor_force() const override { return wall_force_z(kFloor); }     // grains push it down
  double wall_force(int wall) const override {
    if (wall < kFloor || wall > kWallYMax) return 0;
    // The wall pushes the grains along its inward normal; they push it back outwards.
    return dot(wall_force_on_grains(wall), wall_inward_normal(wall, 3));
  }

  // The Contact of the live points recs[i, j) of one pair, if they carried a positive
  // normal force: force = the sum of the joint forces on `a`, point = the normal-force-
  // weighted mean, overlap = the deepest point's depth.
  bool pair_points_contact(std::size_t i, std::size_t j, Contact& c) const {
    Vec3 f, point, normal, couple;
    double fn_sum = 0, depth = 0;
    for (std::size_t k = i; k < j; ++k) {
      const PointRec& r = recs[k];
      const Vec3 fk = vec(r.fb.f1);
      // The joint's torque on the grain about its centre, less the moment of its force: the
      // rolling-resistance couple (dContactRolling).
      if (const dBodyID b = dGeomGetBody(r.contact.geom.g1))
        couple = couple + vec(r.fb.t1) - cross(vec(r.contact.geom.pos) - vec(dBodyGetPosition(b)), fk);
      const Vec3 nk = vec(r.contact.geom.normal);
      const double fn = std::max(dot(fk, nk), 0.0);
      f = f + fk;
      point = point + vec(r.contact.geom.pos) * fn;
      normal = normal + nk * fn;
      fn_sum += fn;
      depth = std::max(depth, static_cast<double>(r.contact.geom.depth));
    }
    if (!(fn_sum > 0)) return false;  // touching without force: not an active contact
    const PointRec& r0 = recs[i];
    const PairSide other = r0.b_id >= 0 ? PairSide{r0.b_id, -1} : PairSide{-1, r0.wall};
    c = pair_contact({r0.a_id, -1}, other, f, scale, couple, scale * scale, normalized(normal),
                     point / (fn_sum * scale), depth / scale);
    return true;
  }

  std::vector<Contact> contacts() const override {
    std::vector<Contact> out;
    // Points of one pair are consecutive (one dCollide call each).
    for (std::size_t i = 0; i < recs.size();) {
      std::size_t j = i;
      while (j < recs.size() && recs[j].contact.geom.g1 == recs[i].contact.geom.g1 &&
             recs[j].contact.geom.g2 == recs[i].contact.geom.g2)
        ++j;
      if (Contact c; recs[i].live && pair_points_contact(i, j, c)) out.push_back(c);
      i = j;
    }
    return out;
  }

  bool body_motion(GrainId id, BodyMotion& m, Vec3& centroid) const override {
    auto it = grains.find(id);
    if (it == grains.end()) return false;
    const GrainBody& gb = *it->second;
    const dReal* q = dBodyGetQuaternion(gb.body);
    m.orientation = Quat{q[0], q[1], q[2], q[3]}.normalized();
    m.com = vec(dBodyGetPosition(gb.body));
    m.velocity = vec(dBodyGetLinearVel(gb.body));
    m.angular_velocity = vec(dBodyGetAngularVel(gb.body));
    centroid = gb.entry->centroid;
    return true;
  }
};

}  // namespace

// ------------------------------------------------------------------ OdeEngine

const OptionTable& ode_options() {
  const double inf = std::numeric_limits<double>::infinity();
  using S = OdeEngine::Options;
  static const OptionTable t = with_concave_shape_options<S>(
      {
          rigid_option::sphere_representation<S>("icosphere hull (dConvex)", "dSphere"),
          rigid_option::length_scale<S>("ODE's and libccd's tolerances are absolute"),
          rigid_option::solver_iterations<S>("QuickStep SOR iterations per step"),
          opt::positive_below("sor_w", &S::sor_w, 2, true, "", "QuickStep over-relaxation factor (ODE's own default 1.3)"),
          rigid_option::erp<S>("contact error reduction (penetration corrected per step); ODE's default 0.2 launches "
                            "grains at Δt ≈ 5e-5 s"),
          opt::number("cfm", &S::cfm, 0, inf, "", "contact constraint force mixing (internal units), a small regularisation"),
          opt::number("max_correcting_velocity", &S::max_correcting_velocity, 0, inf, "m/s",
                      "cap on the velocity that pushes overlapping grains apart; 0 = none"),
          opt::integer("contacts_per_pair", &S::contacts_per_pair, 1, 16,
                       "most contact points between two polyhedra: libccd gives one, flat-on-flat contacts get up to "
                       "this many from the clipped touching faces (1 = libccd's point only)"),
          rigid_option::mass_scale<S>("mass scaling"),
      },
      "one dConvex geom each on the grain's body");
  return t;
}

// Settings built in code pass the table's ranges too (read_options checks a scenario's).
static const OdeEngine::Options& checked_options(const OdeEngine::Options& o) {
  check_options(ode_options(), o, "ode");
  return o;
}

OdeEngine::Options OdeEngine::read_options(const Config& cfg) {
  return read_rigid_engine_options<Options>(cfg, "ode", ode_options());
}

OdeEngine::OdeEngine(const Options& opts, const EngineContext& ctx) : RigidEngine(std::make_unique<OdeWorld>(checked_options(opts), ctx)) {}

std::unique_ptr<Engine> make_ode_engine(const Config& cfg, const EngineContext& ctx) {
  return make_rigid_engine<OdeEngine>(cfg, ctx, "ode");
}

// dReal is double in this translation unit (the static_assert above); whether the linked
// libode is too is asked of the library itself.
bool ode_double_precision_ok(std::string* why) {
  init_ode_for_this_thread();
  if (!dCheckConfiguration("ODE_double_precision")) {
    if (why) *why = "the linked libode is not the double-precision build";
    return false;
  }
  return true;
}

}  // namespace crumble
