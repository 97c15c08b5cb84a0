// Checks read traces (channels by name), never live objects, so they run the same on a fresh
// simulation (row by row as the run goes) and on a stored trace file.
//
// Check types are registered in a CheckRegistry (check_registry.hpp): each type has its own
// params struct, a parser (its keys of a case file's `checks` entry) and an evaluator (a Check),
// in one file pair per family:
//   sim_checks       frame_drift, force_balance, contact_slip, frame_height (docs/simulator.md)
//   task_checks      task_error, task_error_rate_sign_changes, task_error_closed_form,
//                    task_overshoot; method comparisons
//   joint_checks     torque_limits, joint_acceleration_sign_changes, joint_velocity_hf_energy
//   contact_checks   contact_unilateral, contact_friction, contact_cop, contact_wrench_match
//   health_checks    controller_status, active_set_peak, factorization_peak, augmented_fraction,
//                    tick_time (machine-dependent: it decides only when asked,
//                    applyWallClockPolicy)
// (docs/cases.md, "Checks"; docs/architecture.md, "Adding a check type").
// A check passes when it saw at least one row in its window [from_s, to_s] and its value is on
// the right side of its limit.
#pragma once

#include "harness/checks/trace.hpp"

#include <any>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace lexdyn::checks {

/// A check of a case file: the fields every check type has, and the params struct of its type
/// (CheckType::parse sets it; e.g. TaskErrorParams for task_error, task_checks.hpp).
struct CheckSpec {
  std::string name;
  std::string type;                                       ///< a registered check type (checkTypes())
  std::string where;                                      ///< origin in the case file, for messages
  double from_s = 0.0;                                    ///< start of the window
  double to_s = std::numeric_limits<double>::infinity();  ///< end of the window
  double limit = 0.0;
  std::vector<std::string> methods;  ///< the check applies to these methods only (empty: all)
  std::any params;                   ///< the type's params struct (empty for a type without)

  /// The params struct of the check's type; aborts when the spec holds another (an internal
  /// error: the type's parser or the code that built the spec set the wrong one).
  template <class P>
  const P& paramsAs() const {
    const P* p = std::any_cast<P>(&params);
    if (!p) paramsMismatch();
    return *p;
  }
  template <class P>
  P& paramsAs() {
    P* p = std::any_cast<P>(&params);
    if (!p) paramsMismatch();
    return *p;
  }

 private:
  [[noreturn]] void paramsMismatch() const;
};

/// Comparison of two runs of the same case with different methods (e.g. exp1: the final sum of
/// hand errors of bfgs <= that of wls): value = stat(better) - stat(worse), passes when
/// value <= margin.
struct ComparisonSpec {
  std::string name;
  std::string type = "method_comparison";
  std::vector<std::string> tasks;
  std::string statistic = "final";  ///< final | mean | max of the sum of the tasks' error norms
  std::string better, worse;        ///< methods
  double margin = 0.0;
  double from_s = 0.0;
  double to_s = std::numeric_limits<double>::infinity();
  std::string where;
  /// `expected_to_fail: REASON`: the case documents that this comparison fails (a paper's
  /// result not reproduced here); the failure is then the expected outcome and a pass is the
  /// change (docs/cases.md, "Expected failures").
  std::string expected_failure_reason;
};

struct CheckResult {
  std::string name;
  std::string type;
  bool passed = false;
  double value = 0.0;  ///< NaN when no row was seen
  double limit = 0.0;
  std::string unit;
  std::string detail;
  /// A wall-clock measurement (tick_time): its value depends on the machine and its load.
  bool machine_dependent = false;
  /// Counts towards the verdict (all_checks_passed, exit code). False for a machine-dependent
  /// check unless wall-clock checks were asked to decide (applyWallClockPolicy).
  bool decides = true;
  /// The check bounds its value from below (passes when value >= limit), e.g. frame_height.
  bool bounds_below = false;
  /// A run stopped early (stop_at_s, `run --duration`) inside the check's window: what of the
  /// window was run (empty otherwise). The value covers that part only.
  std::string partial_window;
  /// False when no trace row fell in the window (value NaN; the detail says which rows it wanted).
  bool saw_rows = true;
};

/// Where a run stopped early (at run_end_s, before the scenario's end at scenario_end_s) leaves a
/// check's window [from_s, to_s] (to_s infinite: the scenario's end).
struct WindowCut {
  bool skip = false;  ///< the window starts after the run's end: not evaluated
  std::string note;   ///< why it is skipped, or what of the window was run (empty: all of it)
};
WindowCut cutWindow(const CheckSpec& spec, double run_end_s, double scenario_end_s);

/// Sets `decides` of a machine-dependent result: it decides only when `wall_clock_checks`.
void applyWallClockPolicy(CheckResult& r, bool wall_clock_checks);
/// True when every result that decides passed (an empty list passes).
bool allPassed(const std::vector<CheckResult>& results);

class Check {
 public:
  virtual ~Check() = default;
  /// Resolves channels; throws lexdyn::InputError (naming spec.where) if the trace lacks them.
  virtual void bind(const TraceSchema& schema, const TraceMetadata& metadata) = 0;
  virtual void consume(const double* row) = 0;
  virtual CheckResult result() const = 0;
};

/// How far a result lies on the passing side of its limit, in the value's unit: limit - value
/// for the checks that bound a value from above (most, and method comparisons), value - limit
/// for those that bound it from below (CheckResult::bounds_below: frame_height,
/// contact_unilateral). Negative: failed by that much; NaN when there is no value.
double margin(const CheckResult& result);

/// The built-in check types (builtinChecks(), check_registry.hpp), in registration order.
const std::vector<std::string>& checkTypes();
/// The evaluator of a check of a built-in type; InputError naming spec.where for an unknown type.
std::unique_ptr<Check> makeCheck(const CheckSpec& spec);
/// Frames whose channels (frame.<F>.x/y/z) the check reads: the runner records them.
std::vector<std::string> framesRead(const CheckSpec& spec);
/// True for a check whose value is a wall-clock measurement (tick_time): it decides only when
/// asked (applyWallClockPolicy). False for an unknown type.
bool machineDependent(const CheckSpec& spec);
/// True when the check applies to runs of `method` (an empty method: a trace without one).
bool appliesTo(const CheckSpec& spec, const std::string& method);

/// Channel names the runner records and the checks read.
std::string frameChannel(const std::string& frame, char axis);                      // frame.<F>.<x|y|z>
std::string contactForceChannel(const std::string& surface);                        // contact.<S>.fz
std::string contactPointChannel(const std::string& surface, int point, char axis);  // contact.<S>.p<i>.<x|y>
// The lexdyn controller's channels (docs/cases.md, "Trace channels").
std::string taskChannel(const std::string& task, const char* what);  // task.<T>.<error|active|engaged>
std::string levelChannel(const std::string& level,
                         const char* what);  // level.<L>.<augmented|hessian_updated|violation|second_order_ratio|curvature_ratio>
std::string wrenchChannel(const std::string& contact, bool sensed, const char* component);  // wrench[_sensed].<C>.<fx..tz>
std::string contactActiveChannel(const std::string& contact);                               // ctrl_contact.<C>.active
std::string timerChannel(const std::string& timer);                                         // time.<timer>_us
constexpr const char* kTimeChannel = "t";
constexpr const char* kWeightMetadata = "robot_weight_N";
constexpr const char* kMethodMetadata = "method";
/// The scenario's duration, recorded when a run was stopped before it (stop_at_s); the trace's
/// duration_s is the run's.
constexpr const char* kScenarioDurationMetadata = "scenario_duration_s";
constexpr const char* kControllerStatusChannel = "ctrl.status";
constexpr const char* kSolverStatusChannel = "solver.status";
constexpr const char* kSolverIterationsChannel = "solver.iterations";
constexpr const char* kSolverFactorizationsChannel = "solver.factorizations";
/// ctrl.status holds the index of the controller's tick status in this list.
const std::vector<std::string>& controllerStatusNames();  // ok, solver_stopped_early, ...
/// solver.status holds the index of the solver's status in this list.
const std::vector<std::string>& solverStatusNames();  // solved, stopped_early, ...

/// Runs checks over a stored trace. Checks that do not apply to the trace's method (metadata
/// `method`) are left out. Machine-dependent checks decide only with `wall_clock_checks`.
std::vector<CheckResult> runChecks(const std::vector<CheckSpec>& specs, const TraceTable& trace, bool wall_clock_checks = false);

/// The figure a comparison compares, for one method: a task_error check of the comparison's
/// tasks, statistic and window, without a limit (+inf).
CheckSpec comparisonStatistic(const ComparisonSpec& spec);

/// Evaluates a comparison on two traces (of the methods `better` and `worse`).
CheckResult compareMethods(const ComparisonSpec& spec, const TraceTable& better, const TraceTable& worse);

}  // namespace lexdyn::checks
