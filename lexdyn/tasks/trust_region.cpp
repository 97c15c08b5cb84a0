#include "lexdyn/tasks/trust_region.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

TrustRegionTask::TrustRegionTask(std::string name, const model::RobotModel& model, const TrustRegionParams& params)
    : VelocityRowsTask(std::move(name), model), delta_(params.delta) {
  requirePositive(params.delta, this->name(), "delta");
}

void TrustRegionTask::compute(const TickContext& ctx, TaskData& d) const {
  LEXDYN_ALWAYS_ASSERT(ctx.domain == Domain::Velocity, "trust_region: velocity domain only");
  d.lower.setConstant(-delta_ / ctx.dt);
  d.upper.setConstant(delta_ / ctx.dt);
}

}  // namespace lexdyn::tasks
