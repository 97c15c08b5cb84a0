// The sweep driver (docs/sweeps.md): every point x method is a whole simulation in its own
// process (`lexdyn-harness sweep point`), run in parallel with a timeout, so that a crash or a
// hang is that run's recorded failure and never the sweep's. Results go to disk as they finish
// (OUT/runs/<point>/<method>/result.json, then OUT/points/<point>.json), so killing the driver at
// any moment loses nothing, and running it again does only what is missing. At the end:
// OUT/results.jsonl (one record per point, by index), OUT/summary.json (pass rates, worst
// margins, method win rates, robustness maps, shrunk failures), OUT/maps/.
#pragma once

#include "harness/records/sweep_record.hpp"
#include "harness/sweep/sweep_file.hpp"

#include <atomic>
#include <map>
#include <string>
#include <vector>

namespace lexdyn::sweep {

/// One simulation of a sweep: a method, the parameters' values ("" = the base case's) and the
/// run's length (0: the sweep's).
struct RunConfig {
  std::string method;
  std::vector<std::string> values;
  double duration_s = 0.0;
};

/// One property check of a run, and what one simulation gave (OUT/runs/.../result.json): the
/// records layer's (harness/records/sweep_record.hpp).
using CheckOutcome = records::SweepCheckRecord;
using RunResult = records::SweepRunRecord;

struct DriverOptions {
  std::string out_dir;
  int jobs = 0;              ///< parallel processes (0: the number of cores)
  long points = -1;          ///< run only the first N points (-1: the sweep's)
  double timeout_s = 0.0;    ///< per run (0: the sweep's)
  bool keep_traces = false;  ///< keep the traces of passing runs too
  bool shrink = true;
  std::string db_path;  ///< failure database ("" = none)
  bool progress = true;
  std::string harness_exe;  ///< the lexdyn-harness binary to run points with
  /// Draws the robustness maps: a command taking OUT (e.g. "/usr/bin/python3
  /// .../sweep_plots.py"); "" for none.
  std::string plot_command;
  const std::atomic<int>* interrupt = nullptr;  ///< the signal that asks to stop (0: none)
};

/// `lexdyn-harness sweep run`: replays the failure database, runs the missing points, merges
/// and shrinks. Returns the exit code (0: every property held at every point; 1: a failure;
/// 130 / 143: interrupted).
int runSweep(const SweepSpec& spec, const DriverOptions& options);

/// Runs the given points only (a Slurm array task's chunk): no merge, no shrink.
int runPoints(const SweepSpec& spec, const std::vector<long>& points, const DriverOptions& options);

/// Merges what OUT holds (results.jsonl, summary.json, maps) and shrinks the failures. Returns
/// 0 when every point is done and passed, 1 when a point failed, 4 when points are missing.
int mergeSweep(const SweepSpec& spec, const DriverOptions& options);

/// The points of the sweep that OUT has no record of.
std::vector<long> missingPoints(const SweepSpec& spec, const std::string& out_dir, long points = -1);

/// `lexdyn-harness sweep point`: one simulation, in this process. The run's directory gets the
/// usual trace.csv, summary.json and case.yaml. Returns the run's exit code.
int runPointHere(const SweepSpec& spec, const RunConfig& config, const std::string& out_dir, const std::atomic<bool>* interrupt,
                 bool progress);

/// The command that reproduces a run with `lexdyn-harness run` (checks, not comparisons).
std::string reproduceCommand(const SweepSpec& spec, const RunConfig& config);

/// Creates OUT and records the sweep file in it; InputError when OUT holds another sweep.
void prepareOutDir(const SweepSpec& spec, const std::string& out_dir);

}  // namespace lexdyn::sweep
