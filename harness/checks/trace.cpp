#include "harness/checks/trace.hpp"

#include "lexdyn/common/error.hpp"

#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <limits>
#include <unordered_set>

namespace lexdyn::checks {

const std::string* findMetadata(const TraceMetadata& m, const std::string& key) {
  for (const auto& kv : m) {
    if (kv.first == key) return &kv.second;
  }
  return nullptr;
}

int TraceSchema::add(const std::string& name) {
  LEXDYN_ALWAYS_ASSERT(!name.empty() && name.find_first_of(", \t\r\n\"") == std::string::npos, "invalid trace channel name '" + name + "'");
  LEXDYN_ALWAYS_ASSERT(find(name) < 0, "duplicate trace channel '" + name + "'");
  names_.push_back(name);
  index_.emplace(name, static_cast<int>(names_.size()) - 1);
  return static_cast<int>(names_.size()) - 1;
}

int TraceSchema::find(const std::string& name) const {
  const auto it = index_.find(name);
  return it == index_.end() ? -1 : it->second;
}

TraceWriter::TraceWriter(const std::string& path, TraceSchema schema, const TraceMetadata& metadata, int flush_every_rows)
    : path_(path), partial_(path + ".partial"), schema_(std::move(schema)), flush_every_(flush_every_rows) {
  file_ = std::fopen(partial_.c_str(), "wb");
  if (!file_) throw OutputError(partial_, std::string("cannot open for writing: ") + std::strerror(errno));
  buffer_.resize(1 << 16);
  line_.resize(static_cast<size_t>(schema_.size()) * 32);
  last_.assign(static_cast<size_t>(schema_.size()), LastValue{});
  std::setvbuf(file_, buffer_.data(), _IOFBF, buffer_.size());
  for (const auto& kv : metadata) {
    std::string v = kv.second;
    for (char& c : v) {
      if (c == '\n' || c == '\r') c = ' ';
    }
    std::fprintf(file_, "# %s: %s\n", kv.first.c_str(), v.c_str());
  }
  for (int i = 0; i < schema_.size(); ++i) {
    std::fputs(schema_.names()[static_cast<size_t>(i)].c_str(), file_);
    std::fputc(i + 1 < schema_.size() ? ',' : '\n', file_);
  }
  flushOrThrow();
}

// A failed write is found at the first flush that fails (every flush_every_rows rows, and when
// stdio's buffer fills), with the operating system's reason, not at the end of the run.
void TraceWriter::flushOrThrow() {
  if (std::fflush(file_) != 0 || std::ferror(file_)) {
    const int err = errno;
    throw OutputError(partial_, std::string("cannot write: ") + std::strerror(err) + " (after " + std::to_string(rows_) + " rows)");
  }
}

TraceWriter::~TraceWriter() {
  if (file_) {
    // Not finished (an exception unwound the run): keep the data under the partial name.
    std::fflush(file_);
    std::fclose(file_);
    file_ = nullptr;
  }
}

void TraceWriter::write(const double* row) {
  LEXDYN_ALWAYS_ASSERT(file_ != nullptr, "TraceWriter::write after finish()");
  // Shortest representation that reads back to the same double (std::to_chars), so the
  // file round-trips bit for bit.
  // The row is formatted into line_ and written with one fwrite (each fwrite takes the
  // stream's lock). 32 characters hold any double (at most 24) and its separator.
  // A value with the same bits as the channel's value in the previous row (about a quarter of
  // a humanoid trace's values: flags, counters, zeros, held targets) reuses that row's text.
  const int n = schema_.size();
  char* p = line_.data();
  for (int i = 0; i < n; ++i) {
    LastValue& c = last_[static_cast<size_t>(i)];
    std::uint64_t bits;
    std::memcpy(&bits, &row[i], sizeof bits);
    if (c.length == 0 || bits != c.bits) {
      const std::to_chars_result r = std::to_chars(c.text, c.text + sizeof c.text, row[i]);
      LEXDYN_ALWAYS_ASSERT(r.ec == std::errc{}, "TraceWriter: a value's text is longer than 24 characters");
      c.length = static_cast<unsigned char>(r.ptr - c.text);
      c.bits = bits;
    }
    std::memcpy(p, c.text, sizeof c.text);
    p += c.length;
    *p++ = i + 1 < n ? ',' : '\n';
  }
  const size_t len = static_cast<size_t>(p - line_.data());
  if (std::fwrite(line_.data(), 1, len, file_) != len) flushOrThrow();
  ++rows_;
  if (flush_every_ > 0 && rows_ % flush_every_ == 0) flushOrThrow();
}

void TraceWriter::finish(records::RunStatus end_status, const std::string& why) {
  if (!file_) return;
  std::string mark = std::string("# end: ") + records::toString(end_status) + (why.empty() ? "" : ": " + why);
  for (char& c : mark) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  mark += '\n';
  const bool written = std::fwrite(mark.data(), 1, mark.size(), file_) == mark.size() && std::fflush(file_) == 0 && !std::ferror(file_);
  int err = errno;
  const bool synced = written && (::fsync(::fileno(file_)) == 0 || errno == EINVAL);
  if (written && !synced) err = errno;
  const bool closed = std::fclose(file_) == 0;
  if (written && synced && !closed) err = errno;
  file_ = nullptr;
  if (!written || !synced || !closed) throw OutputError(partial_, std::string("cannot write: ") + std::strerror(err));
  if (std::rename(partial_.c_str(), path_.c_str()) != 0) {
    throw OutputError(path_, std::string("cannot rename the finished trace: ") + std::strerror(errno));
  }
}

int TraceTable::column(const std::string& name) const {
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return -1;
}  // linear: called for a few channels per check

std::string TraceTable::completeness() const {
  if (!end_status) return "no end mark: the run was killed, is still running, or the file was not written by a finished run";
  if (complete()) return "the run completed";
  return std::string("the run did not complete: ") + records::toString(*end_status) + (end_message.empty() ? "" : " (" + end_message + ")");
}

namespace {

// A value as TraceWriter writes it (std::to_chars): a decimal number, inf, -inf or nan; nothing
// else (no spaces, no hexadecimal, nothing out of range).
bool parseValue(const std::string& s, double& v) {
  if (s.empty()) return false;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  const std::from_chars_result r = std::from_chars(b, e, v, std::chars_format::general);
  if (r.ec == std::errc() && r.ptr == e) return true;
  if (s == "inf" || s == "-inf" || s == "nan" || s == "-nan") {
    v = s == "inf" ? std::numeric_limits<double>::infinity()
                   : (s == "-inf" ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::quiet_NaN());
    return true;
  }
  return false;
}

// A positive finite number of a header line (control_period_s, duration_s), or 0 when absent.
double headerNumber(const TraceTable& t, const char* key, const std::string& name) {
  const std::string* s = findMetadata(t.metadata, key);
  if (!s) return 0.0;
  double v = 0.0;
  if (!parseValue(*s, v) || !std::isfinite(v) || !(v > 0.0)) {
    throw InputError(name, std::string("header line '") + key + "': expected a positive number, found '" + *s + "'");
  }
  return v;
}

}  // namespace

TraceTable parseTrace(std::istream& in, const std::string& name, bool partial) {
  TraceTable t;
  std::string line;
  int lineno = 0;
  bool have_names = false, ended = false;
  int tc = -1;
  double period = 0.0, duration = 0.0;
  std::string offgrid;  // "file:line" of a row off the tick grid (allowed as the last row of a failed run)
  while (std::getline(in, line)) {
    ++lineno;
    const std::string where = name + ":" + std::to_string(lineno);
    if (line.find('\0') != std::string::npos) {
      throw InputError(where,
                       "expected a text trace file, found binary data (a NUL byte) at column " + std::to_string(line.find('\0') + 1));
    }
    if (!line.empty() && line.back() == '\r') {
      throw InputError(where, "the line ends with a carriage return (CRLF line endings); trace files use LF only");
    }
    if (line.empty()) continue;
    // Every line the writer writes ends with a newline. A last line without one was cut by a
    // killed run: dropped from a .partial trace (the rows before it are complete), an error in
    // a finished one.
    if (in.eof() && have_names) {
      if (partial) break;
      throw InputError(where, "the last line has no newline: the file was cut short");
    }
    if (ended) throw InputError(where, std::string("a line after the end mark ('# end: ") + records::toString(*t.end_status) + "')");
    if (line.rfind("# ", 0) == 0) {
      if (have_names) {
        // The only comment after the channel line is the end mark.
        if (line.rfind("# end: ", 0) != 0)
          throw InputError(where, "a header line after the channel names (only '# end: STATUS' may follow the rows)");
        const std::string mark = line.substr(7);
        const size_t colon = mark.find(": ");
        const std::string status = mark.substr(0, colon);
        if (colon != std::string::npos) t.end_message = mark.substr(colon + 2);
        if (status.empty()) throw InputError(where, "empty end mark");
        t.end_status = records::parseRunStatus(status);
        if (!t.end_status || !records::isRunsOwn(*t.end_status)) {
          throw InputError(where, "end mark '" + status + "' is no run status (" + records::spellings(records::runsOwnStatuses()) + ")");
        }
        ended = true;
        continue;
      }
      const size_t colon = line.find(": ", 2);
      if (colon == std::string::npos) throw InputError(where, "metadata line without 'key: value'");
      t.metadata.emplace_back(line.substr(2, colon - 2), line.substr(colon + 2));
      continue;
    }
    std::vector<std::string> fields;
    size_t start = 0;
    while (true) {
      const size_t comma = line.find(',', start);
      fields.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
      if (comma == std::string::npos) break;
      start = comma + 1;
      if (!have_names && static_cast<long>(fields.size()) > kMaxTraceChannels) {
        throw InputError(where, "more than " + std::to_string(kMaxTraceChannels) + " channels (size guard)");
      }
    }
    if (!have_names) {
      // Channel names as TraceSchema accepts them (checks rebuild a schema from them).
      std::unordered_set<std::string> seen;
      seen.reserve(fields.size());
      for (size_t i = 0; i < fields.size(); ++i) {
        const std::string& n = fields[i];
        if (n.empty() || n.find_first_of(" \t\r\n\"") != std::string::npos) {
          throw InputError(where, "invalid channel name '" + n + "' in column " + std::to_string(i + 1));
        }
        if (!seen.insert(n).second) throw InputError(where, "duplicate channel name '" + n + "'");
      }
      t.names = fields;
      have_names = true;
      tc = t.column("t");  // checks::kTimeChannel
      period = headerNumber(t, "control_period_s", name);
      duration = headerNumber(t, "duration_s", name);
      continue;
    }
    if (fields.size() != t.names.size()) {
      throw InputError(where, "expected " + std::to_string(t.names.size()) + " values, found " + std::to_string(fields.size()));
    }
    std::vector<double> row(fields.size());
    for (size_t i = 0; i < fields.size(); ++i) {
      if (!parseValue(fields[i], row[i])) {
        throw InputError(where, "column '" + t.names[i] + "': not a number: '" + fields[i] + "'");
      }
    }
    if (tc >= 0) {
      // The time column orders the rows: every check and comparison relies on it.
      const double tv = row[static_cast<size_t>(tc)];
      if (!std::isfinite(tv) || tv < 0.0)
        throw InputError(where, "time 't': expected a finite time >= 0 s, found " + fields[static_cast<size_t>(tc)]);
      if (!t.rows.empty()) {
        const double prev = t.rows.back()[static_cast<size_t>(tc)];
        if (!(tv > prev)) {
          throw InputError(where, "time 't': rows must be in strictly increasing time, found " + fields[static_cast<size_t>(tc)] +
                                      " s after " + std::to_string(prev) + " s");
        }
      }
      if (period > 0.0 && !offgrid.empty()) {
        // Only the last row may be off the tick grid: the state where a failed run stopped.
        throw InputError(offgrid,
                         "time 't': not a tick of the header's control period (" + std::to_string(period) + " s), and not the last row");
      }
      if (period > 0.0) {
        const double k = tv / period;
        if (std::abs(k - std::round(k)) > 1e-6 * std::max(1.0, k)) offgrid = where;
      }
      if (duration > 0.0 && tv > duration + std::max(period, 1e-9)) {
        throw InputError(where, "time 't': " + fields[static_cast<size_t>(tc)] + " s is beyond the header's duration (" +
                                    std::to_string(duration) + " s)");
      }
    }
    t.rows.push_back(std::move(row));
  }
  if (!have_names) throw InputError(name, "no header line with channel names");
  if (!offgrid.empty() && (t.complete() || !t.end_status || t.end_status == records::RunStatus::Interrupted)) {
    throw InputError(offgrid, "time 't': the last row is not a tick of the header's control period (" + std::to_string(period) +
                                  " s), which only the last state of a failed run may be");
  }
  return t;
}

TraceTable readTrace(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, "expected a trace file, found a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the trace for reading");
  const std::string kPartial = ".partial";
  const bool partial = path.size() >= kPartial.size() && path.compare(path.size() - kPartial.size(), kPartial.size(), kPartial) == 0;
  TraceTable t = parseTrace(in, path, partial);
  if (in.bad()) throw InputError(path, "read error");
  return t;
}

}  // namespace lexdyn::checks
