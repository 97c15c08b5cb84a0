// Sweep files (docs/sweeps.md): a base case, the methods, the parameters (key paths of the case,
// each with a range, a set of values or a distribution, and the simplest value it shrinks
// toward), a seed, a number of points or a grid, and the properties: the case's checks (or a
// subset) and comparisons between methods. Strict YAML; every error names the file, the line
// and the key path, and a sweep that cannot run is rejected before any point runs.
#pragma once

#include "harness/cases/case_file.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace lexdyn::sweep {

/// How a parameter draws its value (random sampling) or lists its values (grid).
enum class Distribution {
  Uniform,     ///< range [lo, hi]
  LogUniform,  ///< range [lo, hi], lo > 0, uniform in log
  Integers,    ///< integers lo..hi (both included)
  Values,      ///< one of `values` (YAML values, e.g. numbers or vectors)
  Choices,     ///< one of `choices`: bundles of overrides with a label
};

struct Choice {
  std::string label;
  std::vector<cases::Override> sets;
};

struct Parameter {
  std::string name;                ///< label in records and maps (default: the path)
  std::vector<std::string> paths;  ///< the key paths it sets (path, then also...)
  Distribution distribution = Distribution::Uniform;
  double lo = 0.0, hi = 0.0;
  std::vector<std::string> values;  ///< Values: YAML text of each value
  std::vector<Choice> choices;      ///< Choices
  int steps = 0;                    ///< grid: values over the range (0: not given)
  /// The value it shrinks toward (YAML text; for Choices a label). Default: the base case's
  /// value at the first path, when that is a value of the distribution's kind.
  std::string simplest;
  std::string where;  ///< file:line: parameters[i]
  bool numeric() const {
    return distribution == Distribution::Uniform || distribution == Distribution::LogUniform || distribution == Distribution::Integers;
  }
};

/// A comparison between two methods of the same point (checks::ComparisonSpec).
using Comparison = checks::ComparisonSpec;

struct ShrinkSettings {
  bool enabled = true;
  int max_runs = 40;            ///< simulations per shrunk failure
  int max_total_runs = 200;     ///< trials for all the sweep's failures together, shared evenly (at most max_runs each)
  int bisection_steps = 6;      ///< per numeric parameter
  double min_duration_s = 1.0;  ///< the duration is shrunk to this resolution
};

struct SweepSpec {
  std::string path;  ///< the sweep file
  std::string name, description;
  std::string base_case;       ///< resolved path
  std::string base_case_text;  ///< as written (relative to the sweep file)
  std::vector<std::string> methods;
  std::uint64_t seed = 0;
  bool grid = false;
  long points = 0;                    ///< random: the number of points; grid: the product
  std::optional<double> duration_s;   ///< stop_at_s of every point
  double timeout_s = 1800.0;          ///< per run (one point, one method)
  int trace_every_n_ticks = 50;       ///< decimation of the kept traces
  std::vector<cases::Override> sets;  ///< constant overrides, before the parameters
  std::vector<Parameter> parameters;
  std::vector<std::string> checks;  ///< property checks (names in the base case)
  std::vector<Comparison> comparisons;
  ShrinkSettings shrink;
  cases::CaseSpec base;  ///< the base case with `sets` (for validation)
};

/// Reads and validates a sweep file: the base case loads, every parameter path and every value
/// of every parameter resolves in it (a case is loaded at each end of each range and with each
/// value or choice: `validate`; a worker running one point skips it), the properties name checks
/// and methods the case has. Throws InputError.
SweepSpec loadSweep(const std::string& path, bool validate = true);

/// One point: its index and the value of every parameter (YAML text; a Choice's label).
struct Point {
  long index = 0;
  std::vector<std::string> values;
};

/// Point i of the sweep: random sampling from (seed, i) alone, or the i-th grid point (the
/// first parameter varies slowest).
Point pointAt(const SweepSpec& s, long index);

/// The grid values of a parameter (grid sweeps), or empty.
std::vector<std::string> gridValues(const Parameter& p);

/// The overrides of a configuration: the sweep's constant sets, then each parameter whose value
/// is given (an empty string leaves the parameter at the base case's value).
std::vector<cases::Override> overridesOf(const SweepSpec& s, const std::vector<std::string>& values);

/// Shortest text that reads back to the same double (std::to_chars).
std::string numberText(double v);

/// The checks of `method` that are properties of the sweep (those that apply to it).
std::vector<std::string> propertyChecks(const SweepSpec& s, const std::string& method);

}  // namespace lexdyn::sweep
