// Runs a case: simulator + controller + events, records the trace, evaluates the checks, and
// writes DIR/trace.csv and DIR/summary.json (docs/simulator.md, "Running a case").
#pragma once

#include "harness/cases/case_file.hpp"
#include "harness/cases/lexdyn_driver.hpp"
#include "harness/records/run_record.hpp"

#include <atomic>
#include <optional>
#include <string>
#include <vector>

namespace lexdyn::cases {

struct RunOptions {
  std::string out_dir;
  bool progress = true;  ///< progress lines on stderr
  /// Wall-clock seconds between progress lines. Only stderr depends on it, never the
  /// simulation, the trace or the summary.
  double progress_interval_s = 2.0;
  const std::atomic<bool>* interrupt = nullptr;  ///< set (e.g. by SIGINT) to stop after a tick
  /// Figures to record besides the checks (their limits are ignored): e.g. the per-method
  /// statistics of a sweep's method comparisons, summary.json "statistics".
  std::vector<checks::CheckSpec> statistics;
  /// The signal that set `interrupt` (SIGINT, SIGTERM), named in the trace's end mark and the
  /// summary; 0 when unknown.
  const std::atomic<int>* interrupt_signal = nullptr;
  /// Wall-clock checks (tick_time) decide pass/fail only when true; otherwise they are reported
  /// and labelled machine-dependent (docs/cases.md, "Checks").
  bool wall_clock_checks = false;
  /// When not empty: the solver problem of every controller tick with dump_from_s <= t <=
  /// dump_to_s is written to this directory as tick_NNNNNN.json (the problem file format,
  /// docs/file-formats.md), for lexdyn-solve (a single tick, or --bench on the sequence). Only
  /// for a lexdyn controller; writing does not change the run.
  std::string dump_problems_dir;
  double dump_from_s = 0.0;
  double dump_to_s = 1e300;  // the end of any run
};

/// A run's result in memory: its outcome (status: completed, integrator_failure,
/// controller_failure, diverged, internal_error, interrupted, input_error or output_error; times;
/// start warnings), shared with its record, and the rich check results the record is made from.
struct RunSummary : records::RunOutcome {
  int signal = 0;  ///< interrupted: the signal (SIGINT, SIGTERM), 0 when unknown
  sim::CvodeStats integrator;
  long integrator_restarts = 0;
  std::vector<checks::CheckResult> checks;
  std::vector<checks::CheckResult> statistics;  ///< RunOptions::statistics, evaluated
  /// Checks not evaluated: restricted to other methods, or whose window starts after a run
  /// stopped early (stop_at_s) ends; each with the reason.
  struct Skipped {
    std::string name, reason;
  };
  std::vector<Skipped> skipped_checks;
  bool has_controller_stats = false;
  ControllerStats controller;  ///< lexdyn: per task errors, iterations, timings
  std::string trace_path, summary_path;
  std::string case_path;  ///< DIR/case.yaml: the effective case (effectiveCaseText)
  /// The case's expected failure for this run's method (expected_failures), if it has one,
  /// and how the run departs from it (empty: the run failed exactly as expected).
  std::optional<ExpectedFailure> expected_failure;
  std::vector<std::string> expectation_mismatches;
  /// False when a run stopped early (stop_at_s) ended before the expected failure showed: the
  /// expected status not reached and none of the listed checks failing. True otherwise.
  bool expected_failure_reached = true;
};

/// How a finished run departs from an expected failure: a status other than the expected one,
/// a check that decides and fails but is not listed, a listed check that passed or was not
/// evaluated. Empty when the run failed exactly as expected.
/// `cut_short`: the run was stopped early (stop_at_s): the expected failure may lie beyond its end,
/// so only a failure that is not expected departs from it.
std::vector<std::string> expectationMismatches(const ExpectedFailure& expected, records::RunStatus status,
                                               const std::vector<checks::CheckResult>& results, bool cut_short = false);

/// Throws lexdyn::InputError for bad input (nothing is simulated then). An exception once the
/// run has started (an internal error, out of memory) stops it: the trace is kept with the end
/// mark internal_error, the summary says why (status internal_error).
RunSummary runCase(const CaseSpec& spec, const RunOptions& options);

/// The exit codes of docs/architecture.md ("Errors and exit codes").
inline constexpr int kExitPass = 0;           ///< completed, every check that decides passed
inline constexpr int kExitCheckFailed = 1;    ///< a check, comparison or golden failed
inline constexpr int kExitBadInput = 2;       ///< bad input: file, line and key path named
inline constexpr int kExitRunFailure = 3;     ///< integrator, controller or solver failure, internal error
inline constexpr int kExitInterrupted = 128;  ///< + the signal: 130 SIGINT, 143 SIGTERM

/// 128 + signal when interrupted (130 when the signal is unknown); 3 on a run failure; 1 when a
/// check that decides failed; 0 otherwise. With an expected failure: 0 when the run failed
/// exactly as expected, else 3 for a run failure other than the expected status, else 1.
int exitCode(const RunSummary& summary);

/// The run's record (summary.json): the summary with the case's name, file, overrides and robot
/// warnings and the trace's header.
records::RunRecord runRecord(const CaseSpec& spec, const RunSummary& summary, const checks::TraceMetadata& trace_header);
/// One check's outcome as records keep it (the margin computed).
records::CheckRecord checkRecord(const checks::CheckResult& result);

/// {"checks": [...], "all_checks_passed": bool} with the checks as summary.json writes them
/// (`lexdyn-harness check --json`, `compare --json`).
std::string checkResultsJson(const std::vector<checks::CheckResult>& results);

/// The channel names a run of the case (its current method) records, in trace order, without
/// running it (the simulator and the controller are built, nothing is simulated).
std::vector<std::string> traceChannels(const CaseSpec& spec);

}  // namespace lexdyn::cases
