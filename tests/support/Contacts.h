// A wall contact on a grain for model tests: the force on the grain at position + offset,
// its normal along the force.
#pragma once
#include "core/Contact.h"
#include "core/Grain.h"

namespace crumble::testing_support {

inline Contact wall_contact(const Grain& g, int wall, const Vec3& offset, const Vec3& force) {
  Contact c;
  c.a = g.id;
  c.b = -1;
  c.wall = wall;
  c.point = g.position + offset;
  c.force = force;
  c.normal = normalized(force);
  return c;
}

}  // namespace crumble::testing_support
