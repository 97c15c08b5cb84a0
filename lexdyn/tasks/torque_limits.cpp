#include "lexdyn/tasks/torque_limits.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

TorqueLimitsTask::TorqueLimitsTask(std::string name, const model::RobotModel& model, const TorqueLimitsParams& params)
    : DynamicsTask(std::move(name), model, model.jointVelocityOffset(), model.numJoints()) {
  requirePositive(params.scale, this->name(), "scale");
  if (params.scale > 1.0) {
    throwTaskInput(this->name(), "scale", "must be in (0, 1] (a fraction of the effort limits), found " + std::to_string(params.scale));
  }
  tau_max_ = params.scale * model.jointTorqueLimits();
}

void TorqueLimitsTask::compute(const TickContext& ctx, TaskData& base) const {
  auto& d = static_cast<DynamicsTaskData&>(base);
  writeDynamicsRows(ctx, d);  // the actuated rows
  const Eigen::MatrixXd& M = *ctx.M;
  const Eigen::VectorXd& N = *ctx.N;
  const Eigen::VectorXd& u = *ctx.u;
  const double dt = ctx.dt;
  for (int j = 0; j < rows_; ++j) {
    const int i = first_ + j;
    if (ctx.domain == Domain::Velocity) {
      const double c = M.row(i).dot(u) - dt * N[i];  // eq. 86, actuated row
      d.lower[j] = c - tau_max_[j] * dt;
      d.upper[j] = c + tau_max_[j] * dt;
    } else {
      d.lower[j] = -tau_max_[j] - N[i];
      d.upper[j] = tau_max_[j] - N[i];
    }
  }
}

}  // namespace lexdyn::tasks
