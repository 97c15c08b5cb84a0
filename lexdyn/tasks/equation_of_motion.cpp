#include "lexdyn/tasks/equation_of_motion.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/contact_jacobian.hpp"

namespace lexdyn::tasks {

DynamicsTask::DynamicsTask(std::string name, const model::RobotModel& model, int first, int rows)
    : TaskModel(std::move(name)), nv_(model.nv()), first_(first), rows_(rows) {}

std::unique_ptr<TaskData> DynamicsTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = makeData<DynamicsTaskData>(layout, true);
  d->Jp.setZero(3, layout.nv());
  d->JcT.setZero(layout.nv(), layout.ng());
  return d;
}

void DynamicsTask::writeDynamicsRows(const TickContext& ctx, DynamicsTaskData& d) const {
  const Eigen::MatrixXd& M = *ctx.M;
  const int ng = ctx.contacts->ng();
  LEXDYN_ALWAYS_ASSERT(M.rows() == nv_ && ctx.N->size() == nv_ && d.JcT.cols() == ng, "dynamics rows: sizes");
  if (ctx.JcT == nullptr) contactJacobianTranspose(ctx, d.Jp, d.JcT);
  const Eigen::MatrixXd& JcT = ctx.JcT != nullptr ? *ctx.JcT : d.JcT;
  LEXDYN_ALWAYS_ASSERT(JcT.rows() == nv_ && JcT.cols() == ng, "dynamics rows: shared Jc^T size");
  d.A.leftCols(nv_) = M.middleRows(first_, rows_);  // eq. 86: [M, -Jc^T] (tau substituted out)
  d.A.rightCols(ng) = -JcT.middleRows(first_, rows_);
}

EquationOfMotionTask::EquationOfMotionTask(std::string name, const model::RobotModel& model)
    : DynamicsTask(std::move(name), model, 0, model.jointVelocityOffset()) {}

void EquationOfMotionTask::compute(const TickContext& ctx, TaskData& base) const {
  if (rows_ == 0) return;
  auto& d = static_cast<DynamicsTaskData&>(base);
  writeDynamicsRows(ctx, d);
  const Eigen::MatrixXd& M = *ctx.M;
  const Eigen::VectorXd& N = *ctx.N;
  const Eigen::VectorXd& u = *ctx.u;
  for (int i = 0; i < rows_; ++i) {
    // Velocity domain: M u - dt N (eq. 86); acceleration domain: -N.
    const double rhs = ctx.domain == Domain::Velocity ? M.row(i).dot(u) - ctx.dt * N[i] : -N[i];
    d.lower[i] = rhs;
    d.upper[i] = rhs;
  }
}

}  // namespace lexdyn::tasks
