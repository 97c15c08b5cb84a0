#include "lexdyn/tasks/torque_limits.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/contact_jacobian.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

TorqueLimitsTask::TorqueLimitsTask(std::string name, const model::RobotModel& model, const TorqueLimitsParams& params)
    : TaskModel(std::move(name)), nv_(model.nv()), nj_(model.numJoints()), offset_(model.jointVelocityOffset()) {
  requirePositive(params.scale, this->name(), "scale");
  if (params.scale > 1.0) {
    throwTaskInput(this->name(), "scale", "must be in (0, 1] (a fraction of the effort limits), found " +
                                              std::to_string(params.scale));
  }
  tau_max_ = params.scale * model.jointTorqueLimits();
}

std::unique_ptr<TaskData> TorqueLimitsTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = std::make_unique<DynamicsTaskData>();
  initData(*d, layout);
  d->Jp.setZero(3, layout.nv());
  d->JcT.setZero(layout.nv(), layout.ng());
  std::fill(d->engaged.begin(), d->engaged.end(), 1);
  return d;
}

void TorqueLimitsTask::compute(const TickContext& ctx, TaskData& base) const {
  auto& d = static_cast<DynamicsTaskData&>(base);
  const Eigen::MatrixXd& M = *ctx.M;
  const Eigen::VectorXd& N = *ctx.N;
  const Eigen::VectorXd& u = *ctx.u;
  const int ng = ctx.contacts->ng();
  LEXDYN_ALWAYS_ASSERT(M.rows() == nv_ && N.size() == nv_ && d.JcT.cols() == ng, "torque_limits: sizes");
  contactJacobianTranspose(ctx, d.Jp, d.JcT);
  d.A.leftCols(nv_) = M.bottomRows(nj_);
  d.A.rightCols(ng) = -d.JcT.bottomRows(nj_);
  const double dt = ctx.dt;
  for (int j = 0; j < nj_; ++j) {
    const int i = offset_ + j;
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
