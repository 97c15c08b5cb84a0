// Runs a case: simulator + controller + events, records the trace, evaluates the checks, and
// writes DIR/trace.csv and DIR/summary.json (docs/simulator.md, "Running a case").
#pragma once

#include "harness/cases/case_file.hpp"
#include "harness/cases/lexdyn_driver.hpp"

#include <atomic>
#include <string>
#include <vector>

namespace lexdyn::cases {

struct RunOptions {
  std::string out_dir;
  bool progress = true;                          ///< progress lines on stderr
  /// Wall-clock seconds between progress lines. Only stderr depends on it, never the
  /// simulation, the trace or the summary.
  double progress_interval_s = 2.0;
  const std::atomic<bool>* interrupt = nullptr;  ///< set (e.g. by SIGINT) to stop after a tick
  /// Figures to record besides the checks (their limits are ignored): e.g. the per-method
  /// statistics of a sweep's method comparisons, summary.json "statistics".
  std::vector<checks::CheckSpec> statistics;
};

struct RunSummary {
  std::string status;   ///< completed | integrator_failure | controller_failure | interrupted
  std::string message;  ///< what stopped the run early
  std::string method;   ///< lexdyn: bfgs | ah | gn | wls ("" for other controllers)
  double duration_s = 0.0;
  double simulated_s = 0.0;
  double wall_s = 0.0;
  double realtime_factor = 0.0;
  long ticks = 0;
  sim::CvodeStats integrator;
  long integrator_restarts = 0;
  std::vector<checks::CheckResult> checks;
  std::vector<checks::CheckResult> statistics;  ///< RunOptions::statistics, evaluated
  std::vector<std::string> skipped_checks;  ///< checks restricted to other methods
  bool all_checks_passed = false;
  bool has_controller_stats = false;
  ControllerStats controller;               ///< lexdyn: per task errors, iterations, timings
  std::string trace_path, summary_path;
  std::string case_path;  ///< DIR/case.yaml: the effective case (effectiveCaseText)
};

/// Throws lexdyn::InputError for bad input (nothing is simulated then).
RunSummary runCase(const CaseSpec& spec, const RunOptions& options);

/// 0: completed and every check passed; 1: a check failed or the run stopped early.
int exitCode(const RunSummary& summary);

/// {"checks": [...], "all_checks_passed": bool} with the checks as summary.json writes them
/// (`lexdyn-harness check --json`, `compare --json`).
std::string checkResultsJson(const std::vector<checks::CheckResult>& results);

}  // namespace lexdyn::cases
