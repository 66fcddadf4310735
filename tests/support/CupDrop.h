// The concave-grain test of the engines that collide convex pieces (bullet, ode): a 0.6 mm
// ball dropped into the notch of a U-shaped grain (u_prism(3, 1 mm): 3 × 3 × 2 mm, a 1 mm
// notch 1 mm deep) standing on the floor of a 20 mm box. With the grain's convex pieces the
// ball comes to rest on the notch's bottom (its centre 1.3 mm above the grain's base) with
// its contact on the grain's surface; with the hull, on the hull's top (2.3 mm), over the
// notch, 0.5 mm from the grain's material.
#pragma once
#include <algorithm>
#include <cmath>

#include "core/Engine.h"
#include "geometry/Shape.h"
#include "tests/support/Meshes.h"

namespace crumble::testing_support {

struct CupDrop {
  double ball_height = 0;     // the ball's centre above the grain's base (m)
  double contact_offset = 0;  // largest |distance| of a ball–grain contact point from the grain's surface (m); −1 if none
  double cup_speed = 0;       // the grain's speed at the end (m/s)
};

inline CupDrop drop_ball_into_u_notch(Engine& e, int steps, double dt) {
  const auto u = Shape::polyhedron(u_prism(3.0, 1e-3));  // centred: the centroid is 0.9 mm above the base
  Container box;
  box.lx = box.ly = box.height = 20e-3;
  e.set_container(box);
  Grain cup, ball;
  cup.id = 0;
  cup.shape = u;
  cup.position = {10e-3, 10e-3, 0.9e-3};
  ball.id = 1;
  ball.shape = Shape::sphere(0.3e-3);
  ball.position = {10e-3, 10e-3, 3e-3};
  e.add_grain(cup);
  e.add_grain(ball);
  for (int i = 0; i < steps; ++i) e.step(dt);
  Grain gs[2] = {cup, ball};
  e.read_state(gs);
  CupDrop r;
  r.ball_height = gs[1].position.z - gs[0].position.z + 0.9e-3;
  r.cup_speed = norm(gs[0].velocity);
  r.contact_offset = -1;
  for (const auto& k : e.contacts())
    if (k.wall < 0) {
      const Vec3 local = gs[0].orientation.conjugate().rotate(k.point - gs[0].position);
      r.contact_offset = std::max(r.contact_offset, std::abs(u->signed_distance(local)));
    }
  return r;
}

}  // namespace crumble::testing_support
