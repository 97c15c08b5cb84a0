// Shared helpers of the Hessian tests: models, seeded configurations, and the coordinate chart
// of the analytic Hessians.
//
// The chart. The analytic Hessians are second derivatives with respect to the coordinates whose
// rates are u at the current configuration q0: joint angles / displacements, base translation,
// and base Euler angles re-zeroed at q0 (R = Rx(d0) Ry(d1) Rz(d2) R0). One call
//   q(delta) = RobotModel::integrate(q0, delta, 1)
// is exactly that chart, for the whole vector delta at once (composing two integrate calls
// would re-zero the Euler angles in between and leave the chart).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "lexdyn/model/robot_model.hpp"

namespace lexdyn::hessian::testing {

inline std::string sourcePath(const std::string& rel) { return std::string(LEXDYN_SOURCE_DIR) + "/" + rel; }

inline model::RobotModel loadModel(const std::string& dir, const std::string& name) {
  return model::RobotModel::fromFiles(sourcePath(dir + "/" + name + ".urdf"), sourcePath(dir + "/" + name + ".yaml"));
}
inline model::RobotModel loadHumanoid() { return loadModel("models/hrp2kai_like", "hrp2kai_like"); }
inline model::RobotModel loadPlanar3r() { return loadModel("models/planar_3r", "planar_3r"); }
inline model::RobotModel loadArm7() { return loadModel("models/arm_7dof", "arm_7dof"); }
/// Free-flyer test model with a revolute -> prismatic -> revolute branch (tests/data/hessian).
inline model::RobotModel loadBranched() { return loadModel("tests/data/hessian", "branched_rpr"); }
/// Coupled mimic joints: the tree's extra dofs reduced onto their masters.
inline model::RobotModel loadCoupled() { return loadModel("tests/data/model", "coupled"); }

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : gen_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(gen_); }
  Eigen::VectorXd uniformVector(Eigen::Index n, double lo = -1.0, double hi = 1.0) {
    Eigen::VectorXd v(n);
    for (Eigen::Index i = 0; i < n; ++i) v[i] = uniform(lo, hi);
    return v;
  }
  Eigen::MatrixXd symmetric(Eigen::Index n, double scale = 1.0) {
    Eigen::MatrixXd A(n, n);
    for (Eigen::Index j = 0; j < n; ++j) {
      for (Eigen::Index i = j; i < n; ++i) {
        A(i, j) = scale * uniform(-1.0, 1.0);
        A(j, i) = A(i, j);
      }
    }
    return A;
  }
  std::mt19937_64& gen() { return gen_; }

 private:
  std::mt19937_64 gen_;
};

/// A random configuration: joints `spread` around `posture` (or uniform in the limits when the
/// posture is empty), clipped to the limits; a free-flyer base rotated by Euler angles up to
/// 0.6 rad in roll/pitch and any yaw, and displaced.
inline model::Configuration randomConfiguration(const model::RobotModel& m, Rng& rng, const std::string& posture, double spread) {
  model::Configuration q = m.neutralConfiguration();
  if (m.hasFreeFlyer()) {
    q.base_rotation = model::rotationFromEulerXYZ(Eigen::Vector3d(rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-3.0, 3.0)));
    q.base_position = Eigen::Vector3d(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(0.5, 1.0));
  }
  for (int j = 0; j < m.numJoints(); ++j) {
    double lo = m.jointLowerLimits()[j], hi = m.jointUpperLimits()[j];
    if (!std::isfinite(lo)) lo = -3.0;
    if (!std::isfinite(hi)) hi = 3.0;
    double v = posture.empty() ? rng.uniform(lo, hi) : m.posture(posture)[j] + rng.uniform(-spread, spread);
    q.joints[j] = std::min(hi, std::max(lo, v));
  }
  return q;
}

/// Rotation vector (log map) of a rotation matrix.
inline Eigen::Vector3d rotationVector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

/// Rates of the chart coordinates delta -> u at q(delta): u = E(delta) delta_dot, E the identity
/// except for the free-flyer's angular block [e_x, Rx(d0) e_y, Rx(d0) Ry(d1) e_z].
inline Eigen::Matrix3d eulerRateMap(const Eigen::Vector3d& d) {
  const Eigen::Matrix3d Rx = Eigen::AngleAxisd(d[0], Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(d[1], Eigen::Vector3d::UnitY()).toRotationMatrix();
  Eigen::Matrix3d E;
  E.col(0) = Eigen::Vector3d::UnitX();
  E.col(1) = Rx * Eigen::Vector3d::UnitY();
  E.col(2) = Rx * Ry * Eigen::Vector3d::UnitZ();
  return E;
}

}  // namespace lexdyn::hessian::testing
