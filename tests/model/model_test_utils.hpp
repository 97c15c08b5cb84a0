// Shared helpers for the model tests: model paths and seeded random states.
#pragma once

#include "lexdyn/model/robot_model.hpp"

#include <Eigen/Core>

#include <random>
#include <string>

namespace lexdyn::model::testing {

inline std::string sourcePath(const std::string& rel) { return std::string(LEXDYN_SOURCE_DIR) + "/" + rel; }

inline RobotModel loadModel(const std::string& dir, const std::string& name) {
  return RobotModel::fromFiles(sourcePath(dir + "/" + name + ".urdf"), sourcePath(dir + "/" + name + ".yaml"));
}
inline RobotModel loadHumanoid() { return loadModel("models/hrp2kai_like", "hrp2kai_like"); }

/// Seeded generator of random (but valid) states: joints inside their limits, a tilted base.
class RandomStates {
 public:
  explicit RandomStates(unsigned seed) : rng_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }

  Configuration configuration(const RobotModel& model) {
    Configuration q = model.neutralConfiguration();
    const Eigen::Vector3d e(uniform(-0.6, 0.6), uniform(-0.6, 0.6), uniform(-3.0, 3.0));
    q.base_rotation = rotationFromEulerXYZ(e);
    q.base_position = Eigen::Vector3d(uniform(-1, 1), uniform(-1, 1), uniform(0.2, 1.2));
    if (!model.hasFreeFlyer()) {
      q.base_rotation.setIdentity();
      q.base_position.setZero();
    }
    for (int j = 0; j < model.numJoints(); ++j) {
      double lo = model.jointLowerLimits()[j], hi = model.jointUpperLimits()[j];
      if (!std::isfinite(lo)) lo = -3.0;
      if (!std::isfinite(hi)) hi = 3.0;
      q.joints[j] = uniform(lo, hi);
    }
    return q;
  }
  Eigen::VectorXd velocity(const RobotModel& model, double scale = 1.0) {
    Eigen::VectorXd u(model.nv());
    for (int k = 0; k < u.size(); ++k) u[k] = scale * uniform(-1.0, 1.0);
    return u;
  }

 private:
  std::mt19937 rng_;
};

}  // namespace lexdyn::model::testing
