// velocity_min (equality, nv rows): u(k+1) = 0, free-flyer included (paper sec. IX, level 10).
// Velocity domain only.
#pragma once

#include "lexdyn/tasks/variable_rows.hpp"

namespace lexdyn::tasks {

class VelocityMinTask : public VelocityRowsTask {
 public:
  VelocityMinTask(std::string name, const model::RobotModel& model);

  TaskKind kind() const override { return TaskKind::Equality; }
  /// lower = upper = 0.
  void compute(const TickContext& ctx, TaskData& d) const override;
};

}  // namespace lexdyn::tasks
