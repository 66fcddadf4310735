// Bullet adapter: Bullet's bodies, shapes, solver and contact read-out under the shared
// rules of backends/rigid/RigidWorld.h (units: Bullet sees lengths × scale, seconds and
// kilograms; impulses leave through force_si() and the same factors).
#include "backends/bullet/BulletEngine.h"
#include "backends/bullet/BulletWorldReport.h"
#include "backends/rigid/RigidWorld.h"
#include "base/Format.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <unordered_map>
#include <unordered_set>
#include <cmath>
#include <exception>
#include <iostream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "geometry/ConvexHull.h"
#include "geometry/ConvexPieces.h"
#include "core/Platen.h"

// Mixing the float and double builds of Bullet corrupts memory silently.
#ifndef BT_USE_DOUBLE_PRECISION
#error "crumble_bullet must be compiled with BT_USE_DOUBLE_PRECISION (link PkgConfig::BULLET64)"
#endif
static_assert(sizeof(btScalar) == sizeof(double), "btScalar must be double (BT_USE_DOUBLE_PRECISION)");

namespace crumble {

namespace {

// Collision groups: grains collide with everything, walls and the platen only with grains
// (the platen overlaps the side walls, and two fixed bodies must not make manifolds).
constexpr int kGrainGroup = 1 << 6;
constexpr int kWallGroup = 1 << 7;
constexpr int kPlatenGroup = 1 << 8;
constexpr int kCrumbleTag = 0x0c4b1e;  // userIndex2 of every body this adapter creates

// What the combine callbacks and the force read-out need to know about a body.
struct BodyTag {
  GrainId id = -1;  // grain id, -1 for walls
  int wall = -1;    // WallId for walls and the platen
  double friction = 0;          // grain: material friction μ (walls: unused)
  double wall_friction = 0;     // grain: friction against walls
  double rolling_friction = 0;  // grain: rolling-friction coefficient (Bullet convention)
  double scale = 1;             // grain: Engine::set_friction_scale (settling a packing)
};

const BodyTag* tag_of(const btCollisionObject* o) {
  if (!o || o->getUserIndex2() != kCrumbleTag) return nullptr;
  return static_cast<const BodyTag*>(o->getUserPointer());
}

// The grain's tag when exactly one body of a crumble pair is a wall, else nullptr.
const BodyTag* grain_against_wall(const btCollisionObject* b0, const btCollisionObject* b1) {
  const BodyTag* t0 = tag_of(b0);
  const BodyTag* t1 = tag_of(b1);
  if (!t0 || !t1 || (t0->wall >= 0) == (t1->wall >= 0)) return nullptr;
  return t0->wall >= 0 ? t1 : t0;
}

// Bullet multiplies the two bodies' friction values; each grain carries √μ so that a pair
// of the same material gets μ (and a mixed pair √(μa·μb)). Grain–wall pairs take the
// grain material's wall friction (Zhu & Zhao 2019: 0). Bodies not made by crumble keep Bullet's
// rule.
btScalar combined_friction(const btCollisionObject* b0, const btCollisionObject* b1) {
  if (const BodyTag* g = grain_against_wall(b0, b1)) return g->wall_friction * g->scale;
  return std::clamp(b0->getFriction() * b1->getFriction(), btScalar(-10), btScalar(10));
}

// Rolling friction: the grain material's value against walls, the geometric mean for a
// grain pair. Bullet reads it as a lever arm in its internal length unit (≈ the reference
// grain diameter here): the rolling-resistance torque is at most μr·N·unit.
btScalar combined_rolling_friction(const btCollisionObject* b0, const btCollisionObject* b1) {
  if (const BodyTag* g = grain_against_wall(b0, b1)) return g->rolling_friction * g->scale;
  const BodyTag* t0 = tag_of(b0);
  const BodyTag* t1 = tag_of(b1);
  if (t0 && t1) return std::sqrt(t0->rolling_friction * t0->scale * t1->rolling_friction * t1->scale);
  return std::clamp(b0->getRollingFriction() * b1->getFriction() + b1->getRollingFriction() * b0->getFriction(),
                    btScalar(-10), btScalar(10));  // Bullet's own rule
}

void install_combine_callbacks() {
  // Process-wide hooks of Bullet; the functions fall back to Bullet's rules for foreign bodies.
  gCalculateCombinedFrictionCallback = &combined_friction;
  gCalculateCombinedRollingFrictionCallback = &combined_rolling_friction;
}

btVector3 bt(const Vec3& v) { return {v.x, v.y, v.z}; }
Vec3 vec(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
btQuaternion bt(const Quat& q) { return {q.x, q.y, q.z, q.w}; }
Quat quat(const btQuaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }

// Bullet data shared by every grain of one Shape; the body lives in its principal frame.
struct ShapeEntry : RigidShapeEntry {
  // A concave polyhedron's convex pieces (btCompoundShape children; declared before
  // `collision` so the compound goes first).
  std::vector<std::unique_ptr<btConvexHullShape>> pieces;
  std::unique_ptr<btCollisionShape> collision;
};

// Bullet's PGS solver with an early exit on Zhu & Zhao's measure of convergence (Zhu & Zhao
// 2019 §2.2): stop once the relative change of the contact impulse vector between two
// iterations, ε = |f^k − f^(k−1)| / |f^k|, is at most `tolerance`. (They ran a fixed 2000
// iterations and report ε near or below 2e-4 after them; as a stopping rule ε ≤ 2e-4 is met
// early, on a transient dip: docs/validation.md, "The contact solver's convergence".) Bullet's own
// absolute least-squares residual threshold still applies when set. Records the largest
// iteration count and ε of any island in a step (Bullet's analytics keep only the last,
// often empty, solver call).
class ToleranceSolver : public btSequentialImpulseConstraintSolver {
 public:
  double tolerance = 0;
  int max_iterations = -1;
  double max_change = 0;
  double deep_depth = 0;  // internal units; 0 = every contact at the global β (eq. 8)
  double deep_erp = 0;

  // Contact points deeper than deep_depth take deep_erp as their own β (Bullet's per-point
  // ERP); with the split impulse on (see scale_fixed) their correction adds no velocity.
  btScalar solveGroupCacheFriendlySetup(btCollisionObject** bodies, int numBodies, btPersistentManifold** manifolds,
                                        int numManifolds, btTypedConstraint** constraints, int numConstraints,
                                        const btContactSolverInfo& info, btIDebugDraw* debug) override {
    if (deep_depth > 0)
      for (int i = 0; i < numManifolds; ++i)
        for (int j = 0; j < manifolds[i]->getNumContacts(); ++j) {
          btManifoldPoint& cp = manifolds[i]->getContactPoint(j);
          if (cp.getDistance() < -deep_depth) {
            cp.m_contactERP = deep_erp;
            cp.m_contactPointFlags |= BT_CONTACT_FLAG_HAS_CONTACT_ERP;
          } else {
            cp.m_contactPointFlags &= ~BT_CONTACT_FLAG_HAS_CONTACT_ERP;
          }
        }
    return btSequentialImpulseConstraintSolver::solveGroupCacheFriendlySetup(bodies, numBodies, manifolds, numManifolds,
                                                                            constraints, numConstraints, info, debug);
  }

  btScalar solveGroupCacheFriendlyIterations(btCollisionObject** bodies, int numBodies, btPersistentManifold** manifolds,
                                             int numManifolds, btTypedConstraint** constraints, int numConstraints,
                                             const btContactSolverInfo& info, btIDebugDraw* debug) override {
    solveGroupCacheFriendlySplitImpulseIterations(bodies, numBodies, manifolds, numManifolds, constraints,
                                                  numConstraints, info, debug);  // no-op: split impulse is off
    const int max_it = std::max(m_maxOverrideNumSolverIterations, info.m_numIterations);
    const bool relative = tolerance > 0 && numManifolds > 0;
    if (relative) snapshot(previous_);
    int used = 0;
    double change = 0;
    for (int it = 0; it < max_it; ++it) {
      m_leastSquaresResidual = solveSingleIteration(it, bodies, numBodies, manifolds, numManifolds, constraints,
                                                    numConstraints, info, debug);
      used = it + 1;
      bool done = m_leastSquaresResidual <= info.m_leastSquaresResidualThreshold;
      if (relative) {
        change = relative_change();
        done = done || change <= tolerance;
      }
      if (done) break;
    }
    m_analyticsData.m_numSolverCalls++;
    m_analyticsData.m_numIterationsUsed = used;
    m_analyticsData.m_numBodies = numBodies;
    m_analyticsData.m_numContactManifolds = numManifolds;
    m_analyticsData.m_remainingLeastSquaresResidual = m_leastSquaresResidual;
    if (numManifolds > 0) {
      max_iterations = std::max(max_iterations, used);
      max_change = std::max(max_change, change);
    }
    return 0;
  }

 private:
  // Normal and friction impulses of every contact row, in pool order.
  void snapshot(std::vector<double>& f) const {
    f.clear();
    for (int i = 0; i < m_tmpSolverContactConstraintPool.size(); ++i)
      f.push_back(m_tmpSolverContactConstraintPool[i].m_appliedImpulse);
    for (int i = 0; i < m_tmpSolverContactFrictionConstraintPool.size(); ++i)
      f.push_back(m_tmpSolverContactFrictionConstraintPool[i].m_appliedImpulse);
  }

  double relative_change() {
    double diff = 0, total = 0;
    std::size_t k = 0;
    auto visit = [&](const btConstraintArray& pool) {
      for (int i = 0; i < pool.size(); ++i, ++k) {
        const double f = pool[i].m_appliedImpulse;
        diff += (f - previous_[k]) * (f - previous_[k]);
        total += f * f;
        previous_[k] = f;
      }
    };
    visit(m_tmpSolverContactConstraintPool);
    visit(m_tmpSolverContactFrictionConstraintPool);
    return total > 0 ? std::sqrt(diff / total) : 0.0;
  }

  std::vector<double> previous_;

 public:
  // Angular impulse on body0 of each contact point's rolling and spinning rows in the last
  // solve (internal units). Bullet writes the normal and friction impulses back to the
  // manifold point but not these: they are read from the solver's pools before it clears
  // them. Cleared before each step (BulletEngine::step).
  std::unordered_map<const btManifoldPoint*, btVector3> rolling;

 protected:
  btScalar solveGroupCacheFriendlyFinish(btCollisionObject** bodies, int numBodies,
                                         const btContactSolverInfo& info) override {
    const btConstraintArray& rows = m_tmpSolverContactRollingFrictionConstraintPool;
    for (int i = 0; i < rows.size(); ++i) {
      const btSolverConstraint& c = rows[i];
      // m_frictionIndex: the contact row of the same point (convertContact); the torque axis on
      // body0 is m_relpos1CrossNormal (setupTorsionalFrictionConstraint).
      const auto* cp =
          static_cast<const btManifoldPoint*>(m_tmpSolverContactConstraintPool[c.m_frictionIndex].m_originalContactPoint);
      rolling.try_emplace(cp, 0, 0, 0).first->second += c.m_relpos1CrossNormal * c.m_appliedImpulse;
    }
    return btSequentialImpulseConstraintSolver::solveGroupCacheFriendlyFinish(bodies, numBodies, info);
  }
};

struct GrainBody {
  BodyTag tag;
  std::shared_ptr<ShapeEntry> entry;
  std::unique_ptr<btRigidBody> body;
  double mass = 0;  // kg, physical (unscaled)
};

struct WallBody {
  BodyTag tag;
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btRigidBody> body;
};

}  // namespace

struct BulletEngine::Impl final : RigidWorld {
  Options opt;

  std::unique_ptr<btDefaultCollisionConfiguration> config;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<ToleranceSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;

  std::vector<std::unique_ptr<WallBody>> walls;  // floor, x-, x+, y-, y+ (static planes)
  // Under a force command Bullet integrates the platen as a dynamic body (implicitly
  // coupled to the contacts by the solver) and the driver is synced to it.
  std::unique_ptr<WallBody> platen;

  std::map<GrainId, std::unique_ptr<GrainBody>> grains;
  ShapeCache<ShapeEntry> shapes;

  // Sliding friction √(μ·s) per grain body (Bullet multiplies a pair's), and the tag's scale
  // for the wall and rolling terms of the combine callbacks. Bullet combines a contact's
  // friction whenever it refreshes the contact point, so the change acts from the next step.
  void friction_scale_changed() override {
    for (auto& [id, gb] : grains) {
      gb->tag.scale = friction_scale;
      gb->body->setFriction(std::sqrt(gb->tag.friction * friction_scale));
    }
  }

  static void check_context(const EngineContext& ctx) {
    std::string why;
    if (!bullet_double_precision_ok(&why)) throw std::runtime_error("bullet: " + why);
    if (ctx.dimension != 3) throw std::invalid_argument("bullet: the engine is 3D only");
    if (ctx.materials.empty()) throw std::invalid_argument("bullet: no materials");
    if (!is_finite(ctx.gravity)) throw std::invalid_argument("bullet: gravity is not finite");
    for (std::size_t i = 0; i < ctx.materials.size(); ++i) {
      const Material& m = ctx.materials[i];
      if (!(m.density > 0) || !(m.friction >= 0) || !(m.wall_friction >= 0) || !(m.rolling_friction >= 0))
        throw std::invalid_argument("bullet: material " + std::to_string(i) +
                                    " needs density > 0 and non-negative friction coefficients");
    }
  }

  Impl(const Options& o, const EngineContext& c) : RigidWorld("bullet", o, c), opt(o) {
    check_context(ctx);
    install_combine_callbacks();
    // Bullet's default narrow phase: GJK/EPA, one new point per pair and step, gathered in
    // persistent manifolds (up to 4 points). Perturbed multi-point GJK was measured: 25 %
    // slower on the packing test and no better for the sliding-friction test.
    config = std::make_unique<btDefaultCollisionConfiguration>();
    dispatcher = std::make_unique<btCollisionDispatcher>(config.get());
    // Contact breaking threshold relative to each shape's size (gContactBreakingThreshold
    // 0.02 × bounding radius ≈ 1.7 % of d at our scale), so the global is left alone.
    dispatcher->setDispatcherFlags(dispatcher->getDispatcherFlags() |
                                   btCollisionDispatcher::CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD);
    broadphase = std::make_unique<btDbvtBroadphase>();
    solver = std::make_unique<ToleranceSolver>();
    solver->tolerance = opt.solver_tolerance;
    world = std::make_unique<btDiscreteDynamicsWorld>(dispatcher.get(), broadphase.get(), solver.get(), config.get());
    world->setGravity(btVector3(0, 0, 0));  // per body, see add_body
    world->getDispatchInfo().m_deterministicOverlappingPairs = true;
    btContactSolverInfo& si = world->getSolverInfo();
    si.m_numIterations = opt.solver_iterations;
    si.m_erp2 = opt.erp;        // Zhu & Zhao 2019 eq. 8: v_d = β Δd / Δt on contacts
    si.m_erp = opt.erp;         // (no joints; kept equal)
    si.m_splitImpulse = 0;      // correction inside the contact impulse, as eq. 8
    si.m_restitution = 0;
    // Warm starting also makes Bullet write the impulses back to the manifold points, which
    // the force read-out needs. No SOLVER_RANDMIZE_ORDER: runs are deterministic.
    si.m_solverMode = SOLVER_USE_WARMSTARTING | SOLVER_USE_2_FRICTION_DIRECTIONS;
    si.m_leastSquaresResidualThreshold = 0;
  }

  ~Impl() override {
    // Bodies leave the world before the world goes.
    for (auto& [id, g] : grains) world->removeRigidBody(g->body.get());
    grains.clear();
    remove_container_bodies();
    world.reset();
    solver.reset();
    broadphase.reset();
    dispatcher.reset();
    config.reset();
  }

  // ---------------------------------------------------------------- units
  double force_si(double internal_impulse) const { return internal_impulse / (scale * last_dt); }

  void scale_fixed() override {
    if (opt.deep_penetration > 0) {
      // Contacts deeper than deep_penetration × d get their own β (deep_erp, ToleranceSolver)
      // and Bullet's split impulse: the correction moves the bodies without adding velocity,
      // so no kinetic energy (the reason eq. 8's β is small); shallower ones keep eq. 8.
      btContactSolverInfo& si = world->getSolverInfo();
      si.m_splitImpulse = 1;
      si.m_splitImpulsePenetrationThreshold = -opt.deep_penetration * ref_length;
      solver->deep_depth = opt.deep_penetration * ref_length;
      solver->deep_erp = opt.deep_erp;
    }
  }

  // ---------------------------------------------------------------- container
  void remove_container_bodies() {
    for (auto& w : walls) world->removeRigidBody(w->body.get());
    walls.clear();
    if (platen) world->removeRigidBody(platen->body.get());
    platen.reset();
  }

  // A crumble body of `shape` (mass 0: static until configured), frictionless and without
  // restitution: grain–wall friction comes from the combine callback.
  std::unique_ptr<WallBody> make_wall_body(int wall, std::unique_ptr<btCollisionShape> shape,
                                           const btTransform& start) const {
    auto w = std::make_unique<WallBody>();
    w->tag.wall = wall;
    w->shape = std::move(shape);
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, w->shape.get());
    info.m_startWorldTransform = start;
    w->body = std::make_unique<btRigidBody>(info);
    w->body->setUserPointer(&w->tag);
    w->body->setUserIndex2(kCrumbleTag);
    w->body->setFriction(0);
    w->body->setRestitution(0);
    return w;
  }

  void build_container() override {
    remove_container_bodies();
    btTransform t;
    t.setIdentity();
    for (const WallPlane& w : fixed_walls()) {
      walls.push_back(make_wall_body(w.id, std::make_unique<btStaticPlaneShape>(bt(w.normal), to_int(w.offset())), t));
      world->addRigidBody(walls.back()->body.get(), kWallGroup, kGrainGroup);
    }
    // The platen box's margin lies inside the box, so the face stays where it is.
    const PlatenBox box = platen_box();
    auto shape = std::make_unique<btBoxShape>(bt(box.half_extents));
    shape->setMargin(std::min(opt.margin_fraction * ref_length, 0.5 * platen_half_thickness));
    t.setOrigin(bt(box.centre));
    platen = make_wall_body(kPlaten, std::move(shape), t);
    platen->body->setActivationState(DISABLE_DEACTIVATION);
    platen_dynamic = false;
    configure_platen_body();
  }

  bool has_platen() const override { return platen != nullptr; }
  void set_platen_mass() override { platen->body->setMassProps(platen_mass(), btVector3(0, 0, 0)); }

  // Kinematic body for velocity control; dynamic body moving along z only for force
  // control. Changing the kind means leaving and re-entering the world.
  void configure_platen_body() override {
    btRigidBody* b = platen->body.get();
    if (b->isInWorld()) world->removeRigidBody(b);
    const bool dynamic = driver.force_driven();
    const btVector3 v = b->getLinearVelocity();
    if (dynamic) {
      b->setCollisionFlags(b->getCollisionFlags() & ~btCollisionObject::CF_KINEMATIC_OBJECT);
      b->setMassProps(platen_mass(), btVector3(0, 0, 0));
      b->setLinearFactor(btVector3(0, 0, 1));
      b->setAngularFactor(btVector3(0, 0, 0));
      b->setFlags(b->getFlags() | BT_DISABLE_WORLD_GRAVITY);
      b->setGravity(btVector3(0, 0, 0));
      b->setLinearVelocity(btVector3(0, 0, v.z()));
    } else {
      b->setMassProps(0, btVector3(0, 0, 0));
      b->setCollisionFlags(b->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      b->setLinearVelocity(btVector3(0, 0, 0));
    }
    b->setAngularVelocity(btVector3(0, 0, 0));
    b->updateInertiaTensor();
    b->setActivationState(DISABLE_DEACTIVATION);
    platen_dynamic = dynamic;
    world->addRigidBody(b, kPlatenGroup, kGrainGroup);
    // A kinematic body's velocity is Bullet's (current − previous transform)/dt: start
    // from rest at the current place.
    b->setInterpolationWorldTransform(b->getWorldTransform());
  }

  double platen_body_z() const override { return platen->body->getWorldTransform().getOrigin().z(); }

  // ---------------------------------------------------------------- grains
  std::shared_ptr<ShapeEntry> shape_entry(const Shape::Ptr& shape) {
    return shapes.get(shape, engine, [&](ShapeEntry& e) {
      const double d = shape->equivalent_diameter();
      if (exact_sphere(*shape)) {
        e.collision = std::make_unique<btSphereShape>(to_int(shape->parameters().at(0)));
      } else if (auto pieces = convex_pieces(*shape); !pieces.empty()) {
        // A concave polyhedron (Zhu & Zhao 2019 §3.2 keep children with V/V_hull < 0.85
        // concave in the engine) collides as convex pieces whose hulls cover it; a convex one
        // (within concavity_tolerance of its hull) as its hull, as below.
        auto compound = std::make_unique<btCompoundShape>(true, static_cast<int>(pieces.size()));
        btTransform identity;
        identity.setIdentity();
        for (const auto& piece : pieces) {
          e.pieces.push_back(hull_shape(piece, d, e));
          compound->addChildShape(identity, e.pieces.back().get());
        }
        e.collision = std::move(compound);
      } else {
        e.collision = hull_shape(shape->convex_hull(), d, e);
      }
    });
  }

  // A convex hull (shape frame) as Bullet's hull in the principal frame of `e`, in internal
  // units. Bullet inflates a hull by its margin: inset the hull by the same amount so the
  // inflated surface is the grain's. A sliver whose centroid is closer to a
  // face than twice the margin gets a smaller margin; a flat hull (its centroid on or, by
  // rounding, outside a face) gets none and is taken as it is.
  std::unique_ptr<btConvexHullShape> hull_shape(const TriMesh& hull, double d, const ShapeEntry& e) const {
    const double inradius = convex_inradius_about_centroid(hull);
    double margin = 0;
    if (inradius > 0 && std::isfinite(inradius)) margin = std::min(opt.margin_fraction * d, 0.5 * inradius);
    const std::vector<Vec3> inset = margin > 0 ? inset_convex_vertices(hull, margin) : hull.vertices;
    const Quat to_principal = e.principal.conjugate();
    std::vector<btScalar> pts;
    pts.reserve(3 * inset.size());
    for (const auto& v : inset) {
      const Vec3 p = to_principal.rotate(v - e.centroid) * scale;
      pts.insert(pts.end(), {p.x, p.y, p.z});
    }
    auto hs = std::make_unique<btConvexHullShape>(pts.data(), static_cast<int>(inset.size()),
                                                  static_cast<int>(3 * sizeof(btScalar)));
    hs->setMargin(to_int(margin));
    hs->recalcLocalAabb();
    return hs;
  }

  bool has_grain(GrainId id) const override { return grains.count(id) != 0; }
  std::size_t grain_count() const override { return grains.size(); }

  // A rigid body in the principal frame of its shape, with the shape's exact mass
  // properties (calculateLocalInertia of a hull is a box estimate), both scaled by
  // mass_scale (Zhu & Zhao 2019 §5).
  std::unique_ptr<btRigidBody> make_grain_body(const ShapeEntry& e, const Material& mat, double mass,
                                               const BodyMotion& start) const {
    const Vec3 inertia = e.moments * (mat.density * opt.mass_scale * scale * scale);
    btRigidBody::btRigidBodyConstructionInfo info(mass * opt.mass_scale, nullptr, e.collision.get(), bt(inertia));
    info.m_startWorldTransform.setOrigin(bt(start.com));
    info.m_startWorldTransform.setRotation(bt((start.orientation * e.principal).normalized()));
    info.m_friction = std::sqrt(mat.friction * friction_scale);
    info.m_rollingFriction = mat.rolling_friction;
    info.m_restitution = 0;
    info.m_linearDamping = 0;
    info.m_angularDamping = 0;
    return std::make_unique<btRigidBody>(info);
  }

  double add_body(const Grain& g, const Material& mat) override {
    auto gb = std::make_unique<GrainBody>();
    gb->entry = shape_entry(g.shape);
    gb->tag.id = g.id;
    gb->tag.friction = mat.friction;
    gb->tag.wall_friction = mat.wall_friction;
    gb->tag.rolling_friction = mat.rolling_friction;
    gb->tag.scale = friction_scale;
    gb->mass = mat.density * g.shape->volume();
    const BodyMotion start = initial_motion(g, gb->entry->centroid);
    gb->body = make_grain_body(*gb->entry, mat, gb->mass, start);
    btRigidBody* b = gb->body.get();
    b->setUserPointer(&gb->tag);
    b->setUserIndex2(kCrumbleTag);
    b->setActivationState(DISABLE_DEACTIVATION);
    b->setFlags(b->getFlags() | BT_DISABLE_WORLD_GRAVITY);
    // Mass scaling slows the dynamics; the weight stays m·g.
    b->setGravity(bt(ctx.gravity * (scale / opt.mass_scale)));
    b->setLinearVelocity(bt(start.velocity));
    b->setAngularVelocity(bt(start.angular_velocity));
    world->addRigidBody(b, kGrainGroup, kGrainGroup | kWallGroup | kPlatenGroup);
    const double mass = gb->mass;
    grains.emplace(g.id, std::move(gb));
    return mass;
  }

  double remove_body(GrainId id) override {
    auto it = grains.find(id);
    world->removeRigidBody(it->second->body.get());
    const double mass = it->second->mass;
    grains.erase(it);
    return mass;
  }

  // ---------------------------------------------------------------- stepping
  // The change of ω over dt from the gyroscopic term of Euler's equations, I ω̇ = −ω × I ω,
  // by one implicit Newton step in the body frame: the update of Bullet's
  // computeGyroscopicImpulseImplicit_Body with the inertia normalised by its largest moment.
  // Bullet's own returns 0 for small grains: btMatrix3x3::solve33 leaves the determinant
  // uninverted below 2.2e-16, and a mm grain's Jacobian has a determinant near I³ ≈ 1e-19.
  // Bullet applies its own (BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY, on by default) only
  // inside the contact solver, which skips an island without contacts, so a free tumbling
  // grain would not precess at all (tests/integration/extremes). Known limit: a mm grain in
  // contact still gets Bullet's ≈ 0 term; adding ours there changed the settled rigid
  // packing's void ratio by 8 % and made one ×1 mass-scaling case pass through a wall,
  // which needs its own study before it replaces Bullet's.
  static btVector3 gyroscopic_step(const btRigidBody& b, double dt) {
    const btVector3 il = b.getLocalInertia();
    const double imax = std::max({il.x(), il.y(), il.z()});
    if (!(imax > 0)) return btVector3(0, 0, 0);
    const btVector3 w1 = b.getAngularVelocity();
    const btQuaternion q = b.getWorldTransform().getRotation();
    const btVector3 wb = quatRotate(q.inverse(), w1);
    const btMatrix3x3 ib(il.x() / imax, 0, 0, 0, il.y() / imax, 0, 0, 0, il.z() / imax);
    const btVector3 f = dt * wb.cross(ib * wb);  // residual of I (ω' − ω) + dt ω' × I ω' at ω' = ω
    btMatrix3x3 s0, s1;
    wb.getSkewSymmetricMatrix(&s0[0], &s0[1], &s0[2]);
    (ib * wb).getSkewSymmetricMatrix(&s1[0], &s1[1], &s1[2]);
    const btMatrix3x3 jac = ib + (s0 * ib - s1) * dt;  // its determinant is ≈ the product of I/imax
    const btVector3 wb2 = wb - jac.solve33(f);
    return quatRotate(q, wb2) - w1;
  }

  void advance(double dt) override {
    btContactSolverInfo& si = world->getSolverInfo();
    // Bullet's residual = the largest squared velocity change of a row in the last
    // iteration (internal units); solver_residual is that change times dt, in length units.
    const double vres = opt.solver_residual / dt;
    si.m_leastSquaresResidualThreshold = vres * vres;
    btRigidBody* p = platen->body.get();
    if (platen_dynamic) {
      p->applyCentralForce(btVector3(0, 0, driver.applied_force() * scale));
    } else {
      // Kinematic: Bullet derives the velocity from the new transform.
      driver.advance(dt, 0, 0);
      btTransform t = p->getWorldTransform();
      t.setOrigin(btVector3(t.getOrigin().x(), t.getOrigin().y(), platen_centre_z()));
      p->setWorldTransform(t);
    }
    precess_free_grains(dt);
    solver->max_iterations = 0;
    solver->max_change = 0;
    solver->rolling.clear();
    world->stepSimulation(dt, 0);  // exactly one internal step of dt
    if (platen_dynamic) sync_platen(p->getLinearVelocity().z());
  }

  // Torque-free precession (Euler's equations) of the grains that touched nothing in the
  // last step; a grain in contact gets Bullet's own term inside the solver (see
  // gyroscopic_step for why that one is ≈ 0 for mm grains).
  void precess_free_grains(double dt) {
    std::unordered_set<const btCollisionObject*> touching;
    for (int i = 0, n = dispatcher->getNumManifolds(); i < n; ++i) {
      const btPersistentManifold* m = dispatcher->getInternalManifoldPointer()[i];
      if (m->getNumContacts() == 0) continue;
      touching.insert(m->getBody0());
      touching.insert(m->getBody1());
    }
    for (auto& [id, gb] : grains) {
      btRigidBody* b = gb->body.get();
      if (!touching.count(b)) b->setAngularVelocity(b->getAngularVelocity() + gyroscopic_step(*b, dt));
    }
  }

  // Impulse (internal units) on body0 of a manifold point: normal plus both friction directions.
  static btVector3 impulse_on_body0(const btManifoldPoint& p) {
    return p.m_normalWorldOnB * p.m_appliedImpulse + p.m_lateralFrictionDir1 * p.m_appliedImpulseLateral1 +
           p.m_lateralFrictionDir2 * p.m_appliedImpulseLateral2;
  }

  // Impulse on a wall body (internal units), summed over its manifolds.
  btVector3 wall_impulse(int wall) const {
    btVector3 j(0, 0, 0);
    if (last_dt <= 0) return j;
    const int n = dispatcher->getNumManifolds();
    for (int i = 0; i < n; ++i) {
      const btPersistentManifold* m = dispatcher->getInternalManifoldPointer()[i];
      const BodyTag* t0 = tag_of(m->getBody0());
      const BodyTag* t1 = tag_of(m->getBody1());
      if (!t0 || !t1) continue;
      btVector3 j0(0, 0, 0);
      for (int k = 0; k < m->getNumContacts(); ++k) j0 += impulse_on_body0(m->getContactPoint(k));
      if (t0->wall == wall) j += j0;
      if (t1->wall == wall) j -= j0;
    }
    return j;
  }
  double wall_impulse_z(int wall) const { return wall_impulse(wall).z(); }

  double platen_force() const override {
    if (last_dt <= 0) return 0;
    return force_si(wall_impulse_z(kPlaten));  // up on the platen = compression
  }

  double floor_force() const override {
    if (last_dt <= 0) return 0;
    return -force_si(wall_impulse_z(kFloor));  // grains push the floor down
  }

  double wall_force(int wall) const override {
    if (last_dt <= 0 || wall < kFloor || wall > kWallYMax) return 0;
    const Vec3 n = wall_inward_normal(wall, 3);
    const btVector3 j = wall_impulse(wall);
    return -force_si(j.x() * n.x + j.y() * n.y + j.z() * n.z);  // outwards on the wall
  }

  // The Contact of a manifold that carried a positive normal impulse: force = summed
  // impulses / Δt, point = the normal-impulse-weighted mean of its points' midpoints.
  bool manifold_contact(const btPersistentManifold& m, const BodyTag& t0, const BodyTag& t1, Contact& c) const {
    btVector3 j(0, 0, 0), point(0, 0, 0), normal(0, 0, 0), couple(0, 0, 0);
    double jn = 0, depth = 0;
    for (int k = 0; k < m.getNumContacts(); ++k) {
      const btManifoldPoint& p = m.getContactPoint(k);
      depth = std::max(depth, -static_cast<double>(p.getDistance()));
      const btVector3 mid = 0.5 * (p.getPositionWorldOnA() + p.getPositionWorldOnB());
      j += impulse_on_body0(p);
      if (const auto r = solver->rolling.find(&p); r != solver->rolling.end()) couple += r->second;
      const double w = std::max(p.m_appliedImpulse, btScalar(0));
      point += mid * w;
      normal += p.m_normalWorldOnB * w;
      jn += w;
    }
    if (!(jn > 0)) return false;  // touching without force: not an active contact
    point /= jn;
    normal = normal.length2() > 0 ? normal.normalized() : m.getContactPoint(0).m_normalWorldOnB;
    // Bullet's normal on B points from B to A, and j is the impulse on A (body0).
    c = pair_contact({t0.id, t0.wall}, {t1.id, t1.wall}, vec(j), scale * last_dt, vec(couple),
                     scale * scale * last_dt, vec(normal), vec(point) / scale, depth / scale);
    return true;
  }

  std::vector<Contact> contacts() const override {
    std::vector<Contact> out;
    if (last_dt <= 0) return out;
    const int n = dispatcher->getNumManifolds();
    for (int i = 0; i < n; ++i) {
      const btPersistentManifold* m = dispatcher->getInternalManifoldPointer()[i];
      if (m->getNumContacts() == 0) continue;
      const BodyTag* t0 = tag_of(m->getBody0());
      const BodyTag* t1 = tag_of(m->getBody1());
      if (!t0 || !t1 || (t0->wall >= 0 && t1->wall >= 0)) continue;
      if (Contact c; manifold_contact(*m, *t0, *t1, c)) out.push_back(c);
    }
    return out;
  }

  bool body_motion(GrainId id, BodyMotion& m, Vec3& centroid) const override {
    auto it = grains.find(id);
    if (it == grains.end()) return false;
    const GrainBody& gb = *it->second;
    const btRigidBody* b = gb.body.get();
    const btTransform& t = b->getWorldTransform();
    m.orientation = (quat(t.getRotation()) * gb.entry->principal.conjugate()).normalized();
    m.com = vec(t.getOrigin());
    m.velocity = vec(b->getLinearVelocity());
    m.angular_velocity = vec(b->getAngularVelocity());
    centroid = gb.entry->centroid;
    return true;
  }
};

// ------------------------------------------------------------------ BulletEngine

const OptionTable& bullet_options() {
  using S = BulletEngine::Options;
  static const OptionTable t = with_concave_shape_options<S>(
      {
          rigid_option::sphere_representation<S>("icosphere mesh (42 vertices, as Zhu & Zhao 2019)", "btSphereShape"),
          rigid_option::length_scale<S>("2 mm → 512"),
          opt::positive_below("margin_fraction", &S::margin_fraction, 0.1, false, "",
                              "collision margin / d (hulls are inset by it)"),
          rigid_option::solver_iterations<S>(
              "projected Gauss-Seidel iterations at most (the shipped oedometers use 1000: at 100 the packing creeps)"),
          opt::number("solver_tolerance", &S::solver_tolerance, 0, 1, "",
                      "stop when impulses change by at most this fraction between iterations (0 = always run "
                      "solver_iterations, as Zhu & Zhao 2019 §2.2)"),
          opt::number("solver_residual", &S::solver_residual, 0, 1, "", "Bullet's own absolute residual threshold (0 = off)"),
          rigid_option::erp<S>("penetration correction β (Zhu & Zhao 2019, eq. 8), Bullet's m_erp2"),
          opt::number("deep_penetration", &S::deep_penetration, 0, 1, "",
                      "contacts deeper than this × d (the first grain's) are pushed apart by Bullet's split impulse at "
                      "deep_erp, without adding velocity; 0 = off (eq. 8 everywhere, as Zhu & Zhao 2019)"),
          opt::number("deep_erp", &S::deep_erp, 0, 1, "", "penetration correction of the contacts past deep_penetration"),
          rigid_option::mass_scale<S>("Zhu & Zhao 2019 §5 use 70"),
      },
      "btCompoundShape");
  return t;
}

// Settings built in code pass the table's ranges too (read_options checks a scenario's).
static const BulletEngine::Options& checked_options(const BulletEngine::Options& o) {
  check_options(bullet_options(), o, "bullet");
  return o;
}

BulletEngine::Options BulletEngine::read_options(const Config& cfg) {
  return read_rigid_engine_options<Options>(cfg, "bullet", bullet_options());
}

BulletEngine::BulletEngine(const Options& opts, const EngineContext& ctx)
    : RigidEngine(std::make_unique<Impl>(checked_options(opts), ctx)), impl_(static_cast<Impl*>(&world())) {}

double BulletEngine::last_solver_change() const { return impl_->solver->max_change; }

Engine::SolverReport BulletEngine::solver_report() const {
  const ToleranceSolver& s = *impl_->solver;
  SolverReport r;
  r.iterations = s.max_iterations > 0 ? s.max_iterations : -1;
  r.change = s.max_change;
  r.limit_before_tolerance =
      s.tolerance > 0 && s.max_iterations >= impl_->world->getSolverInfo().m_numIterations && s.max_change > s.tolerance;
  return r;
}

int BulletEngine::last_solver_iterations() const { return impl_->solver->max_iterations; }

std::map<std::string, double> BulletEngine::world_settings() const { return bullet_world_settings(*impl_->world); }
std::map<std::string, double> BulletEngine::contact_work() const { return bullet_contact_work(*impl_->world); }

std::unique_ptr<Engine> make_bullet_engine(const Config& cfg, const EngineContext& ctx) {
  return make_rigid_engine<BulletEngine>(cfg, ctx, "bullet");
}

// btScalar is double in this translation unit (the static_assert above); whether the linked
// library is too is asked of the library itself.
bool bullet_double_precision_ok(std::string* why) {
  // Ask the linked library: a sphere's AABB is computed inside libBulletCollision. With the
  // single-precision library linked against double headers the layout differs and the
  // value comes back wrong.
  const double r = 0.123456789012345678;
  btSphereShape s(r);
  btVector3 lo, hi;
  btTransform id;
  id.setIdentity();
  s.getAabb(id, lo, hi);
  if (hi.x() != r || lo.z() != -r) {
    if (why) *why = "the linked Bullet library is not the double-precision build (libBullet*-float64)";
    return false;
  }
  return true;
}

}  // namespace crumble
