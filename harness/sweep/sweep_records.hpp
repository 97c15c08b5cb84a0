// Internal to harness/sweep: the records a sweep writes (run results, point records, the
// summary, robustness maps), shrinking and the failure database (docs/sweeps.md).
#pragma once

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
constexpr const char* kRunCompleted = "run_completed";

void writeAtomically(const std::string& path, const std::string& text);
/// The whole file ("" when it cannot be read).
std::string readFileText(const std::string& path);
/// A word for the shell: as it is when it is plain, in single quotes otherwise.
std::string shellQuote(const std::string& word);

nlohmann::json toJson(const RunResult& r);
/// A check's result as summary.json and result.json write it.
CheckOutcome checkFromJson(const nlohmann::json& c);
RunResult fromJson(const nlohmann::json& j);

/// One point's record: index, parameter values, overrides, per method the run's result and its
/// reproducer command, the comparisons, the failures ("method:check").
nlohmann::json pointRecord(const SweepSpec& s, const Point& p, const std::map<std::string, RunResult>& runs);

/// Runs one configuration in its own process in `dir`; nullopt when interrupted.
using RunOne = std::function<std::optional<RunResult>(const RunConfig&, const std::string& dir)>;

/// Shrinks each distinct (method, check) failure of the records to the simplest configuration
/// that still fails it (docs/sweeps.md, "Shrinking"); writes OUT/failures/. Returns the list
/// of failures for summary.json.
std::vector<nlohmann::json> shrinkFailures(const SweepSpec& s, const std::vector<nlohmann::json>& records, const DriverOptions& o,
                                           const RunOne& run);
/// The same list without shrinking (each failure at its simplest failing point).
std::vector<nlohmann::json> minimalFailures(const SweepSpec& s, const std::vector<nlohmann::json>& records, const DriverOptions& o);

/// Appends the failures to the database (one JSON line each, without duplicates).
void recordFailures(const SweepSpec& s, const std::vector<nlohmann::json>& failures, const std::string& db_path);
/// Runs the database's failures of this sweep first; writes OUT/replays.jsonl.
void replayFailures(const SweepSpec& s, const DriverOptions& o, const RunOne& run);

/// summary.json: pass rates and worst margins per check and method, win rates of the
/// comparisons, maps, failures.
nlohmann::json summarize(const SweepSpec& s, const std::vector<nlohmann::json>& records, long points,
                         const std::vector<nlohmann::json>& failures, const std::vector<nlohmann::json>& maps);
/// OUT/maps/*.csv for a grid over two parameters, and their pictures through
/// `plot_command` (harness/scripts/sweep_plots.py; "" for none). Returns summary.json's maps.
std::vector<nlohmann::json> writeMaps(const SweepSpec& s, const std::vector<nlohmann::json>& records, const std::string& out_dir,
                                      const std::string& plot_command);
void printSummary(const SweepSpec& s, const nlohmann::json& summary, std::FILE* out);

}  // namespace lexdyn::sweep
