// Raw Bullet on the bodies of a RawScene: the baseline of `crumble bench engine --engine
// bullet` (the adapter's overhead against its raw library). Written against Bullet's public
// API only, as a user of plain Bullet would set up the same scene: a btConvexHullShape per
// body in its principal frame (inset by the collision margin), static planes, a static lid,
// btSequentialImpulseConstraintSolver with the same iterations, erp and warm starting.
#pragma once
#include "core/RawScene.h"

namespace crumble {

std::unique_ptr<RawWorld> make_raw_bullet_world(const RawScene& scene);

}  // namespace crumble
