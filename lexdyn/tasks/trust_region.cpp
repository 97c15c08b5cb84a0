#include "lexdyn/tasks/trust_region.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

TrustRegionTask::TrustRegionTask(std::string name, const model::RobotModel& model, const TrustRegionParams& params)
    : TaskModel(std::move(name)), nv_(model.nv()), delta_(params.delta) {
  requirePositive(params.delta, this->name(), "delta");
}

std::unique_ptr<TaskData> TrustRegionTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = std::make_unique<TaskData>();
  initData(*d, layout);
  d->A.leftCols(nv_).setIdentity();
  std::fill(d->engaged.begin(), d->engaged.end(), 1);
  return d;
}

void TrustRegionTask::compute(const TickContext& ctx, TaskData& d) const {
  LEXDYN_ALWAYS_ASSERT(ctx.domain == Domain::Velocity, "trust_region: velocity domain only");
  d.lower.setConstant(-delta_ / ctx.dt);
  d.upper.setConstant(delta_ / ctx.dt);
}

}  // namespace lexdyn::tasks
