#include "harness/sweep/sweep_run.hpp"

#include "harness/cases/runner.hpp"
#include "harness/sweep/process.hpp"
#include "harness/sweep/sweep_records.hpp"
#include "lexdyn/common/error.hpp"

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

namespace lexdyn::sweep {

namespace fs = std::filesystem;
using nlohmann::json;

std::vector<std::string> RunResult::failures() const {
  std::vector<std::string> out;
  if (status != "completed") out.push_back(kRunCompleted);
  for (const auto& c : checks) {
    if (!c.passed) out.push_back(c.name);
  }
  return out;
}

const CheckOutcome* RunResult::check(const std::string& name) const {
  for (const auto& c : checks) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

namespace {

// The statistics a run records for the sweep's comparisons (one task_error figure per side).
std::vector<checks::CheckSpec> comparisonStatistics(const SweepSpec& s, const std::string& method) {
  std::vector<checks::CheckSpec> out;
  for (const Comparison& c : s.comparisons) {
    if (c.better != method && c.worse != method) continue;
    out.push_back(checks::comparisonStatistic(c));
  }
  return out;
}

std::vector<cases::Override> runOverrides(const SweepSpec& s, const RunConfig& c) {
  std::vector<cases::Override> o = overridesOf(s, c.values);
  const double d = c.duration_s > 0.0 ? c.duration_s : (s.duration_s ? *s.duration_s : 0.0);
  if (d > 0.0) o.push_back({"stop_at_s", numberText(d), "--duration " + numberText(d)});
  o.push_back({"trace.every_n_ticks", std::to_string(s.trace_every_n_ticks), "--set trace.every_n_ticks=" + std::to_string(s.trace_every_n_ticks)});
  return o;
}

// The result of a finished process, from its summary.json.
RunResult readRunResult(const SweepSpec& s, const std::string& method, const std::string& dir, const ProcessOutcome& p) {
  RunResult r;
  r.exit_code = p.exit_code;
  r.wall_s = p.wall_s;
  const std::string summary = (fs::path(dir) / "summary.json").string();
  const std::string log = (fs::path(dir) / "log.txt").string();
  if (p.timed_out) {
    r.status = "timeout";
    r.message = "killed after the timeout";
    return r;
  }
  if (p.signal != 0) {
    r.status = "crashed";
    r.message = "ended by signal " + std::to_string(p.signal) + ": " + tailOfFile(log, 3);
    return r;
  }
  if (p.exit_code == 2) {
    r.status = "bad_input";
    r.message = tailOfFile(log, 1);
    return r;
  }
  if (!fs::is_regular_file(summary)) {
    r.status = "no_summary";
    r.message = "exit code " + std::to_string(p.exit_code) + ", no summary.json: " + tailOfFile(log, 3);
    return r;
  }
  json j;
  try {
    j = json::parse(readFileText(summary));
  } catch (const std::exception& e) {
    r.status = "no_summary";
    r.message = std::string("unreadable summary.json: ") + e.what();
    return r;
  }
  auto num = [](const json& v) { return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN(); };
  r.status = j.value("status", "no_summary");
  r.message = j.value("message", "");
  r.simulated_s = j.value("simulated_s", 0.0);
  const std::vector<std::string> wanted = propertyChecks(s, method);
  for (const auto& c : j.value("checks", json::array())) {
    const std::string name = c.value("name", "");
    if (std::find(wanted.begin(), wanted.end(), name) == wanted.end()) continue;
    r.checks.push_back(checkFromJson(c));
  }
  // Checks the run did not report (it stopped before they were set up) count as failed.
  for (const auto& name : wanted) {
    if (r.check(name)) continue;
    CheckOutcome o;
    o.name = name;
    o.value = o.limit = o.margin = std::numeric_limits<double>::quiet_NaN();
    o.detail = "not evaluated";
    r.checks.push_back(o);
  }
  if (j.contains("statistics")) {
    for (auto it = j["statistics"].begin(); it != j["statistics"].end(); ++it) r.statistics[it.key()] = num(it.value().value("value", json()));
  }
  if (j.contains("tasks")) {
    for (auto it = j["tasks"].begin(); it != j["tasks"].end(); ++it) r.final_errors[it.key()] = num(it.value().value("final_error", json()));
  }
  if (j.contains("solver")) r.peak_iterations = j["solver"].value("peak_iterations", 0);
  return r;
}

std::string pointName(long i) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06ld", i);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// One run in this process (the worker).

int runPointHere(const SweepSpec& s, const RunConfig& c, const std::string& out_dir, const std::atomic<bool>* interrupt,
                 bool progress) {
  cases::CaseSpec spec = cases::loadCase(s.base_case, runOverrides(s, c));
  cases::overrideMethod(spec, c.method, "--method");
  cases::RunOptions o;
  o.out_dir = out_dir;
  o.progress = progress;
  o.interrupt = interrupt;
  o.statistics = comparisonStatistics(s, c.method);
  const cases::RunSummary r = cases::runCase(spec, o);
  return cases::exitCode(r);
}

std::string reproduceCommand(const SweepSpec& s, const RunConfig& c) {
  std::string cmd = "lexdyn-harness run " + shellQuote(s.base_case) + " --method " + c.method;
  for (const auto& o : runOverrides(s, c)) {
    if (o.path == "stop_at_s") cmd += " --duration " + o.value;
    else if (o.path != "trace.every_n_ticks") cmd += " --set " + shellQuote(o.path + "=" + o.value);
  }
  return cmd + " --out DIR";
}

// ---------------------------------------------------------------------------------------------
// The driver.

void prepareOutDir(const SweepSpec& s, const std::string& out_dir) {
  std::error_code ec;
  fs::create_directories(fs::path(out_dir) / "points", ec);
  fs::create_directories(fs::path(out_dir) / "runs", ec);
  if (ec || !fs::is_directory(out_dir)) throw InputError(out_dir, "cannot create the output directory");
  // What decides the results: the sweep file (but its description and shrink settings, which
  // only change the summary) and its base case. Resuming with other ones would mix results.
  YAML::Node doc = YAML::LoadFile(s.path);
  doc.remove("description");
  doc.remove("shrink");
  YAML::Emitter e;
  e << doc;
  const std::string text = std::string(e.c_str()) + "\n# base case " + s.base_case + ":\n" + readFileText(s.base_case);
  const std::string recorded = (fs::path(out_dir) / "sweep.txt").string();
  if (fs::is_regular_file(recorded)) {
    if (readFileText(recorded) != text) {
      throw InputError(out_dir, "holds the results of another version of " + s.path + " or of its base case; use another --out or remove it");
    }
  } else {
    writeAtomically(recorded, text);
  }
}

namespace {

struct Job {
  long point = 0;
  RunConfig config;
  std::string dir;
};

// Runs the jobs on `jobs` threads, each running one process at a time. Calls `done` (under a
// lock) with each finished job and its result; an interrupted job is not reported.
class Pool {
 public:
  Pool(const SweepSpec& s, const DriverOptions& o) : s_(s), o_(o) {}

  template <class Done>
  void run(const std::vector<Job>& jobs, Done done) {
    std::mutex m;
    size_t next = 0;
    const int n = std::max(1, std::min<int>(o_.jobs > 0 ? o_.jobs : 1, static_cast<int>(jobs.size())));
    std::vector<std::thread> threads;
    for (int t = 0; t < n; ++t) {
      threads.emplace_back([&]() {
        for (;;) {
          size_t k;
          {
            std::lock_guard<std::mutex> lock(m);
            if (next >= jobs.size() || (o_.interrupt && o_.interrupt->load() != 0)) return;
            k = next++;
          }
          const Job& job = jobs[k];
          RunResult r;
          if (!execute(job, r)) continue;  // interrupted: left for the next run
          std::lock_guard<std::mutex> lock(m);
          done(job, r);
        }
      });
    }
    for (auto& t : threads) t.join();
  }

  // One job in a process. False when it was interrupted (nothing recorded).
  bool execute(const Job& job, RunResult& r) {
    std::error_code ec;
    fs::remove_all(job.dir, ec);
    fs::create_directories(job.dir, ec);
    std::vector<std::string> argv = {o_.harness_exe, "sweep", "point", s_.path, "--method", job.config.method, "--out", job.dir, "--quiet"};
    if (job.point >= 0) {
      argv.insert(argv.end(), {"--index", std::to_string(job.point)});
    } else {
      for (size_t k = 0; k < s_.parameters.size(); ++k) {
        if (!job.config.values[k].empty()) argv.insert(argv.end(), {"--value", s_.parameters[k].name + "=" + job.config.values[k]});
      }
    }
    if (job.config.duration_s > 0.0) argv.insert(argv.end(), {"--duration", numberText(job.config.duration_s)});
    const std::string log = (fs::path(job.dir) / "log.txt").string();
    const ProcessOutcome p = runProcess(argv, log, o_.timeout_s > 0.0 ? o_.timeout_s : s_.timeout_s, o_.interrupt);
    if (!p.started) throw std::runtime_error("cannot start " + o_.harness_exe + ": " + p.error);
    if (p.interrupted) return false;
    r = readRunResult(s_, job.config.method, job.dir, p);
    writeAtomically((fs::path(job.dir) / "result.json").string(), toJson(r).dump(1) + "\n");
    // Traces of passing runs go (their summaries stay); a failure keeps its trace.
    if (!o_.keep_traces && r.failures().empty()) fs::remove(fs::path(job.dir) / "trace.csv", ec);
    return true;
  }

 private:
  const SweepSpec& s_;
  const DriverOptions& o_;
};

class Progress {
 public:
  Progress(const SweepSpec& s, const DriverOptions& o, long total_runs, long done_runs)
      : s_(s), o_(o), total_(total_runs), done0_(done_runs), done_(done_runs), t0_(std::chrono::steady_clock::now()) {}
  void finished(bool failed, long points_done, long points_total, long points_failed) {
    ++done_;
    failed_runs_ += failed ? 1 : 0;
    const double w = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    if (!o_.progress || (w - last_ < 2.0 && done_ != total_)) return;
    last_ = w;
    const long fresh = done_ - done0_;
    const double left = fresh > 0 ? w / static_cast<double>(fresh) * static_cast<double>(total_ - done_) : 0.0;
    std::fprintf(stderr, "[sweep %s] %ld/%ld points done, %ld failed (%ld/%ld runs), %.0f s elapsed, about %.0f s left\n", s_.name.c_str(),
                 points_done, points_total, points_failed, done_, total_, w, left);
  }

 private:
  const SweepSpec& s_;
  const DriverOptions& o_;
  long total_, done0_, done_;
  long failed_runs_ = 0;
  std::chrono::steady_clock::time_point t0_;
  double last_ = -1e9;
};

long totalPoints(const SweepSpec& s, long points) { return points >= 0 ? std::min(points, s.points) : s.points; }

std::string pointFile(const std::string& out, long i) { return (fs::path(out) / "points" / (pointName(i) + ".json")).string(); }
std::string runDir(const std::string& out, long i, const std::string& m) { return (fs::path(out) / "runs" / pointName(i) / m).string(); }

// Runs what is missing of `points`; writes the point records. Returns false when interrupted.
bool runMissing(const SweepSpec& s, const std::vector<long>& points, const DriverOptions& o) {
  std::vector<Job> jobs;
  std::map<long, int> left;  // runs still to do per point
  long done_runs = 0;
  for (long i : points) {
    if (fs::is_regular_file(pointFile(o.out_dir, i))) {
      done_runs += static_cast<long>(s.methods.size());
      continue;
    }
    const Point pt = pointAt(s, i);
    for (const auto& m : s.methods) {
      const std::string dir = runDir(o.out_dir, i, m);
      if (fs::is_regular_file(fs::path(dir) / "result.json")) {
        ++done_runs;
        continue;
      }
      jobs.push_back({i, {m, pt.values, 0.0}, dir});
      ++left[i];
    }
  }
  auto writePoint = [&](long i) {
    const Point pt = pointAt(s, i);
    std::map<std::string, RunResult> runs;
    for (const auto& m : s.methods) runs[m] = fromJson(json::parse(readFileText((fs::path(runDir(o.out_dir, i, m)) / "result.json").string())));
    writeAtomically(pointFile(o.out_dir, i), pointRecord(s, pt, runs).dump() + "\n");
  };
  // Points whose runs are all done but whose record is not (killed in between).
  for (long i : points) {
    if (!fs::is_regular_file(pointFile(o.out_dir, i)) && left.find(i) == left.end()) writePoint(i);
  }
  const long total_runs = static_cast<long>(points.size() * s.methods.size());
  long points_done = static_cast<long>(points.size() - left.size()), points_failed = 0;
  Progress progress(s, o, total_runs, done_runs);
  if (o.progress && !jobs.empty()) {
    std::fprintf(stderr, "[sweep %s] %zu points x %zu methods: %ld runs done, %zu to run on %d processes\n", s.name.c_str(), points.size(),
                 s.methods.size(), done_runs, jobs.size(), std::max(1, o.jobs));
  }
  std::map<long, bool> point_failed;
  Pool pool(s, o);
  pool.run(jobs, [&](const Job& job, const RunResult& r) {
    point_failed[job.point] = point_failed[job.point] || !r.failures().empty();
    if (--left[job.point] == 0) {
      writePoint(job.point);
      ++points_done;
      points_failed += point_failed[job.point] ? 1 : 0;
    }
    progress.finished(!r.failures().empty(), points_done, static_cast<long>(points.size()), points_failed);
  });
  return !(o.interrupt && o.interrupt->load() != 0);
}

// One configuration at a time through the pool's process runner (shrinking, replays).
RunOne runnerOf(Pool& pool) {
  return [&pool](const RunConfig& c, const std::string& dir) -> std::optional<RunResult> {
    RunResult r;
    if (!pool.execute({-1, c, dir}, r)) return std::nullopt;
    return r;
  };
}

int interruptedCode(const DriverOptions& o) {
  const int sig = o.interrupt ? o.interrupt->load() : 0;
  return sig > 0 ? 128 + sig : 130;
}

}  // namespace

std::vector<long> missingPoints(const SweepSpec& s, const std::string& out_dir, long points) {
  std::vector<long> out;
  const long n = totalPoints(s, points);
  for (long i = 0; i < n; ++i) {
    if (!fs::is_regular_file(pointFile(out_dir, i))) out.push_back(i);
  }
  return out;
}

int runPoints(const SweepSpec& s, const std::vector<long>& points, const DriverOptions& o) {
  prepareOutDir(s, o.out_dir);
  return runMissing(s, points, o) ? 0 : interruptedCode(o);
}

int mergeSweep(const SweepSpec& s, const DriverOptions& o) {
  prepareOutDir(s, o.out_dir);
  const long n = totalPoints(s, o.points);
  std::vector<json> records;
  long missing = 0;
  for (long i = 0; i < n; ++i) {
    const std::string f = pointFile(o.out_dir, i);
    if (!fs::is_regular_file(f)) {
      ++missing;
      continue;
    }
    records.push_back(json::parse(readFileText(f)));
  }
  std::string lines;
  for (const auto& r : records) lines += r.dump() + "\n";
  writeAtomically((fs::path(o.out_dir) / "results.jsonl").string(), lines);
  // Shrinking, the failure database, the summary and the maps.
  Pool pool(s, o);
  std::vector<json> failures = o.shrink && s.shrink.enabled ? shrinkFailures(s, records, o, runnerOf(pool)) : minimalFailures(s, records, o);
  if (o.interrupt && o.interrupt->load() != 0) return interruptedCode(o);
  if (!o.db_path.empty()) recordFailures(s, failures, o.db_path);
  const std::vector<json> maps = writeMaps(s, records, o.out_dir, o.plot_command);
  const json summary = summarize(s, records, n, failures, maps);
  writeAtomically((fs::path(o.out_dir) / "summary.json").string(), summary.dump(2) + "\n");
  printSummary(s, summary, stderr);
  if (missing > 0) {
    std::fprintf(stderr, "[sweep %s] %ld of %ld points have no result yet (run the same command again)\n", s.name.c_str(), missing, n);
    return cases::kExitRunFailure;  // incomplete: neither a pass nor a failed property
  }
  return summary.value("failed_points", 0) == 0 ? 0 : 1;
}

int runSweep(const SweepSpec& s, const DriverOptions& o) {
  prepareOutDir(s, o.out_dir);
  if (!o.db_path.empty()) {
    Pool pool(s, o);
    replayFailures(s, o, runnerOf(pool));
    if (o.interrupt && o.interrupt->load() != 0) return interruptedCode(o);
  }
  std::vector<long> all;
  for (long i = 0; i < totalPoints(s, o.points); ++i) all.push_back(i);
  if (!runMissing(s, all, o)) return interruptedCode(o);
  return mergeSweep(s, o);
}

}  // namespace lexdyn::sweep
