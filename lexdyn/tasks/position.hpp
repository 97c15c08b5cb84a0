// position (equality, 3 rows): PD (pd.hpp, eq. 55/61) on the world position of a point of a
// frame. f(q) = p (world, m), J = the point Jacobian (3 x nv), Jdot u = the point bias.
// Target: d.target = p_d (3, world). Without an initial target the task holds the point where
// it is at the first compute(). Hessian: lexdyn::hessian::accumulatePointHessian.
#pragma once

#include <optional>

#include "lexdyn/tasks/tracking.hpp"

namespace lexdyn::tasks {

struct PositionParams {
  std::string frame;                                ///< model frame name
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< in the frame, m
  std::optional<Eigen::Vector3d> target;            ///< world, m; absent: hold
  PdGains gains;                                    ///< kp default 1 /s^2
};

class PositionTask : public TrackingTask {
 public:
  PositionTask(std::string name, const model::RobotModel& model, const PositionParams& params);

  bool geometric() const override { return true; }
  void compute(const TickContext& ctx, TaskData& d) const override;
  void accumulateHessian(const TickContext& ctx, const TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& w,
                         Eigen::Ref<Eigen::MatrixXd> H) const override;
  void chainDofs(const model::RobotModel& model, std::vector<char>& mask) const override;

  model::FrameId frame() const { return frame_; }
  const Eigen::Vector3d& point() const { return point_; }

 private:
  model::FrameId frame_ = -1;
  int body_ = -1;
  Eigen::Vector3d point_ = Eigen::Vector3d::Zero();
};

}  // namespace lexdyn::tasks
