// The controller's methods (docs/controller.md, "Methods"; docs/architecture.md, "Adding a
// method"): LexDynBFGS, LexDynAH, pure Gauss-Newton and WLS, each a ControlMethod in one file pair
// of lexdyn/control/methods/, created by name through the method registry.
//
// The controller's tick is the same for every method: model, tasks, rows copied into the
// solver's levels, the method's rows, solve, command, record. What differs is asked of the
// method, through this interface: the domain of the decision variables, how the configured
// levels become solver levels (a level of its own for the equation of motion, row weights, rows
// reserved for second-order terms), what goes into the reserved rows at each tick (Newton rows
// eq. 35/62 from BFGS eq. 87-89 or the analytic Hessian eq. 21/91, damping rows eq. 50/81), how
// the solution becomes the commanded state (eq. 32, 73-76 or 57) and whether the solution is
// acceptable (WLS: a feasible hard level).
//
// Setup functions may allocate; addRows(), command(), checkSolution() and afterSolve() are
// called at every tick and must not (tests/control/test_controller_humanoid.cpp).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "lexdyn/control/config.hpp"
#include "lexdyn/control/controller.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/solver.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::control {

/// A task's rows inside a solver level.
struct TaskSlot {
  int task = -1;
  int row = 0;                 ///< first row in the solver level
  double scale = 1.0;          ///< ControlMethod::rowScale (sqrt(weight) on the WLS objective level)
  bool velocity_only = false;  ///< TaskModel::velocityOnly(): A is zero past its first nv columns
  bool constant = false;       ///< TaskModel::constantMatrix(): A copied into the problem once
};

/// How the controller's tasks map onto one of the solver's general levels.
struct SolverLevel {
  int problem_level = -1;  ///< index in the solver problem
  int config_level = -1;   ///< configured level it comes from
  std::vector<TaskSlot> slots;
  int task_rows = 0;         ///< rows of the tasks
  int spare_row = -1;        ///< first of the nv rows reserved for Newton / damping rows, -1 if none
  bool augmentable = false;  ///< reserves nv rows (ControlMethod::reservesRows)
  bool separate = false;     ///< the equation-of-motion level split off a configured level
};

/// What a method sees of its controller once the solver problem is laid out. The references
/// stay valid for the controller's lifetime.
struct MethodSetup {
  const model::RobotModel& model;
  const ControllerConfig& config;
  const tasks::ContactLayout& layout;
  const solver::Problem& problem;
  const std::vector<SolverLevel>& levels;
};

/// What a method reads at a tick.
struct MethodTick {
  const tasks::TickContext& ctx;                            ///< model updated, M, N
  const std::vector<std::unique_ptr<tasks::TaskData>>& td;  ///< every task's rows of this tick
  const std::vector<SolverLevel>& levels;
  const RobotState& state;  ///< measured state
  /// addRows: the previous tick's solver result (valid when have_last); afterSolve: this tick's.
  const solver::Result& last;
  bool have_last = false;  ///< a previous solve exists (false after reset)
};

class ControlMethod {
 public:
  virtual ~ControlMethod() = default;

  // --- The hierarchy (setup; may throw lexdyn::InputError) ---
  /// Domain of the decision variables: velocity [u(k+1); dt gamma] or acceleration [udot; gamma].
  virtual tasks::Domain domain() const = 0;
  /// Checks the configured levels (after the controller's own checks), e.g. WLS: exactly two.
  virtual void checkLevels(const ControllerConfig& config) const { (void)config; }
  /// Whether tasks asking for a level of their own (TaskModel::separateLevel: the equation of
  /// motion) get one in front of the rest of their configured level.
  virtual bool separatesLevels() const { return false; }
  /// Scale of the rows of task `k` of configured level `level` (WLS objective: sqrt(weight)).
  virtual double rowScale(const LevelSpec& spec, size_t level, size_t k) const {
    (void)spec, (void)level, (void)k;
    return 1.0;
  }
  /// Whether configured level `level` (its non-separate part; `geometric`: it holds a geometric
  /// task) reserves nv rows for second-order rows (Newton, damping).
  virtual bool reservesRows(size_t level, bool geometric) const {
    (void)level, (void)geometric;
    return false;
  }
  /// Whether the tick must update the kinematic Hessian workspace (TickContext::hessian).
  virtual bool needsKinematicHessians() const { return false; }
  /// Whether the method reads the tasks' Jacobians of an earlier tick, weighted by the multipliers
  /// of the previous solve, so that a free row's must be computed when the row was active in that
  /// solve (TickContext::free_row_jacobians, TaskData::held). True unless a method opts out.
  virtual bool readsPreviousJacobians() const { return true; }
  /// Allocates the method's per-tick memory, once the solver problem is laid out.
  virtual void setup(const MethodSetup& setup) = 0;

  // --- Every tick (allocation-free) ---
  /// Forgets the previous ticks (controller reset).
  virtual void reset() = 0;
  /// Fills the reserved rows of the levels for this tick (free rows, -inf <= 0 x <= inf, when
  /// unused) and sets rec.level_augmented / level_hessian_updated (zero on entry) and
  /// level_second_order_ratio / level_curvature_ratio of augmented levels (NaN on entry).
  virtual void addRows(const MethodTick& tick, solver::Problem& problem, TickRecord& rec) = 0;
  /// The commanded u, udot, gamma and q from the solution x; the controller then adds the
  /// torques and the contact wrenches.
  virtual void command(const RobotState& state, const Eigen::VectorXd& x, Command& cmd) = 0;
  /// The tick's status once the command is made (`status`: the solver's).
  virtual TickStatus checkSolution(const solver::Problem& problem, const solver::Result& result, TickStatus status) const {
    (void)problem, (void)result;
    return status;
  }
  /// Stores what the next tick needs (Jacobians, state).
  virtual void afterSolve(const MethodTick& tick) { (void)tick; }
};

/// A method in the registry.
using MethodFactory = std::unique_ptr<ControlMethod> (*)(const ControllerParams& params);
struct MethodInfo {
  std::string name;         ///< as in ControllerParams::method and case files ("bfgs")
  std::string description;  ///< one line
  /// Configured as the two-level weighted hierarchy (hard constraints, weighted objective;
  /// case files: `wls_levels`) rather than the strict hierarchy (`levels`).
  bool weighted_hierarchy = false;
  MethodFactory make = nullptr;
};

/// The factory of a method class constructed from its parameters: `&makeMethodOf<MyMethod>`.
template <class M>
std::unique_ptr<ControlMethod> makeMethodOf(const ControllerParams& params) {
  return std::make_unique<M>(params);
}

/// Registered methods, in registration order (the built-in ones first: bfgs, ah, gn, wls).
std::vector<std::string> methodNames();
/// The method called `name`; throws lexdyn::InputError(where, "expected one of bfgs, ah, gn,
/// wls, found \"x\"") for an unknown name.
const MethodInfo& findMethod(const std::string& name, const std::string& where);
/// Registers a method (e.g. from a test or an application, before its controllers are made);
/// throws lexdyn::InputError for an empty or taken name or a missing factory. Not thread-safe.
void registerMethod(MethodInfo info);
/// The method named by params.method, made with params (findMethod's error naming `where`).
std::unique_ptr<ControlMethod> makeMethod(const ControllerParams& params, const std::string& where);

}  // namespace lexdyn::control
