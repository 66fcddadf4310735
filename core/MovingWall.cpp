#include "core/MovingWall.h"

#include <cmath>
#include <stdexcept>


namespace crumble {

double WallMotion::amplitude() const {
  if (type != Type::Eccentric) return 0;
  // Harmon et al. 2020 §4.1: the eccentric throw is the stroke at the discharge end; the
  // chord between the extreme positions of a point at radius L is 2·L·sin(A).
  return std::asin(throw_ / (2 * lever));
}

double WallMotion::omega() const { return 2 * kPi * rpm / 60.0; }

double WallMotion::angle(double t) const {
  if (type != Type::Eccentric) return 0;
  return amplitude() * std::sin(omega() * t + phase);
}

WallKinematics wall_kinematics(const MovingWall& w, double t) {
  const WallMotion& m = w.motion;
  WallKinematics k{w.position, w.orientation, {}, {}};
  switch (m.type) {
    case WallMotion::Type::Fixed:
      break;
    case WallMotion::Type::Velocity: {
      k.position = w.position + m.velocity * t;
      const double wn = norm(m.angular_velocity);
      if (wn > 0) k.orientation = (Quat::from_axis_angle(m.angular_velocity, wn * t) * w.orientation).normalized();
      k.velocity = m.velocity;
      k.angular_velocity = m.angular_velocity;
      break;
    }
    case WallMotion::Type::Eccentric: {
      const Vec3 axis = normalized(m.axis);
      const double th = m.angle(t);
      const double thdot = m.amplitude() * m.omega() * std::cos(m.omega() * t + m.phase);
      const Quat q = Quat::from_axis_angle(axis, th);
      k.position = m.pivot + q.rotate(w.position - m.pivot);
      k.orientation = (q * w.orientation).normalized();
      k.angular_velocity = axis * thdot;
      k.velocity = cross(k.angular_velocity, k.position - m.pivot);
      break;
    }
  }
  return k;
}

WallKinematics wall_step_kinematics(const MovingWall& w, double t, double dt) {
  WallKinematics k0 = wall_kinematics(w, t);
  if (w.motion.type != WallMotion::Type::Eccentric) return k0;
  const WallKinematics k1 = wall_kinematics(w, t + dt);
  // Mean velocities over the step: the rotation by Δθ about the pivot equals the rotation
  // by Δθ about the centroid plus the centroid's chord translation.
  k0.velocity = (k1.position - k0.position) * (1.0 / dt);
  k0.angular_velocity = normalized(w.motion.axis) * ((w.motion.angle(t + dt) - w.motion.angle(t)) / dt);
  return k0;
}

double wall_max_speed(const MovingWall& w, double radius) {
  const WallMotion& m = w.motion;
  switch (m.type) {
    case WallMotion::Type::Fixed:
      return 0;
    case WallMotion::Type::Velocity:
      return norm(m.velocity) + norm(m.angular_velocity) * radius;
    case WallMotion::Type::Eccentric:
      return m.amplitude() * m.omega() * (norm(w.position - m.pivot) + radius);
  }
  return 0;
}

}  // namespace crumble
