// Checks read traces (channels by name), never live objects, so they run the same on a fresh
// simulation (row by row as the run goes) and on a stored trace file.
//
// Check types (docs/simulator.md, "Checks"; docs/cases.md, "Checks" for the controller's):
//   frame_drift     max |p(t) - p(from_s)| of a frame's origin over t >= from_s        [m]
//   force_balance   max |sum of contact normal forces - robot weight| / weight, t >= from_s
//   contact_slip    max horizontal displacement of any contact point of the given surfaces
//                   from its position at from_s, over t >= from_s                     [m]
//   frame_height    lowest height of a frame's origin over t >= from_s (e.g. "has not fallen")
// and, on the channels of the lexdyn controller (controller_checks.cpp):
//   task_error, torque_limits, contact_unilateral, contact_friction, contact_cop,
//   contact_wrench_match, joint_acceleration_sign_changes, joint_velocity_hf_energy,
//   task_error_rate_sign_changes, task_error_closed_form, task_overshoot, controller_status,
//   active_set_peak, factorization_peak, augmented_fraction, tick_time (machine-dependent: it
//   decides only when asked, applyWallClockPolicy).
// A check passes when it saw at least one row in its window [from_s, to_s] and its value is on
// the right side of its limit.
#pragma once

#include "harness/checks/trace.hpp"

#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace lexdyn::checks {

struct CheckSpec {
  std::string name;
  std::string type;                    ///< one of checkTypes()
  std::string frame;                   ///< frame_drift, frame_height
  std::vector<std::string> surfaces;   ///< force_balance, contact_slip
  double from_s = 0.0;
  double limit = 0.0;
  std::string where;                   ///< origin in the case file, for messages
  // --- controller checks (docs/cases.md, "Checks") ---
  double to_s = std::numeric_limits<double>::infinity();  ///< end of the window
  std::vector<std::string> methods;    ///< the check applies to these methods only (empty: all)
  std::vector<std::string> tasks;      ///< task_error (sum of norms), task_error_rate_sign_changes (one)
  std::string statistic;               ///< task_error: final | mean | max; contact_wrench_match: rms | max
  std::string source;                  ///< torque_limits: applied | commanded | both; joint_*: measured |
                                       ///< commanded; contact_*: computed | sensed
  std::vector<std::string> joints;     ///< joint names (resolved by the case loader)
  std::vector<double> joint_limits;    ///< torque_limits: effort limit of each joint of `joints`
  std::string contact;                 ///< contact_* checks: a controller contact
  double normal[3] = {0.0, 0.0, 1.0};  ///< contact normal in the contact frame
  double friction = 0.0;               ///< contact_friction: mu
  std::vector<std::pair<double, double>> polygon;  ///< contact_cop: convex support polygon (x, y) in
                                                   ///< the contact frame, counter-clockwise
  double min_normal_N = 0.0;           ///< contact_friction, contact_cop: rows below are skipped
  std::string component;               ///< contact_wrench_match: force | torque
  double dead_band = 0.0;              ///< *_sign_changes: |rate| <= dead_band carries no sign
  double cutoff_hz = 0.0;              ///< joint_velocity_hf_energy
  double percentile = 100.0;           ///< tick_time
  std::string level;                   ///< augmented_fraction
  std::string timer;                   ///< tick_time: model | tasks | hessian | solver | tick
  std::vector<std::string> allowed;    ///< controller_status: statuses that count as fine
  double kp = 0.0, kv = 0.0;           ///< task_error_closed_form: the PD gains (1/s^2, 1/s)
};

/// Comparison of two runs of the same case with different methods (e.g. exp1: the final sum of
/// hand errors of bfgs <= that of wls): value = stat(better) - stat(worse), passes when
/// value <= margin.
struct ComparisonSpec {
  std::string name;
  std::string type = "method_comparison";
  std::vector<std::string> tasks;
  std::string statistic = "final";     ///< final | mean | max of the sum of the tasks' error norms
  std::string better, worse;           ///< methods
  double margin = 0.0;
  double from_s = 0.0;
  double to_s = std::numeric_limits<double>::infinity();
  std::string where;
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
};

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
/// for those that bound it from below (frame_height, contact_unilateral). Negative: failed by
/// that much; NaN when there is no value.
double margin(const CheckResult& result);

/// The known check types.
const std::vector<std::string>& checkTypes();
std::unique_ptr<Check> makeCheck(const CheckSpec& spec);
/// True when the check applies to runs of `method` (an empty method: a trace without one).
bool appliesTo(const CheckSpec& spec, const std::string& method);

/// Channel names the runner records and the checks read.
std::string frameChannel(const std::string& frame, char axis);               // frame.<F>.<x|y|z>
std::string contactForceChannel(const std::string& surface);                 // contact.<S>.fz
std::string contactPointChannel(const std::string& surface, int point, char axis);  // contact.<S>.p<i>.<x|y>
// The lexdyn controller's channels (docs/cases.md, "Trace channels").
std::string taskChannel(const std::string& task, const char* what);        // task.<T>.<error|active|engaged>
std::string levelChannel(const std::string& level, const char* what);      // level.<L>.<augmented|hessian_updated|violation>
std::string wrenchChannel(const std::string& contact, bool sensed, const char* component);  // wrench[_sensed].<C>.<fx..tz>
std::string contactActiveChannel(const std::string& contact);              // ctrl_contact.<C>.active
std::string timerChannel(const std::string& timer);                        // time.<timer>_us
constexpr const char* kTimeChannel = "t";
constexpr const char* kWeightMetadata = "robot_weight_N";
constexpr const char* kMethodMetadata = "method";
constexpr const char* kControllerStatusChannel = "ctrl.status";
constexpr const char* kSolverStatusChannel = "solver.status";
constexpr const char* kSolverIterationsChannel = "solver.iterations";
constexpr const char* kSolverFactorizationsChannel = "solver.factorizations";
/// ctrl.status holds the index of the controller's tick status in this list.
const std::vector<std::string>& controllerStatusNames();  // ok, solver_stopped_early, ...
/// solver.status holds the index of the solver's status in this list.
const std::vector<std::string>& solverStatusNames();      // solved, stopped_early, ...

/// Runs checks over a stored trace. Checks that do not apply to the trace's method (metadata
/// `method`) are left out. Machine-dependent checks decide only with `wall_clock_checks`.
std::vector<CheckResult> runChecks(const std::vector<CheckSpec>& specs, const TraceTable& trace,
                                   bool wall_clock_checks = false);

/// The figure a comparison compares, for one method: a task_error check of the comparison's
/// tasks, statistic and window, without a limit (+inf).
CheckSpec comparisonStatistic(const ComparisonSpec& spec);

/// Evaluates a comparison on two traces (of the methods `better` and `worse`).
CheckResult compareMethods(const ComparisonSpec& spec, const TraceTable& better, const TraceTable& worse);

}  // namespace lexdyn::checks
