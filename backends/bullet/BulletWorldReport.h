// What a Bullet world is set up to do and what its last step asked of the contact solver,
// read from Bullet's own objects. `crumble bench engine --engine bullet` prints both for the
// adapter's world and for the raw baseline's (tools/RawBulletBench.cpp), so a configuration
// difference between the two shows up as a named figure, not as unexplained time.
#pragma once
#include <map>
#include <string>

class btDiscreteDynamicsWorld;

namespace crumble {

// Solver settings (iterations, erp, modes, thresholds), the dispatcher's flags and the
// dynamic bodies' settings (friction, damping, gravity, margin; min and max over the
// bodies), the number of static, kinematic and dynamic bodies. Not the bodies' rolling
// friction: what Bullet solves with is the pair's combined value (a process-wide callback or
// Bullet's rule), which bullet_contact_work reports.
std::map<std::string, double> bullet_world_settings(const btDiscreteDynamicsWorld& world);

// The last step's contact work: manifolds, contact points, the contact solver's rows by
// kind (normal, friction, rolling: Bullet makes one normal row, one or two friction rows and,
// when the point's combined rolling friction is positive, three rolling rows per point within
// the manifold's processing threshold), and the mean combined friction and rolling friction
// of grain–grain points (two dynamic bodies) and grain–wall points.
std::map<std::string, double> bullet_contact_work(const btDiscreteDynamicsWorld& world);

}  // namespace crumble
