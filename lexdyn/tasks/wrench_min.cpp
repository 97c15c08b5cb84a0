#include "lexdyn/tasks/wrench_min.hpp"

namespace lexdyn::tasks {

WrenchMinTask::WrenchMinTask(std::string name, const ContactLayout& layout) : GeneratorRowsTask(std::move(name), layout) {}

void WrenchMinTask::compute(const TickContext&, TaskData& d) const {
  d.lower.setZero();
  d.upper.setZero();
}

}  // namespace lexdyn::tasks
