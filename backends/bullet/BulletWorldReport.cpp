#include "backends/bullet/BulletWorldReport.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <limits>

namespace crumble {

namespace {

// min and max of a value over the dynamic bodies, as "<name>_min" and "<name>_max".
struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  void write(std::map<std::string, double>& out, const std::string& name) const {
    out[name + "_min"] = lo <= hi ? lo : 0;
    out[name + "_max"] = lo <= hi ? hi : 0;
  }
};

void solver_settings(const btContactSolverInfo& si, std::map<std::string, double>& out) {
  out["solver.iterations"] = si.m_numIterations;
  out["solver.erp"] = si.m_erp;
  out["solver.erp2"] = si.m_erp2;
  out["solver.split_impulse"] = si.m_splitImpulse;
  out["solver.split_impulse_threshold"] = si.m_splitImpulse ? si.m_splitImpulsePenetrationThreshold : 0;
  out["solver.mode"] = si.m_solverMode;
  out["solver.residual_threshold"] = si.m_leastSquaresResidualThreshold;
  out["solver.global_cfm"] = si.m_globalCfm;
  out["solver.linear_slop"] = si.m_linearSlop;
  out["solver.warmstarting_factor"] = si.m_warmstartingFactor;
  out["solver.sor"] = si.m_sor;
}

void body_settings(const btDiscreteDynamicsWorld& world, std::map<std::string, double>& out) {
  Range friction, spinning, restitution, lin_damping, ang_damping, gravity, margin, flags;
  double statics = 0, kinematics = 0, dynamics = 0, sleepless = 0;
  const btCollisionObjectArray& objs = world.getCollisionObjectArray();
  for (int i = 0; i < objs.size(); ++i) {
    const btRigidBody* b = btRigidBody::upcast(objs[i]);
    if (!b) continue;
    if (b->isKinematicObject()) {
      ++kinematics;
      continue;
    }
    if (b->isStaticObject()) {
      ++statics;
      continue;
    }
    ++dynamics;
    friction.add(b->getFriction());
    spinning.add(b->getSpinningFriction());
    restitution.add(b->getRestitution());
    lin_damping.add(b->getLinearDamping());
    ang_damping.add(b->getAngularDamping());
    gravity.add(b->getGravity().length());
    margin.add(b->getCollisionShape()->getMargin());
    flags.add(b->getFlags() & ~BT_DISABLE_WORLD_GRAVITY);  // per-body gravity: in `gravity`
    sleepless += b->getActivationState() == DISABLE_DEACTIVATION ? 1 : 0;
  }
  out["bodies.static"] = statics;
  out["bodies.kinematic"] = kinematics;
  out["bodies.dynamic"] = dynamics;
  out["bodies.deactivation_disabled"] = sleepless;
  friction.write(out, "bodies.friction");
  spinning.write(out, "bodies.spinning_friction");
  restitution.write(out, "bodies.restitution");
  lin_damping.write(out, "bodies.linear_damping");
  ang_damping.write(out, "bodies.angular_damping");
  gravity.write(out, "bodies.gravity");
  margin.write(out, "bodies.margin");
  flags.write(out, "bodies.flags");
}

}  // namespace

std::map<std::string, double> bullet_world_settings(const btDiscreteDynamicsWorld& world) {
  std::map<std::string, double> out;
  solver_settings(world.getSolverInfo(), out);
  const auto* d = dynamic_cast<const btCollisionDispatcher*>(world.getDispatcher());
  out["dispatcher.flags"] = d ? d->getDispatcherFlags() : -1;
  out["dispatch.deterministic_pairs"] = world.getDispatchInfo().m_deterministicOverlappingPairs;
  out["broadphase.dbvt"] = dynamic_cast<const btDbvtBroadphase*>(world.getBroadphase()) ? 1 : 0;
  body_settings(world, out);
  return out;
}

std::map<std::string, double> bullet_contact_work(const btDiscreteDynamicsWorld& world) {
  auto& w = const_cast<btDiscreteDynamicsWorld&>(world);  // Bullet's manifold access is not const
  btDispatcher* d = w.getDispatcher();
  const int friction_rows = w.getSolverInfo().m_solverMode & SOLVER_USE_2_FRICTION_DIRECTIONS ? 2 : 1;
  double manifolds = 0, touching = 0, points = 0, rows_points = 0, rolling_points = 0, pushing = 0;
  double n_pair[2] = {0, 0}, f_pair[2] = {0, 0}, r_pair[2] = {0, 0};  // [0] grain–grain, [1] grain–wall
  for (int i = 0; i < d->getNumManifolds(); ++i) {
    const btPersistentManifold* m = d->getManifoldByIndexInternal(i);
    ++manifolds;
    if (m->getNumContacts() == 0) continue;
    ++touching;
    const bool wall = m->getBody0()->isStaticOrKinematicObject() || m->getBody1()->isStaticOrKinematicObject();
    const bool solved = !(m->getBody0()->isStaticOrKinematicObject() && m->getBody1()->isStaticOrKinematicObject());
    for (int k = 0; k < m->getNumContacts(); ++k) {
      const btManifoldPoint& p = m->getContactPoint(k);
      ++points;
      pushing += p.m_appliedImpulse > 0 ? 1 : 0;
      n_pair[wall] += 1;
      f_pair[wall] += p.m_combinedFriction;
      r_pair[wall] += p.m_combinedRollingFriction;
      if (!solved || p.getDistance() > m->getContactProcessingThreshold()) continue;
      ++rows_points;
      rolling_points += p.m_combinedRollingFriction > 0 ? 1 : 0;
    }
  }
  std::map<std::string, double> out;
  out["manifolds"] = manifolds;
  out["manifolds_touching"] = touching;
  out["points"] = points;
  out["points_pushing"] = pushing;
  out["rows_normal"] = rows_points;
  out["rows_friction"] = friction_rows * rows_points;
  out["rows_rolling"] = 3 * rolling_points;
  out["points_grain_grain"] = n_pair[0];
  out["points_grain_wall"] = n_pair[1];
  for (int k = 0; k < 2; ++k) {
    const std::string kind = k == 0 ? "grain_grain" : "grain_wall";
    out["mean_friction_" + kind] = n_pair[k] > 0 ? f_pair[k] / n_pair[k] : 0;
    out["mean_rolling_friction_" + kind] = n_pair[k] > 0 ? r_pair[k] / n_pair[k] : 0;
  }
  return out;
}

}  // namespace crumble
