// Helpers for case-file tests: a minimal valid case whose sections tests replace.
#pragma once

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

namespace lexdyn::cases::testing {

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
  for (const auto& [joint, value] : {std::pair<std::string, std::string>{"RLEG_JOINT2: -0.4538", "RLEG_JOINT2: -1.2"},
                                     {"RLEG_JOINT3: 0.8727", "RLEG_JOINT3: 1.8"}}) {
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
