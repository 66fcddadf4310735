#pragma once
#include "core/Grain.h"

namespace crumble {

// Wall indices of the standard container (see Container).
enum WallId : int { kFloor = 0, kPlaten = 1, kWallXMin = 2, kWallXMax = 3, kWallYMin = 4, kWallYMax = 5 };

// One contact as seen by grain `a`: `force` is the force (N) exerted on `a` by `b` (or
// by wall `wall` when wall >= 0), applied at world point `point`. `normal` is the unit
// contact normal pointing from b towards a.
struct Contact {
  GrainId a = -1;
  GrainId b = -1;   // -1 when the partner is a wall
  int wall = -1;
  Vec3 point;
  Vec3 normal;
  Vec3 force;
  // A couple (N·m) on `a` at this contact besides `force` at `point`: Bullet's rolling (and
  // spinning) resistance. Zero where the engine has none.
  Vec3 torque;
  // Deepest interpenetration of the two surfaces (m, >= 0) as the engine sees it; the
  // Simulation's guards compare it with the smaller grain's size.
  double overlap = 0;
  bool is_wall() const { return wall >= 0; }
};

}  // namespace crumble
