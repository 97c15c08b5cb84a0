// trust_region (inequality, nv rows): ||dt u(k+1)||_inf <= Delta, free-flyer included (paper
// sec. IX: Delta = 0.01 rad or m), i.e. -Delta/dt <= u_i(k+1) <= Delta/dt. Velocity domain only.
// An inequality level of its own in the paper (after the equation of motion), hence not a
// bounds task although each row has one variable.
#pragma once

#include "lexdyn/tasks/variable_rows.hpp"

namespace lexdyn::tasks {

struct TrustRegionParams {
  double delta = 0.01;  ///< Delta, rad or m per tick, > 0
};

class TrustRegionTask : public VelocityRowsTask {
 public:
  TrustRegionTask(std::string name, const model::RobotModel& model, const TrustRegionParams& params = {});

  TaskKind kind() const override { return TaskKind::Inequality; }
  void compute(const TickContext& ctx, TaskData& d) const override;

  double delta() const { return delta_; }

 private:
  double delta_ = 0.01;
};

}  // namespace lexdyn::tasks
