#include "harness/sweep/sweep_records.hpp"

#include "harness/checks/output_files.hpp"
#include "harness/records/json_numbers.hpp"

#include "lexdyn/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <map>
#include <set>
#include <sstream>

namespace lexdyn::sweep {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using records::finiteOrNull;
using records::numberOrNaN;

}  // namespace

std::string readFileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string textDigest(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  char buf[24];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string shellQuote(const std::string& a) {
  if (!a.empty() && a.find_first_of(" \t\n'\"\\$`*?[]{}()<>|&;#~!") == std::string::npos) return a;
  std::string q = "'";
  for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

void writeAtomically(const std::string& path, const std::string& text) { files::writeAtomically(path, text); }

std::optional<json> readJsonFile(const std::string& path, std::string& why) {
  const std::optional<std::string> text = files::readWhole(path);
  if (!text) {
    why = "cannot be read";
    return std::nullopt;
  }
  try {
    return json::parse(*text);
  } catch (const json::parse_error& e) {
    why = "damaged: " + records::jsonSyntaxProblem(*text, e.byte, e.what());
    return std::nullopt;
  } catch (const json::exception& e) {  // a number beyond the double range (out_of_range.406)
    why = std::string("damaged: ") + e.what();
    return std::nullopt;
  }
}

std::optional<PointRecord> readPointRecord(const SweepSpec& s, long index, const std::string& path, std::string& why) {
  const std::optional<json> j = readJsonFile(path, why);
  if (!j) return std::nullopt;
  std::optional<PointRecord> r = records::sweepPointFromJson(*j, why);
  if (!r) return std::nullopt;
  if (r->point != index) {
    why = "not the record of point " + std::to_string(index);
    return std::nullopt;
  }
  for (const auto& m : s.methods) {
    if (!r->runs.count(m)) {
      why = "no run of " + m;
      return std::nullopt;
    }
  }
  return r;
}

PointRecord pointRecord(const SweepSpec& s, const Point& p, const std::map<std::string, RunResult>& runs) {
  PointRecord rec;
  rec.point = p.index;
  for (size_t k = 0; k < s.parameters.size(); ++k) rec.values[s.parameters[k].name] = p.values[k];
  for (const auto& o : overridesOf(s, p.values)) rec.overrides.emplace_back(o.path, o.value);
  for (const auto& m : s.methods) {
    const RunResult& r = runs.at(m);
    rec.runs[m] = {r, reproduceCommand(s, {m, p.values, 0.0}),
                   "lexdyn-harness sweep point " + s.path + " --index " + std::to_string(p.index) + " --method " + m + " --out DIR"};
    for (const auto& f : r.failures()) rec.failures.push_back(m + ":" + f);
  }
  for (const Comparison& c : s.comparisons) {
    const RunResult& rb = runs.at(c.better);
    const RunResult& rw = runs.at(c.worse);
    records::SweepComparisonRecord jc;
    jc.name = c.name;
    jc.better = c.better;
    jc.worse = c.worse;
    jc.limit = c.margin;
    // Two runs compare only when both ran to the end: a run that stopped early (fell, failed)
    // has its statistic over a shorter window.
    for (const RunResult* r : {&rb, &rw}) {
      if (r->status != records::RunStatus::Completed) jc.stopped_early.push_back(r == &rb ? c.better : c.worse);
    }
    if (jc.stopped_early.empty() && rb.statistics.count(c.name) && rw.statistics.count(c.name))
      jc.value = rb.statistics.at(c.name) - rw.statistics.at(c.name);
    const bool has = std::isfinite(jc.value);
    jc.margin = has ? c.margin - jc.value : jc.value;
    jc.better_wins = has && jc.value <= c.margin;
    rec.comparisons.push_back(std::move(jc));
  }
  return rec;
}

// ---------------------------------------------------------------------------------------------
// Summary and maps.

records::SweepSummary summarize(const SweepSpec& s, const std::vector<PointRecord>& records, long points,
                                std::vector<FailureRecord> failures, std::vector<records::SweepMapRecord> maps) {
  records::SweepSummary out;
  out.name = s.name;
  out.description = s.description;
  out.sweep_file = s.path;
  out.base_case = s.base_case;
  out.methods = s.methods;
  out.seed = s.seed;
  out.grid = s.grid;
  out.duration_s = s.duration_s;
  using Kind = records::SweepParameterRecord::Kind;
  for (const auto& p : s.parameters) {
    records::SweepParameterRecord jp{p.name, p.paths, p.simplest, Kind::Range, p.lo, p.hi, {}};
    switch (p.distribution) {
      case Distribution::Uniform:
        break;
      case Distribution::LogUniform:
        jp.kind = Kind::LogRange;
        break;
      case Distribution::Integers:
        jp.kind = Kind::Integers;
        break;
      case Distribution::Values:
        jp.kind = Kind::Values;
        jp.values = p.values;
        break;
      case Distribution::Choices:
        jp.kind = Kind::Choices;
        jp.values = gridValues(p);
        break;
    }
    out.parameters.push_back(std::move(jp));
  }
  out.points = points;
  out.completed = static_cast<long>(records.size());
  for (const auto& r : records) out.failed_points += r.failures.empty() ? 0 : 1;
  // Per check and method: pass rate and worst margin.
  for (const auto& m : s.methods) {
    std::vector<std::string> names = {kRunCompleted};
    for (const auto& c : propertyChecks(s, m)) names.push_back(c);
    for (const auto& name : names) {
      records::SweepCheckSummary cs;
      cs.check = name;
      cs.method = m;
      double worst = std::numeric_limits<double>::infinity();
      for (const auto& r : records) {
        const RunResult& run = r.run(m);
        ++cs.runs;
        if (name == kRunCompleted) {
          cs.passed += run.status == records::RunStatus::Completed ? 1 : 0;
          continue;
        }
        for (const auto& c : run.checks) {
          if (c.name != name) continue;
          cs.passed += c.passed ? 1 : 0;
          cs.unit = c.unit;
          // The worst: the lowest margin; a failure without a value ranks below every value.
          const double key = std::isnan(c.margin)
                                 ? (c.passed ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity())
                                 : c.margin;
          if (key < worst || cs.worst_point < 0) {
            worst = key;
            cs.worst_point = r.point;
          }
        }
      }
      cs.worst_margin = worst;
      out.checks.push_back(std::move(cs));
    }
  }
  // Comparisons: win rates and the spread of the difference, overall and per value of each
  // parameter with a set of values.
  for (const Comparison& c : s.comparisons) {
    records::SweepComparisonSummary cs;
    cs.name = c.name;
    cs.better = c.better;
    cs.worse = c.worse;
    cs.statistic = c.statistic;
    cs.tasks = c.tasks;
    cs.from_s = c.from_s;
    cs.to_s = c.to_s;
    cs.margin = c.margin;
    for (const auto& r : records) {
      for (const auto& jc : r.comparisons) {
        if (jc.name != c.name) continue;
        for (const auto& m : jc.stopped_early) {
          cs.better_stopped_early += m == c.better ? 1 : 0;
          cs.worse_stopped_early += m == c.worse ? 1 : 0;
        }
        if (!std::isfinite(jc.value)) continue;
        cs.diffs.push_back(jc.value);
        ++cs.overall.points;
        cs.overall.wins += jc.better_wins ? 1 : 0;
        for (const auto& p : s.parameters) {
          if (p.numeric()) continue;
          records::SweepWinCount& cell = cs.by_parameter[p.name][r.value(p.name)];
          ++cell.points;
          cell.wins += jc.better_wins ? 1 : 0;
        }
      }
    }
    std::sort(cs.diffs.begin(), cs.diffs.end());
    out.comparisons.push_back(std::move(cs));
  }
  out.maps = std::move(maps);
  out.failures = std::move(failures);
  return out;
}

std::vector<records::SweepMapRecord> writeMaps(const SweepSpec& s, const std::vector<PointRecord>& records, const std::string& out_dir,
                                               const std::string& plot_command) {
  std::vector<records::SweepMapRecord> maps;
  if (!s.grid || s.parameters.size() != 2) return maps;
  const Parameter& px = s.parameters[0];
  const Parameter& py = s.parameters[1];
  const fs::path dir = fs::path(out_dir) / "maps";
  std::error_code ec;
  fs::create_directories(dir, ec);
  auto axis = [](const Parameter& p) {
    return records::SweepMapRecord::Axis{p.name, p.paths.empty() ? p.name : p.paths.front(), gridValues(p)};
  };
  auto row = [&](const PointRecord& r) { return r.value(px.name) + "," + r.value(py.name); };
  auto cell = [](double v) { return std::isfinite(v) ? numberText(v) : std::string("nan"); };
  auto add = [&](const std::string& property, const std::string& method, const std::string& file, const std::string& csv) {
    writeAtomically((dir / file).string(), csv);
    maps.push_back({axis(px), axis(py), property, method, "maps/" + file, ""});
  };
  const std::string header = "," + py.name + ",passed,margin,value\n";
  for (const auto& m : s.methods) {
    std::vector<std::string> names = {kRunCompleted};
    for (const auto& c : propertyChecks(s, m)) names.push_back(c);
    for (const auto& name : names) {
      std::string csv = "# " + name + " of " + m + " over " + px.name + " x " + py.name + "\n" + px.name + header;
      for (const auto& r : records) {
        const RunResult& run = r.run(m);
        if (name == kRunCompleted) {
          csv += row(r) + "," + (run.status == records::RunStatus::Completed ? "1" : "0") + ",nan,nan\n";
          continue;
        }
        for (const auto& c : run.checks) {
          if (c.name == name) csv += row(r) + "," + (c.passed ? "1" : "0") + "," + cell(c.margin) + "," + cell(c.value) + "\n";
        }
      }
      add(name, m, name + "." + m + ".csv", csv);
    }
  }
  for (const Comparison& c : s.comparisons) {
    std::string csv = "# " + c.name + ": " + c.statistic + " " + c.better + " - " + c.worse + " over " + px.name + " x " + py.name + "\n" +
                      px.name + header;
    for (const auto& r : records) {
      for (const auto& jc : r.comparisons) {
        if (jc.name == c.name) csv += row(r) + "," + (jc.better_wins ? "1" : "0") + "," + cell(jc.margin) + "," + cell(jc.value) + "\n";
      }
    }
    add(c.name, c.better + " vs " + c.worse, c.name + ".csv", csv);
  }
  if (plot_command.empty() && !maps.empty()) {
    std::fprintf(stderr,
                 "warning: the map pictures are not drawn (needs /usr/bin/python3 with matplotlib and harness/scripts/sweep_plots.py)\n");
  }
  if (!plot_command.empty()) {
    const std::string cmd = plot_command + " " + shellQuote(out_dir) + " > " + shellQuote((dir / "plot.log").string()) + " 2>&1";
    if (std::system(cmd.c_str()) != 0) {
      std::fprintf(stderr, "warning: the map pictures could not be drawn (%s; see %s)\n", plot_command.c_str(),
                   (dir / "plot.log").string().c_str());
    }
  }
  for (auto& m : maps) {
    std::string png = m.csv;
    png.replace(png.size() - 4, 4, ".png");
    if (fs::is_regular_file(fs::path(out_dir) / png)) m.png = png;
  }
  return maps;
}

void printSummary(const records::SweepSummary& summary, std::FILE* out) {
  std::fprintf(out, "sweep %s: %ld of %ld points done, %ld failed (methods:", summary.name.c_str(), summary.completed, summary.points,
               summary.failed_points);
  for (const auto& m : summary.methods) std::fprintf(out, " %s", m.c_str());
  std::fprintf(out, ")\n  %-34s %-6s %-14s %s\n", "check", "method", "passed", "worst margin (point)");
  for (const auto& c : summary.checks) {
    char rate[64];
    std::snprintf(rate, sizeof(rate), "%ld/%ld %.0f%%", c.passed, c.runs, 100.0 * c.passRate());
    std::string worst = "-";
    if (std::isfinite(c.worst_margin) && c.check != kRunCompleted) {
      char b[96];
      std::snprintf(b, sizeof(b), "%.6g %s (%ld)", c.worst_margin, c.unit.c_str(), c.worst_point);
      worst = b;
    }
    std::fprintf(out, "  %-34s %-6s %-14s %s\n", c.check.c_str(), c.method.c_str(), rate, worst.c_str());
  }
  if (!summary.comparisons.empty()) {
    std::fprintf(out, "  %-34s %-14s %s\n", "comparison", "better wins", "difference: median [p10, p90]");
    for (const auto& c : summary.comparisons) {
      char rate[64];
      std::snprintf(rate, sizeof(rate), "%ld/%ld %.0f%%", c.overall.wins, c.overall.points, 100.0 * c.overall.winRate());
      std::string stopped;
      if (c.better_stopped_early + c.worse_stopped_early > 0)
        stopped = "; left out: " + c.better + " stopped early " + std::to_string(c.better_stopped_early) + ", " + c.worse + " " +
                  std::to_string(c.worse_stopped_early);
      std::fprintf(out, "  %-34s %-14s %.4g [%.4g, %.4g]%s\n", c.name.c_str(), rate, c.diffQuantile(0.5), c.diffQuantile(0.1),
                   c.diffQuantile(0.9), stopped.c_str());
    }
  }
  for (const auto& f : summary.failures) {
    std::fprintf(out, "  FAIL %s %s (%ld points; %s): %s\n", f.method.c_str(), f.check.c_str(), f.points_failing,
                 f.shrunk ? "shrunk" : "not shrunk", f.command.c_str());
  }
}

// ---------------------------------------------------------------------------------------------
// The failure database.

namespace {

// The failure database's entries, each with its line number (a line that is no entry of this
// format is skipped, with a warning naming FILE:LINE when `warn`; recordFailures keeps it).
struct Database {
  std::vector<std::pair<long, records::SweepFailureEntry>> entries;
};

Database readDatabase(const std::string& text, const std::string& path, const std::string& sweep, bool warn) {
  Database db;
  std::istringstream in(text);
  std::string line;
  long line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    std::string why;
    std::optional<records::SweepFailureEntry> e;
    try {
      e = records::sweepFailureFromJson(json::parse(line), why);
    } catch (const json::parse_error& ex) {
      why = "damaged: " + records::jsonSyntaxProblem(line, ex.byte, ex.what());
    } catch (const std::exception& ex) {
      why = std::string("damaged: ") + ex.what();
    }
    if (e)
      db.entries.emplace_back(line_no, std::move(*e));
    else if (warn)
      std::fprintf(stderr, "[sweep %s] warning: %s:%ld: %s; the line is skipped\n", sweep.c_str(), path.c_str(), line_no, why.c_str());
  }
  return db;
}

}  // namespace

bool recordFailures(const SweepSpec& s, const std::vector<FailureRecord>& failures, const std::string& db_path,
                    const std::atomic<int>* interrupt) {
  // The database is shared by every sweep of this name (each night's): one writer at a time.
  const files::FileLock lock(db_path, "lexdyn-harness sweep " + s.name, interrupt);
  if (!lock.held()) return false;
  std::string text = readFileText(db_path);
  std::set<std::string> known;  // the entries as this build writes them (a line of no format reads as version 1)
  for (const auto& [line_no, e] : readDatabase(text, db_path, s.name, false).entries) known.insert(toJson(e).dump());
  if (!text.empty() && text.back() != '\n') text += '\n';  // a cut last line stays skipped, apart
  std::string add;
  for (const auto& f : failures) {
    const std::string line = toJson(f.entry(s.name)).dump();
    if (known.insert(line).second) add += line + "\n";
  }
  if (add.empty()) return true;
  writeAtomically(db_path, text + add);
  return true;
}

bool replayFailures(const SweepSpec& s, const DriverOptions& o, const RunOne& run, std::vector<std::string>& lost) {
  const std::string out = (fs::path(o.out_dir) / "replays.jsonl").string();
  if (fs::is_regular_file(out)) return true;  // done by an earlier, interrupted run of this sweep
  std::string text;
  {
    const files::FileLock lock(o.db_path, "lexdyn-harness sweep " + s.name, o.interrupt);
    if (!lock.held()) return false;
    text = readFileText(o.db_path);
  }
  std::string lines;
  int k = 0, replayed = 0, still = 0;
  for (const auto& [line_no, e] : readDatabase(text, o.db_path, s.name, true).entries) {
    if (e.sweep != s.name) continue;
    if (std::find(s.methods.begin(), s.methods.end(), e.method) == s.methods.end()) continue;
    RunConfig c;
    c.method = e.method;
    c.values.assign(s.parameters.size(), "");
    bool usable = true;
    for (const auto& [name, value] : e.values) {
      size_t p = 0;
      while (p < s.parameters.size() && s.parameters[p].name != name) ++p;
      if (p == s.parameters.size())
        usable = false;
      else
        c.values[p] = value;
    }
    if (!usable) continue;  // the sweep no longer has that parameter
    c.duration_s = e.duration_s;
    const Trial t = run(c, (fs::path(o.out_dir) / "replay" / std::to_string(k++) / c.method).string());
    if (t.end == Trial::End::kInterrupted) return false;  // replayed again next time
    if (t.end == Trial::End::kLost) {
      lost.push_back("the replay of " + c.method + " " + e.check + " from " + o.db_path + ": " + t.why);
      return false;
    }
    const RunResult& r = t.result;
    const std::vector<std::string> f = r.failures();
    records::SweepReplayRecord rec;
    rec.entry = e;
    rec.status = r.status;
    rec.still_fails = std::find(f.begin(), f.end(), e.check) != f.end();
    if (const CheckOutcome* co = r.check(e.check)) {
      rec.value = co->value;
      rec.limit = co->limit;
    }
    ++replayed;
    still += rec.still_fails ? 1 : 0;
    lines += toJson(rec).dump() + "\n";
  }
  writeAtomically(out, lines);
  if (o.progress && replayed > 0) {
    std::fprintf(stderr, "[sweep %s] replayed %d earlier failure(s) from %s: %d still fail\n", s.name.c_str(), replayed, o.db_path.c_str(),
                 still);
  }
  return true;
}

}  // namespace lexdyn::sweep
