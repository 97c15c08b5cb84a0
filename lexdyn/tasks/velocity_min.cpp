#include "lexdyn/tasks/velocity_min.hpp"

#include "lexdyn/common/error.hpp"

namespace lexdyn::tasks {

VelocityMinTask::VelocityMinTask(std::string name, const model::RobotModel& model) : VelocityRowsTask(std::move(name), model) {}

void VelocityMinTask::compute(const TickContext& ctx, TaskData& d) const {
  LEXDYN_ALWAYS_ASSERT(ctx.domain == Domain::Velocity, "velocity_min: velocity domain only");
  d.lower.setZero();
  d.upper.setZero();
}

}  // namespace lexdyn::tasks
