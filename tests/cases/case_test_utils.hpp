// Helpers for case-file tests: a minimal valid case whose sections tests replace (and the text
// expectations of tests/common/expect_text.hpp).
#pragma once

#include "../common/expect_text.hpp"

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

namespace lexdyn::cases::testing {

using lexdyn::testing::containsAll;
using lexdyn::testing::inputErrorOf;

inline std::string outputDir(const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(LEXDYN_BINARY_DIR) / "test_output" / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

/// Sections of a case file, keyed by their top-level key, in this order.
inline std::map<std::string, std::string> minimalCase(double duration_s = 0.5) {
  const std::string models = std::string(LEXDYN_SOURCE_DIR) + "/models/hrp2kai_like/";
  return {
      {"a_name", "name: minimal\n"},
      {"b_robot", "robot:\n  urdf: " + models + "hrp2kai_like.urdf\n  data: " + models + "hrp2kai_like.yaml\n"},
      {"c_duration", "duration_s: " + std::to_string(duration_s) + "\n"},
      {"d_initial", "initial_state:\n  posture: half_sitting\n"},
      {"e_controller", "controller:\n  type: posture_servo\n  posture: half_sitting\n"},
      {"f_sim",
       "sim:\n"
       "  contact:\n"
       "    stiffness: 2.0e6\n"
       "    exponent: 1.5\n"
       "    dissipation_s_per_m: 5.0\n"
       "    slip_velocity_m_per_s: 1.0e-3\n"
       "  servo:\n"
       "    setpoint_profile: hermite\n"
       "    gains:\n"
       "      - {match: \"*\", kp: 2000, kd: 40}\n"
       "      - {match: \"*LEG_JOINT*\", kp: 20000, kd: 400}\n"},
      {"g_trace", "trace:\n  frames: [WAIST]\n"},
      {"h_checks", "checks:\n  - {name: waist_drift, type: frame_drift, frame: WAIST, from_s: 0.2, limit_m: 0.01}\n"},
  };
}

/// An exp. 1-like lexdyn controller section (both feet, hands to targets; every method).
inline std::string lexdynController(const std::string& method = "bfgs", const std::string& extra = "") {
  return "controller:\n"
         "  type: lexdyn\n"
         "  method: " +
         method +
         "\n"
         "  state_feedback: integrated\n"
         "  solver: {paper_rules: true}\n"
         "  contacts:\n"
         "    - {name: RIGHT_FOOT, surface: RIGHT_FOOT, sensor: RightFootForceSensor}\n"
         "    - {name: LEFT_FOOT, surface: LEFT_FOOT, sensor: LeftFootForceSensor}\n"
         "    - {name: POLE, frame: LGRASP, points: [[0, 0, 0]], fixed: true, grasp: left, sensor: LeftHandForceSensor}\n"
         "  initial_contacts: [RIGHT_FOOT, LEFT_FOOT]\n"
         "  tasks:\n"
         "    - {name: joint_limits, type: joint_limits}\n"
         "    - {name: force_bounds, type: contact_force_bounds}\n"
         "    - {name: dynamics, type: equation_of_motion}\n"
         "    - {name: torque_limits, type: torque_limits}\n"
         "    - {name: trust, type: trust_region}\n"
         "    - {name: right_foot, type: contact, contact: RIGHT_FOOT}\n"
         "    - {name: left_foot, type: contact, contact: LEFT_FOOT}\n"
         "    - {name: pole, type: contact, contact: POLE}\n"
         "    - {name: com_box, type: com_box, lower: [-0.03, -0.1, -.inf], upper: [0.03, 0.1, .inf]}\n"
         "    - {name: right_hand, type: position, frame: RGRASP, target: [0.3, -0.4, 0.9], gains: {kp: 0.3}}\n"
         "    - {name: left_hand, type: position, frame: LGRASP, gains: {kp: 0.3}}\n"
         "    - {name: velocity, type: velocity_min}\n"
         "    - {name: wrench, type: wrench_min}\n"
         "    - {name: posture, type: posture, posture: half_sitting}\n" +
         extra +
         "  levels:\n"
         "    - {name: bounds, tasks: [joint_limits, force_bounds]}\n"
         "    - {name: dynamics, tasks: [dynamics, torque_limits]}\n"
         "    - {name: trust, tasks: [trust]}\n"
         "    - {name: contacts, tasks: [right_foot, left_foot, pole]}\n"
         "    - {name: com, tasks: [com_box]}\n"
         "    - {name: hands, tasks: [right_hand, left_hand]}\n"
         "    - {name: velocity, tasks: [velocity]}\n"
         "    - {name: wrench, tasks: [wrench]}\n"
         "  wls_levels:\n"
         "    - {name: hard, tasks: [joint_limits, force_bounds, dynamics, torque_limits, right_foot, left_foot, pole, com_box]}\n"
         "    - {name: objective, tasks: [right_hand, left_hand, posture, wrench],\n"
         "       weights: {right_hand: 1.0, left_hand: 1.0, posture: 1.0e-3, wrench: 1.0e-5}}\n";
}

/// minimalCase() with the lexdyn controller above and a simulator grasp `left` on LGRASP.
inline std::map<std::string, std::string> minimalLexdynCase(double duration_s = 0.3, const std::string& method = "bfgs") {
  auto s = minimalCase(duration_s);
  s["e_controller"] = lexdynController(method);
  s["f_sim"] +=
      "  grasps:\n    - {name: left, frame: LGRASP, stiffness_N_per_m: 2e4, damping_Ns_per_m: 400,"
      " rot_stiffness_Nm_per_rad: 500, rot_damping_Nms_per_rad: 10}\n";
  s["g_trace"] = "trace:\n  frames: [WAIST, RGRASP]\n";
  s["h_checks"] = "checks:\n  - {name: hands, type: task_error, tasks: [right_hand], statistic: final, limit: 10.0}\n";
  return s;
}

/// A copy of the humanoid's data file in `dir` with an extra posture `one_leg` (the right foot
/// lifted: no static equilibrium on the feet). Returns its path.
inline std::string dataFileWithOneLegPosture(const std::string& dir) {
  const std::string models = std::string(LEXDYN_SOURCE_DIR) + "/models/hrp2kai_like/";
  std::ifstream in(models + "hrp2kai_like.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t a = text.find("  half_sitting:\n");
  const size_t b = text.find("\n\n", a);
  std::string posture = text.substr(a, b == std::string::npos ? std::string::npos : b - a);
  posture.replace(0, 15, "  one_leg:");
  for (const auto& [joint, value] :
       {std::pair<std::string, std::string>{"RLEG_JOINT2: -0.4538", "RLEG_JOINT2: -1.2"}, {"RLEG_JOINT3: 0.8727", "RLEG_JOINT3: 1.8"}}) {
    posture.replace(posture.find(joint), joint.size(), value);
  }
  text.insert(b == std::string::npos ? text.size() : b, "\n" + posture);
  const std::string path = dir + "/one_leg.yaml";
  std::ofstream(path) << text;
  return path;
}

inline std::string writeCase(const std::string& dir, const std::map<std::string, std::string>& sections,
                             const std::string& file = "case.yaml") {
  const std::string path = dir + "/" + file;
  std::ofstream out(path);
  for (const auto& kv : sections) out << kv.second;
  return path;
}

}  // namespace lexdyn::cases::testing
