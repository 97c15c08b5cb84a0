#include "lexdyn/tasks/variable_rows.hpp"

namespace lexdyn::tasks {

VelocityRowsTask::VelocityRowsTask(std::string name, const model::RobotModel& model) : TaskModel(std::move(name)), nv_(model.nv()) {}

std::unique_ptr<TaskData> VelocityRowsTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = makeData(layout, true);
  d->A.leftCols(nv_).setIdentity();
  return d;
}

GeneratorRowsTask::GeneratorRowsTask(std::string name, const ContactLayout& layout)
    : TaskModel(std::move(name)), nv_(layout.nv()), ng_(layout.ng()) {}

std::unique_ptr<TaskData> GeneratorRowsTask::createData(const ContactLayout& layout) const {
  requireLayoutSizes(layout, nv_, ng_);
  auto d = makeData(layout, kind() == TaskKind::Equality);
  d->A.rightCols(ng_).setIdentity();
  return d;
}

}  // namespace lexdyn::tasks
