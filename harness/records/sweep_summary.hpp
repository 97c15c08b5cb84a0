// A sweep's summary (OUT/summary.json, docs/sweeps.md "summary.json"), defined once: what the
// driver computes from the point records, written by toJson and read by lexdyn.read_sweep_summary.
#pragma once

#include "harness/records/run_status.hpp"
#include "harness/records/sweep_record.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lexdyn::records {

/// A parameter of the sweep as its file gives it.
struct SweepParameterRecord {
  enum class Kind { Range, LogRange, Integers, Values, Choices };
  std::string name;
  std::vector<std::string> paths;
  std::string simplest;
  Kind kind = Kind::Range;
  double lo = 0.0, hi = 0.0;        ///< Range, LogRange, Integers
  std::vector<std::string> values;  ///< Values (YAML text), Choices (labels)
};

/// A check (or run_completed) of a method over every point.
struct SweepCheckSummary {
  std::string check, method;
  long runs = 0, passed = 0;
  /// The lowest margin; not finite (written as null) when none was computed (+inf: every check
  /// passed without a value, -inf: one failed without one).
  double worst_margin = std::numeric_limits<double>::quiet_NaN();
  long worst_point = -1;
  std::string unit;
  double passRate() const { return runs ? static_cast<double>(passed) / static_cast<double>(runs) : 0.0; }
};

/// Points and wins of a comparison.
struct SweepWinCount {
  long points = 0, wins = 0;
  double winRate() const { return points ? static_cast<double>(wins) / static_cast<double>(points) : 0.0; }
};

/// A comparison over every point where both runs compare.
struct SweepComparisonSummary {
  std::string name, better, worse, statistic;
  std::vector<std::string> tasks;
  double from_s = 0.0, to_s = std::numeric_limits<double>::infinity(), margin = 0.0;
  long better_stopped_early = 0, worse_stopped_early = 0;
  SweepWinCount overall;
  std::vector<double> diffs;  ///< better - worse at each point that compares, sorted
  /// The nearest-rank quantile q of `diffs` (NaN when none).
  double diffQuantile(double q) const;
  /// Per parameter with a set of values (not a range), per value.
  std::map<std::string, std::map<std::string, SweepWinCount>> by_parameter;
};

/// A robustness map over the two parameters of a grid sweep.
struct SweepMapRecord {
  struct Axis {
    std::string name, path;
    std::vector<std::string> values;
  };
  Axis x, y;
  std::string property;  ///< a check, run_completed or a comparison
  std::string method;    ///< a method, or "BETTER vs WORSE"
  std::string csv;       ///< relative to the sweep's folder
  std::string png;       ///< "" when not drawn
};

/// A distinct (method, check) failure at its simplest failing configuration.
struct SweepFailureRecord {
  std::string check, method;
  long point = -1;  ///< the point shrinking started from
  long points_failing = 0;
  std::map<std::string, std::string> values;                   ///< the parameters away from their simplest values
  std::vector<std::pair<std::string, std::string>> overrides;  ///< every override of the configuration
  double duration_s = 0.0;
  std::string command;  ///< runs it again
  RunStatus status = RunStatus::Completed;
  std::optional<SweepCheckRecord> outcome;  ///< the check in that run (none for run_completed)
  bool shrunk = false;
  // Shrunk failures only:
  std::string case_file;  ///< failures/METHOD.CHECK.yaml
  int runs = 0;           ///< trials the shrink counted
  bool budget_exhausted = false;
  /// The failure database's entry of this failure in sweep `sweep`.
  SweepFailureEntry entry(const std::string& sweep) const { return {sweep, method, check, values, duration_s}; }
};

struct SweepSummary {
  std::string name, description, sweep_file, base_case;
  std::vector<std::string> methods;
  std::uint64_t seed = 0;
  bool grid = false;
  std::optional<double> duration_s;
  std::vector<SweepParameterRecord> parameters;
  long points = 0;     ///< the sweep's points
  long completed = 0;  ///< those with a record
  long failed_points = 0;
  std::vector<SweepCheckSummary> checks;
  std::vector<SweepComparisonSummary> comparisons;
  std::vector<SweepMapRecord> maps;
  std::vector<SweepFailureRecord> failures;
};

nlohmann::json toJson(const SweepFailureRecord& f);
nlohmann::json toJson(const SweepSummary& s);

}  // namespace lexdyn::records
