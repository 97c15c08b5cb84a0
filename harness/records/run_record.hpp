// A run's record: what `lexdyn-harness run` writes as DIR/summary.json (docs/file-formats.md,
// "Run summary"), as one type with one writer and one reader. The runner fills it, the sweep
// driver, the golden tool and the Python package read it; no tool maps the JSON by hand.
#pragma once

#include "harness/records/run_status.hpp"

#include <nlohmann/json_fwd.hpp>

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lexdyn::records {

/// summary.json's "format": readers refuse other versions and say so.
inline constexpr const char* kRunSummaryFormat = "lexdyn-run-summary/1";
/// The "format" of `lexdyn-harness check --json` and `compare --json` ({format, checks,
/// all_checks_passed}).
inline constexpr const char* kCheckResultsFormat = "lexdyn-check-results/1";

/// One check's outcome (NaN value/limit/margin: not computed; written as null).
struct CheckRecord {
  std::string name, type;
  bool passed = false;
  double value = 0.0, limit = 0.0, margin = 0.0;
  std::string unit, detail;
  /// A wall-clock measurement: reported, and a verdict only when `decides`.
  bool machine_dependent = false;
  bool decides = true;
  std::string partial_window;  ///< a run stopped early inside the check's window: what was run
};

struct IntegratorRecord {
  long steps = 0, rhs_evals = 0, jac_evals = 0, jac_rhs_evals = 0, nonlin_iters = 0, nonlin_conv_fails = 0, err_test_fails = 0,
       restarts = 0;
};

struct ExpectedFailureRecord {
  RunStatus status = RunStatus::Completed;
  std::vector<std::string> checks;
  std::string reason;
  bool met = false;  ///< the run failed exactly as expected
  std::vector<std::string> mismatches;
  bool reached = false;
};

/// The controller's figures (lexdyn controllers only).
struct ControllerRecord {
  struct Task {
    double final_error = 0.0, mean_error = 0.0;
  };
  struct Timing {
    double median = 0.0, p99 = 0.0, max = 0.0;  ///< microseconds
  };
  std::map<std::string, Task> tasks;
  long ticks = 0;
  std::map<std::string, long> status_counts, augmented_ticks;
  int peak_iterations = 0;
  double peak_iterations_at_s = 0.0;
  int peak_factorizations = 0;
  double peak_factorizations_at_s = 0.0;
  std::map<std::string, long> solver_status_counts;
  std::map<std::string, Timing> timing_us;
};

/// How a run ended and what it covered: the fields a run's in-memory result (RunSummary, with
/// the rich check results) and its record share, defined once.
struct RunOutcome {
  RunStatus status = RunStatus::Completed;
  std::string message;  ///< what stopped the run early
  std::string method;   ///< lexdyn: bfgs | ah | gn | wls; "" for a case without methods (not written then)
  double duration_s = 0.0, simulated_s = 0.0, wall_s = 0.0, realtime_factor = 0.0;
  long ticks = 0;
  bool all_checks_passed = false;
  /// What the start found questionable (read as none when absent).
  std::vector<std::string> start_warnings;
};

struct RunRecord : RunOutcome {
  std::string format = kRunSummaryFormat;
  std::string case_name, case_file;
  IntegratorRecord integrator;
  std::vector<CheckRecord> checks;
  struct Statistic {
    double value = 0.0;
    std::string detail;
  };
  std::map<std::string, Statistic> statistics;                      ///< not written when empty
  std::vector<std::pair<std::string, std::string>> overrides;       ///< path, value
  std::string effective_case;                                       ///< file name in the run's folder
  std::vector<std::pair<std::string, std::string>> skipped_checks;  ///< name, reason
  std::optional<double> scenario_duration_s;                        ///< written when the run was cut short (--duration)
  std::vector<std::string> robot_warnings;
  std::optional<ExpectedFailureRecord> expected_failure;
  int exit_code = 0;
  std::optional<ControllerRecord> controller;
  std::string trace;  ///< file name in the run's folder
  std::vector<std::pair<std::string, std::string>> trace_header;

  const CheckRecord* check(const std::string& name) const;
};

/// A list of checks as summary.json writes it ("checks"; `lexdyn-harness check --json` too).
nlohmann::json toJson(const std::vector<CheckRecord>& checks);
/// summary.json's object.
nlohmann::json toJson(const RunRecord& r);
/// Reads summary.json's object; `where` names the file in errors. A summary of another format
/// (or none) is refused first, naming the format; otherwise every missing or mistyped field is
/// reported at once (lexdyn::InputError, "FILE: field: problem; field: problem").
RunRecord runRecordFromJson(const nlohmann::json& j, const std::string& where);
/// Reads and parses the file (lexdyn::InputError for a file that is missing or not JSON too).
RunRecord readRunRecord(const std::string& path);

}  // namespace lexdyn::records
