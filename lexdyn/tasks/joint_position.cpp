#include "lexdyn/tasks/joint_position.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"

namespace lexdyn::tasks {

namespace {

// The model joints named by `names` (field "joints"): at least one, none twice.
std::vector<int> resolveJoints(const model::RobotModel& model, const std::vector<std::string>& names, const std::string& task) {
  if (names.empty()) throwTaskInput(task, "joints", "must name at least one joint, found none");
  std::vector<int> joints;
  for (size_t k = 0; k < names.size(); ++k) {
    const std::string field = "joints[" + std::to_string(k) + "]";
    const int j = resolveJoint(model, names[k], task, field);
    if (std::find(joints.begin(), joints.end(), j) != joints.end()) {
      throwTaskInput(task, field, "joint '" + names[k] + "' listed twice");
    }
    joints.push_back(j);
  }
  return joints;
}

}  // namespace

JointTrackingTask::JointTrackingTask(std::string name, const model::RobotModel& model, std::vector<int> joints)
    : TrackingTask(std::move(name), model, static_cast<int>(joints.size()), static_cast<int>(joints.size())),
      offset_(model.jointVelocityOffset()),
      joints_(std::move(joints)) {}

void JointTrackingTask::setInitialJointTarget(const Eigen::VectorXd& target) {
  if (target.size() == 0) return;
  if (target.size() != rows()) {
    throwTaskInput(name(), "target", "needs " + std::to_string(rows()) + " values (one per joint), found " + std::to_string(target.size()));
  }
  setInitialTarget(target);
}

std::unique_ptr<TaskData> JointTrackingTask::createData(const ContactLayout& layout) const {
  auto d = makeTrackingData<TaskData>(layout);
  for (int r = 0; r < rows(); ++r) {
    d->A(r, offset_ + joints_[static_cast<size_t>(r)]) = 1.0;
    d->J(r, offset_ + joints_[static_cast<size_t>(r)]) = 1.0;
  }
  return d;
}

void JointTrackingTask::compute(const TickContext& ctx, TaskData& d) const {
  const Eigen::VectorXd& q = ctx.q->joints;
  const Eigen::VectorXd& u = *ctx.u;
  const int m = rows();
  if (!d.target_set) {
    for (int r = 0; r < m; ++r) d.target[r] = q[joints_[static_cast<size_t>(r)]];  // hold
    d.target_set = true;
  }
  for (int r = 0; r < m; ++r) {
    const int j = joints_[static_cast<size_t>(r)];
    const double e = d.target[r] - q[j];
    d.error[r] = e;
    const double rhs = pdRowTarget(ctx.domain, ctx.dt, pd_, e, u[offset_ + j], 0.0);  // eq. 61 / 55, Jdot = 0
    d.lower[r] = rhs;
    d.upper[r] = rhs;
  }
}

JointPositionTask::JointPositionTask(std::string name, const model::RobotModel& model, const JointPositionParams& params)
    : JointTrackingTask(name, model, resolveJoints(model, params.joints, name)) {
  setInitialJointTarget(params.target);
  pd_ = resolvePd(params.gains, this->name());
}

}  // namespace lexdyn::tasks
