// torque_limits (inequality, nj rows): the actuated rows of the equation of motion give the
// torque (docs/controller.md, "Decision variables"), bounded by the URDF effort limits times
// `scale`:
//   velocity domain:     -tau_max dt <= [M, -Jc^T]_a x - (M u - dt N)_a <= tau_max dt
//                        (dt tau = M (u(k+1) - u) + dt N - Jc^T dt gamma, eq. 86)
//   acceleration domain: -tau_max - N_a <= [M, -Jc^T]_a x <= tau_max - N_a
// Row j is the row of joint j (u index jointVelocityOffset() + j). Not a task function.
#pragma once

#include "lexdyn/tasks/equation_of_motion.hpp"

namespace lexdyn::tasks {

struct TorqueLimitsParams {
  double scale = 1.0;  ///< fraction of the URDF effort limits, in (0, 1]
};

class TorqueLimitsTask : public DynamicsTask {
 public:
  TorqueLimitsTask(std::string name, const model::RobotModel& model, const TorqueLimitsParams& params = {});

  TaskKind kind() const override { return TaskKind::Inequality; }
  void compute(const TickContext& ctx, TaskData& d) const override;

  const Eigen::VectorXd& torqueLimits() const { return tau_max_; }  ///< Nm (N), per joint

 private:
  Eigen::VectorXd tau_max_;
};

}  // namespace lexdyn::tasks
