// joint_position (equality, one row per selected joint): PD (pd.hpp, eq. 55/61) on joint
// positions, e.g. the head yaw of the paper's exp. 2-3. f(q) = q_j (linear: J is a selection of
// u, Jdot u = 0, no Hessian). Target d.target = the selected joints' targets (rad or m, in the
// order of `joints`); without an initial target the task holds the joints at the first compute().
#pragma once

#include "lexdyn/tasks/tracking.hpp"

namespace lexdyn::tasks {

struct JointPositionParams {
  std::vector<std::string> joints;  ///< model joint names, at least one, no repetition
  Eigen::VectorXd target;           ///< one per joint; empty: hold
  PdGains gains;
};

/// Base of the joint-space PD tasks (joint_position, posture): one row per joint of joints(),
/// e = target - q_j, J u = qdot_j, Jdot u = 0 (eq. 55, 61).
class JointTrackingTask : public TrackingTask {
 public:
  /// A and J: the unit rows of the joints' velocities (constant).
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  /// Allocation-free.
  void compute(const TickContext& ctx, TaskData& d) const override;
  bool velocityOnly() const override { return true; }

  const std::vector<int>& joints() const { return joints_; }  ///< model joint indices

 protected:
  JointTrackingTask(std::string name, const model::RobotModel& model, std::vector<int> joints);
  /// The initial target: one value per joint (InputError otherwise), or none when empty.
  void setInitialJointTarget(const Eigen::VectorXd& target);

 private:
  int offset_ = 0;
  std::vector<int> joints_;
};

class JointPositionTask : public JointTrackingTask {
 public:
  JointPositionTask(std::string name, const model::RobotModel& model, const JointPositionParams& params);
};

}  // namespace lexdyn::tasks
