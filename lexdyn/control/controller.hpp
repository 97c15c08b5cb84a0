// The whole-body controller (docs/controller.md): LexDynBFGS, LexDynAH, pure Gauss-Newton and the
// WLS baseline, one 5 ms tick at a time.
//
// Each tick: read the measured state, update the model (M, N, kinematics), let every task fill
// its rows, let the method (ControllerParams::method, a ControlMethod of the registry in
// lexdyn/control/method.hpp) add its rows to the levels (Newton rows eq. 35, 62 with switching
// eq. 95, R from BFGS eq. 87-89 or the analytic Hessian eq. 21, 91; damping eq. 50, 81), solve the
// hierarchy warm-started from the previous tick, let the method integrate the solution to the
// commanded configuration (eq. 32 or the q_mod variant eq. 73-76; WLS: eq. 57) and report q, u,
// tau, gamma and a record of the tick.
//
// Model / Data split: the configuration (tasks, levels, parameters) is const after
// construction; all per-tick memory is allocated in the constructor and tick() allocates
// nothing (tests/control/test_controller_humanoid.cpp, TickAllocatesNothing).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "lexdyn/control/config.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "lexdyn/solver/solver.hpp"

namespace lexdyn::control {

struct RobotState {
  model::Configuration q;
  Eigen::VectorXd u;  ///< nv
  double time = 0.0;  ///< s
};

enum class TickStatus {
  Ok,
  SolverStoppedEarly,  ///< the paper's termination rules stopped the active-set search (normal)
  SolverIterationLimit,
  Infeasible,  ///< WLS: the hard level is infeasible (the paper's LSSOL failure)
  NonFinite,   ///< NaN/inf in the problem or the solution
};
const char* toString(TickStatus s);

struct Command {
  model::Configuration q;  ///< commanded configuration
  Eigen::VectorXd u;       ///< commanded velocity (nv)
  Eigen::VectorXd udot;    ///< (u(k+1) - u(k)) / dt, or the WLS acceleration
  Eigen::VectorXd tau;     ///< joint torques (nj), N m or N
  Eigen::VectorXd gamma;   ///< contact wrench generators (ng), N
  TickStatus status = TickStatus::Ok;
  bool ok() const { return status == TickStatus::Ok || status == TickStatus::SolverStoppedEarly; }
};

/// Everything the paper plots, per tick (Fig. 3-27). Sizes fixed at construction.
struct TickRecord {
  double time = 0.0;
  TickStatus status = TickStatus::Ok;
  solver::Status solver_status = solver::Status::Solved;
  int iterations = 0;  ///< active-set iterations
  int optimality_iterations = 0;
  int factorizations = 0;  ///< level stages the solver factorised (solver::Result::factorizations)
  // Wall time, microseconds (measurement only; never used for decisions).
  double model_us = 0.0, tasks_us = 0.0, hessian_us = 0.0, solver_us = 0.0, tick_us = 0.0;
  Eigen::VectorXd task_error_norm;          ///< per task: ||e||
  std::vector<int> task_active_rows;        ///< per task: rows held by the solver (active set)
  std::vector<int> task_engaged_rows;       ///< per task: rows engaged (inequalities inside their distance)
  std::vector<char> level_augmented;        ///< per configured level: Newton rows added this tick
  std::vector<char> level_hessian_updated;  ///< per configured level: BFGS update accepted this tick
  Eigen::VectorXd level_violation;          ///< per configured level: ||w_ctrl|| of its task rows
  /// Per configured level while augmented (level_augmented), NaN otherwise: the size of the
  /// second-order rows R against the level's Gauss-Newton term, trace(R^T R) / trace(J^T J),
  /// J the level's constraining task rows (finite bound) on the velocity columns. R^T R is what
  /// the rows add: the method's curvature term plus any identity (eps, alpha) or damping.
  Eigen::VectorXd level_second_order_ratio;
  /// The same for the method's own curvature term (BFGS: B; analytic: Higham's regularised
  /// Hessian), without the identity terms eps I* and alpha I*; 0 for damping rows.
  Eigen::VectorXd level_curvature_ratio;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  /// Per contact: [force; torque] (world axes, torque about the contact frame origin) from gamma.
  Eigen::MatrixXd contact_wrench;
};

class Controller {
 public:
  /// Validates the configuration (throws lexdyn::InputError naming the task / level) and
  /// allocates everything.
  Controller(const model::RobotModel& model, ControllerConfig config);
  ~Controller();
  Controller(Controller&&) noexcept;
  Controller& operator=(Controller&&) noexcept;

  /// Starts from a state: captures contact poses, resets the Hessian approximations and the
  /// solver's warm start.
  void reset(const RobotState& state);
  /// One control tick. Allocation-free.
  const Command& tick(const RobotState& state);

  const TickRecord& record() const;
  const Command& command() const;
  const solver::Result& solverResult() const;
  const solver::Problem& problem() const;
  /// The solver's options as the controller set them up (split coordinates and the early stop's
  /// level resolved).
  const solver::Options& solverOptions() const;

  // Runtime events (timeline).
  int taskIndex(const std::string& name) const;  ///< throws InputError listing the task names
  void setTaskTarget(int task, const Eigen::Ref<const Eigen::VectorXd>& target);
  int contactIndex(const std::string& name) const;
  /// Activates a contact (its pose becomes the contact constraint's target) or releases it.
  void setContactActive(int contact, bool active);
  bool contactActive(int contact) const;

  const ControllerConfig& config() const;
  const tasks::ContactLayout& contacts() const;
  const model::RobotModel& model() const;
  /// The model's data at the state of the last tick (poses, Jacobians of the state it read).
  const model::ModelData& modelData() const;
  int taskCount() const;
  const tasks::TaskModel& task(int i) const;
  const tasks::TaskData& taskData(int i) const;
  int levelCount() const;  ///< configured levels

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lexdyn::control
