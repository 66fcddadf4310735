// Raw Bullet on the bodies of a RawScene: the baseline of `crumble bench engine --engine
// bullet` (the adapter's overhead against its raw library). Written against Bullet's public
// API only, as a user of plain Bullet would set up the same scene: a btConvexHullShape per
// body in its principal frame (inset by the collision margin of the grain's diameter), static
// planes, a kinematic lid, btSequentialImpulseConstraintSolver with the same iterations, erp
// and warm starting, and per-body friction values that give the adapter's combined sliding
// and rolling friction under Bullet's own rules. The bench reports both worlds' settings and
// contact work (backends/bullet/BulletWorldReport.h) and the settings that differ.
#pragma once
#include "core/RawScene.h"

namespace crumble {

std::unique_ptr<RawWorld> make_raw_bullet_world(const RawScene& scene);

}  // namespace crumble
