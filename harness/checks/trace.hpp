// Traces: one row of named channels per control tick, written as CSV.
//
// File format (docs/file-formats.md, "Trace files"): metadata lines "# key: value", then one line
// of channel names, then one line per row, every value in the shortest form that reads back to
// the same double (so a trace round-trips bit for bit), then the end mark "# end: STATUS[: why]"
// written by finish(): a trace carries its own verdict on completeness (completed, interrupted,
// integrator_failure, ...), so that a trace separated from its summary is never taken for a
// complete run; a trace without the mark was cut (killed run) or not written by a finished run.
// The writer writes to "<path>.partial", flushes every `flush_every_rows` rows so that an
// interrupted run keeps its data, and renames the file to <path> in finish(). Channels are
// registered before the first row; later components (the controller, tasks) add their own
// channels the same way.
#pragma once

#include "harness/records/run_status.hpp"

#include <cstdint>
#include <cstdio>
#include <iosfwd>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace lexdyn::checks {

/// Ordered (key, value) pairs written as "# key: value" header lines.
using TraceMetadata = std::vector<std::pair<std::string, std::string>>;

/// Looks a key up; returns nullptr when absent.
const std::string* findMetadata(const TraceMetadata& m, const std::string& key);

class TraceSchema {
 public:
  /// Adds a channel and returns its column. Names must be unique, non-empty, without commas,
  /// quotes or whitespace (checked; a duplicate is a programming error and aborts).
  int add(const std::string& name);
  /// Column of a channel, -1 when absent.
  int find(const std::string& name) const;
  int size() const { return static_cast<int>(names_.size()); }
  const std::vector<std::string>& names() const { return names_; }

 private:
  std::vector<std::string> names_;
  std::unordered_map<std::string, int> index_;  ///< name -> column (a trace may have 1e5 channels)
};

class TraceWriter {
 public:
  TraceWriter(const std::string& path, TraceSchema schema, const TraceMetadata& metadata, int flush_every_rows = 200);
  ~TraceWriter();
  TraceWriter(const TraceWriter&) = delete;
  TraceWriter& operator=(const TraceWriter&) = delete;

  const TraceSchema& schema() const { return schema_; }
  /// Writes one row of schema().size() values.
  void write(const double* row);
  /// Writes the end mark "# end: <end_status>[: <why>]" (newlines become spaces), flushes, closes
  /// and renames the file to its final name. Idempotent.
  void finish(records::RunStatus end_status = records::RunStatus::Completed, const std::string& why = "");
  long rows() const { return rows_; }
  const std::string& path() const { return path_; }
  const std::string& partialPath() const { return partial_; }

 private:
  void flushOrThrow();
  std::string path_, partial_;
  TraceSchema schema_;
  std::FILE* file_ = nullptr;
  int flush_every_;
  long rows_ = 0;
  std::vector<char> buffer_;
  std::vector<char> line_;  ///< one row, formatted before a single fwrite
  /// Per channel: the bits of its value in the previous row and their text.
  struct LastValue {
    std::uint64_t bits = 0;
    unsigned char length = 0;  ///< 0: no previous row
    char text[24] = {};        ///< the longest shortest form of a double has 24 characters
  };
  std::vector<LastValue> last_;
};

/// A trace read back into memory.
struct TraceTable {
  TraceMetadata metadata;
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;
  /// The end mark's status (a run's own: completed, interrupted, integrator_failure, ...) and
  /// why; no status when the file has no end mark (cut, or an older writer).
  std::optional<records::RunStatus> end_status;
  std::string end_message;
  int column(const std::string& name) const;  ///< -1 when absent
  /// True when the end mark says the run completed.
  bool complete() const { return end_status == records::RunStatus::Completed; }
  /// One sentence on completeness for messages ("the run completed", "interrupted: ...",
  /// "no end mark: the run was killed or is still running").
  std::string completeness() const;
};

/// Size guard of trace files: channels per row.
inline constexpr long kMaxTraceChannels = 200000;

/// Reads a trace file; throws lexdyn::InputError naming the file and line on malformed input.
/// For a "<path>.partial" file (a run that was killed) an unterminated last row, cut by the
/// kill in the middle of a write, is dropped; in any other file it is an error. Validated: the
/// time channel `t` (when present) is finite, >= 0 and strictly increasing, on the grid of the
/// header's control_period_s and within its duration_s (when the header has them); values are
/// numbers as the writer writes them (inf, -inf and nan allowed outside `t`).
TraceTable readTrace(const std::string& path);
/// The same from a stream; `name` names it in messages, `partial` as for a ".partial" file.
TraceTable parseTrace(std::istream& in, const std::string& name, bool partial);

}  // namespace lexdyn::checks
