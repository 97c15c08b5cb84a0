// The switching rule (eq. 95 and the rank option) on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "lexdyn/control/switching.hpp"

namespace lexdyn::control {
namespace {

// --- Switching rule ---

LevelOutcome outcome(double violation, int held = 0, int rank = 0) {
  LevelOutcome o;
  o.violation_norm = violation;
  o.held_rows = held;
  o.rank = rank;
  return o;
}

TEST(Switching, Eq95ThresholdOnHalfTheSquaredOptimisationViolation) {
  const double dt = 0.005, nu_dt2 = 1e-12;
  // omega = 1/2 dt^2 ||w_ctrl||^2 >= nu_dt2 dt^2  <=>  ||w_ctrl|| >= sqrt(2 nu_dt2).
  const double edge = std::sqrt(2.0 * nu_dt2);
  EXPECT_FALSE(switchToNewton(outcome(0.0), dt, nu_dt2, false));
  EXPECT_FALSE(switchToNewton(outcome(0.5 * edge), dt, nu_dt2, false));
  EXPECT_TRUE(switchToNewton(outcome(2.0 * edge), dt, nu_dt2, false));
  EXPECT_TRUE(switchToNewton(outcome(1.0), dt, nu_dt2, false));
  // The threshold scales with dt^2 on both sides: the decision depends on ||w_ctrl|| only.
  for (double h : {1e-4, 1e-3, 0.01, 0.1}) {
    EXPECT_FALSE(switchToNewton(outcome(0.9 * edge), h, nu_dt2, false)) << h;
    EXPECT_TRUE(switchToNewton(outcome(1.1 * edge), h, nu_dt2, false)) << h;
  }
  // At equality the level is augmented (>=): omega exactly nu for a violation whose arithmetic is exact.
  EXPECT_TRUE(switchToNewton(outcome(1.0), 0.5, 0.5, false));
  EXPECT_FALSE(switchToNewton(outcome(1.0), 0.5, 0.5000001, false));
  // nu = 0: any violation, even none, augments.
  EXPECT_TRUE(switchToNewton(outcome(0.0), dt, 0.0, false));
}

TEST(Switching, RankOptionAugmentsALevelWhoseHeldRowsLostRank) {
  const double dt = 0.005, nu_dt2 = 1e-12;
  // No violation: eq. 95 alone keeps Gauss-Newton.
  EXPECT_FALSE(switchToNewton(outcome(0.0, 3, 2), dt, nu_dt2, false));
  EXPECT_TRUE(switchToNewton(outcome(0.0, 3, 2), dt, nu_dt2, true));
  EXPECT_FALSE(switchToNewton(outcome(0.0, 3, 3), dt, nu_dt2, true));
  EXPECT_FALSE(switchToNewton(outcome(0.0, 0, 0), dt, nu_dt2, true));
  // Either condition suffices.
  EXPECT_TRUE(switchToNewton(outcome(1.0, 3, 3), dt, nu_dt2, true));
}

}  // namespace
}  // namespace lexdyn::control
