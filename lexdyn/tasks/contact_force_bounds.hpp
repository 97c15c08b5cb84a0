// contact_force_bounds (bounds level, ng rows): one row per contact wrench generator variable
// (docs/controller.md). Active friction contact: gamma >= 0 (paper sec. V-C, linearised friction
// cone); active fixed (grasp) contact: free; inactive contact: gamma = 0. Velocity domain bounds
// dt gamma, acceleration domain gamma: the bounds (0 or infinite) are the same.
#pragma once

#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

class ContactForceBoundsTask : public TaskModel {
 public:
  /// The layout fixes the rows (its ng); createData() requires a layout of the same sizes.
  ContactForceBoundsTask(std::string name, const ContactLayout& layout);

  int rows() const override { return ng_; }
  TaskKind kind() const override { return TaskKind::Bounds; }
  bool supports(Domain) const override { return true; }
  /// A holds the unit coefficient of each row's variable (constant; A x = the generators).
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;
  void boundVariables(const ContactLayout& layout, std::vector<int>& vars) const override;

 private:
  int nv_ = 0, ng_ = 0;
};

}  // namespace lexdyn::tasks
