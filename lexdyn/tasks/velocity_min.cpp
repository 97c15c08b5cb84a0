#include "lexdyn/tasks/velocity_min.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

VelocityMinTask::VelocityMinTask(std::string name, const model::RobotModel& model)
    : TaskModel(std::move(name)), nv_(model.nv()) {}

std::unique_ptr<TaskData> VelocityMinTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = std::make_unique<TaskData>();
  initData(*d, layout);
  d->A.leftCols(nv_).setIdentity();
  std::fill(d->engaged.begin(), d->engaged.end(), 1);
  return d;
}

void VelocityMinTask::compute(const TickContext& ctx, TaskData& d) const {
  LEXDYN_ALWAYS_ASSERT(ctx.domain == Domain::Velocity, "velocity_min: velocity domain only");
  d.lower.setZero();
  d.upper.setZero();
}

}  // namespace lexdyn::tasks
