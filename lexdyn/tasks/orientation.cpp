#include "lexdyn/tasks/orientation.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace lexdyn::tasks {

Eigen::Matrix<double, 9, 1> rotationToTarget(const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 9, 1> t;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) t[3 * r + c] = R(r, c);
  return t;
}

Eigen::Matrix3d rotationFromTarget(const Eigen::Ref<const Eigen::VectorXd>& target) {
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = target[3 * r + c];
  return R;
}

OrientationTask::OrientationTask(std::string name, const model::RobotModel& model, const OrientationParams& params)
    : TrackingTask(std::move(name), model, 3, 9) {
  frame_ = resolveFrame(model, params.frame, this->name(), "frame");
  body_ = model.frameBody(frame_);
  if (params.target) setInitialTarget(rotationToTarget(*params.target));
  pd_ = resolvePd(params.gains, this->name());
}

void OrientationTask::checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const {
  requireRotation(rotationFromTarget(target), name(), "target");
}

std::unique_ptr<TaskData> OrientationTask::createData(const ContactLayout& layout) const {
  auto d = makeTrackingData<OrientationTaskData>(layout);
  d->J6.setZero(6, nv_);
  return d;
}

void OrientationTask::compute(const TickContext& ctx, TaskData& base) const {
  auto& d = static_cast<OrientationTaskData&>(base);
  const model::RobotModel& model = *ctx.model;
  const model::ModelData& data = *ctx.data;
  model.frameJacobian(data, frame_, d.J6);
  d.J = d.J6.bottomRows(3);  // angular rows
  const Eigen::Matrix3d R = model.framePlacement(data, frame_).linear();
  holdTarget(d, rotationToTarget(R));
  const Eigen::Vector3d e = rotationError(rotationFromTarget(d.target), R);  // log(R_d R^T)
  const Eigen::Vector3d bias = model.frameBias(data, frame_).tail<3>();      // angular Jdot u
  writePdRows<3>(ctx, pd_, e, bias, nv_, d);                                 // eq. 61 / 55
}

void OrientationTask::accumulateHessian(const TickContext& ctx, const TaskData&, const Eigen::Ref<const Eigen::VectorXd>& w,
                                        Eigen::Ref<Eigen::MatrixXd> H) const {
  LEXDYN_ALWAYS_ASSERT(ctx.hessian != nullptr && w.size() == 3, "orientation: accumulateHessian needs ctx.hessian, w(3)");
  hessian::accumulateOrientationHessian(*ctx.model, *ctx.data, *ctx.hessian, frame_, Eigen::Vector3d(w), H);
}

void OrientationTask::chainDofs(const model::RobotModel& model, std::vector<char>& mask) const { markBodyChain(model, body_, mask); }

}  // namespace lexdyn::tasks
