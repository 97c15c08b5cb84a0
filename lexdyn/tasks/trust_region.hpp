// trust_region (inequality, nv rows): ||dt u(k+1)||_inf <= Delta, free-flyer included (paper
// sec. IX: Delta = 0.01 rad or m), i.e. -Delta/dt <= u_i(k+1) <= Delta/dt. Velocity domain only.
// An inequality level of its own in the paper (after the equation of motion), hence not a
// bounds task although each row has one variable.
#pragma once

#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

struct TrustRegionParams {
  double delta = 0.01;  ///< Delta, rad or m per tick, > 0
};

class TrustRegionTask : public TaskModel {
 public:
  TrustRegionTask(std::string name, const model::RobotModel& model, const TrustRegionParams& params = {});

  int rows() const override { return nv_; }
  TaskKind kind() const override { return TaskKind::Inequality; }
  bool supports(Domain d) const override { return d == Domain::Velocity; }
  /// A = [I 0] (constant).
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;

  double delta() const { return delta_; }

 private:
  int nv_ = 0;
  double delta_ = 0.01;
};

}  // namespace lexdyn::tasks
