// The lexdyn controller's case-file section (docs/cases.md): the repository's controller cases
// load for every method they define; every task type is built from YAML with every params
// field; errors name the file, the line and the key path; target trajectories and swings.
#include "harness/cases/case_file.hpp"
#include "harness/cases/target_path.hpp"
#include "case_test_utils.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/control/controller.hpp"
#include "lexdyn/model/robot_description.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "lexdyn/tasks/self_collision.hpp"
#include "lexdyn/tasks/torque_limits.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace lexdyn::cases {
namespace {

using namespace testing;  // case_test_utils.hpp

std::string src(const std::string& rel) { return std::string(LEXDYN_SOURCE_DIR) + "/" + rel; }

std::string errorOf(const std::map<std::string, std::string>& sections, const std::string& dir = "controller_case_errors") {
  const std::string path = writeCase(outputDir(dir), sections);
  return inputErrorOf([&] { loadCase(path); });
}

// Expects an error whose message holds every fragment.
void expectError(const std::map<std::string, std::string>& sections, const std::vector<std::string>& fragments) {
  const std::string msg = errorOf(sections);
  for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << "missing '" << f << "' in: " << msg;
}

// The sections with an events section of one event at 0.1 s, {at_s: 0.1, action: ACTION}, or a
// checks section of the one entry `entry`.
std::map<std::string, std::string> withEvent(std::map<std::string, std::string> sections, const std::string& action) {
  sections["g_events"] = "events:\n  - {at_s: 0.1, action: " + action + "}\n";
  return sections;
}
std::map<std::string, std::string> withCheck(std::map<std::string, std::string> sections, const std::string& entry) {
  sections["h_checks"] = "checks:\n  - " + entry + "\n";
  return sections;
}

TEST(ControllerCase, RepositoryCasesLoadWithEveryMethod) {
  struct Expect {
    const char* file;
    const char* method;
    std::vector<std::string> methods;
  };
  for (const Expect& e :
       {Expect{"cases/exp1.yaml", "bfgs", {"bfgs", "ah", "gn", "wls"}}, Expect{"cases/exp1-gn.yaml", "gn", {"bfgs", "ah", "gn", "wls"}},
        Expect{"cases/exp1-wls-weak.yaml", "wls", {"bfgs", "ah", "gn", "wls"}},
        Expect{"cases/exp1-wls-unbiased.yaml", "wls", {"bfgs", "ah", "gn", "wls"}},
        Expect{"cases/exp2.yaml", "bfgs", {"bfgs", "ah", "gn", "wls"}}, Expect{"cases/exp3.yaml", "bfgs", {"bfgs", "ah", "gn", "wls"}},
        Expect{"cases/pointmass-damping.yaml", "gn", {"bfgs", "ah", "gn", "wls"}},
        Expect{"cases/hrp2kai_heavy/exp1.yaml", "bfgs", {"bfgs", "ah", "gn", "wls"}}}) {
    CaseSpec c = loadCase(src(e.file));
    EXPECT_EQ(c.controller.type, records::ControllerType::Lexdyn) << e.file;
    EXPECT_EQ(methodName(c), e.method) << e.file;
    for (const auto& m : e.methods) {
      overrideMethod(c, m, "--method");
      EXPECT_EQ(methodName(c), m);
    }
  }
  const CaseSpec exp2 = loadCase(src("cases/exp2.yaml"));
  const LexdynSpec& lx = exp2.controller.lexdyn;
  ASSERT_EQ(lx.contacts.size(), 3u);
  EXPECT_EQ(lx.contacts[2].name, "POLE");
  EXPECT_TRUE(lx.contacts[2].fixed);
  EXPECT_EQ(lx.contacts[2].grasp, "left_pole");
  EXPECT_EQ(lx.contacts[0].points.size(), 4u);  // the sole corners of the data file
  EXPECT_EQ(lx.levels.size(), 11u);             // the paper's sec. IX hierarchy
  ASSERT_EQ(lx.wls_levels.size(), 2u);
  EXPECT_EQ(lx.wls_levels[1].weights, (std::vector<double>{1.0, 1.0, 5e-2, 1e-4}));
  // The posture task's head yaw override became its target.
  const TaskSpec& posture = lx.tasks[static_cast<size_t>(lx.findTask("posture"))];
  ASSERT_EQ(posture.paramsAs<tasks::PostureParams>().target.size(), 32);
  EXPECT_EQ(posture.paramsAs<tasks::PostureParams>().target[14], 0.45);
  EXPECT_TRUE(posture.paramsAs<tasks::PostureParams>().posture.empty());
  const CaseSpec exp3 = loadCase(src("cases/exp3.yaml"));
  bool trajectory = false;
  for (const auto& e : exp3.events) {
    if (e.action != EventAction::TargetTrajectory) continue;
    trajectory = true;
    EXPECT_EQ(e.trajectory.movingAverage(), 3.0);
    EXPECT_GT(e.trajectory.samples(), 100);
  }
  EXPECT_TRUE(trajectory);
  // Split coordinates are the controller's default: exp1 does not set them, with paper_rules.
  const CaseSpec exp1 = loadCase(src("cases/exp1.yaml"));
  EXPECT_EQ(exp1.controller.lexdyn.params.solver.split_from_variable, solver::Options::kSplitAtControllerForces);
  EXPECT_GT(exp1.controller.lexdyn.params.solver.stop_total_iterations, 0);  // paper_rules kept
}

TEST(ControllerCase, EveryTaskTypeIsBuiltWithEveryParamsField) {
  auto s = minimalLexdynCase();
  const std::string extra =
      "    - {name: jl, type: joint_limits, interaction_fraction: 0.2, safety_fraction: 0.05, xi: 0.7, adaptive: false,"
      " velocity_limits: false}\n"
      "    - {name: tl, type: torque_limits, scale: 0.5}\n"
      "    - {name: tr, type: trust_region, delta: 0.02}\n"
      "    - {name: sc, type: self_collision, pairs: [[WAIST_C, RARM_LINK3_C]], interaction_distance: 0.06,"
      " safety_distance: 0.02, xi: 0.3, adaptive: false}\n"
      "    - {name: ct, type: contact, contact: RIGHT_FOOT, gains: {kp: 50, kv: 7}}\n"
      "    - {name: po, type: position, frame: RGRASP, point: [0.01, 0.02, 0.03], target: [0.3, -0.3, 1.0],"
      " gains: {kp: 2.0, kv: 3.0}}\n"
      "    - {name: orr, type: orientation, frame: CHEST_LINK1, target_rpy_rad: [0.1, 0.0, 0.0], gains: {kp: 4.0}}\n"
      "    - {name: orm, type: orientation, frame: CHEST_LINK1, target: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}\n"
      "    - {name: cm, type: com, target: [0.0, 0.0, 0.7], gains: {kp: 5.0, kv: 1.0}}\n"
      "    - {name: cb, type: com_box, lower: [-0.1, -.inf, -.inf], upper: [0.1, .inf, .inf],"
      " damper: {interaction: 0.03, safety: 0.005, xi: 0.2, adaptive: false}}\n"
      "    - {name: jp, type: joint_position, joints: [HEAD_JOINT0, HEAD_JOINT1], target: [0.1, -0.1], gains: {kp: 6.0}}\n"
      "    - {name: pt, type: posture, target: [" +
      std::string(
          "0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, "
          "0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0") +
      "], gains: {kp: 0.5}}\n"
      "    - {name: vm, type: velocity_min}\n"
      "    - {name: wm, type: wrench_min}\n"
      "    - {name: eom, type: equation_of_motion}\n"
      "    - {name: fb, type: contact_force_bounds}\n";
  s["e_controller"] = lexdynController("bfgs", extra);
  const std::string solverFrom = "  solver: {paper_rules: true}\n";
  s["e_controller"].replace(s["e_controller"].find(solverFrom), solverFrom.size(),
                            "  solver: {paper_rules: true, last_level_projection: never, split_force_coordinates: false}\n");
  const CaseSpec c = loadCase(writeCase(outputDir("controller_case_registry"), s));
  const LexdynSpec& lx = c.controller.lexdyn;
  EXPECT_EQ(lx.params.solver.last_level_projection, solver::Options::LastLevel::Never);
  EXPECT_EQ(lx.params.solver.split_from_variable, -1);
  EXPECT_EQ(lx.params.solver.stop_total_iterations, 30);
  auto task = [&](const std::string& n) -> const TaskSpec& { return lx.tasks[static_cast<size_t>(lx.findTask(n))]; };
  EXPECT_EQ(task("jl").paramsAs<tasks::JointLimitsParams>().interaction_fraction, 0.2);
  EXPECT_EQ(task("jl").paramsAs<tasks::JointLimitsParams>().safety_fraction, 0.05);
  EXPECT_EQ(task("jl").paramsAs<tasks::JointLimitsParams>().xi, 0.7);
  EXPECT_FALSE(task("jl").paramsAs<tasks::JointLimitsParams>().adaptive);
  EXPECT_FALSE(task("jl").paramsAs<tasks::JointLimitsParams>().velocity_limits);
  EXPECT_EQ(task("tl").paramsAs<tasks::TorqueLimitsParams>().scale, 0.5);
  EXPECT_EQ(task("tr").paramsAs<tasks::TrustRegionParams>().delta, 0.02);
  ASSERT_EQ(task("sc").paramsAs<tasks::SelfCollisionParams>().pairs.size(), 1u);
  EXPECT_EQ(task("sc").paramsAs<tasks::SelfCollisionParams>().pairs[0].second, "RARM_LINK3_C");
  EXPECT_EQ(*task("sc").paramsAs<tasks::SelfCollisionParams>().interaction_distance, 0.06);
  EXPECT_EQ(*task("sc").paramsAs<tasks::SelfCollisionParams>().safety_distance, 0.02);
  EXPECT_EQ(task("sc").paramsAs<tasks::SelfCollisionParams>().xi, 0.3);
  EXPECT_FALSE(task("sc").paramsAs<tasks::SelfCollisionParams>().adaptive);
  EXPECT_EQ(task("ct").paramsAs<tasks::ContactTaskParams>().gains.kp, 50.0);
  EXPECT_EQ(*task("ct").paramsAs<tasks::ContactTaskParams>().gains.kv, 7.0);
  EXPECT_EQ(task("po").paramsAs<tasks::PositionParams>().point, Eigen::Vector3d(0.01, 0.02, 0.03));
  EXPECT_EQ(*task("po").paramsAs<tasks::PositionParams>().target, Eigen::Vector3d(0.3, -0.3, 1.0));
  EXPECT_EQ(*task("po").paramsAs<tasks::PositionParams>().gains.kv, 3.0);
  EXPECT_NEAR((*task("orr").paramsAs<tasks::OrientationParams>().target)(2, 1), std::sin(0.1), 1e-15);
  EXPECT_EQ(task("orr").paramsAs<tasks::OrientationParams>().gains.kp, 4.0);
  EXPECT_TRUE(task("orm").paramsAs<tasks::OrientationParams>().target->isIdentity());
  EXPECT_EQ(*task("cm").paramsAs<tasks::ComParams>().target, Eigen::Vector3d(0.0, 0.0, 0.7));
  EXPECT_EQ(task("cb").paramsAs<tasks::ComBoxParams>().lower.x(), -0.1);
  EXPECT_TRUE(std::isinf(task("cb").paramsAs<tasks::ComBoxParams>().upper.y()));
  EXPECT_EQ(task("cb").paramsAs<tasks::ComBoxParams>().damper.interaction, 0.03);
  EXPECT_EQ(task("cb").paramsAs<tasks::ComBoxParams>().damper.safety, 0.005);
  EXPECT_EQ(task("cb").paramsAs<tasks::ComBoxParams>().damper.xi, 0.2);
  EXPECT_FALSE(task("cb").paramsAs<tasks::ComBoxParams>().damper.adaptive);
  EXPECT_EQ(task("jp").paramsAs<tasks::JointPositionParams>().joints.size(), 2u);
  EXPECT_EQ(task("jp").paramsAs<tasks::JointPositionParams>().target[1], -0.1);
  EXPECT_EQ(task("pt").paramsAs<tasks::PostureParams>().target.size(), 32);
  EXPECT_EQ(task("pt").paramsAs<tasks::PostureParams>().gains.kp, 0.5);
  // The tasks are built by the controller (the loader did, for every method); spot-check
  // through the controller's own view.
  const model::RobotModel m = model::RobotModel::fromFiles(c.urdf_path, c.data_path);
  control::Controller ctl(m, buildControllerConfig(lx, m));
  const auto& tl = dynamic_cast<const tasks::TorqueLimitsTask&>(ctl.task(ctl.taskIndex("tl")));
  EXPECT_DOUBLE_EQ(tl.torqueLimits()[3], 0.5 * 300.0);  // RLEG_JOINT3, effort 300 N m
  const auto& sc = dynamic_cast<const tasks::SelfCollisionTask&>(ctl.task(ctl.taskIndex("sc")));
  EXPECT_EQ(sc.rows(), 1);
  EXPECT_EQ(sc.damper().interaction, 0.06);
  for (const std::string& t : taskTypes()) {
    bool used = false;
    for (const auto& ts : lx.tasks) used = used || ts.type == t;
    EXPECT_TRUE(used) << "task type " << t << " not exercised";
  }
  EXPECT_EQ(taskTypes().size(), 15u);
}

TEST(ControllerCase, ErrorsNameFileLineAndKeyPath) {
  auto base = minimalLexdynCase();
  auto with = [&](const std::string& from, const std::string& to) {
    auto s = base;
    const size_t p = s["e_controller"].find(from);
    EXPECT_NE(p, std::string::npos) << from;
    s["e_controller"].replace(p, from.size(), to);
    return s;
  };
  expectError(with("  method: bfgs\n", "  method: newton\n"), {"case.yaml:10: controller.method", "bfgs, ah, gn, wls"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  colour: red\n"),
              {"controller.colour", "unknown key"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  params: {bfgs_secant: sideways}\n"),
              {"case.yaml:12: controller.params.bfgs_secant", "current_multipliers, full_difference, gauss_newton", "sideways"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  params: {multiplier_scale: 2}\n"),
              {"case.yaml:12: controller.params.multiplier_scale", "dt, one"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  params: {ah_add_jtj: maybe}\n"),
              {"case.yaml:12: controller.params.ah_add_jtj"});
  expectError(with("  solver: {paper_rules: true}\n", "  solver: {paper_rules: true, max_iterations: many}\n"),
              {"controller.solver.max_iterations", "expected an integer"});
  expectError(with("  solver: {paper_rules: true}\n", "  solver: {paper_rules: true, last_level_projection: sometimes}\n"),
              {"controller.solver.last_level_projection", "auto, never or always", "sometimes"});
  expectError(with("{name: trust, type: trust_region}", "{name: trust, type: trust_region, delta: -1}"),
              {"controller.tasks[4].delta", "> 0"});
  expectError(with("{name: trust, type: trust_region}", "{name: trust, type: trust_region, radius: 1}"),
              {"controller.tasks[4].radius", "unknown key", "delta"});
  expectError(with("{name: trust, type: trust_region}", "{name: trust, type: trust_zone}"), {"controller.tasks[4].type", "trust_region"});
  expectError(with("frame: RGRASP, target", "frame: RHAND, target"), {"controller.tasks[9].frame", "unknown frame 'RHAND'"});
  expectError(with("gains: {kp: 0.3}}\n    - {name: left_hand", "gains: {kp: fast}}\n    - {name: left_hand"),
              {"controller.tasks[9].gains.kp", "expected a finite number"});
  expectError(with("contact: RIGHT_FOOT}", "contact: RIGHT_HAND}"), {"controller.tasks[5].contact", "unknown contact 'RIGHT_HAND'"});
  expectError(with("tasks: [trust]}", "tasks: [trusty]}"), {"controller.levels[2].tasks[0]", "unknown task 'trusty'"});
  expectError(with("tasks: [trust]}", "tasks: [joint_limits]}"), {"controller.levels[2].tasks[0]", "appears twice"});
  expectError(with("weights: {right_hand: 1.0, left_hand: 1.0, posture: 1.0e-3, wrench: 1.0e-5}",
                   "weights: {right_hand: 1.0, left_hand: 1.0, posture: 1.0e-3}"),
              {"controller.wls_levels[1].weights", "no weight for task(s) wrench"});
  expectError(with("surface: RIGHT_FOOT, sensor", "surface: RIGHT_SOLE, sensor"),
              {"controller.contacts[0].surface", "unknown contact surface 'RIGHT_SOLE'"});
  expectError(with("sensor: LeftHandForceSensor", "sensor: LeftWristSensor"), {"controller.contacts[2].sensor", "unknown force sensor"});
  expectError(with("grasp: left,", "grasp: right,"), {"controller.contacts[2].grasp", "unknown grasp 'right'"});
  expectError(with("initial_contacts: [RIGHT_FOOT, LEFT_FOOT]", "initial_contacts: [RIGHT_FOOT, LEFT_FOOT, POLE]"),
              {"controller.contacts[2].grasp", "switch together"});
  expectError(with("  levels:\n", "  levels_unused:\n"), {"controller.levels_unused", "unknown key"});
  // Contact margins (docs/controller.md, "Contact margins"): ranges, and a CoP margin the sole
  // cannot give, named at the key that gave it.
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  contact_margins: {friction: 1.0}\n"),
              {"case.yaml:12: controller.contact_margins.friction", "[0, 1)"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  contact_margins: {cop_m: -0.01}\n"),
              {"controller.contact_margins.cop_m", "-0.01"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  contact_margins: {min_normal_N: .nan}\n"),
              {"controller.contact_margins.min_normal_N"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  contact_margins: {cop_m: 0.08, tilt: 1}\n"),
              {"controller.contact_margins.tilt", "unknown key"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  contact_margins: {cop_m: 0.08}\n"),
              {"case.yaml:12: controller.contact_margins", "cop_m: 0.08 m leaves no support polygon of contact RIGHT_FOOT",
               "less than 0.07 m", "give this contact its own `margins`"});
  expectError(with("  state_feedback: integrated\n", "  state_feedback: integrated\n  contact_margins: nothing\n"),
              {"controller.contact_margins", "expected `none` (no margin) or a map {friction, cop_m, min_normal_N}"});
  expectError(with("surface: RIGHT_FOOT, sensor", "surface: RIGHT_FOOT, margins: {min_normal_N: -1}, sensor"),
              {"controller.contacts[0].margins.min_normal_N"});
  expectError(with("surface: RIGHT_FOOT, sensor", "surface: RIGHT_FOOT, margins: {cop_m: 0.1}, sensor"),
              {"controller.contacts[0].margins", "leaves no support polygon of contact RIGHT_FOOT"});
  // A task the controller cannot run in a domain: trust_region has no acceleration form.
  expectError(with("{name: hard, tasks: [joint_limits,", "{name: hard, tasks: [trust, joint_limits,"),
              {"controller.wls_levels", "(method wls)", "task \"trust\"", "acceleration"});
  // --method for a hierarchy the case lacks.
  auto s = base;
  const size_t w = s["e_controller"].find("  wls_levels:");
  s["e_controller"] = s["e_controller"].substr(0, w);
  CaseSpec c = loadCase(writeCase(outputDir("controller_case_nowls"), s));
  EXPECT_TRUE(
      containsAll(inputErrorOf([&] { overrideMethod(c, "wls", "--method"); }), {"--method: method wls needs controller.wls_levels"}));
}

// A case without controller.contact_margins plans with exp1's margins scaled to each contact and
// the robot (docs/controller.md, "Contact margins"); `none` is the paper's formulation; a
// contact's own margins replace the default's keys it gives; a grasp takes none.
TEST(ControllerCase, ContactMarginsDefaultToExp1sScaledToTheRobot) {
  // HRP-2's sole (0.216 x 0.140 m) for 637 N: exp1's 0.1, 1 cm (here 14 % of 0.07 m, 9 mm) and 10 N.
  const std::vector<Eigen::Vector3d> sole = {{0.108, 0.07, 0}, {0.108, -0.07, 0}, {-0.108, 0.07, 0}, {-0.108, -0.07, 0}};
  tasks::ContactMargins m = defaultContactMargins(sole, false, 637.0);
  EXPECT_EQ(m.friction, 0.1);
  EXPECT_NEAR(m.cop_m, 0.009, 1e-15);
  EXPECT_NEAR(m.min_normal_N, 10.0, 1e-12);
  // A narrow foot (3 cm wide): 2 mm; a large one is capped at 1 cm; a point foot gets no CoP margin.
  const std::vector<Eigen::Vector3d> narrow = {{0.1, 0.015, 0}, {0.1, -0.015, 0}, {-0.05, 0.015, 0}, {-0.05, -0.015, 0}};
  EXPECT_NEAR(defaultContactMargins(narrow, false, 500.0).cop_m, 0.002, 1e-15);
  const std::vector<Eigen::Vector3d> large = {{0.2, 0.2, 0}, {0.2, -0.2, 0}, {-0.2, 0.2, 0}, {-0.2, -0.2, 0}};
  EXPECT_EQ(defaultContactMargins(large, false, 500.0).cop_m, 0.01);
  const tasks::ContactMargins point = defaultContactMargins({Eigen::Vector3d::Zero()}, true, 160.0);
  EXPECT_EQ(point.cop_m, 0.0);
  EXPECT_NEAR(point.min_normal_N, 10.1, 1e-12);  // 6.3 % of 160 N on its one point
  EXPECT_EQ(defaultContactMargins({}, false, 637.0).min_normal_N, 0.0);

  auto base = minimalLexdynCase();
  const CaseSpec d = loadCase(writeCase(outputDir("controller_case_margins_default"), base));
  ASSERT_TRUE(d.controller.lexdyn.contact_margins_default);
  double mass = 0.0;
  for (const auto& l : model::loadRobotDescription(d.urdf_path, d.data_path, d.robot_options).links) mass += l.mass;
  for (const auto& c : d.controller.lexdyn.contacts) {
    if (c.fixed) {
      EXPECT_EQ(c.margins.friction, 0.0) << c.name;
      EXPECT_EQ(c.margins.min_normal_N, 0.0) << c.name;
      continue;
    }
    const tasks::ContactMargins want = defaultContactMargins(c.points, c.dims == 3, mass * 9.81);
    EXPECT_EQ(c.margins.friction, want.friction) << c.name;
    EXPECT_EQ(c.margins.cop_m, want.cop_m) << c.name;
    EXPECT_EQ(c.margins.min_normal_N, want.min_normal_N) << c.name;
    EXPECT_GT(c.margins.min_normal_N, 0.0) << c.name;
  }
  auto none = base;
  none["e_controller"] += "";
  const size_t at = none["e_controller"].find("  state_feedback: integrated\n");
  ASSERT_NE(at, std::string::npos);
  none["e_controller"].insert(at, "  contact_margins: none\n");
  const CaseSpec n = loadCase(writeCase(outputDir("controller_case_margins_none"), none));
  EXPECT_FALSE(n.controller.lexdyn.contact_margins_default);
  for (const auto& c : n.controller.lexdyn.contacts) {
    EXPECT_EQ(c.margins.friction, 0.0) << c.name;
    EXPECT_EQ(c.margins.cop_m, 0.0) << c.name;
    EXPECT_EQ(c.margins.min_normal_N, 0.0) << c.name;
  }
  auto own = base;
  const size_t rf = own["e_controller"].find("surface: RIGHT_FOOT, sensor");
  ASSERT_NE(rf, std::string::npos);
  own["e_controller"].replace(rf, 27, "surface: RIGHT_FOOT, margins: {cop_m: 0.002}, sensor");
  const CaseSpec o = loadCase(writeCase(outputDir("controller_case_margins_own"), own));
  const ContactEntry& right = o.controller.lexdyn.contacts[static_cast<size_t>(o.controller.lexdyn.findContact("RIGHT_FOOT"))];
  EXPECT_EQ(right.margins.cop_m, 0.002);
  EXPECT_EQ(right.margins.friction, 0.1);  // the default's, kept
  EXPECT_EQ(right.margins.min_normal_N, defaultContactMargins(right.points, false, mass * 9.81).min_normal_N);
  // A slanted strip: its bounding box would ask for 7 mm, the polygon gives less than 3.54 mm; the
  // default halves its CoP margin until the polygon gives it.
  auto slanted = base;
  const size_t sf = slanted["e_controller"].find("surface: RIGHT_FOOT, sensor");
  slanted["e_controller"].replace(sf, 27, "frame: RSOLE, points: [[0, 0, 0], [0.1, 0.1, 0], [0.1, 0.11, 0], [0, 0.01, 0]], sensor");
  const CaseSpec sl = loadCase(writeCase(outputDir("controller_case_margins_slanted"), slanted));
  const ContactEntry& strip = sl.controller.lexdyn.contacts[static_cast<size_t>(sl.controller.lexdyn.findContact("RIGHT_FOOT"))];
  EXPECT_TRUE(strip.margins_default);
  EXPECT_NEAR(strip.margins.cop_m, 0.007 / 2, 1e-15);  // 7 mm does not fit, 3.5 mm does (the strip allows 3.54 mm)
  EXPECT_FALSE(right.margins_default);                 // its own margins
}

TEST(ControllerCase, EventAndCheckErrors) {
  auto s = minimalLexdynCase();
  expectError(withEvent(s, "set_target, task: right_hand, value: [1, 2]"),
              {"case.yaml", "events[0]", "task 'right_hand' takes a target of 3 values, found 2"});
  expectError(withEvent(s, "set_target, task: com_box, lower: [0.1, 0, 0], upper: [-0.1, 1, 1]"), {"events[0]", "task \"com_box\""});
  expectError(withEvent(s, "set_target, task: velocity, value: [1]"), {"events[0]", "has no target"});
  expectError(withEvent(s, "add_contact, contact: HAND"), {"case.yaml:", "events[0].contact", "unknown controller contact 'HAND'"});
  expectError(withEvent(s, "grasp_on, grasp: left"), {"events[0].grasp", "linked to controller contact 'POLE'"});
  expectError(withEvent(s, "swing, task: posture, from: [0, 0, 0], to: [1, 1, 1], period_s: 2"), {"events[0]", "drives 3-D targets"});
  expectError(withEvent(s, "target_trajectory, task: right_hand, file: nowhere.csv"), {"events[0].file", "file not found"});
  const std::string dir = outputDir("controller_case_traj");
  std::ofstream(dir + "/bad.csv") << "t,x,y,z\n0,0,0,0\n1,0,0\n";
  const std::string path = writeCase(dir, withEvent(s, "target_trajectory, task: right_hand, file: bad.csv"));
  EXPECT_TRUE(containsAll(inputErrorOf([&] { loadCase(path); }), {"events[0].file", "bad.csv:3: expected 4 values"}));
  expectError(withCheck(s, "{name: p, type: task_error, tasks: [posture], statistic: final, limit: 1}"),
              {"checks[0].tasks", "not in the hierarchy of method bfgs", "methods:"});
  EXPECT_EQ(errorOf(withCheck(s, "{name: p, type: task_error, tasks: [posture], statistic: final, limit: 1, methods: [wls]}")),
            "<no error>");
  expectError(withCheck(s, "{name: c, type: contact_wrench_match, contact: RIGHT_FOOT, limit_Nm: 3}"),
              {"checks[0]", "missing required key 'limit_N'"});
  expectError(withCheck(s, "{name: c, type: contact_cop, contact: POLE}"), {"checks[0].contact", "support polygon"});
  expectError(withCheck(s, "{name: a, type: augmented_fraction, level: hands, max_fraction: 1}"),
              {"checks[0].level", "not in the hierarchy of method wls"});
  expectError(withCheck(s, "{name: j, type: joint_velocity_hf_energy, cutoff_hz: 150, limit_rad2_per_s2: 1}"),
              {"checks[0].cutoff_hz", "Nyquist"});
  expectError(withCheck(s, "{name: j, type: joint_acceleration_sign_changes, joints: [\"*FINGER*\"], limit_per_s: 1}"),
              {"checks[0].joints[0]", "matches no joint"});
  // Controller checks need the lexdyn controller.
  expectError(withCheck(testing::minimalCase(), "{name: s, type: active_set_peak, limit_iterations: 3}"), {"checks[0].type", "lexdyn"});
}

// --- Target paths ---------------------------------------------------------------------------

TEST(TargetPath, PiecewiseLinearWithHoldAndLoop) {
  const std::vector<double> t = {1.0, 2.0, 4.0};
  const std::vector<Eigen::Vector3d> x = {{0, 0, 0}, {1, 2, 3}, {3, 2, 1}};
  const TargetTrajectory hold(t, x, 0.0, false, "test");
  EXPECT_EQ(hold.raw(0.0), x[0]);
  EXPECT_EQ(hold.raw(1.5), Eigen::Vector3d(0.5, 1.0, 1.5));
  EXPECT_EQ(hold.raw(3.0), Eigen::Vector3d(2.0, 2.0, 2.0));
  EXPECT_EQ(hold.raw(10.0), x[2]);
  EXPECT_EQ(hold.at(1.5), hold.raw(1.5));  // no moving average
  const TargetTrajectory loop(t, x, 0.0, true, "test");
  EXPECT_TRUE(loop.raw(4.5).isApprox(loop.raw(1.5), 1e-15));  // period 3 s
  EXPECT_TRUE(loop.raw(7.0 + 1.0).isApprox(loop.raw(2.0), 1e-12));
}

TEST(TargetPath, MovingAverageIsTheExactWindowMean) {
  const std::vector<double> t = {0.0, 1.0, 2.5, 3.0, 6.0};
  // Continuous when looped (last sample = first), so that the reference quadrature is accurate.
  const std::vector<Eigen::Vector3d> x = {{0, 0, 0}, {1, -1, 2}, {-2, 0.5, 1}, {4, 1, -1}, {0, 0, 0}};
  for (bool looped : {false, true}) {
    const TargetTrajectory tr(t, x, 3.0, looped, "test");
    for (double tau : {-1.0, 0.0, 0.7, 2.0, 3.3, 5.9, 8.0, 14.2}) {
      // Independent reference: midpoint rule on the raw path over [tau - 3, tau].
      const int n = 30000;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int i = 0; i < n; ++i) sum += tr.raw(tau - 3.0 + (i + 0.5) * 3.0 / n);
      const Eigen::Vector3d ref = sum / n;
      EXPECT_LT((tr.at(tau) - ref).norm(), 2e-6) << "tau " << tau << " loop " << looped;
    }
  }
  // Before the start the window holds the first sample: the filtered target starts there.
  const TargetTrajectory tr(t, x, 3.0, false, "test");
  EXPECT_TRUE(tr.at(0.0).isApprox(x[0]));
  EXPECT_NEAR(tr.at(100.0).norm(), 0.0, 1e-12);
}

TEST(TargetPath, CsvFilesAndTheirErrors) {
  const std::string dir = outputDir("target_path_csv");
  std::ofstream(dir + "/ok.csv") << "# comment\nt,x,y,z\n0, 1, 2, 3\n0.5,2,3,4\n\n1,3,4,5\n";
  const TargetTrajectory t = TargetTrajectory::fromCsv(dir + "/ok.csv", 0.0, false);
  EXPECT_EQ(t.samples(), 3);
  EXPECT_EQ(t.raw(0.25), Eigen::Vector3d(1.5, 2.5, 3.5));
  auto err = [&](const std::string& text) {
    std::ofstream(dir + "/bad.csv") << text;
    return inputErrorOf([&] { TargetTrajectory::fromCsv(dir + "/bad.csv", 0.0, false); });
  };
  EXPECT_NE(err("0,0,0,0\n0,1,1,1\n").find("bad.csv:2: times must increase strictly"), std::string::npos);
  EXPECT_NE(err("0,0,0,0\n1,1,x,1\n").find("bad.csv:2: column y: expected a finite number"), std::string::npos);
  EXPECT_NE(err("-1,0,0,0\n1,1,1,1\n").find("bad.csv:1: times must be >= 0"), std::string::npos);
  EXPECT_NE(err("0,0,0,0\n").find("at least 2 samples"), std::string::npos);
  EXPECT_NE(err("t,x,y,z\n0,0,0,0\nt,x,y,z\n").find("bad.csv:3"), std::string::npos);
}

TEST(TargetPath, SwingStartsAtTheMidpointTowardsTo) {
  Swing s;
  s.from = Eigen::Vector3d(-3, -1.5, 0);
  s.to = Eigen::Vector3d(3, -1.5, 2);
  s.period_s = 60.0;
  EXPECT_TRUE(s.at(0.0).isApprox(Eigen::Vector3d(0, -1.5, 1)));
  EXPECT_TRUE(s.at(15.0).isApprox(s.to));
  EXPECT_TRUE(s.at(45.0).isApprox(s.from));
  EXPECT_GT(s.at(1.0).x(), 0.0);
}

}  // namespace
}  // namespace lexdyn::cases
