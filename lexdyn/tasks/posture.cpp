#include "lexdyn/tasks/posture.hpp"

#include <numeric>

#include "lexdyn/common/error.hpp"

namespace lexdyn::tasks {

namespace {

std::vector<int> allJoints(const model::RobotModel& model) {
  std::vector<int> joints(static_cast<size_t>(model.numJoints()));
  std::iota(joints.begin(), joints.end(), 0);
  return joints;
}

}  // namespace

PostureTask::PostureTask(std::string name, const model::RobotModel& model, const PostureParams& params)
    : JointTrackingTask(std::move(name), model, allJoints(model)) {
  if (params.target.size() != 0 && !params.posture.empty()) {
    throwTaskInput(this->name(), "posture", "give either target or posture, not both");
  }
  setInitialJointTarget(params.target);
  if (!params.posture.empty()) {
    const Eigen::VectorXd* posture = nullptr;
    try {
      posture = &model.posture(params.posture);
    } catch (const InputError& e) {
      throwTaskInput(this->name(), "posture", e.detail());
    }
    setInitialTarget(*posture);
  }
  pd_ = resolvePd(params.gains, this->name());
}

}  // namespace lexdyn::tasks
