// The planar 3R arm (models/planar_3r) driven to an out-of-reach target, as the paper's
// hierarchy: trust region (optional), the tool's position task, minimum velocity. Shared by the
// tests that run it in an ideal loop (the next state is the command).
#pragma once

#include <memory>
#include <string>

#include "lexdyn/control/controller.hpp"
#include "lexdyn/tasks/position.hpp"
#include "lexdyn/tasks/trust_region.hpp"
#include "lexdyn/tasks/velocity_min.hpp"

namespace lexdyn::control::testing {

inline const std::string& planarArmDir() {
  static const std::string dir = std::string(LEXDYN_SOURCE_DIR) + "/models/planar_3r/";
  return dir;
}

inline model::RobotModel planarArm() {
  return model::RobotModel::fromFiles(planarArmDir() + "planar_3r.urdf", planarArmDir() + "planar_3r.yaml");
}

/// Levels: trust, tool, velocity (the tool is level 1), or tool, velocity without the trust region.
inline ControllerConfig planarArmConfig(const model::RobotModel& m, const ControllerParams& params, bool trust_region,
                                        const Eigen::Vector3d& target = Eigen::Vector3d(2.0, 0.0, 0.5)) {
  ControllerConfig cfg;
  cfg.params = params;
  tasks::PositionParams pp;
  pp.frame = "tool";
  pp.target = target;
  pp.gains.kp = 10.0;
  cfg.tasks.push_back(std::make_unique<tasks::PositionTask>("tool", m, pp));
  cfg.tasks.push_back(std::make_unique<tasks::VelocityMinTask>("velocity", m));
  if (trust_region) {
    cfg.tasks.push_back(std::make_unique<tasks::TrustRegionTask>("trust", m));
    cfg.levels = {{"trust", {2}, {}}, {"tool", {0}, {}}, {"velocity", {1}, {}}};
  } else {
    cfg.levels = {{"tool", {0}, {}}, {"velocity", {1}, {}}};
  }
  return cfg;
}

/// At rest in the data file's "bent" posture.
inline RobotState planarArmStart(const model::RobotModel& m) {
  RobotState s;
  s.q = m.neutralConfiguration();
  s.q.joints = m.posture("bent");
  s.u = Eigen::VectorXd::Zero(m.nv());
  return s;
}

}  // namespace lexdyn::control::testing
