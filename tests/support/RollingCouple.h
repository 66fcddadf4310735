// The rolling-ball tests of the engines with rolling resistance (bullet, ode): while the ball
// rolls along +x on the floor, its one contact carries the rolling-resistance couple at its
// limit, μr·L·N (L the engine's internal length unit in metres), against the spin about +y
// (Contact::torque; the screening's unbalanced moment counts it when moment_couples is on).
#pragma once
#include <gtest/gtest.h>

#include <vector>

#include "core/Contact.h"

namespace crumble::testing_support {

inline void expect_rolling_couple_against_y_spin(const std::vector<Contact>& cs, double lever) {
  ASSERT_EQ(cs.size(), 1u);
  const double couple = lever * norm(cs[0].force);
  EXPECT_NEAR(cs[0].torque.y, -couple, 0.02 * couple);
  EXPECT_NEAR(cs[0].torque.x, 0.0, 0.02 * couple);
  EXPECT_NEAR(cs[0].torque.z, 0.0, 0.02 * couple);
}

}  // namespace crumble::testing_support
