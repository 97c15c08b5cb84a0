// Internal to harness/sweep: the records a sweep writes (run results, point records, the
// summary, robustness maps), shrinking and the failure database (docs/sweeps.md).
#pragma once

#include "harness/records/sweep_summary.hpp"
#include "harness/sweep/sweep_run.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lexdyn::sweep {

/// The pseudo-check of a run that stopped early (integrator or controller failure, timeout,
/// crash, bad input).
constexpr const char* kRunCompleted = records::kRunCompletedCheck;

void writeAtomically(const std::string& path, const std::string& text);
/// The whole file ("" when it cannot be read).
std::string readFileText(const std::string& path);
/// A word for the shell: as it is when it is plain, in single quotes otherwise.
std::string shellQuote(const std::string& word);

// FNV-1a of a text, as 16 hex digits (a trial's folder name, sweep.txt's digest).
std::string textDigest(const std::string& text);

/// A run's result read back from OUT (result.json, a shrink-cache line): records::sweepRunFromJson.
inline std::optional<RunResult> recordedResult(const nlohmann::json& j, std::string& why) { return records::sweepRunFromJson(j, why); }
/// The file parsed as JSON, or nullopt with `why` (missing, unreadable, damaged).
std::optional<nlohmann::json> readJsonFile(const std::string& path, std::string& why);

using PointRecord = records::SweepPointRecord;
using FailureRecord = records::SweepFailureRecord;

/// The record of point `index` stored in `path`: nullopt, with `why`, when it does not read back
/// whole as a record of this format, or is not that point's, or lacks a method's run.
std::optional<PointRecord> readPointRecord(const SweepSpec& s, long index, const std::string& path, std::string& why);

/// One point's record: index, parameter values, overrides, per method the run's result and its
/// reproducer command, the comparisons, the failures ("method:check").
PointRecord pointRecord(const SweepSpec& s, const Point& p, const std::map<std::string, RunResult>& runs);

/// What became of one configuration run in its own process.
struct Trial {
  enum class End {
    kRecorded,     ///< it ended on its own (or by the driver's timeout): `result` holds it
    kInterrupted,  ///< the driver was asked to stop: nothing recorded, run again next time
    kLost,         ///< killed by something else twice (`why`): nothing recorded
  };
  End end = End::kRecorded;
  RunResult result;
  std::string why;
};
/// Runs one configuration in its own process in `dir`.
using RunOne = std::function<Trial(const RunConfig&, const std::string& dir)>;

/// Shrinks each distinct (method, check) failure of the records to the simplest configuration
/// that still fails it (docs/sweeps.md, "Shrinking"); writes OUT/failures/. Returns the list
/// of failures for summary.json.
/// A trial lost twice is not cached and leaves its failure unshrunk; its reason is added to `lost`
/// (the caller writes no summary then: the sweep is not finished).
std::vector<FailureRecord> shrinkFailures(const SweepSpec& s, const std::vector<PointRecord>& records, const DriverOptions& o,
                                          const RunOne& run, std::vector<std::string>& lost);
/// The same list without shrinking (each failure at its simplest failing point).
std::vector<FailureRecord> minimalFailures(const SweepSpec& s, const std::vector<PointRecord>& records);

/// Appends the failures to the database (one JSON line each, without duplicates), under its lock.
/// False when `interrupt` became nonzero while waiting for the lock (nothing written).
bool recordFailures(const SweepSpec& s, const std::vector<FailureRecord>& failures, const std::string& db_path,
                    const std::atomic<int>* interrupt = nullptr);
/// Runs the database's failures of this sweep first; writes OUT/replays.jsonl. False when a
/// replay was interrupted or lost (`lost` says why): replayed again next time.
bool replayFailures(const SweepSpec& s, const DriverOptions& o, const RunOne& run, std::vector<std::string>& lost);

/// summary.json: pass rates and worst margins per check and method, win rates of the
/// comparisons, maps, failures.
records::SweepSummary summarize(const SweepSpec& s, const std::vector<PointRecord>& records, long points,
                                std::vector<FailureRecord> failures, std::vector<records::SweepMapRecord> maps);
/// OUT/maps/*.csv for a grid over two parameters, and their pictures through
/// `plot_command` (harness/scripts/sweep_plots.py; "" for none). Returns summary.json's maps.
std::vector<records::SweepMapRecord> writeMaps(const SweepSpec& s, const std::vector<PointRecord>& records, const std::string& out_dir,
                                               const std::string& plot_command);
void printSummary(const records::SweepSummary& summary, std::FILE* out);

}  // namespace lexdyn::sweep
