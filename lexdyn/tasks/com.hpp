// com (equality, 3 rows): PD (pd.hpp, eq. 55/61) on the centre of mass. f(q) = c (world, m),
// J = the CoM Jacobian, Jdot u = the CoM bias. Target d.target = c_d (3); without an initial
// target the task holds the CoM where it is at the first compute(). Hessian:
// lexdyn::hessian::accumulateComHessian.
#pragma once

#include <optional>

#include "lexdyn/tasks/pd.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

struct ComParams {
  std::optional<Eigen::Vector3d> target;  ///< world, m; absent: hold
  PdGains gains;
};

class ComTask : public TaskModel {
 public:
  ComTask(std::string name, const model::RobotModel& model, const ComParams& params = {});

  int rows() const override { return 3; }
  TaskKind kind() const override { return TaskKind::Equality; }
  bool hasFunction() const override { return true; }
  bool geometric() const override { return true; }
  bool supports(Domain) const override { return true; }
  int targetSize() const override { return 3; }
  void checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const override;

  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  /// Back to the initial target (or to holding at the next compute() when there is none).
  void reset(TaskData& d) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;
  void accumulateHessian(const TickContext& ctx, const TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& w,
                         Eigen::Ref<Eigen::MatrixXd> H) const override;
  /// Every dof that moves a body with mass.
  void chainDofs(const model::RobotModel& model, std::vector<char>& mask) const override;

  const Pd& gains() const { return pd_; }

 private:
  int nv_ = 0;
  std::optional<Eigen::Vector3d> initial_target_;
  Pd pd_;
};

/// Marks every dof that moves a body of positive mass (the chain of CoM tasks).
void markMassiveBodiesChain(const model::RobotModel& model, std::vector<char>& mask);

}  // namespace lexdyn::tasks
