#include "lexdyn/tasks/tracking.hpp"

#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

TrackingTask::TrackingTask(std::string name, const model::RobotModel& model, int rows, int target_size)
    : TaskModel(std::move(name)), nv_(model.nv()), rows_(rows), target_size_(target_size) {}

void TrackingTask::checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const { requireFinite(target, name(), "target"); }

void TrackingTask::setInitialTarget(const Eigen::Ref<const Eigen::VectorXd>& target) {
  checkTarget(target);
  initial_target_ = target;
}

std::unique_ptr<TaskData> TrackingTask::createData(const ContactLayout& layout) const { return makeTrackingData<TaskData>(layout); }

void TrackingTask::reset(TaskData& d) const {
  d.target_set = initial_target_.size() != 0;
  if (d.target_set) d.target = initial_target_;
}

void TrackingTask::holdTarget(TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& value) {
  if (d.target_set) return;
  d.target = value;  // hold
  d.target_set = true;
}

}  // namespace lexdyn::tasks
