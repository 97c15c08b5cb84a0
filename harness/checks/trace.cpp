#include "harness/checks/trace.hpp"

#include "lexdyn/common/error.hpp"

#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace lexdyn::checks {

const std::string* findMetadata(const TraceMetadata& m, const std::string& key) {
  for (const auto& kv : m) {
    if (kv.first == key) return &kv.second;
  }
  return nullptr;
}

int TraceSchema::add(const std::string& name) {
  LEXDYN_ALWAYS_ASSERT(!name.empty() && name.find_first_of(", \t\r\n\"") == std::string::npos,
                       "invalid trace channel name '" + name + "'");
  LEXDYN_ALWAYS_ASSERT(find(name) < 0, "duplicate trace channel '" + name + "'");
  names_.push_back(name);
  return static_cast<int>(names_.size()) - 1;
}

int TraceSchema::find(const std::string& name) const {
  for (size_t i = 0; i < names_.size(); ++i) {
    if (names_[i] == name) return static_cast<int>(i);
  }
  return -1;
}

TraceWriter::TraceWriter(const std::string& path, TraceSchema schema, const TraceMetadata& metadata, int flush_every_rows)
    : path_(path), partial_(path + ".partial"), schema_(std::move(schema)), flush_every_(flush_every_rows) {
  file_ = std::fopen(partial_.c_str(), "wb");
  if (!file_) throw InputError(partial_, std::string("cannot open for writing: ") + std::strerror(errno));
  buffer_.resize(1 << 16);
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
  std::fflush(file_);
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
  char buf[64];
  const int n = schema_.size();
  for (int i = 0; i < n; ++i) {
    const std::to_chars_result r = std::to_chars(buf, buf + sizeof(buf) - 1, row[i]);
    *r.ptr = i + 1 < n ? ',' : '\n';
    std::fwrite(buf, 1, static_cast<size_t>(r.ptr - buf + 1), file_);
  }
  ++rows_;
  if (flush_every_ > 0 && rows_ % flush_every_ == 0) std::fflush(file_);
}

void TraceWriter::finish() {
  if (!file_) return;
  const bool ok = std::fflush(file_) == 0;
  std::fclose(file_);
  file_ = nullptr;
  if (!ok) throw InputError(partial_, "write error");
  if (std::rename(partial_.c_str(), path_.c_str()) != 0) {
    throw InputError(path_, std::string("cannot rename the finished trace: ") + std::strerror(errno));
  }
}

int TraceTable::column(const std::string& name) const {
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

TraceTable readTrace(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open the trace for reading");
  TraceTable t;
  std::string line;
  int lineno = 0;
  bool have_names = false;
  const std::string kPartial = ".partial";
  const bool partial = path.size() >= kPartial.size() && path.compare(path.size() - kPartial.size(), kPartial.size(), kPartial) == 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(lineno);
    // Every line the writer writes ends with a newline. A last line without one was cut by a
    // killed run: dropped from a .partial trace (the rows before it are complete), an error in
    // a finished one.
    if (in.eof() && have_names) {
      if (partial) break;
      throw InputError(where, "the last line has no newline: the file was cut short");
    }
    if (!have_names && line.rfind("# ", 0) == 0) {
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
    }
    if (!have_names) {
      // Channel names as TraceSchema accepts them (checks rebuild a schema from them).
      for (size_t i = 0; i < fields.size(); ++i) {
        const std::string& n = fields[i];
        if (n.empty() || n.find_first_of(" \t\r\n\"") != std::string::npos) {
          throw InputError(where, "invalid channel name '" + n + "' in column " + std::to_string(i + 1));
        }
        for (size_t k = 0; k < i; ++k) {
          if (fields[k] == n) throw InputError(where, "duplicate channel name '" + n + "'");
        }
      }
      t.names = fields;
      have_names = true;
      continue;
    }
    if (fields.size() != t.names.size()) {
      throw InputError(where, "expected " + std::to_string(t.names.size()) + " values, found " + std::to_string(fields.size()));
    }
    std::vector<double> row(fields.size());
    for (size_t i = 0; i < fields.size(); ++i) {
      char* end = nullptr;
      row[i] = std::strtod(fields[i].c_str(), &end);
      if (fields[i].empty() || *end != '\0') {
        throw InputError(where, "column '" + t.names[i] + "': not a number: '" + fields[i] + "'");
      }
    }
    t.rows.push_back(std::move(row));
  }
  if (!have_names) throw InputError(path, "no header line with channel names");
  return t;
}

}  // namespace lexdyn::checks
