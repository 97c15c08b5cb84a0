#include "lexdyn/tasks/joint_position.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"

namespace lexdyn::tasks {

void computeJointPdRows(const TickContext& ctx, const Pd& pd, int offset, const std::vector<int>& joints, TaskData& d) {
  const Eigen::VectorXd& q = ctx.q->joints;
  const Eigen::VectorXd& u = *ctx.u;
  const int m = static_cast<int>(joints.size());
  if (!d.target_set) {
    for (int r = 0; r < m; ++r) d.target[r] = q[joints[static_cast<size_t>(r)]];  // hold
    d.target_set = true;
  }
  for (int r = 0; r < m; ++r) {
    const int j = joints[static_cast<size_t>(r)];
    const double e = d.target[r] - q[j];
    d.error[r] = e;
    const double rhs = pdRowTarget(ctx.domain, ctx.dt, pd, e, u[offset + j], 0.0);  // eq. 61 / 55, Jdot = 0
    d.lower[r] = rhs;
    d.upper[r] = rhs;
  }
}

JointPositionTask::JointPositionTask(std::string name, const model::RobotModel& model, const JointPositionParams& params)
    : TaskModel(std::move(name)), nv_(model.nv()), offset_(model.jointVelocityOffset()) {
  if (params.joints.empty()) throwTaskInput(this->name(), "joints", "must name at least one joint, found none");
  for (size_t k = 0; k < params.joints.size(); ++k) {
    const std::string field = "joints[" + std::to_string(k) + "]";
    const int j = resolveJoint(model, params.joints[k], this->name(), field);
    if (std::find(joints_.begin(), joints_.end(), j) != joints_.end()) {
      throwTaskInput(this->name(), field, "joint '" + params.joints[k] + "' listed twice");
    }
    joints_.push_back(j);
  }
  if (params.target.size() != 0) {
    if (params.target.size() != rows()) {
      throwTaskInput(this->name(), "target", "needs " + std::to_string(rows()) + " values (one per joint), found " +
                                                 std::to_string(params.target.size()));
    }
    requireFinite(params.target, this->name(), "target");
    initial_target_ = params.target;
  }
  pd_ = resolvePd(params.gains, this->name());
}

void JointPositionTask::checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const {
  requireFinite(target, name(), "target");
}

std::unique_ptr<TaskData> JointPositionTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = std::make_unique<TaskData>();
  initData(*d, layout);
  for (int r = 0; r < rows(); ++r) {
    d->A(r, offset_ + joints_[static_cast<size_t>(r)]) = 1.0;
    d->J(r, offset_ + joints_[static_cast<size_t>(r)]) = 1.0;
  }
  std::fill(d->engaged.begin(), d->engaged.end(), 1);
  reset(*d);
  return d;
}

void JointPositionTask::reset(TaskData& d) const {
  d.target_set = initial_target_.size() != 0;
  if (d.target_set) d.target = initial_target_;
}

void JointPositionTask::compute(const TickContext& ctx, TaskData& d) const {
  computeJointPdRows(ctx, pd_, offset_, joints_, d);
}

}  // namespace lexdyn::tasks
