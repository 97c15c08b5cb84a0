#include "harness/sweep/sweep_run.hpp"

#include "harness/cases/runner.hpp"
#include "harness/checks/output_files.hpp"
#include "harness/sweep/process.hpp"
#include "harness/sweep/sweep_records.hpp"
#include "lexdyn/common/error.hpp"

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <csignal>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

namespace lexdyn::sweep {

namespace fs = std::filesystem;
using nlohmann::json;

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
  o.push_back(
      {"trace.every_n_ticks", std::to_string(s.trace_every_n_ticks), "--set trace.every_n_ticks=" + std::to_string(s.trace_every_n_ticks)});
  return o;
}

// What the driver makes of a finished process (docs/architecture.md, "Faults"): a result to
// record when the run ended on its own (completed, failed a check, failed in the integrator or
// the controller, bad input) or by the driver's timeout; otherwise (killed or stopped from
// outside, no summary, an output it could not write) nothing is recorded and `why` says what
// happened.
Trial classify(const SweepSpec& s, const std::string& method, const std::string& dir, const ProcessOutcome& p) {
  Trial t;
  RunResult& r = t.result;
  r.exit_code = p.exit_code;
  r.wall_s = p.wall_s;
  const std::string summary = (fs::path(dir) / "summary.json").string();
  const std::string log = (fs::path(dir) / "log.txt").string();
  auto lost = [&](const std::string& why) {
    t.end = Trial::End::kLost;
    std::string tail = lastLines(p.output_tail, 2);
    for (char& c : tail) c = c == '\n' ? ' ' : c;
    t.why =
        why + (tail.empty() ? "" : " (" + tail + ")") + (p.log_error.empty() ? "" : " (the log could not be written: " + p.log_error + ")");
    return t;
  };
  if (p.timed_out) {
    r.status = records::RunStatus::Timeout;
    r.message = "killed after the timeout";
    return t;
  }
  if (p.signal != 0) return lost("killed by " + signalName(p.signal));
  if (!p.log_error.empty()) return lost("its log could not be written");
  if (p.exit_code == 2 && p.output_tail.find("in use by another lexdyn job") != std::string::npos) {
    return lost("its folder was in use by another job");
  }
  if (p.exit_code == 2) {
    r.status = records::RunStatus::BadInput;
    r.message = lastLines(p.output_tail, 1);
    return t;
  }
  // The run's record, read by the records layer: a summary of another format (a folder written by
  // another build), cut or damaged is not this run's.
  if (!fs::exists(summary)) return lost("exit code " + std::to_string(p.exit_code) + ", summary.json not written");
  records::RunRecord rec;
  try {
    rec = records::readRunRecord(summary);
  } catch (const InputError& e) {
    return lost("exit code " + std::to_string(p.exit_code) + ", " + e.what());
  }
  r.status = rec.status;
  r.message = rec.message;
  if (r.status == records::RunStatus::Interrupted)
    return lost("stopped by a signal from outside (exit code " + std::to_string(p.exit_code) + ": " + r.message + ")");
  if (r.status == records::RunStatus::OutputError) return lost("could not write its outputs: " + r.message);
  // Out of memory says nothing of the configuration: the machine's state, like a kill.
  if (r.status == records::RunStatus::InternalError && r.message.find("out of memory") != std::string::npos) return lost(r.message);
  r.simulated_s = rec.simulated_s;
  const std::vector<std::string> wanted = propertyChecks(s, method);
  for (const records::CheckRecord& c : rec.checks) {
    if (std::find(wanted.begin(), wanted.end(), c.name) == wanted.end()) continue;
    r.checks.push_back({c.name, c.passed, c.value, c.limit, c.margin, c.unit, c.detail});
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
  for (const auto& [name, st] : rec.statistics) r.statistics[name] = st.value;
  if (rec.controller) {
    for (const auto& [name, task] : rec.controller->tasks) r.final_errors[name] = task.final_error;
    r.peak_iterations = rec.controller->peak_iterations;
  }
  return t;
}

std::string pointName(long i) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06ld", i);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// One run in this process (the worker).

int runPointHere(const SweepSpec& s, const RunConfig& c, const std::string& out_dir, const std::atomic<bool>* interrupt, bool progress) {
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
    if (o.path == "stop_at_s")
      cmd += " --duration " + o.value;
    else if (o.path != "trace.every_n_ticks")
      cmd += " --set " + shellQuote(o.path + "=" + o.value);
  }
  return cmd + " --out DIR";
}

// ---------------------------------------------------------------------------------------------
// The driver.

namespace {

constexpr const char* kSweepRecordHeader = "# lexdyn sweep record, digest ";

}  // namespace

void prepareOutDir(const SweepSpec& s, const std::string& out_dir) {
  files::createFolder((fs::path(out_dir) / "points").string());
  files::createFolder((fs::path(out_dir) / "runs").string());
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
    std::string stored = readFileText(recorded);
    // sweep.txt starts with the digest of what follows: a file that was cut or edited is told
    // from the record of another sweep (files written before the digest have none).
    const std::string header = kSweepRecordHeader;
    if (stored.compare(0, header.size(), header) == 0) {
      const size_t eol = stored.find('\n');
      const std::string digest = eol == std::string::npos ? "" : stored.substr(header.size(), eol - header.size());
      const std::string body = eol == std::string::npos ? "" : stored.substr(eol + 1);
      if (digest != textDigest(body)) {
        throw InputError(recorded, "is damaged (cut or edited: its digest does not match its text), so the results in " + out_dir +
                                       " cannot be matched to a sweep file; restore it, or remove " + out_dir +
                                       " (or use another --out) and run again");
      }
      stored = body;
    } else if (stored.empty()) {
      throw InputError(recorded, "is empty (damaged), so the results in " + out_dir + " cannot be matched to a sweep file; remove " +
                                     out_dir + " (or use another --out) and run again");
    }
    if (stored != text) {
      throw InputError(out_dir, "holds the results of another version of " + s.path + " or of its base case (" + recorded +
                                    " differs); use another --out or remove it");
    }
  } else {
    const std::string record = kSweepRecordHeader + textDigest(text) + "\n" + text;
    try {
      writeAtomically(recorded, record);
    } catch (const OutputError&) {
      // Slurm array tasks starting at once write the same record: one rename wins.
      if (readFileText(recorded) != record) throw;
    }
  }
}

namespace {

struct Job {
  long point = 0;
  RunConfig config;
  std::string dir;
};

// Runs the jobs on `jobs` threads, each running one process at a time. Calls `done` (under a
// lock) with each finished job and what became of it; an interrupted job is not reported. An
// exception in a thread (an output that cannot be written, a process that cannot be started)
// stops the other processes and is rethrown here, in the caller's thread.
class Pool {
 public:
  Pool(const SweepSpec& s, const DriverOptions& o) : s_(s), o_(o) {}

  template <class Done>
  void run(const std::vector<Job>& jobs, Done done) {
    std::mutex m;
    size_t next = 0;
    std::exception_ptr error;
    const int n = std::max(1, std::min<int>(o_.jobs > 0 ? o_.jobs : 1, static_cast<int>(jobs.size())));
    std::vector<std::thread> threads;
    auto joinAll = [&] {
      for (auto& t : threads) t.join();
    };
    for (int t = 0; t < n; ++t) {
      try {
        threads.emplace_back([&]() {
          try {
            for (;;) {
              size_t k;
              {
                std::lock_guard<std::mutex> lock(m);
                if (next >= jobs.size() || abort_.load() != 0 || (o_.interrupt && o_.interrupt->load() != 0)) return;
                k = next++;
              }
              const Job& job = jobs[k];
              const Trial r = execute(job);
              if (r.end == Trial::End::kInterrupted) continue;  // left for the next run
              std::lock_guard<std::mutex> lock(m);
              done(job, r);
            }
          } catch (...) {
            std::lock_guard<std::mutex> lock(m);
            if (!error) error = std::current_exception();
            abort_.store(1);
          }
        });
      } catch (...) {  // no thread could be created: stop, and let the running ones end first
        abort_.store(1);
        joinAll();
        throw;
      }
    }
    joinAll();
    if (error) std::rethrow_exception(error);
  }

  // One job in a process, run once more when something from outside killed it.
  Trial execute(const Job& job) {
    const Trial first = attempt(job);
    if (first.end != Trial::End::kLost) return first;
    if (o_.progress) std::fprintf(stderr, "[sweep %s] %s: %s; running it again\n", s_.name.c_str(), label(job).c_str(), first.why.c_str());
    Trial second = attempt(job);
    if (second.end != Trial::End::kLost) return second;
    second.why = first.why + "; run again: " + second.why;
    // A crash of the run itself (not a signal from outside) that repeats is the run's result.
    auto crashed = [](const Trial& t) {
      const int sig = t.result.exit_code - 128;
      return sig == SIGSEGV || sig == SIGABRT || sig == SIGBUS || sig == SIGFPE || sig == SIGILL;
    };
    if (crashed(first) && crashed(second)) {
      second.end = Trial::End::kRecorded;
      second.result.status = records::RunStatus::Crashed;
      second.result.message = second.why;
      writeAtomically((fs::path(job.dir) / "result.json").string(), toJson(second.result).dump(1) + "\n");
    }
    return second;
  }

  std::string label(const Job& job) const {
    return (job.point >= 0 ? "point " + std::to_string(job.point) + " " : "trial " + job.dir + " ") + job.config.method;
  }

 private:
  Trial attempt(const Job& job) {
    std::error_code ec;
    fs::remove_all(job.dir, ec);
    if (ec) throw OutputError(job.dir, "cannot remove an earlier attempt: " + ec.message());
    files::createFolder(job.dir);
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
    const ProcessOutcome p = runProcess(argv, log, o_.timeout_s > 0.0 ? o_.timeout_s : s_.timeout_s, o_.interrupt, &abort_);
    if (!p.started) {
      if (p.error_errno != 0) throw OutputError(log, p.error);
      throw std::runtime_error("cannot start " + o_.harness_exe + ": " + p.error);
    }
    if (p.interrupted) return Trial{Trial::End::kInterrupted, {}, ""};
    Trial t = classify(s_, job.config.method, job.dir, p);
    if (t.end != Trial::End::kRecorded) return t;
    writeAtomically((fs::path(job.dir) / "result.json").string(), toJson(t.result).dump(1) + "\n");
    // Traces of passing runs go (their summaries stay); a failure keeps its trace.
    if (!o_.keep_traces && t.result.failures().empty()) fs::remove(fs::path(job.dir) / "trace.csv", ec);
    return t;
  }

  const SweepSpec& s_;
  const DriverOptions& o_;
  std::atomic<int> abort_{0};
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

// A stored point record or run result that does not read back whole is removed with a warning
// and made again (docs/architecture.md, "Faults").
void dropDamaged(const std::string& path, const std::string& why, const DriverOptions& o, const SweepSpec& s, const char* what) {
  if (o.progress) std::fprintf(stderr, "[sweep %s] warning: %s: %s; %s\n", s.name.c_str(), path.c_str(), why.c_str(), what);
  std::error_code ec;
  fs::remove(path, ec);
  if (ec) throw OutputError(path, "cannot remove a damaged file: " + ec.message());
}

// The stored record of point i when it reads back whole (a damaged one is removed).
std::optional<PointRecord> storedPoint(const SweepSpec& s, const DriverOptions& o, long i) {
  const std::string f = pointFile(o.out_dir, i);
  if (!fs::is_regular_file(f)) return std::nullopt;
  std::string why;
  std::optional<PointRecord> r = readPointRecord(s, i, f, why);
  if (!r) dropDamaged(f, why, o, s, "made again");
  return r;
}

// Runs what is missing of `points`; writes the point records. Returns false when interrupted;
// runs lost twice are added to `lost` (their points get no record).
bool runMissing(const SweepSpec& s, const std::vector<long>& points, const DriverOptions& o, std::vector<std::string>& lost) {
  std::vector<Job> jobs;
  std::map<long, int> left;  // runs still to do per point
  std::map<long, std::map<std::string, RunResult>> have;
  long done_runs = 0;
  for (long i : points) {
    if (storedPoint(s, o, i)) {
      done_runs += static_cast<long>(s.methods.size());
      continue;
    }
    const Point pt = pointAt(s, i);
    for (const auto& m : s.methods) {
      const std::string dir = runDir(o.out_dir, i, m);
      const std::string result = (fs::path(dir) / "result.json").string();
      if (fs::is_regular_file(result)) {
        std::string why;
        const std::optional<json> j = readJsonFile(result, why);
        const std::optional<RunResult> r = j ? recordedResult(*j, why) : std::nullopt;
        if (r) {
          have[i][m] = *r;
          ++done_runs;
          continue;
        }
        dropDamaged(result, why, o, s, "the run is run again");
      }
      jobs.push_back({i, {m, pt.values, 0.0}, dir});
      ++left[i];
    }
  }
  auto writePoint = [&](long i) { writeAtomically(pointFile(o.out_dir, i), toJson(pointRecord(s, pointAt(s, i), have[i])).dump() + "\n"); };
  // Points whose runs are all done but whose record is not (killed in between).
  for (long i : points) {
    if (left.find(i) == left.end() && have.count(i)) writePoint(i);
  }
  const long total_runs = static_cast<long>(points.size() * s.methods.size());
  long points_done = static_cast<long>(points.size() - left.size()), points_failed = 0;
  Progress progress(s, o, total_runs, done_runs);
  if (o.progress && !jobs.empty()) {
    std::fprintf(stderr, "[sweep %s] %zu points x %zu methods: %ld runs done, %zu to run on %d processes\n", s.name.c_str(), points.size(),
                 s.methods.size(), done_runs, jobs.size(), std::max(1, o.jobs));
  }
  std::map<long, bool> point_failed, point_lost;
  Pool pool(s, o);
  pool.run(jobs, [&](const Job& job, const Trial& t) {
    if (t.end == Trial::End::kLost) {
      point_lost[job.point] = true;
      lost.push_back(pool.label(job) + ": " + t.why);
      std::fprintf(stderr, "[sweep %s] %s lost: %s\n", s.name.c_str(), pool.label(job).c_str(), t.why.c_str());
    } else {
      have[job.point][job.config.method] = t.result;
      point_failed[job.point] = point_failed[job.point] || !t.result.failures().empty();
    }
    if (--left[job.point] == 0 && !point_lost[job.point]) {
      writePoint(job.point);
      ++points_done;
      points_failed += point_failed[job.point] ? 1 : 0;
    }
    progress.finished(t.end == Trial::End::kRecorded && !t.result.failures().empty(), points_done, static_cast<long>(points.size()),
                      points_failed);
  });
  return !(o.interrupt && o.interrupt->load() != 0);
}

// The end of a sweep command that lost runs: what was lost, and the run failure's exit code.
int reportLost(const SweepSpec& s, const std::vector<std::string>& lost) {
  std::fprintf(stderr,
               "[sweep %s] %zu run(s) lost: killed or stopped from outside twice, or unable to write their outputs; nothing was "
               "recorded for them (run the same command again to run them):\n",
               s.name.c_str(), lost.size());
  for (const auto& l : lost) std::fprintf(stderr, "  %s\n", l.c_str());
  return cases::kExitRunFailure;
}

// One configuration at a time through the pool's process runner (shrinking, replays).
RunOne runnerOf(Pool& pool) {
  return [&pool](const RunConfig& c, const std::string& dir) -> Trial { return pool.execute({-1, c, dir}); };
}

int interruptedCode(const DriverOptions& o) {
  const int sig = o.interrupt ? o.interrupt->load() : 0;
  return sig > 0 ? 128 + sig : 130;
}

}  // namespace

std::vector<long> missingPoints(const SweepSpec& s, const std::string& out_dir, long points) {
  std::vector<long> out;
  const long n = totalPoints(s, points);
  DriverOptions o;
  o.out_dir = out_dir;
  for (long i = 0; i < n; ++i) {
    if (!storedPoint(s, o, i)) out.push_back(i);
  }
  return out;
}

int runPoints(const SweepSpec& s, const std::vector<long>& points, const DriverOptions& o) {
  prepareOutDir(s, o.out_dir);
  std::vector<std::string> lost;
  if (!runMissing(s, points, o, lost)) return interruptedCode(o);
  return lost.empty() ? 0 : reportLost(s, lost);
}

int mergeSweep(const SweepSpec& s, const DriverOptions& o) {
  prepareOutDir(s, o.out_dir);
  // The summary is written again from the records; until then there is none, so that a merge
  // that stops (interrupted, a lost trial, a full disk) never leaves the summary of other records.
  const std::string summary_path = (fs::path(o.out_dir) / "summary.json").string();
  std::error_code ec;
  fs::remove(summary_path, ec);
  if (ec) throw OutputError(summary_path, "cannot remove the earlier summary: " + ec.message());
  const long n = totalPoints(s, o.points);
  std::vector<PointRecord> records;
  long missing = 0;
  for (long i = 0; i < n; ++i) {
    std::optional<PointRecord> r = storedPoint(s, o, i);
    if (r)
      records.push_back(std::move(*r));
    else
      ++missing;
  }
  std::string lines;
  for (const auto& r : records) lines += toJson(r).dump() + "\n";
  writeAtomically((fs::path(o.out_dir) / "results.jsonl").string(), lines);
  // Shrinking, the failure database, the summary and the maps.
  Pool pool(s, o);
  std::vector<std::string> lost;
  std::vector<FailureRecord> failures =
      o.shrink && s.shrink.enabled ? shrinkFailures(s, records, o, runnerOf(pool), lost) : minimalFailures(s, records);
  if (o.interrupt && o.interrupt->load() != 0) return interruptedCode(o);
  if (!lost.empty()) return reportLost(s, lost);
  if (!o.db_path.empty() && !recordFailures(s, failures, o.db_path, o.interrupt)) return interruptedCode(o);
  std::vector<records::SweepMapRecord> maps = writeMaps(s, records, o.out_dir, o.plot_command);
  const records::SweepSummary summary = summarize(s, records, n, std::move(failures), std::move(maps));
  writeAtomically(summary_path, toJson(summary).dump(2) + "\n");
  printSummary(summary, stderr);
  if (missing > 0) {
    std::fprintf(stderr, "[sweep %s] %ld of %ld points have no result yet (run the same command again)\n", s.name.c_str(), missing, n);
    return cases::kExitRunFailure;  // incomplete: neither a pass nor a failed property
  }
  return summary.failed_points == 0 ? 0 : 1;
}

int runSweep(const SweepSpec& s, const DriverOptions& o) {
  prepareOutDir(s, o.out_dir);
  // Until the merge writes it again there is no summary: a sweep that stops (lost runs, a full
  // disk) never leaves the summary of fewer records.
  {
    const std::string summary_path = (fs::path(o.out_dir) / "summary.json").string();
    std::error_code ec;
    fs::remove(summary_path, ec);
    if (ec) throw OutputError(summary_path, "cannot remove the earlier summary: " + ec.message());
  }
  std::vector<std::string> lost;
  if (!o.db_path.empty()) {
    Pool pool(s, o);
    if (!replayFailures(s, o, runnerOf(pool), lost) && o.interrupt && o.interrupt->load() != 0) return interruptedCode(o);
  }
  std::vector<long> all;
  for (long i = 0; i < totalPoints(s, o.points); ++i) all.push_back(i);
  if (!runMissing(s, all, o, lost)) return interruptedCode(o);
  if (!lost.empty()) {
    // The records of the points that were run are kept; the merge waits for the whole sweep.
    return reportLost(s, lost);
  }
  return mergeSweep(s, o);
}

}  // namespace lexdyn::sweep
