#include "lexdyn/tasks/posture.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/joint_position.hpp"

namespace lexdyn::tasks {

PostureTask::PostureTask(std::string name, const model::RobotModel& model, const PostureParams& params)
    : TaskModel(std::move(name)), nv_(model.nv()), nj_(model.numJoints()), offset_(model.jointVelocityOffset()) {
  for (int j = 0; j < nj_; ++j) joints_.push_back(j);
  if (params.target.size() != 0 && !params.posture.empty()) {
    throwTaskInput(this->name(), "posture", "give either target or posture, not both");
  }
  if (params.target.size() != 0) {
    if (params.target.size() != nj_) {
      throwTaskInput(this->name(), "target", "needs " + std::to_string(nj_) + " values (one per joint), found " +
                                                 std::to_string(params.target.size()));
    }
    requireFinite(params.target, this->name(), "target");
    initial_target_ = params.target;
  } else if (!params.posture.empty()) {
    try {
      initial_target_ = model.posture(params.posture);
    } catch (const InputError& e) {
      throwTaskInput(this->name(), "posture", e.detail());
    }
  }
  pd_ = resolvePd(params.gains, this->name());
}

void PostureTask::checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const {
  requireFinite(target, name(), "target");
}

std::unique_ptr<TaskData> PostureTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = std::make_unique<TaskData>();
  initData(*d, layout);
  for (int j = 0; j < nj_; ++j) {
    d->A(j, offset_ + j) = 1.0;
    d->J(j, offset_ + j) = 1.0;
  }
  std::fill(d->engaged.begin(), d->engaged.end(), 1);
  reset(*d);
  return d;
}

void PostureTask::reset(TaskData& d) const {
  d.target_set = initial_target_.size() != 0;
  if (d.target_set) d.target = initial_target_;
}

void PostureTask::compute(const TickContext& ctx, TaskData& d) const {
  computeJointPdRows(ctx, pd_, offset_, joints_, d);
}

}  // namespace lexdyn::tasks
