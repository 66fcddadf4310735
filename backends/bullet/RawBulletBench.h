// Raw Bullet on the bodies of a RawScene: the baseline of `crumble bench engine --engine
// bullet` (issue "every engine × model × geometry": the adapter's overhead against its raw
// library). Written against Bullet's public API only, as a user of plain Bullet would set up
// the same scene: btConvexHullShape per body in its principal frame, static planes, a static
// lid, btSequentialImpulseConstraintSolver with the same iterations, erp and warm starting.
#pragma once
#include "core/RawScene.h"

namespace crumble {

RawBenchResult raw_bullet_bench(const RawScene& scene, long steps);

}  // namespace crumble
