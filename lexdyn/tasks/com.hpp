// com (equality, 3 rows): PD (pd.hpp, eq. 55/61) on the centre of mass. f(q) = c (world, m),
// J = the CoM Jacobian, Jdot u = the CoM bias. Target d.target = c_d (3); without an initial
// target the task holds the CoM where it is at the first compute(). Hessian:
// lexdyn::hessian::accumulateComHessian.
#pragma once

#include <optional>

#include "lexdyn/tasks/tracking.hpp"

namespace lexdyn::tasks {

struct ComParams {
  std::optional<Eigen::Vector3d> target;  ///< world, m; absent: hold
  PdGains gains;
};

class ComTask : public TrackingTask {
 public:
  ComTask(std::string name, const model::RobotModel& model, const ComParams& params = {});

  bool geometric() const override { return true; }
  void compute(const TickContext& ctx, TaskData& d) const override;
  void accumulateHessian(const TickContext& ctx, const TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& w,
                         Eigen::Ref<Eigen::MatrixXd> H) const override;
  /// Every dof that moves a body with mass.
  void chainDofs(const model::RobotModel& model, std::vector<char>& mask) const override;
};

/// Marks every dof that moves a body of positive mass (the chain of CoM tasks).
void markMassiveBodiesChain(const model::RobotModel& model, std::vector<char>& mask);
/// H += sum_i w_i d^2 c_i / dq^2 for the three rows of the CoM c (com, com_box; w: 3 entries).
void accumulateComRowsHessian(const TickContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& w, Eigen::Ref<Eigen::MatrixXd> H);

}  // namespace lexdyn::tasks
