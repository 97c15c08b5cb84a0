// `lexdyn-harness sweep submit` (docs/sweeps.md, "Slurm"): the missing points of a sweep as a
// Slurm job array (each task runs a chunk of points with the same per-point runner as a local
// sweep, `sweep chunk`), and a job depending on it that merges and shrinks (`sweep merge`).
// Every task writes its own result files, so no accounting database is needed, and submitting
// again runs only the points that are still missing.
#pragma once

#include "harness/sweep/sweep_run.hpp"

#include <string>

namespace lexdyn::sweep {

struct SlurmOptions {
  int chunk = 4;          ///< points per array task
  std::string partition;  ///< "" = the cluster's default
  int throttle = 0;       ///< at most this many tasks at once (0: no limit)
  int merge_cpus = 1;     ///< CPUs of the merge job
  bool dry_run = false;   ///< write the scripts only
  std::string sbatch = "sbatch";
};

/// Writes OUT/slurm/submit-N/{points.txt, array.sh, merge.sh}, submits them (sbatch
/// --parsable) and prints the job ids. Returns 0, or 3 when sbatch fails.
int submitSweep(const SweepSpec& spec, const DriverOptions& options, const SlurmOptions& slurm);

}  // namespace lexdyn::sweep
