#include "lexdyn/tasks/contact_force_bounds.hpp"

#include <cmath>
#include <limits>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/contact_jacobian.hpp"

namespace lexdyn::tasks {

ContactForceBoundsTask::ContactForceBoundsTask(std::string name, const ContactLayout& layout)
    : GeneratorRowsTask(std::move(name), layout) {}

void ContactForceBoundsTask::compute(const TickContext& ctx, TaskData& d) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const ContactLayout& layout = *ctx.contacts;
  LEXDYN_ALWAYS_ASSERT(layout.ng() == ng_, "contact_force_bounds: layout differs from construction");
  for (int c = 0; c < layout.count(); ++c) {
    const ContactSpec& spec = layout.contact(c);
    const bool active = contactActive(ctx, c);
    // Active friction contact: gamma >= 0; inactive: gamma = 0. Active fixed contact: no sign
    // bound, and generator 3 of each point is held at 0: the 4 pyramid directions of a point
    // span R^3 with one redundant combination (g0 + g1 - g2 - g3 gives no force), which no level
    // but the last (wrench minimisation) would fix; early-stopped solves then let it drift from
    // tick to tick without bound. Generators 0..2 alone span R^3 (n +- mu t1 and n + mu t2), so
    // the set of contact forces is unchanged.
    // The minimum normal force of a point (its contact margin): each generator's normal
    // component is 1 / sqrt(1 + mu^2), so 4 generators at min_normal_force sqrt(1 + mu^2) / 4
    // give it. The velocity domain's variables are impulses dt gamma.
    const double share = std::sqrt(1.0 + spec.friction * spec.friction) / 4.0;
    const double scale = ctx.domain == Domain::Velocity ? ctx.dt : 1.0;
    const double g_min = spec.min_normal_force * share;
    const double lo = active ? (spec.fixed ? -kInf : g_min) : 0.0;
    const double hi = active ? kInf : 0.0;
    const int n = 4 * static_cast<int>(spec.points.size());
    for (int j = 0; j < n; ++j) {
      const int k = layout.offset(c) + j;
      const bool gauge = active && spec.fixed && j % 4 == 3;
      d.lower[k] = gauge ? 0.0 : lo * scale;
      d.upper[k] = gauge ? 0.0 : hi * scale;
      d.engaged[static_cast<size_t>(k)] = (active && spec.fixed && !gauge) ? 0 : 1;
    }
  }
}

void ContactForceBoundsTask::boundVariables(const ContactLayout& layout, std::vector<int>& vars) const {
  vars.resize(static_cast<size_t>(ng_));
  for (int k = 0; k < ng_; ++k) vars[static_cast<size_t>(k)] = layout.nv() + k;
}

}  // namespace lexdyn::tasks
