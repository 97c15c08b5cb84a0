#include "lexdyn/tasks/equation_of_motion.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/contact_jacobian.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

EquationOfMotionTask::EquationOfMotionTask(std::string name, const model::RobotModel& model)
    : TaskModel(std::move(name)), nv_(model.nv()), rows_(model.jointVelocityOffset()) {}

std::unique_ptr<TaskData> EquationOfMotionTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = std::make_unique<DynamicsTaskData>();
  initData(*d, layout);
  d->Jp.setZero(3, layout.nv());
  d->JcT.setZero(layout.nv(), layout.ng());
  std::fill(d->engaged.begin(), d->engaged.end(), 1);
  return d;
}

void EquationOfMotionTask::compute(const TickContext& ctx, TaskData& base) const {
  if (rows_ == 0) return;
  auto& d = static_cast<DynamicsTaskData&>(base);
  const Eigen::MatrixXd& M = *ctx.M;
  const Eigen::VectorXd& N = *ctx.N;
  const Eigen::VectorXd& u = *ctx.u;
  const int ng = ctx.contacts->ng();
  LEXDYN_ALWAYS_ASSERT(M.rows() == nv_ && N.size() == nv_ && d.JcT.cols() == ng, "equation_of_motion: sizes");
  contactJacobianTranspose(ctx, d.Jp, d.JcT);
  d.A.leftCols(nv_) = M.topRows(rows_);                 // eq. 86: [M, -Jc^T] (tau substituted out)
  d.A.rightCols(ng) = -d.JcT.topRows(rows_);
  for (int i = 0; i < rows_; ++i) {
    // Velocity domain: M u - dt N (eq. 86); acceleration domain: -N.
    const double rhs = ctx.domain == Domain::Velocity ? M.row(i).dot(u) - ctx.dt * N[i] : -N[i];
    d.lower[i] = rhs;
    d.upper[i] = rhs;
  }
}

}  // namespace lexdyn::tasks
