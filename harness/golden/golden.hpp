// Golden traces (docs/file-formats.md, "Golden traces"): decimated traces of case x method runs,
// kept in golden/ with provenance headers, and their comparison channel by channel with
// absolute and relative tolerances, reporting the first time and channel that diverge.
//
// golden/manifest.yaml lists the cases, their methods, the horizon and the decimation of each
// golden, the channels kept and the tolerances. `lexdyn-harness golden update` regenerates the
// files (explicitly; never inside ctest); `lexdyn-harness golden check` re-runs and compares.
#pragma once

#include "harness/checks/trace.hpp"

#include <atomic>
#include <string>
#include <vector>

namespace lexdyn::golden {

/// |fresh - golden| <= abs + rel * |golden| (NaN matches NaN, an infinity only itself).
struct Tolerance {
  double abs = 1e-6;
  double rel = 1e-6;
};

/// A tolerance for the channels matching a glob pattern ('*'); later entries win.
struct ChannelTolerance {
  std::string match;
  Tolerance tolerance;
};

struct Entry {
  std::string case_path;             ///< resolved
  std::string case_name;             ///< the case's `name` (file names, --cases)
  std::vector<std::string> methods;  ///< {""} for a case without methods (posture servo)
  double duration_s = 0.0;           ///< horizon (at most the case's duration)
  int every_n_ticks = 10;            ///< decimation
  std::string where;
};

struct Manifest {
  std::string path, dir;
  Tolerance tolerance;
  std::vector<ChannelTolerance> channel_tolerances;
  std::vector<std::string> channels = {"*"};  ///< kept (glob patterns)
  std::vector<std::string> exclude;           ///< dropped (glob patterns); time.* is always dropped
  std::vector<Entry> entries;
};

/// Reads golden/manifest.yaml (strict: errors name file, line and key). The cases are loaded to
/// validate them and their methods.
Manifest loadManifest(const std::string& path);

/// "<case>.<method>", or "<case>" without a method: names goldens in files, messages and --only.
std::string goldenId(const std::string& case_name, const std::string& method);
/// "<dir>/<id>.csv"
std::string goldenPath(const Manifest& m, const std::string& case_name, const std::string& method);

/// The channels kept in a golden: matching `channels`, not matching `exclude`, never time.*
/// (wall-clock measurements).
checks::TraceTable selectChannels(const checks::TraceTable& t, const Manifest& m);

/// Runs one case x method over the entry's horizon with its decimation (quietly, timings off)
/// in `work_dir`, returns the selected trace and the run status in `status`. `interrupt` (e.g.
/// set by SIGINT) stops the run after a tick (status "interrupted").
checks::TraceTable runGolden(const Entry& e, const std::string& method, const Manifest& m, const std::string& work_dir,
                             records::RunStatus& status, bool progress, const std::atomic<bool>* interrupt = nullptr);

/// Header lines recorded in a golden besides the trace's own (which hold the build: compiler,
/// flags, library versions): format, case, method, horizon, decimation, run status, git revision.
checks::TraceMetadata provenance(const Entry& e, const std::string& method, records::RunStatus status, const std::string& source_dir);

/// Writes a golden file (temporary name, then rename).
void writeGolden(const std::string& path, const checks::TraceTable& t, const checks::TraceMetadata& provenance);

struct Comparison {
  bool ok = true;
  long rows = 0, channels = 0;
  /// First divergence (in time, then in the golden's channel order); empty channel if none.
  double first_t = 0.0;
  std::string first_channel;
  double golden_value = 0.0, fresh_value = 0.0, allowed = 0.0;
  int diverging_at_first_t = 0;       ///< channels beyond tolerance at that time
  long diverging_values = 0;          ///< (row, channel) pairs beyond tolerance
  std::vector<std::string> problems;  ///< structural: missing channels, row counts, status, times
  std::vector<std::string> notes;     ///< e.g. channels only in the fresh trace, build differences
  double max_abs_diff = 0.0;
  std::string max_abs_channel;
  /// One paragraph: "ok ..." or the first divergence and the problems.
  std::string report() const;
};

/// What is wrong with a golden file read back (empty when nothing): one without its end mark
/// ('# end: completed', written last by `golden update`) was cut, also when it was cut at a line
/// end and would otherwise differ only in its row count.
std::vector<std::string> goldenFileProblems(const checks::TraceTable& golden);

/// Compares a fresh trace with a golden one. Rows are matched in order (their times must agree
/// to 1e-9 s); every golden channel must be in the fresh trace. Wall-clock channels (time.*)
/// are never compared, in whichever trace they are.
Comparison compare(const checks::TraceTable& golden, const checks::TraceTable& fresh, const Tolerance& tolerance,
                   const std::vector<ChannelTolerance>& channel_tolerances);

}  // namespace lexdyn::golden
