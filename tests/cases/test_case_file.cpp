// Case files are strict data: the repository's cases load; unknown keys, wrong types and
// unknown references are errors naming the file, the line and the key path.
#include "harness/cases/case_file.hpp"
#include "lexdyn/common/error.hpp"
#include "case_test_utils.hpp"

#include <gtest/gtest.h>

namespace lexdyn::cases {
namespace {

using namespace testing;  // case_test_utils.hpp

std::string src(const std::string& rel) { return std::string(LEXDYN_SOURCE_DIR) + "/" + rel; }

std::string errorOf(const std::map<std::string, std::string>& sections) {
  const std::string path = writeCase(outputDir("case_file_errors"), sections);
  return inputErrorOf([&] { loadCase(path); });
}

TEST(CaseFile, RepositoryCasesLoad) {
  const CaseSpec stand = loadCase(src("cases/stand.yaml"));
  EXPECT_EQ(stand.name, "stand");
  EXPECT_DOUBLE_EQ(stand.duration_s, 10.0);
  EXPECT_DOUBLE_EQ(stand.control_period_s, 0.005);
  ASSERT_EQ(stand.sim.servo.kp.size(), 32);
  // Gains: later groups override earlier ones.
  EXPECT_EQ(stand.sim.servo.kp[3], 20000.0);  // RLEG_JOINT3
  EXPECT_EQ(stand.sim.servo.kp[14], 500.0);   // HEAD_JOINT0
  EXPECT_EQ(stand.sim.servo.kp[16], 2000.0);  // RARM_JOINT0
  EXPECT_EQ(stand.sim.servo.kp[23], 100.0);   // RARM_JOINT7
  EXPECT_EQ(stand.sim.servo.profile, sim::SetpointProfile::Hermite);
  EXPECT_DOUBLE_EQ(stand.sim.contact.friction_coefficient, 0.7);  // from the data file
  ASSERT_EQ(stand.checks.size(), 3u);
  EXPECT_EQ(stand.checks[0].type, "frame_drift");
  const CaseSpec squat = loadCase(src("cases/squat_sway.yaml"));
  EXPECT_EQ(squat.controller.motions.size(), 5u);
}

TEST(CaseFile, MinimalCaseLoads) {
  const CaseSpec c = loadCase(writeCase(outputDir("case_file_min"), minimalCase()));
  EXPECT_EQ(c.name, "minimal");
  EXPECT_EQ(c.trace.frames.size(), 1u);
}

TEST(CaseFile, InitialStateSettleDefaultsToTheStaticEquilibrium) {
  EXPECT_EQ(loadCase(src("cases/stand.yaml")).initial_state.settle, sim::Settle::StaticEquilibrium);
  const CaseSpec c = loadCase(writeCase(outputDir("case_file_settle"), minimalCase()));
  EXPECT_EQ(c.initial_state.settle, sim::Settle::StaticEquilibrium);  // free-flyer with feet
  EXPECT_FALSE(c.initial_state.settle_given);
  EXPECT_NE(c.initial_state.settle_where.find("initial_state"), std::string::npos) << c.initial_state.settle_where;
  for (const char* v : {"static_equilibrium", "base_only", "none"}) {
    auto s = minimalCase();
    s["d_initial"] = std::string("initial_state:\n  posture: half_sitting\n  settle: ") + v + "\n";
    const CaseSpec cv = loadCase(writeCase(outputDir("case_file_settle"), s));
    EXPECT_STREQ(sim::toString(cv.initial_state.settle), v);
    EXPECT_TRUE(cv.initial_state.settle_given);
    EXPECT_NE(cv.initial_state.settle_where.find("case.yaml:8: initial_state.settle"), std::string::npos) << cv.initial_state.settle_where;
  }
  auto s = minimalCase();
  s["d_initial"] = "initial_state:\n  posture: half_sitting\n  settle: yes\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"initial_state.settle", "static_equilibrium"}));  // lists the choices
}

TEST(CaseFile, UnknownKeysAreErrorsWithFileLineAndPath) {
  auto s = minimalCase();
  s["c_duration"] = "duration_s: 0.5\ncolour: red\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"case.yaml:6: colour", "unknown key"}));
  s = minimalCase();
  s["f_sim"] += "  extra: 1\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"sim.extra"}));
}

TEST(CaseFile, WrongTypesAreErrors) {
  auto s = minimalCase();
  s["c_duration"] = "duration_s: ten\n";
  EXPECT_NE(errorOf(s).find("case.yaml:5: duration_s: expected a finite number, found 'ten'"), std::string::npos) << errorOf(s);
  s = minimalCase();
  s["c_duration"] = "duration_s: -1\n";
  EXPECT_NE(errorOf(s).find("expected a number > 0"), std::string::npos);
  s = minimalCase();
  s["f_sim"] += "  integrator: {max_order: 7}\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"sim.integrator.max_order"}));
  s = minimalCase();
  s["f_sim"] += "  integrator: {rtol: \"1e-4\"}\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"sim.integrator.rtol"}));
  s = minimalCase();
  s["f_sim"] += "  integrator: {linear_solver: sparse_lu}\n";
  EXPECT_TRUE(containsAll(
      errorOf(s), {"case.yaml:", "sim.integrator.linear_solver", "expected one of {block_elimination, dense_lu}", "found 'sparse_lu'"}))
      << errorOf(s);
  s = minimalCase();
  s["f_sim"] += "  integrator: {jacobian: analytic}\n";
  EXPECT_TRUE(containsAll(
      errorOf(s), {"case.yaml:", "sim.integrator.jacobian", "expected one of {difference_quotient, applied_forces}", "found 'analytic'"}))
      << errorOf(s);
}

TEST(CaseFile, IntegratorLinearSolver) {
  EXPECT_EQ(loadCase(src("cases/stand.yaml")).sim.integrator.linear_solver, sim::LinearSolver::BlockElimination);
  for (const char* v : {"block_elimination", "dense_lu"}) {
    auto s = minimalCase();
    s["f_sim"] += std::string("  integrator: {linear_solver: ") + v + "}\n";
    EXPECT_STREQ(sim::toString(loadCase(writeCase(outputDir("case_file_linear_solver"), s)).sim.integrator.linear_solver), v);
  }
}

TEST(CaseFile, IntegratorJacobian) {
  EXPECT_EQ(loadCase(src("cases/stand.yaml")).sim.integrator.jacobian, sim::IntegratorJacobian::AppliedForces);
  for (const char* v : {"difference_quotient", "applied_forces"}) {
    auto s = minimalCase();
    s["f_sim"] += std::string("  integrator: {jacobian: ") + v + "}\n";
    EXPECT_STREQ(sim::toString(loadCase(writeCase(outputDir("case_file_jacobian"), s)).sim.integrator.jacobian), v);
  }
}

TEST(CaseFile, MissingKeysAreErrors) {
  auto s = minimalCase();
  s.erase("h_checks");
  EXPECT_TRUE(containsAll(errorOf(s), {"missing required key 'checks'"}));
}

TEST(CaseFile, UnknownReferencesAreErrors) {
  auto s = minimalCase();
  s["d_initial"] = "initial_state:\n  posture: kneeling\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"initial_state.posture", "half_sitting"}));  // lists the known ones

  s = minimalCase();
  s["h_checks"] = "checks:\n  - {type: frame_drift, frame: NOSE, limit_m: 0.01}\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"checks[0].frame", "'NOSE'"}));

  s = minimalCase();
  s["h_checks"] = "checks:\n  - {type: contact_slip, surfaces: [RIGHT_HAND], limit_m: 0.01}\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"checks[0].surfaces[0]"}));

  s = minimalCase();
  s["h_checks"] = "checks:\n  - {type: zmp_inside, limit_m: 0.01}\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"checks[0].type", "frame_drift"}));

  s = minimalCase();
  s["e_controller"] =
      "controller:\n  type: posture_servo\n  posture: half_sitting\n  motions:\n"
      "    - {joints: [RKNEE], amplitude: 0.1, period_s: 1}\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"controller.motions[0].joints[0]"}));

  s = minimalCase();
  s["e_controller"] = "controller:\n  type: lexdyn_bfgs\n  posture: half_sitting\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"controller.type"}));

  s = minimalCase();
  s["b_robot"] = "robot:\n  urdf: no/such.urdf\n  data: no/such.yaml\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"robot.urdf: file not found"}));
}

TEST(CaseFile, GainGroupsMustMatchAndCoverEveryJoint) {
  auto s = minimalCase();
  s["f_sim"] += "";
  s["f_sim"].replace(s["f_sim"].find("\"*\""), 3, "\"*ARM*\"");
  EXPECT_TRUE(containsAll(errorOf(s), {"sim.servo.gains", "CHEST_JOINT0"}));  // not covered
  s = minimalCase();
  s["f_sim"] += "";
  s["f_sim"].replace(s["f_sim"].find("\"*LEG_JOINT*\""), 13, "\"*KNEE*\"");
  EXPECT_TRUE(containsAll(errorOf(s), {"matches no joint"}));
}

TEST(CaseFile, EventsAndGrasps) {
  auto s = minimalCase();
  s["f_sim"] +=
      "  grasps:\n    - {name: left, frame: LGRASP, stiffness_N_per_m: 2e4, damping_Ns_per_m: 400,"
      " rot_stiffness_Nm_per_rad: 500, rot_damping_Nms_per_rad: 10}\n";
  s["e_controller"] += "events:\n  - {at_s: 0.3, action: grasp_off, grasp: left}\n  - {at_s: 0.1, action: grasp_on, grasp: left}\n";
  const CaseSpec c = loadCase(writeCase(outputDir("case_file_events"), s));
  ASSERT_EQ(c.events.size(), 2u);
  EXPECT_EQ(c.events[0].action, EventAction::GraspOn);  // sorted by time
  EXPECT_DOUBLE_EQ(c.events[1].at_s, 0.3);

  auto bad = s;
  bad["e_controller"] =
      "controller:\n  type: posture_servo\n  posture: half_sitting\n"
      "events:\n  - {at_s: 0.1, action: grasp_on, grasp: right}\n";
  EXPECT_TRUE(containsAll(errorOf(bad), {"events[0].grasp"}));
  bad["e_controller"] =
      "controller:\n  type: posture_servo\n  posture: half_sitting\n"
      "events:\n  - {at_s: 9, action: grasp_on, grasp: left}\n";
  EXPECT_TRUE(containsAll(errorOf(bad), {"after the end of the run"}));
}

TEST(CaseFile, DuplicateCheckNamesAreErrors) {
  auto s = minimalCase();
  s["h_checks"] =
      "checks:\n  - {type: frame_drift, frame: WAIST, limit_m: 0.01}\n"
      "  - {type: frame_drift, frame: WAIST, limit_m: 0.02}\n";
  EXPECT_TRUE(containsAll(errorOf(s), {"duplicate check name 'frame_drift'"}));
}

TEST(CaseFile, GlobMatching) {
  EXPECT_TRUE(globMatch("*", "RLEG_JOINT0"));
  EXPECT_TRUE(globMatch("*LEG_JOINT*", "LLEG_JOINT5"));
  EXPECT_TRUE(globMatch("RARM_JOINT7", "RARM_JOINT7"));
  EXPECT_TRUE(globMatch("*ARM_JOINT7", "LARM_JOINT7"));
  EXPECT_FALSE(globMatch("*ARM_JOINT7", "LARM_JOINT6"));
  EXPECT_FALSE(globMatch("CHEST*", "HEAD_JOINT0"));
  EXPECT_TRUE(globMatch("*_*_*", "A_B_C"));
  EXPECT_FALSE(globMatch("", "A"));
}

}  // namespace
}  // namespace lexdyn::cases
