#include "lexdyn/tasks/wrench_min.hpp"

#include <algorithm>

#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

WrenchMinTask::WrenchMinTask(std::string name, const ContactLayout& layout)
    : TaskModel(std::move(name)), nv_(layout.nv()), ng_(layout.ng()) {}

std::unique_ptr<TaskData> WrenchMinTask::createData(const ContactLayout& layout) const {
  if (layout.nv() != nv_ || layout.ng() != ng_) {
    throwTaskInput(name(), "", "built for a contact layout with nv = " + std::to_string(nv_) + ", ng = " +
                                   std::to_string(ng_) + ", given nv = " + std::to_string(layout.nv()) +
                                   ", ng = " + std::to_string(layout.ng()));
  }
  auto d = std::make_unique<TaskData>();
  initData(*d, layout);
  d->A.rightCols(ng_).setIdentity();
  std::fill(d->engaged.begin(), d->engaged.end(), 1);
  return d;
}

void WrenchMinTask::compute(const TickContext&, TaskData& d) const {
  d.lower.setZero();
  d.upper.setZero();
}

}  // namespace lexdyn::tasks
