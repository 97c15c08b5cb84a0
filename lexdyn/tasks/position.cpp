#include "lexdyn/tasks/position.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace lexdyn::tasks {

PositionTask::PositionTask(std::string name, const model::RobotModel& model, const PositionParams& params)
    : TrackingTask(std::move(name), model, 3, 3) {
  frame_ = resolveFrame(model, params.frame, this->name(), "frame");
  body_ = model.frameBody(frame_);
  requireFinite(params.point, this->name(), "point");
  point_ = params.point;
  if (params.target) setInitialTarget(*params.target);
  pd_ = resolvePd(params.gains, this->name());
}

void PositionTask::compute(const TickContext& ctx, TaskData& d) const {
  const model::RobotModel& model = *ctx.model;
  const model::ModelData& data = *ctx.data;
  model.pointJacobian(data, frame_, point_, d.J);
  const Eigen::Vector3d p = model.pointPosition(data, frame_, point_);
  holdTarget(d, p);
  const Eigen::Vector3d e = d.target.head<3>() - p;
  writePdRows<3>(ctx, pd_, e, model.pointBias(data, frame_, point_), nv_, d);  // eq. 61 / 55
}

void PositionTask::accumulateHessian(const TickContext& ctx, const TaskData&, const Eigen::Ref<const Eigen::VectorXd>& w,
                                     Eigen::Ref<Eigen::MatrixXd> H) const {
  LEXDYN_ALWAYS_ASSERT(ctx.hessian != nullptr && w.size() == 3, "position: accumulateHessian needs ctx.hessian, w(3)");
  hessian::accumulatePointHessian(*ctx.model, *ctx.data, *ctx.hessian, frame_, point_, Eigen::Vector3d(w), H);
}

void PositionTask::chainDofs(const model::RobotModel& model, std::vector<char>& mask) const { markBodyChain(model, body_, mask); }

}  // namespace lexdyn::tasks
