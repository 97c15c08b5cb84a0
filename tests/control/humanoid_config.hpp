// An exp. 1-like hierarchy on the humanoid (paper sec. IX, method.md §7) for controller tests.
#pragma once

#include <limits>
#include <memory>
#include <string>

#include "lexdyn/control/controller.hpp"
#include "lexdyn/tasks/com_box.hpp"
#include "lexdyn/tasks/contact.hpp"
#include "lexdyn/tasks/contact_force_bounds.hpp"
#include "lexdyn/tasks/equation_of_motion.hpp"
#include "lexdyn/tasks/joint_limits.hpp"
#include "lexdyn/tasks/position.hpp"
#include "lexdyn/tasks/posture.hpp"
#include "lexdyn/tasks/self_collision.hpp"
#include "lexdyn/tasks/torque_limits.hpp"
#include "lexdyn/tasks/trust_region.hpp"
#include "lexdyn/tasks/velocity_min.hpp"
#include "lexdyn/tasks/wrench_min.hpp"

namespace lexdyn::control::test {

inline const std::string kHumanoidDir = std::string(LEXDYN_SOURCE_DIR) + "/models/hrp2kai_like/";

inline model::RobotModel loadHumanoid() {
  return model::RobotModel::fromFiles(kHumanoidDir + "hrp2kai_like.urdf", kHumanoidDir + "hrp2kai_like.yaml");
}

/// Half-sitting with the soles on the ground (z = 0).
inline RobotState halfSitting(const model::RobotModel& m) {
  RobotState s;
  s.q = m.neutralConfiguration();
  s.q.joints = m.posture("half_sitting");
  s.u = Eigen::VectorXd::Zero(m.nv());
  model::ModelData d = m.createData();
  m.update(d, s.q, s.u);
  s.q.base_position.z() -= m.framePlacement(d, m.frameId("RSOLE")).translation().z();
  return s;
}

inline ControllerConfig exp1Config(const model::RobotModel& m, const std::string& method, double handKp = 0.3) {
  ControllerConfig cfg;
  cfg.params.method = method;
  for (const auto& cs : m.description().contact_surfaces) {
    tasks::ContactSpec c;
    c.name = cs.name;
    c.frame = cs.frame;
    c.points = cs.points;
    c.friction = m.description().friction_coefficient;
    cfg.contacts.push_back(c);
  }
  cfg.initial_contacts = {"RIGHT_FOOT", "LEFT_FOOT"};
  const tasks::ContactLayout layout(m.nv(), cfg.contacts);
  auto add = [&](std::unique_ptr<tasks::TaskModel> t) {
    cfg.tasks.push_back(std::move(t));
    return static_cast<int>(cfg.tasks.size()) - 1;
  };
  const int jl = add(std::make_unique<tasks::JointLimitsTask>("joint_limits", m));
  const int fb = add(std::make_unique<tasks::ContactForceBoundsTask>("force_bounds", layout));
  const int eom = add(std::make_unique<tasks::EquationOfMotionTask>("dynamics", m));
  const int tl = add(std::make_unique<tasks::TorqueLimitsTask>("torque_limits", m));
  const int tr = add(std::make_unique<tasks::TrustRegionTask>("trust", m));
  const int sc = add(std::make_unique<tasks::SelfCollisionTask>("collisions", m));
  tasks::ContactTaskParams cr, cl;
  cr.contact = "RIGHT_FOOT";
  cl.contact = "LEFT_FOOT";
  const int crf = add(std::make_unique<tasks::ContactTask>("right_foot", m, layout, cr));
  const int clf = add(std::make_unique<tasks::ContactTask>("left_foot", m, layout, cl));
  tasks::ComBoxParams cb;
  cb.lower = Eigen::Vector3d(-0.05, -0.1, -std::numeric_limits<double>::infinity());
  cb.upper = Eigen::Vector3d(0.07, 0.1, std::numeric_limits<double>::infinity());
  const int com = add(std::make_unique<tasks::ComBoxTask>("com_box", m, cb));
  tasks::PositionParams rh, lh;
  rh.frame = "RGRASP";
  rh.target = Eigen::Vector3d(0.4, -0.5, 1.3);
  rh.gains.kp = handKp;
  lh.frame = "LGRASP";
  lh.target = Eigen::Vector3d(0.4, 0.5, 1.3);
  lh.gains.kp = handKp;
  const int rhi = add(std::make_unique<tasks::PositionTask>("right_hand", m, rh));
  const int lhi = add(std::make_unique<tasks::PositionTask>("left_hand", m, lh));
  const int vm = add(std::make_unique<tasks::VelocityMinTask>("velocity", m));
  const int wm = add(std::make_unique<tasks::WrenchMinTask>("wrench", layout));
  tasks::PostureParams pp;
  pp.posture = "half_sitting";
  const int post = add(std::make_unique<tasks::PostureTask>("posture", m, pp));
  if (method == "wls") {
    cfg.levels = {{"hard", {jl, fb, eom, tl, sc, crf, clf, com}, {}}, {"objective", {rhi, lhi, post, wm}, {1.0, 1.0, 1e-3, 1e-5}}};
  } else {
    cfg.levels = {{"bounds", {jl, fb}, {}},  {"dynamics", {eom, tl}, {}},  {"trust", {tr}, {}},
                  {"collisions", {sc}, {}},  {"contacts", {crf, clf}, {}}, {"com", {com}, {}},
                  {"hands", {rhi, lhi}, {}}, {"velocity", {vm}, {}},       {"wrench", {wm}, {}}};
  }
  return cfg;
}

}  // namespace lexdyn::control::test
