// Bullet adapter. Units: Bullet sees lengths multiplied by `scale_` (so a grain is about
// one unit: Bullet's tolerances are absolute lengths tuned for ~1-unit objects),
// seconds and kilograms. Hence internal velocity = scale·v, force and impulse =
// scale·(SI), inertia = scale²·(SI); every value leaves through to_si()/from the same
// factors. With the automatic scale a power of two, these conversions are exact.
#include "backends/bullet/BulletEngine.h"
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

#include "geometry/SymmetricEigen.h"
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

// Bullet data shared by every grain of one Shape.
struct ShapeEntry {
  Shape::Ptr shape;
  // A concave polyhedron's convex pieces (btCompoundShape children; declared before
  // `collision` so the compound goes first).
  std::vector<std::unique_ptr<btConvexHullShape>> pieces;
  std::unique_ptr<btCollisionShape> collision;
  Quat principal;         // principal frame → shape frame
  Vec3 centroid;          // shape frame (≈ 0 by Shape's invariant)
  Vec3 moments;           // principal moments per unit density (SI, m⁵)
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
  // ERP); with the split impulse on (see fix_scale) their correction adds no velocity.
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

void require_finite(const Vec3& v, const char* what, GrainId id) {
  if (!is_finite(v))
    throw std::invalid_argument("bullet: grain " + std::to_string(id) + " has a non-finite " + what);
}

}  // namespace

struct BulletEngine::Impl {
  Options opt;
  EngineContext ctx;

  std::unique_ptr<btDefaultCollisionConfiguration> config;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<ToleranceSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;

  double scale = 0;      // internal units per metre; 0 until fixed
  double ref_length = 0; // internal length of the reference grain (≈ 1)

  bool have_container = false;
  Container container;
  std::vector<std::unique_ptr<WallBody>> walls;  // floor, x-, x+, y-, y+ (static planes)
  std::unique_ptr<WallBody> platen;
  double platen_half_thickness = 0;  // internal
  // Command, mass rule and the kinematic motion come from the shared platen piece
  // (core/Platen.h); under a force command Bullet integrates the platen as a dynamic body
  // (implicitly coupled to the contacts by the solver) and the driver is synced to it.
  PlatenDriver driver;
  bool platen_dynamic = false;

  std::map<GrainId, std::unique_ptr<GrainBody>> grains;
  std::map<const Shape*, std::weak_ptr<ShapeEntry>> shape_cache;
  long compound_shapes = 0;  // concave polyhedra collided as convex pieces (shapes, not grains)
  long compound_pieces = 0;
  long compound_failures = 0;  // concave polyhedra collided as their hull because the cutting failed
  double total_mass = 0;  // kg, physical
  double last_dt = 0;
  double friction_scale = 1;  // set_friction_scale

  // Sliding friction √(μ·s) per grain body (Bullet multiplies a pair's), and the tag's scale
  // for the wall and rolling terms of the combine callbacks. Bullet combines a contact's
  // friction whenever it refreshes the contact point, so the change acts from the next step.
  void apply_friction_scale(double s) {
    friction_scale = s;
    for (auto& [id, gb] : grains) {
      gb->tag.scale = s;
      gb->body->setFriction(std::sqrt(gb->tag.friction * s));
    }
  }

  Impl(const Options& o, const EngineContext& c) : opt(o), ctx(c) {
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
    world->setGravity(btVector3(0, 0, 0));  // per body, see add_grain
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

  ~Impl() {
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
  double to_int(double si_length) const { return si_length * scale; }
  double force_si(double internal_impulse) const { return internal_impulse / (scale * last_dt); }

  void fix_scale(double first_diameter) {
    if (scale > 0) return;
    if (opt.length_scale > 0) {
      scale = opt.length_scale;
    } else if (first_diameter > 0) {
      // The power of two nearest to 1/d: a grain is ≈ 1 unit and conversions are exact.
      scale = std::exp2(std::round(std::log2(1.0 / first_diameter)));
    } else {
      scale = 1;
    }
    ref_length = first_diameter > 0 ? first_diameter * scale : 1.0;
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
    if (have_container) build_container();
  }

  // ---------------------------------------------------------------- container
  void remove_container_bodies() {
    for (auto& w : walls) world->removeRigidBody(w->body.get());
    walls.clear();
    if (platen) world->removeRigidBody(platen->body.get());
    platen.reset();
  }

  std::unique_ptr<WallBody> make_static_plane(int wall, const Vec3& normal, double constant) {
    auto w = std::make_unique<WallBody>();
    w->tag.wall = wall;
    w->shape = std::make_unique<btStaticPlaneShape>(bt(normal), constant);
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, w->shape.get());
    w->body = std::make_unique<btRigidBody>(info);
    w->body->setUserPointer(&w->tag);
    w->body->setUserIndex2(kCrumbleTag);
    w->body->setFriction(0);  // grain–wall friction comes from the combine callback
    w->body->setRestitution(0);
    world->addRigidBody(w->body.get(), kWallGroup, kGrainGroup);
    return w;
  }

  void build_container() {
    remove_container_bodies();
    const double lx = to_int(container.lx), ly = to_int(container.ly);
    for (const WallPlane& w : container_planes(container, 3))
      if (w.id != kPlaten) walls.push_back(make_static_plane(w.id, w.normal, to_int(w.offset())));
    // Platen: a thick box a little wider than the box (it only meets grains), bottom face
    // at `height`. Its margin lies inside the box, so the face stays where it is.
    platen = std::make_unique<WallBody>();
    platen->tag.wall = kPlaten;
    platen_half_thickness = 0.25 * std::max(lx, ly);
    auto box = std::make_unique<btBoxShape>(btVector3(0.55 * lx, 0.55 * ly, platen_half_thickness));
    box->setMargin(std::min(opt.margin_fraction * ref_length, 0.5 * platen_half_thickness));
    platen->shape = std::move(box);
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, platen->shape.get());
    info.m_startWorldTransform.setIdentity();
    info.m_startWorldTransform.setOrigin(btVector3(0.5 * lx, 0.5 * ly, to_int(driver.position()) + platen_half_thickness));
    platen->body = std::make_unique<btRigidBody>(info);
    platen->body->setUserPointer(&platen->tag);
    platen->body->setUserIndex2(kCrumbleTag);
    platen->body->setFriction(0);
    platen->body->setRestitution(0);
    platen->body->setActivationState(DISABLE_DEACTIVATION);
    platen_dynamic = false;
    configure_platen_body();
  }

  double platen_mass() const {
    return std::max(crumble::platen_mass(container, total_mass), 1e-30) * opt.mass_scale;
  }

  // Kinematic body for velocity control; dynamic body moving along z only for force
  // control. Changing the kind means leaving and re-entering the world.
  void configure_platen_body() {
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

  double current_platen_z() const {
    if (!platen || !platen_dynamic) return driver.position();
    return (platen->body->getWorldTransform().getOrigin().z() - platen_half_thickness) / scale;
  }

  // ---------------------------------------------------------------- grains
  std::shared_ptr<ShapeEntry> shape_entry(const Shape::Ptr& shape) {
    auto it = shape_cache.find(shape.get());
    if (it != shape_cache.end()) {
      if (auto e = it->second.lock()) return e;
    }
    // Drop stale entries now and then so the cache does not grow with fragments.
    for (auto i = shape_cache.begin(); i != shape_cache.end();)
      i = i->second.expired() ? shape_cache.erase(i) : std::next(i);

    auto e = std::make_shared<ShapeEntry>();
    e->shape = shape;
    const MassProperties& mp = shape->mass_properties();
    if (!(mp.volume > 0)) throw std::invalid_argument("bullet: shape " + shape->describe() + " has no volume");
    e->centroid = mp.centroid;
    // Bullet keeps a diagonal inertia: use the principal frame when the shape's is not.
    const Mat3& I = mp.inertia;
    const double tr = std::abs(I.trace());
    const double offdiag = std::max({std::abs(I(0, 1)), std::abs(I(0, 2)), std::abs(I(1, 2))});
    if (offdiag <= 1e-12 * tr) {
      e->moments = {I(0, 0), I(1, 1), I(2, 2)};
      e->principal = Quat{};
    } else {
      const auto pa = principal_axes(I);
      e->moments = pa.moments;
      e->principal = pa.rotation;
    }
    if (!(e->moments.x > 0 && e->moments.y > 0 && e->moments.z > 0))
      throw std::invalid_argument("bullet: shape " + shape->describe() + " has a non-positive principal moment");

    const double d = shape->equivalent_diameter();
    if (shape->kind() == ShapeKind::Sphere && opt.exact_spheres) {
      e->collision = std::make_unique<btSphereShape>(to_int(shape->parameters().at(0)));
    } else if (auto pieces = concave_shape_pieces(*shape, opt.concave, "bullet", &compound_failures); !pieces.empty()) {
      // A concave polyhedron (Zhu & Zhao 2019 §3.2 keep children with V/V_hull < 0.85
      // concave in the engine) collides as convex pieces whose hulls cover it; a convex one
      // (within concavity_tolerance of its hull) as its hull, as below.
      auto compound = std::make_unique<btCompoundShape>(true, static_cast<int>(pieces.size()));
      btTransform identity;
      identity.setIdentity();
      for (const auto& piece : pieces) {
        e->pieces.push_back(hull_shape(piece, d, *e));
        compound->addChildShape(identity, e->pieces.back().get());
      }
      e->collision = std::move(compound);
      ++compound_shapes;
      compound_pieces += static_cast<long>(pieces.size());
    } else {
      e->collision = hull_shape(shape->convex_hull(), d, *e);
    }
    shape_cache[shape.get()] = e;
    return e;
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

  btTransform body_transform(const ShapeEntry& e, const Vec3& position, const Quat& orientation) const {
    const Quat q = orientation.normalized();
    const Vec3 com = position + q.rotate(e.centroid);
    btTransform t;
    t.setOrigin(bt(com * scale));
    t.setRotation(bt((q * e.principal).normalized()));
    return t;
  }

  void add_grain(const Grain& g) {
    if (!g.shape) throw std::invalid_argument("bullet: grain " + std::to_string(g.id) + " has no shape");
    if (g.shape->dimension() != 3)
      throw std::invalid_argument("bullet: grain " + std::to_string(g.id) + " has a 2D shape; the engine is 3D");
    if (g.material < 0 || g.material >= static_cast<int>(ctx.materials.size()))
      throw std::invalid_argument("bullet: grain " + std::to_string(g.id) + " has material index " +
                                  std::to_string(g.material) + " out of range");
    if (grains.count(g.id)) throw std::invalid_argument("bullet: grain id " + std::to_string(g.id) + " added twice");
    require_finite(g.position, "position", g.id);
    require_finite(g.velocity, "velocity", g.id);
    require_finite(g.angular_velocity, "angular velocity", g.id);
    const double qn = std::sqrt(g.orientation.w * g.orientation.w + g.orientation.x * g.orientation.x +
                                g.orientation.y * g.orientation.y + g.orientation.z * g.orientation.z);
    if (!(qn > 0) || !std::isfinite(qn))
      throw std::invalid_argument("bullet: grain " + std::to_string(g.id) + " has an invalid orientation");

    fix_scale(g.shape->equivalent_diameter());
    const Material& mat = ctx.materials[g.material];
    auto gb = std::make_unique<GrainBody>();
    gb->entry = shape_entry(g.shape);
    gb->tag.id = g.id;
    gb->tag.friction = mat.friction;
    gb->tag.wall_friction = mat.wall_friction;
    gb->tag.rolling_friction = mat.rolling_friction;
    gb->tag.scale = friction_scale;
    gb->mass = mat.density * g.shape->volume();
    // Inertia from the shape's exact mass properties (calculateLocalInertia of a hull is a
    // box estimate); both scaled by mass_scale (Zhu & Zhao 2019 §5).
    const double m = gb->mass * opt.mass_scale;
    const Vec3 inertia = gb->entry->moments * (mat.density * opt.mass_scale * scale * scale);
    btRigidBody::btRigidBodyConstructionInfo info(m, nullptr, gb->entry->collision.get(), bt(inertia));
    info.m_startWorldTransform = body_transform(*gb->entry, g.position, g.orientation);
    info.m_friction = std::sqrt(mat.friction * friction_scale);
    info.m_rollingFriction = mat.rolling_friction;
    info.m_restitution = 0;
    info.m_linearDamping = 0;
    info.m_angularDamping = 0;
    gb->body = std::make_unique<btRigidBody>(info);
    btRigidBody* b = gb->body.get();
    b->setUserPointer(&gb->tag);
    b->setUserIndex2(kCrumbleTag);
    b->setActivationState(DISABLE_DEACTIVATION);
    b->setFlags(b->getFlags() | BT_DISABLE_WORLD_GRAVITY);
    // Mass scaling slows the dynamics; the weight stays m·g.
    b->setGravity(bt(ctx.gravity * (scale / opt.mass_scale)));
    const Quat q = g.orientation.normalized();
    b->setLinearVelocity(bt((g.velocity + cross(g.angular_velocity, q.rotate(gb->entry->centroid))) * scale));
    b->setAngularVelocity(bt(g.angular_velocity));
    world->addRigidBody(b, kGrainGroup, kGrainGroup | kWallGroup | kPlatenGroup);
    total_mass += gb->mass;
    grains.emplace(g.id, std::move(gb));
    if (platen && platen_dynamic && container.platen_mass <= 0) platen->body->setMassProps(platen_mass(), btVector3(0, 0, 0));
  }

  void remove_grain(GrainId id) {
    auto it = grains.find(id);
    if (it == grains.end()) throw std::invalid_argument("bullet: remove_grain: unknown grain id " + std::to_string(id));
    world->removeRigidBody(it->second->body.get());
    total_mass -= it->second->mass;
    grains.erase(it);
    if (grains.empty()) total_mass = 0;
    if (platen && platen_dynamic && container.platen_mass <= 0) platen->body->setMassProps(platen_mass(), btVector3(0, 0, 0));
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

  void step(double dt) {
    if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("bullet: step needs a finite dt > 0");
    if (scale <= 0) fix_scale(0);
    if (!have_container) throw std::logic_error("bullet: step() before set_container()");
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
      t.setOrigin(btVector3(t.getOrigin().x(), t.getOrigin().y(), to_int(driver.position()) + platen_half_thickness));
      p->setWorldTransform(t);
    }
    // Torque-free precession (Euler's equations) of the grains that touched nothing in the
    // last step; a grain in contact gets Bullet's own term inside the solver (see
    // gyroscopic_step for why that one is ≈ 0 for mm grains).
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
    last_dt = dt;
    solver->max_iterations = 0;
    solver->max_change = 0;
    solver->rolling.clear();
    world->stepSimulation(dt, 0);  // exactly one internal step of dt
    if (platen_dynamic) driver.sync(current_platen_z(), p->getLinearVelocity().z() / scale);
  }

  // Impulse (internal units) on body0 of a manifold: normal plus both friction directions.
  static btVector3 impulse_on_body0(const btPersistentManifold* m) {
    btVector3 j(0, 0, 0);
    for (int k = 0; k < m->getNumContacts(); ++k) {
      const btManifoldPoint& p = m->getContactPoint(k);
      j += p.m_normalWorldOnB * p.m_appliedImpulse + p.m_lateralFrictionDir1 * p.m_appliedImpulseLateral1 +
           p.m_lateralFrictionDir2 * p.m_appliedImpulseLateral2;
    }
    return j;
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
      const btVector3 j0 = impulse_on_body0(m);
      if (t0->wall == wall) j += j0;
      if (t1->wall == wall) j -= j0;
    }
    return j;
  }
  double wall_impulse_z(int wall) const { return wall_impulse(wall).z(); }

  std::vector<Contact> contacts() const {
    std::vector<Contact> out;
    if (last_dt <= 0) return out;
    const int n = dispatcher->getNumManifolds();
    for (int i = 0; i < n; ++i) {
      const btPersistentManifold* m = dispatcher->getInternalManifoldPointer()[i];
      const int np = m->getNumContacts();
      if (np == 0) continue;
      const BodyTag* t0 = tag_of(m->getBody0());
      const BodyTag* t1 = tag_of(m->getBody1());
      if (!t0 || !t1 || (t0->wall >= 0 && t1->wall >= 0)) continue;
      btVector3 j(0, 0, 0), point(0, 0, 0), normal(0, 0, 0), mid_sum(0, 0, 0), couple(0, 0, 0);
      double jn = 0, depth = 0;
      for (int k = 0; k < np; ++k) {
        const btManifoldPoint& p = m->getContactPoint(k);
        depth = std::max(depth, -static_cast<double>(p.getDistance()));
        const btVector3 mid = 0.5 * (p.getPositionWorldOnA() + p.getPositionWorldOnB());
        j += p.m_normalWorldOnB * p.m_appliedImpulse + p.m_lateralFrictionDir1 * p.m_appliedImpulseLateral1 +
             p.m_lateralFrictionDir2 * p.m_appliedImpulseLateral2;
        if (const auto r = solver->rolling.find(&p); r != solver->rolling.end()) couple += r->second;
        const double w = std::max(p.m_appliedImpulse, btScalar(0));
        point += mid * w;
        normal += p.m_normalWorldOnB * w;
        jn += w;
        mid_sum += mid;
      }
      if (!(jn > 0)) continue;  // touching without force: not an active contact
      point /= jn;
      normal = normal.length2() > 0 ? normal.normalized() : m->getContactPoint(0).m_normalWorldOnB;
      // Bullet's normal on B points from B to A, and j is the impulse on A (body0).
      Contact c;
      bool flip = false;
      if (t0->wall >= 0) {  // wall is body0: the grain (body1) is `a`
        c.a = t1->id;
        c.wall = t0->wall;
        flip = true;
      } else if (t1->wall >= 0) {
        c.a = t0->id;
        c.wall = t1->wall;
      } else {
        // Grain pair once, `a` the smaller id.
        flip = t1->id < t0->id;
        c.a = flip ? t1->id : t0->id;
        c.b = flip ? t0->id : t1->id;
      }
      const double sgn = flip ? -1.0 : 1.0;
      c.force = vec(j) * (sgn / (scale * last_dt));
      c.torque = vec(couple) * (sgn / (scale * scale * last_dt));
      c.normal = vec(normal) * sgn;
      c.point = vec(point) / scale;
      c.overlap = depth / scale;
      out.push_back(c);
    }
    return out;
  }

  void read_state(std::span<Grain> gs) const {
    for (auto& g : gs) {
      auto it = grains.find(g.id);
      if (it == grains.end()) continue;
      const GrainBody& gb = *it->second;
      const btRigidBody* b = gb.body.get();
      const btTransform& t = b->getWorldTransform();
      const Quat q = (quat(t.getRotation()) * gb.entry->principal.conjugate()).normalized();
      const Vec3 com = vec(t.getOrigin()) / scale;
      const Vec3 arm = q.rotate(gb.entry->centroid);
      const Vec3 w = vec(b->getAngularVelocity());
      g.orientation = q;
      g.position = com - arm;
      g.angular_velocity = w;
      g.velocity = vec(b->getLinearVelocity()) / scale - cross(w, arm);
    }
  }

  void set_container(const Container& c) {
    require_closed_box(c, "bullet");
    container = c;
    have_container = true;
    driver.reset(c.height);
    if (scale > 0) build_container();
  }

  void set_platen(const PlatenCommand& cmd) {
    if (!std::isfinite(cmd.value)) throw std::invalid_argument("bullet: platen command value is not finite");
    const bool mode_change = cmd.mode != driver.command().mode;
    driver.set_command(cmd);
    if (platen && mode_change) configure_platen_body();
  }
};

// ------------------------------------------------------------------ BulletEngine

const OptionTable& bullet_options() {
  static const OptionTable t = [] {
    const BulletEngine::Options d;
    OptionTable table{
        opt::choice("sphere_representation", "polyhedron", {"polyhedron", "sphere"},
                    "spheres as their icosphere mesh (42 vertices, as Zhu & Zhao 2019) or \"sphere\" (exact btSphereShape)"),
        opt::number("length_scale", d.length_scale, 0, std::numeric_limits<double>::infinity(), "",
                    "internal units per metre; 0 = the power of two nearest 1/d of the first grain (2 mm → 512)"),
        opt::positive_below("margin_fraction", d.margin_fraction, 0.1, false, "", "collision margin / d (hulls are inset by it)"),
        opt::integer("solver_iterations", d.solver_iterations, 1, 1000000,
                     "projected Gauss-Seidel iterations at most (the shipped oedometers use 1000: at 100 the packing creeps)"),
        opt::number("solver_tolerance", d.solver_tolerance, 0, 1, "",
                    "stop when impulses change by at most this fraction between iterations (0 = always run solver_iterations, as Zhu & Zhao 2019 §2.2)"),
        opt::number("solver_residual", d.solver_residual, 0, 1, "", "Bullet's own absolute residual threshold (0 = off)"),
        opt::number("erp", d.erp, 0, 1, "", "penetration correction β (Zhu & Zhao 2019, eq. 8), Bullet's m_erp2"),
        opt::number("deep_penetration", d.deep_penetration, 0, 1, "",
                    "contacts deeper than this × d (the first grain's) are pushed apart by Bullet's split impulse at "
                    "deep_erp, without adding velocity; 0 = off (eq. 8 everywhere, as Zhu & Zhao 2019)"),
        opt::number("deep_erp", d.deep_erp, 0, 1, "", "penetration correction of the contacts past deep_penetration"),
        opt::positive("mass_scale", d.mass_scale, "", "mass and inertia ×; weight unchanged (Zhu & Zhao 2019 §5 use 70)"),
    };
    for (auto& spec : concave_shape_options("btCompoundShape")) table.push_back(std::move(spec));
    return table;
  }();
  return t;
}

BulletEngine::Options BulletEngine::read_options(const Config& cfg) {
  cfg.string("type", "bullet");
  const crumble::Options r(cfg, bullet_options());
  Options o;
  o.exact_spheres = r.string("sphere_representation") == "sphere";
  o.length_scale = r.number("length_scale");
  o.margin_fraction = r.number("margin_fraction");
  o.solver_iterations = static_cast<int>(r.integer("solver_iterations"));
  o.solver_tolerance = r.number("solver_tolerance");
  o.solver_residual = r.number("solver_residual");
  o.erp = r.number("erp");
  o.deep_penetration = r.number("deep_penetration");
  o.deep_erp = r.number("deep_erp");
  o.mass_scale = r.number("mass_scale");
  o.concave = read_concave_shape_options(r);
  return o;
}

BulletEngine::BulletEngine(const Options& opts, const EngineContext& ctx)
    : impl_(std::make_unique<Impl>(opts, ctx)) {}
BulletEngine::~BulletEngine() = default;

void BulletEngine::set_container(const Container& c) { impl_->set_container(c); }
void BulletEngine::add_grain(const Grain& g) { impl_->add_grain(g); }
bool BulletEngine::set_friction_scale(double scale) {
  if (!(scale >= 0 && scale <= 1)) return false;
  impl_->apply_friction_scale(scale);
  return true;
}
void BulletEngine::remove_grain(GrainId id) { impl_->remove_grain(id); }
std::size_t BulletEngine::grain_count() const { return impl_->grains.size(); }
void BulletEngine::step(double dt) { impl_->step(dt); }
void BulletEngine::read_state(std::span<Grain> grains) const { impl_->read_state(grains); }
std::vector<Contact> BulletEngine::contacts() const { return impl_->contacts(); }
void BulletEngine::set_platen(const PlatenCommand& cmd) { impl_->set_platen(cmd); }
double BulletEngine::platen_position() const { return impl_->current_platen_z(); }

double BulletEngine::platen_force() const {
  if (impl_->last_dt <= 0) return 0;
  return impl_->force_si(impl_->wall_impulse_z(kPlaten));  // up on the platen = compression
}

double BulletEngine::floor_force() const {
  if (impl_->last_dt <= 0) return 0;
  return -impl_->force_si(impl_->wall_impulse_z(kFloor));  // grains push the floor down
}

double BulletEngine::wall_force(int wall) const {
  if (impl_->last_dt <= 0 || wall < kFloor || wall > kWallYMax) return 0;
  const Vec3 n = wall_inward_normal(wall, 3);
  const btVector3 j = impl_->wall_impulse(wall);
  return -impl_->force_si(j.x() * n.x + j.y() * n.y + j.z() * n.z);  // outwards on the wall
}

double BulletEngine::last_solver_change() const { return impl_->solver->max_change; }
std::map<std::string, double> BulletEngine::summary_figures() const {
  return {{"compound_shapes", static_cast<double>(impl_->compound_shapes)},
          {"compound_pieces", static_cast<double>(impl_->compound_pieces)},
          {"compound_failures", static_cast<double>(impl_->compound_failures)}};
}

Engine::SolverReport BulletEngine::solver_report() const {
  const ToleranceSolver& s = *impl_->solver;
  SolverReport r;
  r.iterations = s.max_iterations > 0 ? s.max_iterations : -1;
  r.change = s.max_change;
  r.limit_before_tolerance =
      s.tolerance > 0 && s.max_iterations >= impl_->world->getSolverInfo().m_numIterations && s.max_change > s.tolerance;
  return r;
}

double BulletEngine::length_scale() const { return impl_->scale; }

int BulletEngine::last_solver_iterations() const { return impl_->solver->max_iterations; }

std::unique_ptr<Engine> make_bullet_engine(const Config& cfg, const EngineContext& ctx) {
  const auto opts = BulletEngine::read_options(cfg);
  if (ctx.dimension != 3) cfg.fail("", "the bullet engine is 3D only (scenario dimension " + std::to_string(ctx.dimension) + ")");
  return std::make_unique<BulletEngine>(opts, ctx);
}

bool bullet_double_precision_ok(std::string* why) {
  if (sizeof(btScalar) != sizeof(double)) {
    if (why) *why = "btScalar is not double in crumble_bullet";
    return false;
  }
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
