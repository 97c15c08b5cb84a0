// joint_limits (bounds level, nj rows): one row on each joint velocity qdot_j (docs/controller.md).
//
// Velocity domain, on qdot_j(k+1): a velocity damper (damper.hpp) on each limit, with the
// distances d_lower = q - q_min and d_upper = q_max - q and d_i, d_s given as fractions of the
// joint's range, and the URDF velocity limit:
//   lower = clamp(damper bound of d_lower, -v_max, v_max)          (-v_max when inactive)
//   upper = clamp(-(damper bound of d_upper), -v_max, v_max)       (+v_max when inactive)
// Clamping both sides into [-v_max, v_max] keeps lower <= upper also beyond a limit (where the
// damper pushes back faster than v_max allows: the bound becomes v_max); the dampers themselves
// satisfy lower <= upper because d_s < range / 2. Joints without finite limits (continuous) get
// the velocity limit only.
// Acceleration domain (WLS), on qddot_j(k+1): the same bounds on qdot + dt qddot, i.e.
// lower_a = (lower - qdot) / dt, upper_a = (upper - qdot) / dt (the acceleration damper of
// damper.hpp with J_d = +-1, Jdot_d = 0).
// d.error holds min(d_lower, d_upper); d.engaged marks joints inside an interaction distance.
#pragma once

#include "lexdyn/tasks/damper.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

struct JointLimitsParams {
  /// Fractions of each joint's range (mc_rtc's defaults): 0 <= safety < interaction <= 0.5.
  double interaction_fraction = 0.1;
  double safety_fraction = 0.01;
  double xi = 0.5;              ///< rad/s (m/s for prismatic joints)
  bool adaptive = true;         ///< gain raised to the approach speed at engagement (damper.hpp)
  bool velocity_limits = true;  ///< also bound |qdot_j| by the URDF velocity limit
};

class JointLimitsTask : public TaskModel {
 public:
  JointLimitsTask(std::string name, const model::RobotModel& model, const JointLimitsParams& params = {});

  int rows() const override { return nj_; }
  TaskKind kind() const override { return TaskKind::Bounds; }
  bool supports(Domain) const override { return true; }
  /// A holds the unit coefficient of each row's variable (constant).
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  void reset(TaskData& d) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;
  void boundVariables(const ContactLayout& layout, std::vector<int>& vars) const override;

  const JointLimitsParams& params() const { return params_; }

 private:
  JointLimitsParams params_;
  int nv_ = 0, nj_ = 0, offset_ = 0;
  Eigen::VectorXd q_min_, q_max_, v_max_;
};

}  // namespace lexdyn::tasks
