// The shared container and platen piece (core/Platen.h) every engine adapts.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/Platen.h"

using namespace crumble;

TEST(Platen, MassRule) {
  Container c{1e-2, 1e-2, 1e-2, 0};
  EXPECT_DOUBLE_EQ(platen_mass(c, 3e-3, 1), 3e-3);   // 0 = the grains' total mass
  EXPECT_DOUBLE_EQ(platen_mass(c, 3e-3, 70), 0.21);  // scaled like the grains
  c.platen_mass = 0.5;
  EXPECT_DOUBLE_EQ(platen_mass(c, 3e-3, 70), 35.0);
}

TEST(Platen, VelocityCommandMovesKinematically) {
  PlatenDriver d;
  d.reset(4e-3);
  d.set_command({PlatenCommand::Mode::Velocity, -0.01});
  EXPECT_FALSE(d.force_driven());
  EXPECT_EQ(d.applied_force(), 0.0);
  for (int k = 0; k < 1000; ++k) d.advance(5e-5, 123.0, 1.0);  // force and mass ignored
  EXPECT_NEAR(d.position(), 3.5e-3, 1e-15);
  EXPECT_EQ(d.velocity(), -0.01);
}

// Force command: semi-implicit Euler under a constant net force, z_n = z0 + a·Δt²·n(n+1)/2,
// v_n = a·n·Δt with a = (F_grains − F_cmd)/M.
TEST(Platen, ForceCommandIntegratesSemiImplicitly) {
  PlatenDriver d;
  d.reset(1e-2);
  d.set_command({PlatenCommand::Mode::Force, 2.0});
  EXPECT_TRUE(d.force_driven());
  EXPECT_EQ(d.applied_force(), -2.0);
  const double M = 0.5, Fg = 0.5, dt = 1e-4;
  const int n = 400;
  for (int k = 0; k < n; ++k) d.advance(dt, Fg, M);
  const double a = (Fg - 2.0) / M;
  EXPECT_NEAR(d.velocity(), a * n * dt, 1e-12);
  EXPECT_NEAR(d.position(), 1e-2 + a * dt * dt * n * (n + 1) / 2, 1e-14);
  // Linear damping: the velocity decays towards (F_g − F_cmd)/(M·c).
  PlatenDriver e;
  e.reset(0);
  e.set_command({PlatenCommand::Mode::Force, 1.0});
  for (int k = 0; k < 20000; ++k) e.advance(1e-3, 0.0, 1.0, 10.0);
  EXPECT_NEAR(e.velocity(), -1.0 / 10.0, 1e-9);
  // No mass yet (no grains): the velocity is held.
  PlatenDriver f;
  f.reset(1);
  f.set_command({PlatenCommand::Mode::Force, 1.0});
  f.advance(0.1, 0.0, 0.0);
  EXPECT_EQ(f.position(), 1.0);
  EXPECT_THROW(f.set_command({PlatenCommand::Mode::Force, std::nan("")}), std::invalid_argument);
}

TEST(Platen, ContainerPlanesPointIntoTheBox) {
  const Container c{2.0, 3.0, 4.0, 0};
  const auto w3 = container_planes(c, 3, 4.0, -0.5);
  ASSERT_EQ(w3.size(), 6u);
  const int ids[] = {kFloor, kPlaten, kWallXMin, kWallXMax, kWallYMin, kWallYMax};
  const Vec3 inside{1.0, 1.5, 2.0};
  for (std::size_t i = 0; i < w3.size(); ++i) {
    EXPECT_EQ(w3[i].id, ids[i]);
    EXPECT_NEAR(norm(w3[i].normal), 1.0, 1e-15);
    // The box centre is 1, 1, 1.5, 1, 1.5, 2 from the walls.
    EXPECT_GT(dot(w3[i].normal, inside) - w3[i].offset(), 0.9);
  }
  EXPECT_DOUBLE_EQ(w3[1].offset(), -4.0);
  EXPECT_DOUBLE_EQ(w3[3].offset(), -2.0);
  EXPECT_DOUBLE_EQ(w3[5].offset(), -3.0);
  EXPECT_EQ(w3[1].velocity.z, -0.5);
  // 2D: vertical axis y, no y walls; a zero length leaves that side open.
  const auto w2 = container_planes({2.0, 0, 4.0, 0}, 2, 4.0);
  ASSERT_EQ(w2.size(), 4u);
  EXPECT_EQ(w2[0].normal.y, 1.0);
  EXPECT_EQ(w2[1].normal.y, -1.0);
  EXPECT_EQ(container_planes({0, 0, 0, 0}, 3).size(), 1u);
}
