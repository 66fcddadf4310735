// The container and its platen: one piece of physics below the engines. Every engine builds the same box from container_planes() and moves the
// platen by the same rules through a PlatenDriver; an engine only adapts them to its own
// bodies and units.
#pragma once
#include <string>
#include <vector>

#include "core/Engine.h"

namespace crumble {

// One flat wall of the container: the plane through `point` with unit `normal` pointing
// into the box (the grains' side), moving with `velocity` (only the platen moves).
struct WallPlane {
  int id = kFloor;  // WallId
  Vec3 point;
  Vec3 normal;
  Vec3 velocity;
  // Plane constant: dot(normal, x) = offset() on the wall.
  double offset() const { return dot(normal, point); }
};

// Unit normal of the container wall `wall` (WallId) pointing into the box: floor up,
// platen down, x walls ±x, y walls ±y (3D only). Vertical axis: z in 3D, y in 2D. Throws
// std::invalid_argument for another id (a 2D y wall, a shape wall).
Vec3 wall_inward_normal(int wall, int dimension);

// The container's walls in WallId order: floor (at 0 along the vertical axis), platen
// (when c.height > 0, at `platen_position` moving at `platen_velocity` along the vertical
// axis), x walls (when c.lx > 0), y walls (3D, when c.ly > 0). Vertical axis: z in 3D, y
// in 2D.
std::vector<WallPlane> container_planes(const Container& c, int dimension, double platen_position = 0,
                                        double platen_velocity = 0);

// Mass of a force-driven platen as the engine integrates it: Container::platen_mass, or
// the grains' total (unscaled) mass when that is 0, times the engine's mass scale (the
// platen is slowed down like the grains). `grains_mass` is the unscaled total in kg.
double platen_mass(const Container& c, double grains_mass, double mass_scale = 1);

// The closed box of a rigid-body engine (floor, four side walls, platen): throws
// std::invalid_argument naming `engine` for a non-finite or non-positive size, a negative
// platen mass, or an open container (which only engines with moving walls support).
void require_closed_box(const Container& c, const std::string& engine);

// Vertical motion of the platen under a PlatenCommand.
//  - Velocity: the platen moves at the commanded velocity (kinematic).
//  - Force: the command pushes the platen down with `value` newtons while the grains push
//    it up with the measured force F; with the mass M from platen_mass() the platen moves
//    by semi-implicit (symplectic) Euler, v ← v + ((F − value)/M − c·v)·Δt, z ← z + v·Δt,
//    c an optional linear damping rate (1/s). M <= 0 (no grains yet) holds the velocity.
// An engine whose solver couples the platen implicitly to the contacts (Bullet, ODE: a
// dynamic body) integrates a force-driven platen itself and reports the result with sync().
class PlatenDriver {
 public:
  // At rest at `position` (m).
  void reset(double position);
  // Throws std::invalid_argument for a non-finite value.
  void set_command(const PlatenCommand& cmd);
  const PlatenCommand& command() const { return cmd_; }
  bool force_driven() const { return cmd_.mode == PlatenCommand::Mode::Force; }
  // Force the command applies on the platen along the vertical axis (N, negative = down);
  // 0 under a velocity command.
  double applied_force() const { return force_driven() ? -cmd_.value : 0.0; }

  // One step of dt with the grains' upward force on the platen (N, used in force mode).
  void advance(double dt, double grain_force, double mass, double damping = 0);
  // An engine that integrated the platen itself records where it is.
  void sync(double position, double velocity) {
    z_ = position;
    v_ = velocity;
  }
  double position() const { return z_; }
  double velocity() const { return v_; }

 private:
  PlatenCommand cmd_;
  double z_ = 0, v_ = 0;
};

}  // namespace crumble
