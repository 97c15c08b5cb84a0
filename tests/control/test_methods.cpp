// The method interface (lexdyn/control/method.hpp): the switching rule (eq. 95 and the rank
// option) on its own and the registry. A fifth method registered by a test runs the point mass
// in test_point_mass.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "lexdyn/common/error.hpp"
#include "lexdyn/control/controller.hpp"
#include "lexdyn/control/method.hpp"
#include "lexdyn/control/switching.hpp"
#include "../common/expect_text.hpp"

namespace lexdyn::control {
namespace {

const std::string kDir = std::string(LEXDYN_SOURCE_DIR) + "/models/point_mass/";

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

// --- Registry ---

TEST(MethodRegistry, BuiltInMethodsInOrder) {
  const std::vector<std::string> names = methodNames();
  ASSERT_GE(names.size(), 4u);
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 4), (std::vector<std::string>{"bfgs", "ah", "gn", "wls"}));
  EXPECT_FALSE(findMethod("bfgs", "x").weighted_hierarchy);
  EXPECT_TRUE(findMethod("wls", "x").weighted_hierarchy);
  for (const char* n : {"bfgs", "ah", "gn"}) {
    ControllerParams p;
    p.method = n;
    EXPECT_EQ(makeMethod(p, "x")->domain(), tasks::Domain::Velocity) << n;
  }
  ControllerParams p;
  p.method = "wls";
  EXPECT_EQ(makeMethod(p, "x")->domain(), tasks::Domain::Acceleration);
}

std::string errorOf(const std::function<void()>& f) { return lexdyn::testing::inputErrorOf(f); }

TEST(MethodRegistry, UnknownNameListsTheKnownOnes) {
  const std::string msg = errorOf([] { findMethod("newton", "case.yaml:10: controller.method"); });
  EXPECT_NE(msg.find("case.yaml:10: controller.method"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected one of bfgs, ah, gn, wls"), std::string::npos) << msg;
  EXPECT_NE(msg.find("found \"newton\""), std::string::npos) << msg;
  // A controller configured with an unknown method says so before anything else.
  const model::RobotModel m = model::RobotModel::fromFiles(kDir + "point_mass.urdf", kDir + "point_mass.yaml");
  ControllerConfig cfg;
  cfg.params.method = "lm";
  const std::string c = errorOf([&] { Controller ctl(m, std::move(cfg)); });
  EXPECT_NE(c.find("controller.method"), std::string::npos) << c;
  EXPECT_NE(c.find("bfgs, ah, gn, wls"), std::string::npos) << c;
}

TEST(MethodRegistry, RegistrationErrors) {
  EXPECT_NE(errorOf([] {
              registerMethod({"gn", "again", false, findMethod("gn", "").make});
            }).find("registered already"),
            std::string::npos);
  EXPECT_NE(errorOf([] { registerMethod({"", "nameless", false, findMethod("gn", "").make}); }).find("expected a name"), std::string::npos);
  EXPECT_NE(errorOf([] { registerMethod({"nofactory", "", false, nullptr}); }).find("expected a factory"), std::string::npos);
}

}  // namespace
}  // namespace lexdyn::control
