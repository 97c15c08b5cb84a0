#include "lexdyn/tasks/contact_force_bounds.hpp"

#include <limits>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/contact_jacobian.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

ContactForceBoundsTask::ContactForceBoundsTask(std::string name, const ContactLayout& layout)
    : TaskModel(std::move(name)), nv_(layout.nv()), ng_(layout.ng()) {}

std::unique_ptr<TaskData> ContactForceBoundsTask::createData(const ContactLayout& layout) const {
  if (layout.nv() != nv_ || layout.ng() != ng_) {
    throwTaskInput(name(), "", "built for a contact layout with nv = " + std::to_string(nv_) + ", ng = " +
                                   std::to_string(ng_) + ", given nv = " + std::to_string(layout.nv()) +
                                   ", ng = " + std::to_string(layout.ng()));
  }
  auto d = std::make_unique<TaskData>();
  initData(*d, layout);
  for (int k = 0; k < ng_; ++k) d->A(k, nv_ + k) = 1.0;
  return d;
}

void ContactForceBoundsTask::compute(const TickContext& ctx, TaskData& d) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const ContactLayout& layout = *ctx.contacts;
  LEXDYN_ALWAYS_ASSERT(layout.ng() == ng_, "contact_force_bounds: layout differs from construction");
  for (int c = 0; c < layout.count(); ++c) {
    const ContactSpec& spec = layout.contact(c);
    const bool active = contactActive(ctx, c);
    // Active friction contact: gamma >= 0; active fixed contact: free; inactive: gamma = 0.
    const double lo = active ? (spec.fixed ? -kInf : 0.0) : 0.0;
    const double hi = active ? kInf : 0.0;
    const int n = 4 * static_cast<int>(spec.points.size());
    for (int k = layout.offset(c); k < layout.offset(c) + n; ++k) {
      d.lower[k] = lo;
      d.upper[k] = hi;
      d.engaged[static_cast<size_t>(k)] = (active && spec.fixed) ? 0 : 1;
    }
  }
}

void ContactForceBoundsTask::boundVariables(const ContactLayout& layout, std::vector<int>& vars) const {
  vars.resize(static_cast<size_t>(ng_));
  for (int k = 0; k < ng_; ++k) vars[static_cast<size_t>(k)] = layout.nv() + k;
}

}  // namespace lexdyn::tasks
