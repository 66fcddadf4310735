// Moving walls: rigid bodies of any shape whose motion is prescribed (crusher plates,
// excavator buckets, a wall pushed at a constant speed). The description is engine-neutral:
// the Simulation evaluates the motion law at every step and hands the engine the pose and
// velocities, so every engine that supports moving walls moves them identically.
#pragma once
#include <string>

#include "geometry/Shape.h"
#include "geometry/Vec3.h"

namespace crumble {

struct WallMotion {
  enum class Type { Fixed, Eccentric, Velocity } type = Type::Fixed;
  // Eccentric: the swing jaw of a single-toggle jaw crusher (Harmon et al. 2020 §4.1,
  // Table 1): the wall rotates about `pivot` around `axis` (2D: z) by
  // θ(t) = A·sin(ω t + phase), ω = 2π·rpm/60, A = asin(throw / (2·lever)): the point at
  // distance `lever` from the pivot (the discharge end of the plate) travels a chord of
  // length `throw` between its two extreme positions once per revolution.
  Vec3 pivot;
  Vec3 axis{0, 0, 1};
  double throw_ = 0;  // m (chord travelled by the point at `lever`)
  double lever = 0;   // m
  double rpm = 0;
  double phase = 0;   // rad
  // Velocity: constant translation (m/s) and rotation about the wall's centroid (rad/s).
  Vec3 velocity;
  Vec3 angular_velocity;

  double amplitude() const;      // A (rad)
  double omega() const;          // ω (rad/s)
  double angle(double t) const;  // θ(t) (rad), eccentric; 0 otherwise
};

struct MovingWall {
  std::string name;        // for messages and outputs
  Shape::Ptr shape;        // centroid at its local origin (Shape's invariant)
  Vec3 position;           // centroid at t = 0 (m)
  Quat orientation;        // at t = 0
  WallMotion motion;
};

// Pose and velocities of a wall at time t: the centroid, orientation, the centroid's
// velocity and the angular velocity (world frame).
struct WallKinematics {
  Vec3 position;
  Quat orientation;
  Vec3 velocity;
  Vec3 angular_velocity;
};

// Closed form of the motion law at t.
WallKinematics wall_kinematics(const MovingWall& w, double t);

// What an engine is given for the step [t, t + dt]: the exact pose at t and the mean
// velocities over the step (chord velocities), so that an engine that integrates the pose
// with them lands on the exact pose at t + dt.
WallKinematics wall_step_kinematics(const MovingWall& w, double t, double dt);

// Largest speed (m/s) of any point of the wall within `radius` of its centroid, over all t
// (energy bookkeeping of the guards).
double wall_max_speed(const MovingWall& w, double radius);

}  // namespace crumble
