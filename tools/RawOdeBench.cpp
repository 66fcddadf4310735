#include "tools/RawOdeBench.h"

#include <ode/ode.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace crumble {

namespace {

struct ConvexArrays {
  std::vector<dReal> planes, points;
  std::vector<unsigned> polygons;
};

struct RawOde {
  double dt = 0;
  dWorldID world = nullptr;
  dSpaceID space = nullptr;
  dJointGroupID contacts = nullptr;
  double mu = 0, wall_mu = 0, rho = 0, erp = 0.003;
  int per_pair = 1;
  int touching = 0;

  static void near(void* data, dGeomID a, dGeomID b) {
    auto* self = static_cast<RawOde*>(data);
    dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
    if (!ba && !bb) return;
    std::array<dContact, 16> c{};
    const int n = dCollide(a, b, self->per_pair, &c[0].geom, sizeof(dContact));
    const bool wall = !ba || !bb;
    for (int k = 0; k < n; ++k) {
      dSurfaceParameters& s = c[k].surface;
      s.mode = dContactApprox1 | dContactSoftERP | dContactMu2;
      s.mu = s.mu2 = wall ? self->wall_mu : self->mu;
      if (self->rho > 0) {
        s.mode |= dContactRolling;
        s.rho = s.rho2 = self->rho;
      }
      s.soft_erp = self->erp;
      dJointID j = dJointCreateContact(self->world, self->contacts, &c[k]);
      dJointAttach(j, ba, bb);
    }
    self->touching += n;
  }
};

class RawOdeWorld final : public RawWorld {
 public:
  explicit RawOdeWorld(const RawScene& sc);
  ~RawOdeWorld() override {
    dJointGroupDestroy(o.contacts);
    dSpaceDestroy(o.space);  // destroys the geoms it holds
    dWorldDestroy(o.world);
  }
  void step() override {
    dJointGroupEmpty(o.contacts);
    o.touching = 0;
    dSpaceCollide(o.space, &o, &RawOde::near);
    dWorldQuickStep(o.world, o.dt);
  }
  int contact_pairs() const override { return o.touching; }

 private:
  RawOde o;
  std::vector<ConvexArrays> convex;
};

RawOdeWorld::RawOdeWorld(const RawScene& sc) {
  if (sc.contacts_per_pair < 1 || sc.contacts_per_pair > 16)
    throw std::invalid_argument("raw ode bench: contacts_per_pair must be in [1, 16]");
  const double s = sc.length_scale;
  dInitODE2(0);
  dAllocateODEDataForThread(dAllocateMaskAll);
  o.dt = sc.dt;
  o.world = dWorldCreate();
  o.space = dHashSpaceCreate(nullptr);
  o.contacts = dJointGroupCreate(0);
  o.per_pair = sc.contacts_per_pair;
  o.erp = sc.erp;
  o.mu = sc.bodies.empty() ? 0 : sc.bodies.front().friction;
  o.rho = sc.bodies.empty() ? 0 : sc.bodies.front().rolling_friction;
  o.wall_mu = sc.wall_friction;
  // Mass scaling keeps weights physical: the scaled bodies fall at g / mass_scale.
  const Vec3 g = sc.gravity * (s / sc.mass_scale);
  dWorldSetGravity(o.world, g.x, g.y, g.z);
  dWorldSetQuickStepNumIterations(o.world, sc.solver_iterations);
  dWorldSetQuickStepW(o.world, 1.0);
  dWorldSetAutoDisableFlag(o.world, 0);
  dWorldSetContactSurfaceLayer(o.world, 0);
  dCreatePlane(o.space, 0, 0, 1, 0);
  dCreatePlane(o.space, 1, 0, 0, 0);
  dCreatePlane(o.space, -1, 0, 0, -sc.lx * s);
  dCreatePlane(o.space, 0, 1, 0, 0);
  dCreatePlane(o.space, 0, -1, 0, -sc.ly * s);
  const double hz = 0.05 * sc.lx * s;
  dGeomID lid = dCreateBox(o.space, 1.1 * sc.lx * s, 1.1 * sc.ly * s, 2 * hz);
  dGeomSetPosition(lid, 0.5 * sc.lx * s, 0.5 * sc.ly * s, sc.platen_z * s + hz);

  convex.resize(sc.bodies.size());
  for (std::size_t i = 0; i < sc.bodies.size(); ++i) {
    const RawBody& b = sc.bodies[i];
    ConvexArrays& c = convex[i];
    for (const Vec3& v : b.hull.vertices) c.points.insert(c.points.end(), {v.x * s, v.y * s, v.z * s});
    for (const auto& t : b.hull.triangles) {
      const Vec3 p0 = b.hull.vertices[t[0]], p1 = b.hull.vertices[t[1]], p2 = b.hull.vertices[t[2]];
      const Vec3 cr = cross(p1 - p0, p2 - p0);
      if (!(norm(cr) > 0)) continue;
      const Vec3 n = cr / norm(cr);
      c.planes.insert(c.planes.end(), {n.x, n.y, n.z, dot(n, p0) * s});
      c.polygons.insert(c.polygons.end(), {3u, unsigned(t[0]), unsigned(t[1]), unsigned(t[2])});
    }
    dBodyID body = dBodyCreate(o.world);
    dMass m;
    dMassSetZero(&m);
    const Mat3 I = b.inertia * (sc.mass_scale * s * s);
    dMassSetParameters(&m, b.mass * sc.mass_scale, 0, 0, 0, I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2));
    dBodySetMass(body, &m);
    dGeomID geom = dCreateConvex(o.space, c.planes.data(), unsigned(c.planes.size() / 4), c.points.data(),
                                 unsigned(b.hull.vertices.size()), c.polygons.data());
    dGeomSetBody(geom, body);
    dBodySetPosition(body, b.com.x * s, b.com.y * s, b.com.z * s);
    const dQuaternion q = {b.orientation.w, b.orientation.x, b.orientation.y, b.orientation.z};
    dBodySetQuaternion(body, q);
    dBodySetLinearVel(body, b.velocity.x * s, b.velocity.y * s, b.velocity.z * s);
    dBodySetAngularVel(body, b.angular_velocity.x, b.angular_velocity.y, b.angular_velocity.z);
  }
}

}  // namespace

std::unique_ptr<RawWorld> make_raw_ode_world(const RawScene& scene) { return std::make_unique<RawOdeWorld>(scene); }

}  // namespace crumble
