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

/// Data of equation_of_motion and torque_limits: a point Jacobian and Jc^T (nv x ng).
struct DynamicsTaskData : TaskData {
  Eigen::MatrixXd Jp;   ///< 3 x nv
  Eigen::MatrixXd JcT;  ///< nv x ng
};

/// Base of equation_of_motion and torque_limits: their rows are the rows first .. first + rows - 1
/// of the equation of motion with the torques substituted out, A = [M, -Jc^T] (eq. 86).
class DynamicsTask : public TaskModel {
 public:
  int rows() const override { return rows_; }
  bool supports(Domain) const override { return true; }
  /// A DynamicsTaskData, every row engaged.
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;

 protected:
  DynamicsTask(std::string name, const model::RobotModel& model, int first, int rows);
  /// d.A = the task's rows of [M, -Jc^T] (eq. 86), with the tick's shared ctx.JcT or, without
  /// one, d.JcT = Jc^T computed here (contact_jacobian.hpp). Allocation-free.
  void writeDynamicsRows(const TickContext& ctx, DynamicsTaskData& d) const;

  int nv_ = 0, first_ = 0, rows_ = 0;
};

class EquationOfMotionTask : public DynamicsTask {
 public:
  EquationOfMotionTask(std::string name, const model::RobotModel& model);

  TaskKind kind() const override { return TaskKind::Equality; }
  /// The unactuated rows can always be met exactly (by the free-flyer velocity).
  bool separateLevel() const override { return true; }
  void compute(const TickContext& ctx, TaskData& d) const override;
};

}  // namespace lexdyn::tasks
