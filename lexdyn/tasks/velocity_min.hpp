// velocity_min (equality, nv rows): u(k+1) = 0, free-flyer included (paper sec. IX, level 10).
// Velocity domain only.
#pragma once

#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

class VelocityMinTask : public TaskModel {
 public:
  VelocityMinTask(std::string name, const model::RobotModel& model);

  int rows() const override { return nv_; }
  TaskKind kind() const override { return TaskKind::Equality; }
  bool supports(Domain d) const override { return d == Domain::Velocity; }
  /// A = [I 0], lower = upper = 0 (constant).
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;

 private:
  int nv_ = 0;
};

}  // namespace lexdyn::tasks
