// orientation (equality, 3 rows): PD (pd.hpp, eq. 55/61) on the orientation of a frame with the
// error e = log(R_d R^T) (rotation vector, world axes).
//
// Task function: at every tick the function is re-centred, f(q) = log(R(q) R_k^T) with R_k the
// frame's rotation at this tick's measured state, and f_d = log(R_d R_k^T). Then f(q_k) = 0,
// e = f_d - f(q_k) = log(R_d R^T) exactly, J = df/du = the frame's angular Jacobian exactly, and
// Jdot u = the frame's angular acceleration bias (d/dt of J_l^{-1}(f) omega at f = 0 is
// omegadot). This is the function whose second derivatives lexdyn::hessian computes
// (kinematic_hessian.hpp). Target: d.target = R_d, 9 values row-major; without an initial target
// the task holds the frame's orientation at the first compute().
#pragma once

#include <optional>

#include "lexdyn/tasks/tracking.hpp"

namespace lexdyn::tasks {

struct OrientationParams {
  std::string frame;
  std::optional<Eigen::Matrix3d> target;  ///< R_world_frame desired; absent: hold
  PdGains gains;
};

struct OrientationTaskData : TaskData {
  Eigen::MatrixXd J6;  ///< 6 x nv frame Jacobian workspace
};

class OrientationTask : public TrackingTask {
 public:
  OrientationTask(std::string name, const model::RobotModel& model, const OrientationParams& params);

  bool geometric() const override { return true; }
  /// Finite, a rotation (orthonormal to 1e-6, det 1).
  void checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const override;
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;
  void accumulateHessian(const TickContext& ctx, const TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& w,
                         Eigen::Ref<Eigen::MatrixXd> H) const override;
  void chainDofs(const model::RobotModel& model, std::vector<char>& mask) const override;

  model::FrameId frame() const { return frame_; }

 private:
  model::FrameId frame_ = -1;
  int body_ = -1;
};

/// 9 values, row-major, of a rotation matrix (the target layout of orientation tasks).
Eigen::Matrix<double, 9, 1> rotationToTarget(const Eigen::Matrix3d& R);
Eigen::Matrix3d rotationFromTarget(const Eigen::Ref<const Eigen::VectorXd>& target);

}  // namespace lexdyn::tasks
