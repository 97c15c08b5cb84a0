// Newton augmentation of the controller's levels (paper sec. III-IV, VI, VII, VIII-A;
// docs/controller.md "Newton augmentation"). Internal to lexdyn/control.
//
// Every solver level holding a geometric task ("augmentable") reserves nv rows. When the level
// is augmented they carry the Newton rows R u(k+1) = R u(k) (eq. 62) or = 0 (eq. 35), with
// R^T R the level's hierarchical Hessian restricted to the dofs the level occupies:
//  - LexDynBFGS: a per-level BFGS approximation (eq. 87-89) of the Lagrangian Hessian, updated
//    every tick from the step actually taken and the Jacobian change weighted by the current
//    multipliers, never re-initialised (sec. VII), with the sign-change guard (sec. VIII-A);
//  - LexDynAH: sum_i sum_d lambda_{i,l,d} H_{i,d} (eq. 21) from the analytic Hessians, made
//    positive semi-definite by Higham's method (eq. 91) plus eps on the occupied dofs.
// A level is augmented while omega = 1/2 ||dt w_ctrl||^2 >= nu (eq. 95, 37), w_ctrl being the
// level's task-row violation at the previous tick. Otherwise the reserved rows are left free
// (never active: they cost nothing in the solver).
// With ControllerParams::damping = mu > 0 the reserved rows carry the constant
// Levenberg-Marquardt rows mu u(k+1) = 0 (eq. 81; WLS: mu udot = 0 on the objective, eq. 50).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "lexdyn/control/config.hpp"
#include "lexdyn/control/controller.hpp"
#include "lexdyn/control/detail/levels.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/solver.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::control {

class Augmentation {
 public:
  Augmentation(const model::RobotModel& model, const ControllerConfig& cfg, const tasks::ContactLayout& layout,
               const solver::Problem& problem, const std::vector<SolverLevel>& levels);
  ~Augmentation();

  /// Forget every Hessian approximation and the previous tick (controller reset).
  void reset();
  /// Fills the reserved rows of every augmentable level for this tick. `last` is the previous
  /// tick's solver result (valid when `haveLast`).
  void apply(const tasks::TickContext& ctx, const std::vector<std::unique_ptr<tasks::TaskData>>& td,
             const std::vector<SolverLevel>& levels, solver::Problem& problem, const solver::Result& last, bool haveLast,
             const RobotState& state, TickRecord& rec);
  /// Stores what the next tick needs (Jacobians, state).
  void afterSolve(const std::vector<std::unique_ptr<tasks::TaskData>>& td, const RobotState& state);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace lexdyn::control
