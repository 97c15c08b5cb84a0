// A sweep's records (docs/sweeps.md, docs/file-formats.md): what one run of a sweep gave
// (OUT/runs/<point>/<method>/result.json, the shrink cache, each point record's "runs") and the
// point record's format key, each defined once with one writer and one reader.
#pragma once

#include "harness/records/run_status.hpp"

#include <nlohmann/json_fwd.hpp>

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

}  // namespace lexdyn::records
