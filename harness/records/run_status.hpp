// How a run ended, as every tool of the harness names it (docs/file-formats.md, "Run statuses"):
// the run's own statuses, which `lexdyn-harness run` writes into summary.json and the trace's end
// mark, and the ones a sweep driver records for a process it watched. One enum, one spelling per
// status; files carry the spelling, code carries the enum.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lexdyn::records {

enum class RunStatus {
  // A run's own (summary.json "status", the trace's end mark):
  Completed,          ///< ran to its end (its checks decide the verdict)
  IntegratorFailure,  ///< the simulator's integrator gave up
  ControllerFailure,  ///< the controller could not produce a command
  Diverged,           ///< the divergence guard stopped it: the plan left the robot
  InternalError,      ///< an exception inside the harness
  Interrupted,        ///< SIGINT / SIGTERM from outside
  InputError,         ///< bad input found during the run (e.g. a target out of its table)
  OutputError,        ///< its outputs could not be written (disk full, ...)
  // What a sweep driver records of a process (results.jsonl, result.json):
  Timeout,    ///< killed by the driver after the sweep's timeout
  Crashed,    ///< the process died twice on the same configuration
  BadInput,   ///< the process refused its input (exit code 2)
  NoSummary,  ///< older records only: a process that left no summary
};

/// The file spelling: "completed", "integrator_failure", ...
const char* toString(RunStatus s);
/// The status a spelling names; nullopt for any other text.
std::optional<RunStatus> parseRunStatus(std::string_view text);
/// Every status, in declaration order (documentation, tests).
const std::vector<RunStatus>& allRunStatuses();
/// A status `lexdyn-harness run` itself writes (the first eight).
bool isRunsOwn(RunStatus s);
/// Those statuses, in declaration order (the choices a reader names when it refuses another).
const std::vector<RunStatus>& runsOwnStatuses();
/// A verdict about the configuration that a sweep records (the run ended on its own or by the
/// sweep's timeout); the rest (interrupted, output_error, no_summary) say something about the
/// machine, not the configuration.
bool isRecordedBySweeps(RunStatus s);
/// Writes the file spelling (test messages, logs).
std::ostream& operator<<(std::ostream& os, RunStatus s);
/// "completed | integrator_failure | ..." of the given statuses, for error messages.
std::string spellings(const std::vector<RunStatus>& statuses);

}  // namespace lexdyn::records
