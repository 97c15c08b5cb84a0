// contact_force_bounds (bounds level, ng rows): one row per contact wrench generator variable
// (docs/controller.md). Active friction contact: gamma >= 0 (paper sec. V-C, linearised friction
// cone); active fixed (grasp) contact: free; inactive contact: gamma = 0. Velocity domain bounds
// dt gamma, acceleration domain gamma: the bounds (0 or infinite) are the same.
#pragma once

#include "lexdyn/tasks/variable_rows.hpp"

namespace lexdyn::tasks {

class ContactForceBoundsTask : public GeneratorRowsTask {
 public:
  ContactForceBoundsTask(std::string name, const ContactLayout& layout);

  TaskKind kind() const override { return TaskKind::Bounds; }
  void compute(const TickContext& ctx, TaskData& d) const override;
  void boundVariables(const ContactLayout& layout, std::vector<int>& vars) const override;
};

}  // namespace lexdyn::tasks
