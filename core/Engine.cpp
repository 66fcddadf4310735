// The defaults of the Engine interface that engines may keep.
#include "core/Engine.h"

#include <limits>
#include <stdexcept>
#include <string>

namespace crumble {

double Engine::max_stable_dt() const { return std::numeric_limits<double>::infinity(); }

double Engine::wall_force(int wall) const {
  // The contact normal points from the wall into the grain and the force is the one on the
  // grain, so the push on the wall along its outward normal is dot(force, normal).
  double f = 0;
  for (const auto& c : contacts())
    if (c.wall == wall) f += dot(c.force, c.normal);
  return f;
}

// Engines without moving walls refuse them by name (never a silent fallback).
int Engine::add_moving_wall(const MovingWall& w) {
  throw std::invalid_argument("engine '" + name() + "' does not support moving walls (wall '" + w.name +
                              "'); use an engine that does, e.g. \"lsdem\"");
}

void Engine::set_moving_wall(int, const WallKinematics&) {
  throw std::logic_error("engine '" + name() + "' has no moving walls");
}

Vec3 Engine::moving_wall_force(int) const { throw std::logic_error("engine '" + name() + "' has no moving walls"); }

}  // namespace crumble
