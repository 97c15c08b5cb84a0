// contact_force_bounds (bounds level, ng rows): one row per contact wrench generator variable
// (docs/controller.md). Active friction contact: gamma >= 0 (paper sec. V-C, linearised friction
// cone), or gamma >= the share of the contact's minimum normal force (its contact margin,
// contact_margins.hpp); active fixed (grasp) contact: free; inactive contact: gamma = 0. The
// velocity domain bounds dt gamma, the acceleration domain gamma.
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
