#include "lexdyn/tasks/contact.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"
#include "lexdyn/tasks/contact_jacobian.hpp"

namespace lexdyn::tasks {

ContactTask::ContactTask(std::string name, const model::RobotModel& model, const ContactLayout& layout, const ContactTaskParams& params)
    : TaskModel(std::move(name)), nv_(model.nv()), ng_(layout.ng()) {
  if (layout.nv() != nv_) {
    throwTaskInput(this->name(), "",
                   "the contact layout has nv = " + std::to_string(layout.nv()) + ", the model nv = " + std::to_string(nv_));
  }
  contact_ = layout.find(params.contact);
  if (contact_ < 0) {
    std::string known;
    for (int c = 0; c < layout.count(); ++c) known += (c ? ", " : "") + layout.contact(c).name;
    throwTaskInput(this->name(), "contact", "unknown contact '" + params.contact + "' (contacts: " + known + ")");
  }
  frame_ = layout.contact(contact_).frame;
  if (frame_ < 0 || frame_ >= model.numFrames()) {
    throwTaskInput(this->name(), "contact", "contact '" + params.contact + "' has no valid frame");
  }
  body_ = model.frameBody(frame_);
  point_ = layout.contact(contact_).point;
  if (point_) {
    if (layout.contact(contact_).points.size() != 1) {
      throwTaskInput(this->name(), "contact", "point contact '" + params.contact + "' needs exactly one point");
    }
    point_in_frame_ = layout.contact(contact_).points[0];
  }
  pd_ = resolvePd(params.gains, this->name());
}

std::unique_ptr<TaskData> ContactTask::createData(const ContactLayout& layout) const {
  requireLayoutSizes(layout, nv_, ng_);
  return makeData<ContactTaskData>(layout, false);
}

void ContactTask::reset(TaskData& d) const { static_cast<ContactTaskData&>(d).holding = false; }

void ContactTask::compute(const TickContext& ctx, TaskData& base) const {
  auto& d = static_cast<ContactTaskData&>(base);
  if (!contactActive(ctx, contact_)) {
    d.holding = false;
    d.A.setZero();
    d.J.setZero();
    d.lower.setZero();
    d.upper.setZero();
    d.error.setZero();
    std::fill(d.engaged.begin(), d.engaged.end(), 0);
    return;
  }
  const model::RobotModel& model = *ctx.model;
  const model::ModelData& data = *ctx.data;
  const Eigen::Isometry3d X = model.framePlacement(data, frame_);
  if (point_) {
    // A point contact: the point's world position, held where the contact was made.
    const Eigen::Vector3d p = X * point_in_frame_;
    if (!d.holding) {
      d.position = p;
      d.rotation = X.linear();
      d.holding = true;
    }
    model.pointJacobian(data, frame_, point_in_frame_, d.J);
    const Eigen::Vector3d bias = model.pointBias(data, frame_, point_in_frame_);  // Jdot u of the point
    const Eigen::Vector3d e = d.position - p;
    writePdRows<3>(ctx, pd_, e, bias, nv_, d);
    std::fill(d.engaged.begin(), d.engaged.end(), 1);
    return;
  }
  if (!d.holding) {  // the contact is made: hold this pose
    d.position = X.translation();
    d.rotation = X.linear();
    d.holding = true;
  }
  model.frameJacobian(data, frame_, d.J);  // [linear; angular]
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = d.position - X.translation();
  e.tail<3>() = rotationError(d.rotation, X.linear());                 // log(R_d R^T)
  writePdRows<6>(ctx, pd_, e, model.frameBias(data, frame_), nv_, d);  // eq. 61 / 55
  std::fill(d.engaged.begin(), d.engaged.end(), 1);
}

void ContactTask::accumulateHessian(const TickContext& ctx, const TaskData& base, const Eigen::Ref<const Eigen::VectorXd>& w,
                                    Eigen::Ref<Eigen::MatrixXd> H) const {
  const auto& d = static_cast<const ContactTaskData&>(base);
  LEXDYN_ALWAYS_ASSERT(ctx.hessian != nullptr && w.size() == rows(), "contact: accumulateHessian needs ctx.hessian, one weight per row");
  if (!d.holding) return;
  if (point_) {
    hessian::accumulatePointHessian(*ctx.model, *ctx.data, *ctx.hessian, frame_, point_in_frame_, Eigen::Vector3d(w.head<3>()), H);
    return;
  }
  hessian::accumulatePointHessian(*ctx.model, *ctx.data, *ctx.hessian, frame_, Eigen::Vector3d::Zero(), Eigen::Vector3d(w.head<3>()), H);
  hessian::accumulateOrientationHessian(*ctx.model, *ctx.data, *ctx.hessian, frame_, Eigen::Vector3d(w.tail<3>()), H);
}

void ContactTask::chainDofs(const model::RobotModel& model, std::vector<char>& mask) const { markBodyChain(model, body_, mask); }

}  // namespace lexdyn::tasks
