// A sweep's records (docs/sweeps.md, docs/file-formats.md): what one run of a sweep gave
// (OUT/runs/<point>/<method>/result.json, the shrink cache, each point record's "runs") and the
// point record, the failure database's entries and their replays, each defined once with one
// writer and one reader.
#pragma once

#include "harness/records/run_status.hpp"

#include <nlohmann/json_fwd.hpp>

#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace lexdyn::records {

/// result.json's "format" (and the shrink cache's results'); readers refuse others, naming it.
inline constexpr const char* kSweepRunFormat = "lexdyn-sweep-run/1";
/// OUT/points/<i>.json's and results.jsonl's lines' "format".
inline constexpr const char* kSweepPointFormat = "lexdyn-sweep-point/1";
/// OUT/summary.json's "format".
inline constexpr const char* kSweepSummaryFormat = "lexdyn-sweep-summary/1";
/// The failure database's lines' "format" (a line without one, written before the key existed,
/// is read as this version).
inline constexpr const char* kSweepFailureFormat = "lexdyn-sweep-failure/1";
/// OUT/replays.jsonl's lines' "format".
inline constexpr const char* kSweepReplayFormat = "lexdyn-sweep-replay/1";

/// The pseudo-check of a run that stopped early (integrator or controller failure, timeout,
/// crash, bad input).
inline constexpr const char* kRunCompletedCheck = "run_completed";

/// One property check of a sweep run (NaN value/limit/margin: not computed; written as null).
struct SweepCheckRecord {
  std::string name;
  bool passed = false;
  double value = 0.0, limit = 0.0, margin = 0.0;
  std::string unit, detail;
};

/// What one simulation of a sweep gave.
struct SweepRunRecord {
  /// A status a sweep records (isRecordedBySweeps): the run's own (completed,
  /// integrator_failure, controller_failure, diverged, internal_error, input_error) or what the
  /// driver saw of the process (timeout, crashed, bad_input).
  RunStatus status = RunStatus::Completed;
  std::string message;
  int exit_code = 0;    ///< the process's, or 128 + signal
  double wall_s = 0.0;  ///< not deterministic; never compared
  double simulated_s = 0.0;
  std::vector<SweepCheckRecord> checks;        ///< the sweep's property checks for the method
  std::map<std::string, double> statistics;    ///< the comparisons' per-method figures
  std::map<std::string, double> final_errors;  ///< per task
  int peak_iterations = 0;
  /// The failures of this run: kRunCompletedCheck when it stopped early, and every failed check.
  std::vector<std::string> failures() const;
  const SweepCheckRecord* check(const std::string& name) const;
};

nlohmann::json toJson(const SweepRunRecord& r);
/// A run's record read back (result.json, a shrink-cache line, a point record's run): nullopt,
/// with `why`, when `j` is not a whole record of this format of a run that ended on its own or
/// by the driver's timeout (another format or none, a damaged file, or a status a sweep never
/// records: killed, interrupted).
std::optional<SweepRunRecord> sweepRunFromJson(const nlohmann::json& j, std::string& why);

/// One comparison at one point: `better`'s statistic minus `worse`'s (docs/sweeps.md).
struct SweepComparisonRecord {
  std::string name, better, worse;
  /// NaN when the two runs do not compare (one stopped early, a statistic is missing).
  double value = std::numeric_limits<double>::quiet_NaN();
  double limit = 0.0;                                        ///< the comparison's margin
  double margin = std::numeric_limits<double>::quiet_NaN();  ///< limit - value
  bool better_wins = false;
  std::vector<std::string> stopped_early;  ///< the methods whose run stopped early
};

/// A method's run at a point, with the commands that run it again.
struct SweepPointRun {
  SweepRunRecord run;
  std::string reproduce;  ///< the `lexdyn-harness run` command with the point's overrides
  std::string rerun;      ///< the `lexdyn-harness sweep point` command
};

/// One point of a sweep (OUT/points/<i>.json, a line of results.jsonl).
struct SweepPointRecord {
  long point = 0;
  std::map<std::string, std::string> values;                   ///< parameter -> value
  std::vector<std::pair<std::string, std::string>> overrides;  ///< (path, value) as the case takes them
  std::map<std::string, SweepPointRun> runs;                   ///< by method
  std::vector<SweepComparisonRecord> comparisons;
  std::vector<std::string> failures;  ///< "method:check", every run's failures in the sweep's method order
  /// The run of `method` (std::out_of_range when the point has none).
  const SweepRunRecord& run(const std::string& method) const { return runs.at(method).run; }
  /// The value of `parameter` at this point (`otherwise` when the record has none).
  std::string value(const std::string& parameter, const std::string& otherwise = "") const;
};

nlohmann::json toJson(const SweepPointRecord& r);
/// A point record read back: nullopt, with `why`, when `j` is not a whole point record of this
/// format (another format or none, a missing or mistyped field, a run that is no run record).
std::optional<SweepPointRecord> sweepPointFromJson(const nlohmann::json& j, std::string& why);

/// A line of a sweep's failure database (docs/sweeps.md, "The failure database"): a minimal
/// failure of a sweep of that name, replayed first by its next run.
struct SweepFailureEntry {
  std::string sweep, method, check;
  std::map<std::string, std::string> values;  ///< the parameters away from their simplest values
  double duration_s = 0.0;                    ///< the failing run's duration (0: the sweep's own)
};

nlohmann::json toJson(const SweepFailureEntry& e);
/// A database line read back: nullopt, with `why`, when it is no entry of this format.
std::optional<SweepFailureEntry> sweepFailureFromJson(const nlohmann::json& j, std::string& why);

/// A line of OUT/replays.jsonl: an entry of the failure database run again.
struct SweepReplayRecord {
  SweepFailureEntry entry;
  RunStatus status = RunStatus::Completed;
  bool still_fails = false;
  /// The check's value and limit in the replay (NaN: the run has no such check, or not computed).
  double value = std::numeric_limits<double>::quiet_NaN(), limit = std::numeric_limits<double>::quiet_NaN();
};

nlohmann::json toJson(const SweepReplayRecord& r);

}  // namespace lexdyn::records
