// The lexdyn controller in the case runner (docs/cases.md, "The closed loop"): builds the
// controller of a case for its method, applies the controller's timeline events, closes the loop
// with the simulator every tick (measured state in, joint set-points and feed-forward torques
// out) and records the controller's trace channels and summary statistics.
#pragma once

#include "harness/cases/case_file.hpp"
#include "harness/checks/trace.hpp"

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace lexdyn::cases {

/// Per-run statistics of the controller for summary.json (over every tick, not only the rows
/// written to the trace).
struct ControllerStats {
  struct Task {
    std::string name;
    double final_error = 0.0;
    double mean_error = 0.0;  ///< mean over the ticks (uniform in time)
  };
  struct Timing {
    std::string name;  ///< model | tasks | hessian | solver | tick
    double median_us = 0.0, p99_us = 0.0, max_us = 0.0;
  };
  std::string method;
  long ticks = 0;
  std::vector<Task> tasks;
  int peak_iterations = 0;
  double peak_iterations_at_s = 0.0;
  int peak_factorizations = 0;  ///< solver level stages factorised in a tick, the largest
  double peak_factorizations_at_s = 0.0;
  std::vector<std::pair<std::string, long>> status_counts;         ///< controller tick status
  std::vector<std::pair<std::string, long>> solver_status_counts;  ///< solver status
  std::vector<std::pair<std::string, long>> augmented_ticks;       ///< per configured level
  std::vector<Timing> timing;
};

class LexdynDriver {
 public:
  /// Builds the controller (its own RobotModel from the case's robot files) for the case's
  /// method. Throws lexdyn::InputError.
  LexdynDriver(const CaseSpec& spec, const sim::Simulator& simu);
  ~LexdynDriver();
  LexdynDriver(const LexdynDriver&) = delete;
  LexdynDriver& operator=(const LexdynDriver&) = delete;

  /// Registers the controller's channels after the simulator's.
  void addChannels(checks::TraceSchema& schema) const;
  /// Trace header lines describing the controller (method, parameters, hierarchy, codes).
  void addMetadata(checks::TraceMetadata& md) const;
  /// Controller::reset at the simulator's current (initial) state.
  void reset(const sim::Simulator& simu);
  /// Applies a controller event (set_target, add_contact, remove_contact, target_trajectory,
  /// swing) at tick time t; contacts switch their linked simulator grasps too.
  void applyEvent(const EventSpec& e, double t, sim::Simulator& simu);
  /// Moves the running target generators to time t, ticks the controller at the simulator's
  /// state and fills `cmd` (set-point for t + dt). False when the controller failed
  /// (Command::ok() false); `failure` then says how.
  bool tick(double t, const sim::Simulator& simu, sim::JointCommand& cmd, std::string& failure);
  /// The divergence guard after a successful tick at time t (docs/cases.md, "Divergence guard"):
  /// empty while the simulated robot follows the plan, otherwise why the run must stop.
  std::string divergence(double t, const sim::Simulator& simu);
  /// Writes this tick's controller channels (addChannels' order) from `out` on; returns the
  /// number of values written.
  int fill(const sim::Simulator& simu, double* out) const;
  ControllerStats stats() const;
  /// Writes the solver problem of the last tick to `path` (problem file format).
  void writeProblem(const std::string& path) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lexdyn::cases
