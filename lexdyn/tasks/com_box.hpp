// com_box (inequality, 3 rows): keeps the centre of mass c inside the box [lo, hi] (world, m)
// with a velocity damper (damper.hpp) on each side, acting d_i (2 cm by default) before the
// edge (paper sec. IX, exp. 2-3). Row i reads J_i x with J_i the CoM Jacobian row:
//   d_lo = c_i - lo_i, d_hi = hi_i - c_i
//   velocity domain:     lower = damper bound of d_lo (-inf when d_lo >= d_i),
//                        upper = -(damper bound of d_hi) (+inf when d_hi >= d_i)
//   acceleration domain: lower = (velocity lower - J_i u) / dt - Jdot_i u, upper likewise.
// Infinite sides (lo = -inf, hi = +inf) never act. Target d.target = [lo (3); hi (3)]
// (setTarget to change the box; hi_i - lo_i >= 2 d_s is required so that lower <= upper).
// d.error[i] = min(d_lo, d_hi); d.engaged[i] when a side is within d_i.
#pragma once

#include <limits>

#include "lexdyn/tasks/damper.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

struct ComBoxParams {
  Eigen::Vector3d lower = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());  ///< m
  Eigen::Vector3d upper = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());   ///< m
  /// d_i = 2 cm (paper), d_s = 0 (the edge itself), xi in m/s.
  DamperParams damper{0.02, 0.0, 0.1};
};

class ComBoxTask : public TaskModel {
 public:
  ComBoxTask(std::string name, const model::RobotModel& model, const ComBoxParams& params = {});

  int rows() const override { return 3; }
  TaskKind kind() const override { return TaskKind::Inequality; }
  bool hasFunction() const override { return true; }
  bool geometric() const override { return true; }
  bool supports(Domain) const override { return true; }
  int targetSize() const override { return 6; }
  /// No NaN; lo_i < +inf, hi_i > -inf and hi_i - lo_i >= 2 d_s.
  void checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const override;

  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  /// Back to the initial target (or to holding at the next compute() when there is none).
  void reset(TaskData& d) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;
  void accumulateHessian(const TickContext& ctx, const TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& w,
                         Eigen::Ref<Eigen::MatrixXd> H) const override;
  void chainDofs(const model::RobotModel& model, std::vector<char>& mask) const override;

  const DamperParams& damper() const { return damper_; }

 private:
  int nv_ = 0;
  Eigen::Matrix<double, 6, 1> initial_box_;
  DamperParams damper_;
};

}  // namespace lexdyn::tasks
