// joint_position (equality, one row per selected joint): PD (pd.hpp, eq. 55/61) on joint
// positions, e.g. the head yaw of the paper's exp. 2-3. f(q) = q_j (linear: J is a selection of
// u, Jdot u = 0, no Hessian). Target d.target = the selected joints' targets (rad or m, in the
// order of `joints`); without an initial target the task holds the joints at the first compute().
#pragma once

#include "lexdyn/tasks/pd.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

struct JointPositionParams {
  std::vector<std::string> joints;  ///< model joint names, at least one, no repetition
  Eigen::VectorXd target;           ///< one per joint; empty: hold
  PdGains gains;
};

class JointPositionTask : public TaskModel {
 public:
  JointPositionTask(std::string name, const model::RobotModel& model, const JointPositionParams& params);

  int rows() const override { return static_cast<int>(joints_.size()); }
  TaskKind kind() const override { return TaskKind::Equality; }
  bool hasFunction() const override { return true; }
  bool supports(Domain) const override { return true; }
  int targetSize() const override { return rows(); }
  void checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const override;

  /// A and J: the unit rows of the selected joints' velocities (constant).
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  /// Back to the initial target (or to holding at the next compute() when there is none).
  void reset(TaskData& d) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;

  const std::vector<int>& joints() const { return joints_; }  ///< model joint indices
  const Pd& gains() const { return pd_; }

 private:
  int nv_ = 0, offset_ = 0;
  std::vector<int> joints_;
  Eigen::VectorXd initial_target_;
  Pd pd_;
};

/// Rows of a joint-space PD task (joint_position, posture): e = target - q_j, J u = qdot_j,
/// Jdot u = 0 (eq. 55, 61). Allocation-free.
void computeJointPdRows(const TickContext& ctx, const Pd& pd, int offset, const std::vector<int>& joints, TaskData& d);

}  // namespace lexdyn::tasks
