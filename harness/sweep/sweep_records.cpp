#include "harness/sweep/sweep_records.hpp"

#include "harness/checks/output_files.hpp"

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

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double num(const json& v) { return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN(); }

// Nearest-rank quantile of sorted values.
double quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t k = static_cast<size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::min(sorted.size() - 1, k == 0 ? 0 : k - 1)];
}

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

RunResult fromJson(const json& j) {
  std::string why;
  std::optional<RunResult> r = records::sweepRunFromJson(j, why);
  if (!r) throw std::logic_error("a sweep run record that was checked is not one: " + why);
  return *r;
}

std::optional<json> readJsonFile(const std::string& path, std::string& why) {
  const std::optional<std::string> text = files::readWhole(path);
  if (!text) {
    why = "cannot be read";
    return std::nullopt;
  }
  try {
    return json::parse(*text);
  } catch (const std::exception& e) {
    why = std::string("damaged: ") + e.what();
    return std::nullopt;
  }
}

std::string pointRecordProblem(const SweepSpec& s, long index, const json& j) {
  if (!j.is_object()) return "not a JSON object";
  const std::string format = j.contains("format") && j["format"].is_string() ? j["format"].get<std::string>() : "";
  if (format != records::kSweepPointFormat) {
    return (format.empty() ? std::string("a point record of no format (written by an older build)")
                           : "a point record of format '" + format + "'") +
           ", this build reads '" + records::kSweepPointFormat + "'";
  }
  if (!j.contains("point") || !j["point"].is_number_integer() || j["point"].get<long>() != index)
    return "not the record of point " + std::to_string(index);
  if (!j.contains("runs") || !j["runs"].is_object()) return "no runs";
  for (const auto& m : s.methods) {
    if (!j["runs"].contains(m)) return "no run of " + m;
    std::string why;
    if (!recordedResult(j["runs"][m], why)) return "the run of " + m + ": " + why;
  }
  for (const char* key : {"values", "comparisons", "failures"}) {
    if (!j.contains(key)) return std::string("no ") + key;
  }
  return "";
}

json pointRecord(const SweepSpec& s, const Point& p, const std::map<std::string, RunResult>& runs) {
  json values = json::object();
  for (size_t k = 0; k < s.parameters.size(); ++k) values[s.parameters[k].name] = p.values[k];
  json overrides = json::array();
  for (const auto& o : overridesOf(s, p.values)) overrides.push_back({{"path", o.path}, {"value", o.value}});
  json jruns = json::object();
  json failures = json::array();
  for (const auto& m : s.methods) {
    const RunResult& r = runs.at(m);
    json jr = toJson(r);
    jr["reproduce"] = reproduceCommand(s, {m, p.values, 0.0});
    jr["rerun"] = "lexdyn-harness sweep point " + s.path + " --index " + std::to_string(p.index) + " --method " + m + " --out DIR";
    jruns[m] = jr;
    for (const auto& f : r.failures()) failures.push_back(m + ":" + f);
  }
  json comps = json::array();
  for (const Comparison& c : s.comparisons) {
    const RunResult& rb = runs.at(c.better);
    const RunResult& rw = runs.at(c.worse);
    // Two runs compare only when both ran to the end: a run that stopped early (fell, failed)
    // has its statistic over a shorter window.
    json stopped = json::array();
    for (const RunResult* r : {&rb, &rw}) {
      if (r->status != records::RunStatus::Completed) stopped.push_back(r == &rb ? c.better : c.worse);
    }
    double value = std::numeric_limits<double>::quiet_NaN();
    if (stopped.empty() && rb.statistics.count(c.name) && rw.statistics.count(c.name))
      value = rb.statistics.at(c.name) - rw.statistics.at(c.name);
    const bool has = std::isfinite(value);
    comps.push_back({{"name", c.name},
                     {"better", c.better},
                     {"worse", c.worse},
                     {"value", number(value)},
                     {"limit", c.margin},
                     {"margin", number(has ? c.margin - value : value)},
                     {"better_wins", has && value <= c.margin},
                     {"stopped_early", stopped}});
  }
  return {{"format", records::kSweepPointFormat},
          {"point", p.index},
          {"values", values},
          {"overrides", overrides},
          {"runs", jruns},
          {"comparisons", comps},
          {"failures", failures}};
}

// ---------------------------------------------------------------------------------------------
// Summary and maps.

json summarize(const SweepSpec& s, const std::vector<json>& records, long points, const std::vector<json>& failures,
               const std::vector<json>& maps) {
  json params = json::array();
  for (const auto& p : s.parameters) {
    json jp = {{"name", p.name}, {"paths", p.paths}, {"simplest", p.simplest}};
    switch (p.distribution) {
      case Distribution::Uniform:
        jp["range"] = {p.lo, p.hi};
        break;
      case Distribution::LogUniform:
        jp["range"] = {p.lo, p.hi};
        jp["scale"] = "log";
        break;
      case Distribution::Integers:
        jp["integers"] = {static_cast<long>(p.lo), static_cast<long>(p.hi)};
        break;
      case Distribution::Values:
        jp["values"] = p.values;
        break;
      case Distribution::Choices:
        jp["choices"] = gridValues(p);
        break;
    }
    params.push_back(jp);
  }
  // Per check and method: pass rate and worst margin.
  json checks = json::array();
  long failed_points = 0;
  for (const auto& r : records) failed_points += r.value("failures", json::array()).empty() ? 0 : 1;
  for (const auto& m : s.methods) {
    std::vector<std::string> names = {kRunCompleted};
    for (const auto& c : propertyChecks(s, m)) names.push_back(c);
    for (const auto& name : names) {
      long runs = 0, passed = 0;
      double worst = std::numeric_limits<double>::infinity();
      long worst_point = -1;
      std::string unit;
      for (const auto& r : records) {
        const json& run = r["runs"][m];
        ++runs;
        if (name == kRunCompleted) {
          passed += run.value("status", "") == records::toString(records::RunStatus::Completed) ? 1 : 0;
          continue;
        }
        for (const auto& c : run["checks"]) {
          if (c.value("name", "") != name) continue;
          passed += c.value("passed", false) ? 1 : 0;
          unit = c.value("unit", "");
          const double mg = num(c.value("margin", json()));
          // The worst: the lowest margin; a failure without a value ranks below every value.
          const double key = std::isnan(mg) ? (c.value("passed", false) ? std::numeric_limits<double>::infinity()
                                                                        : -std::numeric_limits<double>::infinity())
                                            : mg;
          if (key < worst || worst_point < 0) {
            worst = key;
            worst_point = r.value("point", -1L);
          }
        }
      }
      checks.push_back({{"check", name},
                        {"method", m},
                        {"runs", runs},
                        {"passed", passed},
                        {"pass_rate", runs ? static_cast<double>(passed) / static_cast<double>(runs) : 0.0},
                        {"worst_margin", number(worst)},
                        {"worst_point", worst_point},
                        {"unit", unit}});
    }
  }
  // Comparisons: win rates and the spread of the difference, overall and per value of each
  // parameter with a set of values.
  json comps = json::array();
  for (const Comparison& c : s.comparisons) {
    std::vector<double> diffs;
    long wins = 0, better_stopped = 0, worse_stopped = 0;
    std::map<std::string, std::map<std::string, std::pair<long, long>>> by;  // param -> value -> (points, wins)
    for (const auto& r : records) {
      for (const auto& jc : r["comparisons"]) {
        if (jc.value("name", "") != c.name) continue;
        for (const auto& m : jc.value("stopped_early", json::array())) {
          better_stopped += m == c.better ? 1 : 0;
          worse_stopped += m == c.worse ? 1 : 0;
        }
        const double v = num(jc.value("value", json()));
        if (!std::isfinite(v)) continue;
        diffs.push_back(v);
        const bool win = jc.value("better_wins", false);
        wins += win ? 1 : 0;
        for (const auto& p : s.parameters) {
          if (p.numeric()) continue;
          auto& cell = by[p.name][r["values"].value(p.name, "")];
          ++cell.first;
          cell.second += win ? 1 : 0;
        }
      }
    }
    std::sort(diffs.begin(), diffs.end());
    json jby = json::object();
    for (const auto& [pn, cells] : by) {
      for (const auto& [v, pw] : cells) {
        jby[pn][v] = {{"points", pw.first},
                      {"wins", pw.second},
                      {"win_rate", pw.first ? static_cast<double>(pw.second) / static_cast<double>(pw.first) : 0.0}};
      }
    }
    comps.push_back({{"name", c.name},
                     {"better", c.better},
                     {"worse", c.worse},
                     {"statistic", c.statistic},
                     {"tasks", c.tasks},
                     {"from_s", c.from_s},
                     {"to_s", number(c.to_s)},
                     {"margin", c.margin},
                     {"points", diffs.size()},
                     {"better_stopped_early", better_stopped},
                     {"worse_stopped_early", worse_stopped},
                     {"wins", wins},
                     {"win_rate", diffs.empty() ? 0.0 : static_cast<double>(wins) / static_cast<double>(diffs.size())},
                     {"diff",
                      {{"min", number(quantile(diffs, 0.0))},
                       {"p10", number(quantile(diffs, 0.1))},
                       {"median", number(quantile(diffs, 0.5))},
                       {"p90", number(quantile(diffs, 0.9))},
                       {"max", number(diffs.empty() ? std::numeric_limits<double>::quiet_NaN() : diffs.back())}}},
                     {"by_parameter", jby}});
  }
  return {{"format", records::kSweepSummaryFormat},
          {"name", s.name},
          {"description", s.description},
          {"sweep_file", s.path},
          {"base_case", s.base_case},
          {"methods", s.methods},
          {"seed", s.seed},
          {"sampling", s.grid ? "grid" : "random"},
          {"duration_s", s.duration_s ? json(*s.duration_s) : json(nullptr)},
          {"parameters", params},
          {"points", points},
          {"completed", records.size()},
          {"failed_points", failed_points},
          {"checks", checks},
          {"comparisons", comps},
          {"maps", maps},
          {"failures", failures}};
}

std::vector<json> writeMaps(const SweepSpec& s, const std::vector<json>& records, const std::string& out_dir,
                            const std::string& plot_command) {
  std::vector<json> maps;
  if (!s.grid || s.parameters.size() != 2) return maps;
  const Parameter& px = s.parameters[0];
  const Parameter& py = s.parameters[1];
  const fs::path dir = fs::path(out_dir) / "maps";
  std::error_code ec;
  fs::create_directories(dir, ec);
  auto axis = [](const Parameter& p) {
    return json{{"name", p.name}, {"path", p.paths.empty() ? p.name : p.paths.front()}, {"values", gridValues(p)}};
  };
  auto row = [&](const json& r) { return r["values"].value(px.name, "") + "," + r["values"].value(py.name, ""); };
  auto cell = [](double v) { return std::isfinite(v) ? numberText(v) : std::string("nan"); };
  std::vector<std::string> written;
  for (const auto& m : s.methods) {
    std::vector<std::string> names = {kRunCompleted};
    for (const auto& c : propertyChecks(s, m)) names.push_back(c);
    for (const auto& name : names) {
      std::string csv =
          "# " + name + " of " + m + " over " + px.name + " x " + py.name + "\n" + px.name + "," + py.name + ",passed,margin,value\n";
      for (const auto& r : records) {
        const json& run = r["runs"][m];
        if (name == kRunCompleted) {
          csv += row(r) + "," + (run.value("status", "") == records::toString(records::RunStatus::Completed) ? "1" : "0") + ",nan,nan\n";
          continue;
        }
        for (const auto& c : run["checks"]) {
          if (c.value("name", "") != name) continue;
          csv += row(r) + "," + (c.value("passed", false) ? "1" : "0") + "," + cell(num(c.value("margin", json()))) + "," +
                 cell(num(c.value("value", json()))) + "\n";
        }
      }
      const std::string file = name + "." + m + ".csv";
      writeAtomically((dir / file).string(), csv);
      written.push_back(file);
      maps.push_back({{"x", axis(px)}, {"y", axis(py)}, {"property", name}, {"method", m}, {"csv", "maps/" + file}});
    }
  }
  for (const Comparison& c : s.comparisons) {
    std::string csv = "# " + c.name + ": " + c.statistic + " " + c.better + " - " + c.worse + " over " + px.name + " x " + py.name + "\n" +
                      px.name + "," + py.name + ",passed,margin,value\n";
    for (const auto& r : records) {
      for (const auto& jc : r["comparisons"]) {
        if (jc.value("name", "") != c.name) continue;
        csv += row(r) + "," + (jc.value("better_wins", false) ? "1" : "0") + "," + cell(num(jc.value("margin", json()))) + "," +
               cell(num(jc.value("value", json()))) + "\n";
      }
    }
    const std::string file = c.name + ".csv";
    writeAtomically((dir / file).string(), csv);
    maps.push_back(
        {{"x", axis(px)}, {"y", axis(py)}, {"property", c.name}, {"method", c.better + " vs " + c.worse}, {"csv", "maps/" + file}});
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
    std::string png = m["csv"].get<std::string>();
    png.replace(png.size() - 4, 4, ".png");
    if (fs::is_regular_file(fs::path(out_dir) / png)) m["png"] = png;
  }
  return maps;
}

void printSummary(const SweepSpec& s, const json& summary, std::FILE* out) {
  std::fprintf(out, "sweep %s: %ld of %ld points done, %ld failed (methods:", s.name.c_str(), summary.value("completed", 0L),
               summary.value("points", 0L), summary.value("failed_points", 0L));
  for (const auto& m : s.methods) std::fprintf(out, " %s", m.c_str());
  std::fprintf(out, ")\n  %-34s %-6s %-14s %s\n", "check", "method", "passed", "worst margin (point)");
  for (const auto& c : summary["checks"]) {
    char rate[64];
    std::snprintf(rate, sizeof(rate), "%ld/%ld %.0f%%", c.value("passed", 0L), c.value("runs", 0L), 100.0 * c.value("pass_rate", 0.0));
    std::string worst = "-";
    if (c["worst_margin"].is_number() && c.value("check", "") != kRunCompleted) {
      char b[96];
      std::snprintf(b, sizeof(b), "%.6g %s (%ld)", c["worst_margin"].get<double>(), c.value("unit", "").c_str(),
                    c.value("worst_point", -1L));
      worst = b;
    }
    std::fprintf(out, "  %-34s %-6s %-14s %s\n", c.value("check", "").c_str(), c.value("method", "").c_str(), rate, worst.c_str());
  }
  if (!summary["comparisons"].empty()) {
    std::fprintf(out, "  %-34s %-14s %s\n", "comparison", "better wins", "difference: median [p10, p90]");
    for (const auto& c : summary["comparisons"]) {
      char rate[64];
      std::snprintf(rate, sizeof(rate), "%ld/%ld %.0f%%", c.value("wins", 0L), c.value("points", 0L), 100.0 * c.value("win_rate", 0.0));
      const json& d = c["diff"];
      const long bs = c.value("better_stopped_early", 0L), ws = c.value("worse_stopped_early", 0L);
      std::string stopped;
      if (bs + ws > 0)
        stopped = "; left out: " + c.value("better", "") + " stopped early " + std::to_string(bs) + ", " + c.value("worse", "") + " " +
                  std::to_string(ws);
      std::fprintf(out, "  %-34s %-14s %.4g [%.4g, %.4g]%s\n", c.value("name", "").c_str(), rate, num(d["median"]), num(d["p10"]),
                   num(d["p90"]), stopped.c_str());
    }
  }
  for (const auto& f : summary["failures"]) {
    std::fprintf(out, "  FAIL %s %s (%ld points; %s): %s\n", f.value("method", "").c_str(), f.value("check", "").c_str(),
                 f.value("points_failing", 0L), f.value("shrunk", false) ? "shrunk" : "not shrunk", f.value("command", "").c_str());
  }
}

// ---------------------------------------------------------------------------------------------
// The failure database.

bool recordFailures(const SweepSpec& s, const std::vector<json>& failures, const std::string& db_path, const std::atomic<int>* interrupt) {
  // The database is shared by every sweep of this name (each night's): one writer at a time.
  const files::FileLock lock(db_path, "lexdyn-harness sweep " + s.name, interrupt);
  if (!lock.held()) return false;
  std::set<std::string> known;
  std::string text = readFileText(db_path);
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    try {
      known.insert(json::parse(line).dump());
    } catch (const std::exception&) {}
  }
  if (!text.empty() && text.back() != '\n') text += '\n';  // a cut last line stays skipped, apart
  std::string add;
  for (const auto& f : failures) {
    const json e = {
        {"sweep", s.name}, {"method", f["method"]}, {"check", f["check"]}, {"values", f["values"]}, {"duration_s", f["duration_s"]}};
    if (known.insert(e.dump()).second) add += e.dump() + "\n";
  }
  if (add.empty()) return true;
  writeAtomically(db_path, text + add);
  return true;
}

bool replayFailures(const SweepSpec& s, const DriverOptions& o, const RunOne& run, std::vector<std::string>& lost) {
  const std::string out = (fs::path(o.out_dir) / "replays.jsonl").string();
  if (fs::is_regular_file(out)) return true;  // done by an earlier, interrupted run of this sweep
  std::string db;
  {
    const files::FileLock lock(o.db_path, "lexdyn-harness sweep " + s.name, o.interrupt);
    if (!lock.held()) return false;
    db = readFileText(o.db_path);
  }
  std::istringstream in(db);
  std::string line, records;
  int k = 0, replayed = 0, still = 0;
  long line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    json e;
    std::string bad;
    try {
      e = json::parse(line);
      if (!e.is_object())
        bad = "not a JSON object";
      else if (!e.contains("sweep") || !e["sweep"].is_string() || !e.contains("method") || !e["method"].is_string() ||
               !e.contains("check") || !e["check"].is_string() || !e.contains("values") || !e["values"].is_object()) {
        bad = "expected sweep, method, check and values";
      } else {
        for (auto it = e["values"].begin(); it != e["values"].end(); ++it) {
          if (!it.value().is_string()) bad = "values." + it.key() + ": expected a string";
        }
      }
    } catch (const std::exception& ex) {
      bad = std::string("damaged: ") + ex.what();
    }
    if (!bad.empty()) {
      std::fprintf(stderr, "[sweep %s] warning: %s:%ld: %s; the line is skipped\n", s.name.c_str(), o.db_path.c_str(), line_no,
                   bad.c_str());
      continue;
    }
    if (e.value("sweep", "") != s.name) continue;
    RunConfig c;
    c.method = e.value("method", "");
    if (std::find(s.methods.begin(), s.methods.end(), c.method) == s.methods.end()) continue;
    c.values.assign(s.parameters.size(), "");
    bool usable = true;
    for (auto it = e["values"].begin(); it != e["values"].end(); ++it) {
      size_t p = 0;
      while (p < s.parameters.size() && s.parameters[p].name != it.key()) ++p;
      if (p == s.parameters.size())
        usable = false;
      else
        c.values[p] = it.value().get<std::string>();
    }
    if (!usable) continue;  // the sweep no longer has that parameter
    c.duration_s = num(e.value("duration_s", json()));
    if (!std::isfinite(c.duration_s)) c.duration_s = 0.0;
    const Trial t = run(c, (fs::path(o.out_dir) / "replay" / std::to_string(k++) / c.method).string());
    if (t.end == Trial::End::kInterrupted) return false;  // replayed again next time
    if (t.end == Trial::End::kLost) {
      lost.push_back("the replay of " + c.method + " " + e.value("check", "") + " from " + o.db_path + ": " + t.why);
      return false;
    }
    const RunResult* r = &t.result;
    const std::string check = e.value("check", "");
    const std::vector<std::string> f = r->failures();
    const bool fails = std::find(f.begin(), f.end(), check) != f.end();
    ++replayed;
    still += fails ? 1 : 0;
    json rec = e;
    rec["status"] = records::toString(r->status);
    rec["still_fails"] = fails;
    if (const CheckOutcome* co = r->check(check)) {
      rec["value"] = number(co->value);
      rec["limit"] = number(co->limit);
    }
    records += rec.dump() + "\n";
  }
  writeAtomically(out, records);
  if (o.progress && replayed > 0) {
    std::fprintf(stderr, "[sweep %s] replayed %d earlier failure(s) from %s: %d still fail\n", s.name.c_str(), replayed, o.db_path.c_str(),
                 still);
  }
  return true;
}

}  // namespace lexdyn::sweep
