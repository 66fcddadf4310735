#include "tools/RawBulletBench.h"
#include "backends/bullet/BulletWorldReport.h"

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include "geometry/ConvexHull.h"
#include "geometry/SymmetricEigen.h"
#include "geometry/TriMesh.h"

namespace crumble {

namespace {
btVector3 bt(const Vec3& v) { return {v.x, v.y, v.z}; }
btQuaternion bt(const Quat& q) { return {q.x, q.y, q.z, q.w}; }

struct BodyFrictions;

class RawBulletWorld final : public RawWorld {
 public:
  explicit RawBulletWorld(const RawScene& sc);
  ~RawBulletWorld() override {
    for (auto& b : bodies) world.removeRigidBody(b.get());
  }
  void step() override { world.stepSimulation(dt, 0); }
  int contact_pairs() const override {
    int n = 0;
    for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
      const btPersistentManifold* mf = dispatcher.getManifoldByIndexInternal(m);
      bool pushed = false;
      for (int p = 0; p < mf->getNumContacts(); ++p) pushed = pushed || mf->getContactPoint(p).m_appliedImpulse > 0;
      n += pushed ? 1 : 0;
    }
    return n;
  }
  std::map<std::string, double> settings() const override { return bullet_world_settings(world); }
  std::map<std::string, double> contact_work() const override { return bullet_contact_work(world); }

 private:
  void add_container(const RawScene& sc, const BodyFrictions& f);
  void add_grain(const RawBody& b, const RawScene& sc, const BodyFrictions& f);

  double dt;
  btDefaultCollisionConfiguration config;
  mutable btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btDefaultMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
};

// The per-body friction values that give, under Bullet's own combination rules, the
// adapter's model (one material in the benchmark scenes). Sliding: Bullet multiplies the two
// values, so grains carry √μ and walls μ_wall/√μ. Rolling: μr for a grain pair and for a
// grain against a wall (the adapter's combine callback); Bullet's rule μr = μr0·f1 + μr1·f0
// gives that with μr/(2√μ) on the grains and (μr − μr_grain·f_wall)/√μ on the walls (nothing
// rolls when μ = 0).
struct BodyFrictions {
  double grain = 0, wall = 0, grain_rolling = 0, wall_rolling = 0;
};

BodyFrictions body_frictions(const RawScene& sc) {
  BodyFrictions f;
  if (sc.bodies.empty()) return f;
  f.grain = std::sqrt(sc.bodies.front().friction);
  if (!(f.grain > 0)) return f;
  f.wall = sc.wall_friction / f.grain;
  const double roll = sc.bodies.front().rolling_friction;
  f.grain_rolling = roll / (2 * f.grain);
  f.wall_rolling = (roll - f.grain_rolling * f.wall) / f.grain;
  return f;
}

RawBulletWorld::RawBulletWorld(const RawScene& sc) : dt(sc.dt) {
  dispatcher.setDispatcherFlags(dispatcher.getDispatcherFlags() |
                                btCollisionDispatcher::CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD);
  // Mass scaling keeps weights physical: the scaled bodies fall at g / mass_scale.
  world.setGravity(bt(sc.gravity * (sc.length_scale / sc.mass_scale)));
  world.getDispatchInfo().m_deterministicOverlappingPairs = true;
  btContactSolverInfo& si = world.getSolverInfo();
  si.m_numIterations = sc.solver_iterations;
  si.m_erp = si.m_erp2 = sc.erp;
  si.m_splitImpulse = 0;
  si.m_restitution = 0;
  si.m_solverMode = SOLVER_USE_WARMSTARTING | SOLVER_USE_2_FRICTION_DIRECTIONS;
  si.m_leastSquaresResidualThreshold = 0;
  const BodyFrictions f = body_frictions(sc);
  add_container(sc, f);
  for (const RawBody& b : sc.bodies) add_grain(b, sc, f);
}

// Static planes for the floor and side walls, a kinematic box for the lid.
void RawBulletWorld::add_container(const RawScene& sc, const BodyFrictions& f) {
  const double s = sc.length_scale;
  auto add_static = [&](btCollisionShape* shape, const btTransform& t) {
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape);
    info.m_startWorldTransform = t;
    info.m_friction = f.wall;
    info.m_rollingFriction = f.wall_rolling;
    bodies.push_back(std::make_unique<btRigidBody>(info));
    world.addRigidBody(bodies.back().get());
  };
  const struct { Vec3 n; double c; } planes[] = {
      {{0, 0, 1}, 0}, {{1, 0, 0}, 0}, {{-1, 0, 0}, -sc.lx}, {{0, 1, 0}, 0}, {{0, -1, 0}, -sc.ly}};
  for (const auto& p : planes) {
    shapes.push_back(std::make_unique<btStaticPlaneShape>(bt(p.n), p.c * s));
    add_static(shapes.back().get(), btTransform::getIdentity());
  }
  const double hz = 0.05 * sc.lx * s;
  shapes.push_back(std::make_unique<btBoxShape>(btVector3(0.5 * sc.lx * s, 0.5 * sc.ly * s, hz)));
  btTransform lid = btTransform::getIdentity();
  lid.setOrigin(btVector3(0.5 * sc.lx * s, 0.5 * sc.ly * s, sc.platen_z * s + hz));
  add_static(shapes.back().get(), lid);
  // The lid as a driven platen: a kinematic body (held still here), as the adapter's platen
  // under a velocity command (measured: no cost against a static lid).
  btRigidBody* platen = bodies.back().get();
  world.removeRigidBody(platen);
  platen->setCollisionFlags(platen->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
  platen->setActivationState(DISABLE_DEACTIVATION);
  world.addRigidBody(platen);
}

// A btConvexHullShape in the body's principal frame. Bullet inflates a hull by its margin:
// inset it by the margin first (Bullet's manual, "collision margin"), margin_fraction of the
// grain's equivalent diameter (for a sphere, the sphere's, not its hull's).
void RawBulletWorld::add_grain(const RawBody& b, const RawScene& sc, const BodyFrictions& f) {
  const double s = sc.length_scale;
  if (b.hull.vertices.size() < 4 || !(b.mass > 0)) throw std::invalid_argument("raw bullet bench: a body without volume");
  const PrincipalAxes pa = principal_axes(b.inertia);
  const Quat to_principal = pa.rotation.conjugate();
  const double d = b.diameter;
  const double inradius = convex_inradius_about_centroid(b.hull);
  const double margin = inradius > 0 ? std::min(sc.margin_fraction * d, 0.5 * inradius) : 0;
  const std::vector<Vec3> inset = margin > 0 ? inset_convex_vertices(b.hull, margin) : b.hull.vertices;
  std::vector<btScalar> pts;
  for (const Vec3& v : inset) {
    const Vec3 p = to_principal.rotate(v) * s;
    pts.insert(pts.end(), {p.x, p.y, p.z});
  }
  auto hull = std::make_unique<btConvexHullShape>(pts.data(), static_cast<int>(inset.size()),
                                                  static_cast<int>(3 * sizeof(btScalar)));
  hull->setMargin(margin * s);
  hull->recalcLocalAabb();
  btTransform t;
  t.setOrigin(bt(b.com * s));
  t.setRotation(bt((b.orientation * pa.rotation).normalized()));
  states.push_back(std::make_unique<btDefaultMotionState>(t));
  btRigidBody::btRigidBodyConstructionInfo info(b.mass * sc.mass_scale, states.back().get(), hull.get(),
                                                bt(pa.moments * (sc.mass_scale * s * s)));
  info.m_friction = f.grain;
  info.m_rollingFriction = f.grain_rolling;
  bodies.push_back(std::make_unique<btRigidBody>(info));
  btRigidBody* body = bodies.back().get();
  body->setActivationState(DISABLE_DEACTIVATION);
  body->setLinearVelocity(bt(b.velocity * s));
  body->setAngularVelocity(bt(b.angular_velocity));
  world.addRigidBody(body);
  shapes.push_back(std::move(hull));
}

}  // namespace

std::unique_ptr<RawWorld> make_raw_bullet_world(const RawScene& scene) {
  return std::make_unique<RawBulletWorld>(scene);
}

}  // namespace crumble
