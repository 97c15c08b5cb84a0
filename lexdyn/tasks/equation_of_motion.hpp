// equation_of_motion (equality): the unactuated rows of the equation of motion with the
// torques substituted out (paper eq. 86; docs/controller.md). 6 rows for a free-flyer robot
// (its base rows), 0 for a fixed base.
//   velocity domain,     x = [u(k+1); dt gamma]:  [M, -Jc^T]_u x = (M u - dt N)_u
//   acceleration domain, x = [udot; gamma]:       [M, -Jc^T]_u x = -N_u
// M and N come from the TickContext; Jc^T from contact_jacobian.hpp (inactive contacts: zero
// columns). Not a task function: d.J stays zero.
#pragma once

#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

class EquationOfMotionTask : public TaskModel {
 public:
  EquationOfMotionTask(std::string name, const model::RobotModel& model);

  int rows() const override { return rows_; }
  TaskKind kind() const override { return TaskKind::Equality; }
  bool supports(Domain) const override { return true; }
  /// The unactuated rows can always be met exactly (by the free-flyer velocity).
  bool separateLevel() const override { return true; }
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;

 private:
  int nv_ = 0, rows_ = 0;
};

/// Data of equation_of_motion and torque_limits: a point Jacobian and Jc^T (nv x ng).
struct DynamicsTaskData : TaskData {
  Eigen::MatrixXd Jp;   ///< 3 x nv
  Eigen::MatrixXd JcT;  ///< nv x ng
};

}  // namespace lexdyn::tasks
