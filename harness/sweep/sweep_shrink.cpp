// Shrinking (docs/sweeps.md, "Shrinking"): a failure of a check at a point is reduced to the
// simplest configuration that still fails the same check. Each trial is a whole run in its own
// process; trials are cached (OUT/shrink/cache.jsonl) so that a configuration is never run
// twice, also across runs of the driver.
#include "harness/sweep/sweep_records.hpp"

#include "harness/checks/output_files.hpp"

#include "lexdyn/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

namespace lexdyn::sweep {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

bool parseNumber(const std::string& t, double& v) {
  char* end = nullptr;
  v = std::strtod(t.c_str(), &end);
  return !t.empty() && end == t.c_str() + t.size() && std::isfinite(v);
}

std::string configKey(const RunConfig& c) {
  std::string k = c.method + "|" + numberText(c.duration_s);
  for (const auto& v : c.values) k += "|" + v;
  return k;
}

// Trials shared by the shrinks (thread-safe), persisted to OUT/shrink/cache.jsonl.
class TrialCache {
 public:
  TrialCache(const std::string& out_dir, const RunOne& run, int slots) : dir_(fs::path(out_dir) / "shrink"), run_(run), free_(slots) {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    // A line that does not read back whole (cut by a crash of the machine, damaged) or holds no
    // recorded result is skipped: that trial is run again.
    std::istringstream in(readFileText((dir_ / "cache.jsonl").string()));
    std::string line;
    while (std::getline(in, line)) {
      try {
        const json j = json::parse(line);
        std::string why;
        const std::optional<RunResult> r = recordedResult(j.at("result"), why);
        if (r) results_[j.at("key").get<std::string>()] = *r;
      } catch (const std::exception&) {}
    }
  }

  /// The result of a configuration; `fresh` tells whether it was run now. A trial that is
  /// interrupted or lost is not cached.
  Trial get(const RunConfig& c, bool& fresh) {
    const std::string key = configKey(c);
    fresh = false;
    {
      std::unique_lock<std::mutex> lock(m_);
      // Two shrinks may ask for the same configuration at once: the second waits for the first's
      // trial (one process per trial folder), and takes its result.
      cv_.wait(lock, [&] { return running_.count(key) == 0; });
      auto it = results_.find(key);
      if (it != results_.end()) return Trial{Trial::End::kRecorded, it->second, ""};
      running_.insert(key);
      cv_.wait(lock, [&] { return free_ > 0; });
      --free_;
    }
    auto release = [&] {
      std::lock_guard<std::mutex> lock(m_);
      ++free_;
      running_.erase(key);
      cv_.notify_all();
    };
    Trial t;
    try {
      t = run_(c, (dir_ / "runs" / textDigest(key) / c.method).string());
      if (t.end == Trial::End::kRecorded) {
        files::appendDurably((dir_ / "cache.jsonl").string(), json{{"key", key}, {"result", toJson(t.result)}}.dump() + "\n");
        std::lock_guard<std::mutex> lock(m_);
        results_[key] = t.result;
      }
    } catch (...) {
      release();
      throw;
    }
    release();
    fresh = t.end == Trial::End::kRecorded;
    return t;
  }

 private:
  fs::path dir_;
  const RunOne& run_;
  std::mutex m_;
  std::condition_variable cv_;
  int free_;
  std::map<std::string, RunResult> results_;
  std::set<std::string> running_;  ///< configurations whose trial is running
};

// A failure: a check (or run_completed) of a method, first seen failing at some points.
struct Failure {
  std::string method, check;
  std::vector<long> points;
  const PointRecord* first = nullptr;  // the record of the point shrinking starts from
  const RunResult& firstRun() const { return first->run(method); }
  /// The configuration of the first point (a parameter it has no value of: its simplest).
  RunConfig firstConfig(const SweepSpec& s, double duration_s) const {
    RunConfig c{method, {}, duration_s};
    for (const auto& p : s.parameters) c.values.push_back(first->value(p.name, p.simplest));
    return c;
  }
};

int movedFromSimplest(const SweepSpec& s, const PointRecord& record) {
  int n = 0;
  for (const auto& p : s.parameters) n += record.value(p.name) != p.simplest ? 1 : 0;
  return n;
}

std::vector<Failure> collect(const SweepSpec& s, const std::vector<PointRecord>& records) {
  std::map<std::pair<std::string, std::string>, Failure> by;
  for (const auto& r : records) {
    for (const auto& text : r.failures) {
      const size_t colon = text.find(':');
      Failure& x = by[{text.substr(0, colon), text.substr(colon + 1)}];
      x.method = text.substr(0, colon);
      x.check = text.substr(colon + 1);
      x.points.push_back(r.point);
      // Start from the failing point nearest the simplest configuration (then the lowest index).
      if (!x.first || movedFromSimplest(s, r) < movedFromSimplest(s, *x.first)) x.first = &r;
    }
  }
  std::vector<Failure> out;
  for (auto& [k, v] : by) out.push_back(std::move(v));
  return out;
}

double fullDuration(const SweepSpec& s) { return s.duration_s ? *s.duration_s : s.base.duration_s; }

// summary.json's entry of a failure at configuration `c` (which gave `r`).
FailureRecord failureRecord(const SweepSpec& s, const Failure& f, const RunConfig& c, const RunResult& r) {
  FailureRecord j;
  j.check = f.check;
  j.method = f.method;
  j.point = f.first->point;
  j.points_failing = static_cast<long>(f.points.size());
  for (size_t k = 0; k < s.parameters.size(); ++k) {  // the parameters away from their simplest values
    if (c.values[k] != s.parameters[k].simplest) j.values[s.parameters[k].name] = c.values[k];
  }
  for (const auto& o : overridesOf(s, c.values)) j.overrides.emplace_back(o.path, o.value);
  j.duration_s = c.duration_s;
  j.command = reproduceCommand(s, c);
  j.status = r.status;
  if (const CheckOutcome* co = r.check(f.check)) j.outcome = *co;
  return j;
}

class Shrinker {
 public:
  /// `cap`: the trials this shrink may count (cached or run now).
  Shrinker(const SweepSpec& s, const Failure& f, TrialCache& cache, int cap) : s_(s), f_(f), cache_(cache), cap_(cap) {
    const RunResult& orig = f.firstRun();
    status_ = orig.status;
    if (const CheckOutcome* c = orig.check(f.check)) value_was_nan_ = std::isnan(c->value);
    full_duration_ = fullDuration(s);
  }

  /// False when interrupted.
  bool run() {
    best_ = f_.firstConfig(s_, full_duration_);
    best_result_ = f_.firstRun();
    // 1. All parameters at their simplest values at once, then one at a time (at the full
    // duration: a shorter run first would hold the parameters where the failure comes sooner).
    RunConfig all = best_;
    for (size_t k = 0; k < all.values.size(); ++k) all.values[k] = s_.parameters[k].simplest;
    if (all.values != best_.values) {
      int r = tryConfig(all);
      if (r < 0) return false;
    }
    for (size_t k = 0; k < s_.parameters.size(); ++k) {
      if (best_.values[k] == s_.parameters[k].simplest) continue;
      RunConfig t = best_;
      t.values[k] = s_.parameters[k].simplest;
      if (tryConfig(t) < 0) return false;
    }
    // 2. Each parameter still away from its simplest value moves toward it (binary search).
    for (size_t k = 0; k < s_.parameters.size(); ++k) {
      if (best_.values[k] == s_.parameters[k].simplest) continue;
      if (!towardSimplest(k)) return false;
    }
    // 3. The shortest duration that still fails.
    return shrinkDuration();
  }

  FailureRecord result(const std::string& out_dir) const {
    const std::string file = f_.method + "." + f_.check + ".yaml";
    FailureRecord j = failureRecord(s_, f_, best_, best_result_);
    j.case_file = "failures/" + file;
    j.shrunk = true;
    j.runs = runs_;
    j.budget_exhausted = exhausted_;
    writeCaseFile(out_dir, file);
    return j;
  }

 private:
  // 1: fails the same way (best_ becomes c), 0: does not (or over budget), -1: interrupted or
  // lost (lost_ says why). Every trial counts, from the cache or run now, so that `runs` and the
  // budget do not depend on what an earlier, interrupted driver ran or on the other shrinks.
  int tryConfig(const RunConfig& c) {
    bool fresh = false;
    if (runs_ >= cap_) {
      exhausted_ = true;
      return 0;
    }
    const Trial t = cache_.get(c, fresh);
    if (t.end == Trial::End::kLost) lost_ = t.why;
    if (t.end != Trial::End::kRecorded) return -1;
    ++runs_;
    if (!sameFailure(t.result)) return 0;
    best_ = c;
    best_result_ = t.result;
    return 1;
  }

  bool sameFailure(const RunResult& r) const {
    if (f_.check == kRunCompleted) return r.status == status_;
    const CheckOutcome* c = r.check(f_.check);
    if (!c || c->passed) return false;
    return !std::isnan(c->value) || value_was_nan_;  // "no rows in the window" is not the same failure
  }

  bool shrinkDuration() {
    const double dt = s_.base.control_period_s;
    const double step = std::max(s_.shrink.min_duration_s, dt);
    double lo = 0.0, hi = best_.duration_s;  // hi fails
    auto rounded = [&](double t) { return std::max(dt, std::round(t / dt) * dt); };
    while (hi - lo > step) {
      const double mid = rounded(lo == 0.0 && hi > 4.0 * step ? std::max(step, hi / 4.0) : 0.5 * (lo + hi));
      if (mid <= lo || mid >= hi) break;
      RunConfig t = best_;
      t.duration_s = mid;
      const int r = tryConfig(t);
      if (r < 0) return false;
      if (r == 1)
        hi = mid;
      else
        lo = mid;
      if (exhausted_) break;
    }
    return true;
  }

  bool towardSimplest(size_t k) {
    const Parameter& p = s_.parameters[k];
    if (p.distribution == Distribution::Values || p.distribution == Distribution::Choices) {
      // The values between the simplest and the failing one, nearest the simplest first.
      const std::vector<std::string> list = gridValues(p);
      const auto is = std::find(list.begin(), list.end(), p.simplest);
      const auto ic = std::find(list.begin(), list.end(), best_.values[k]);
      if (is == list.end() || ic == list.end()) return true;
      const long a = is - list.begin(), b = ic - list.begin();
      const long dir = b > a ? 1 : -1;
      for (long i = a + dir; i != b; i += dir) {
        RunConfig t = best_;
        t.values[k] = list[static_cast<size_t>(i)];
        const int r = tryConfig(t);
        if (r < 0) return false;
        if (r == 1) break;
      }
      return true;
    }
    double a = 0.0, b = 0.0;
    if (!parseNumber(p.simplest, a) || !parseNumber(best_.values[k], b)) return true;
    const bool log = p.distribution == Distribution::LogUniform && a > 0.0 && b > 0.0;
    const bool integers = p.distribution == Distribution::Integers;
    for (int i = 0; i < s_.shrink.bisection_steps; ++i) {
      double mid = log ? std::sqrt(a * b) : 0.5 * (a + b);
      if (integers) {
        mid = std::round(mid);
        if (std::abs(b - a) <= 1.0 || mid == a || mid == b) break;
      }
      RunConfig t = best_;
      t.values[k] = integers ? std::to_string(static_cast<long>(mid)) : numberText(mid);
      const int r = tryConfig(t);
      if (r < 0) return false;
      if (r == 1)
        b = mid;  // best_ moved
      else
        a = mid;
      if (exhausted_) break;
    }
    return true;
  }

  void writeCaseFile(const std::string& out_dir, const std::string& file) const {
    const fs::path dir = fs::path(out_dir) / "failures";
    std::error_code ec;
    fs::create_directories(dir, ec);
    try {
      std::vector<cases::Override> o = overridesOf(s_, best_.values);
      o.push_back({"stop_at_s", numberText(best_.duration_s), "--duration " + numberText(best_.duration_s)});
      cases::CaseSpec spec = cases::loadCase(s_.base_case, o);
      cases::overrideMethod(spec, f_.method, "--method");
      writeAtomically((dir / file).string(), cases::effectiveCaseText(spec, dir.string()));
    } catch (const InputError& e) {
      std::fprintf(stderr, "warning: cannot write %s: %s\n", (dir / file).string().c_str(), e.what());
    }
  }

  const SweepSpec& s_;
  const Failure& f_;
  TrialCache& cache_;
  records::RunStatus status_ = records::RunStatus::Completed;
  bool value_was_nan_ = false;
  double full_duration_ = 0.0;
  RunConfig best_;
  RunResult best_result_;
  int runs_ = 0;
  bool exhausted_ = false;
  int cap_ = 0;

 public:
  std::string lost_;  ///< why a trial was lost ("" when none was)
};

}  // namespace

std::vector<FailureRecord> minimalFailures(const SweepSpec& s, const std::vector<PointRecord>& records) {
  std::vector<FailureRecord> out;
  for (const Failure& f : collect(s, records)) out.push_back(failureRecord(s, f, f.firstConfig(s, fullDuration(s)), f.firstRun()));
  return out;
}

std::vector<FailureRecord> shrinkFailures(const SweepSpec& s, const std::vector<PointRecord>& records, const DriverOptions& o,
                                          const RunOne& run, std::vector<std::string>& lost) {
  std::vector<Failure> failures = collect(s, records);
  std::vector<FailureRecord> out(failures.size());
  if (failures.empty()) return out;
  TrialCache cache(o.out_dir, run, std::max(1, o.jobs));
  // The sweep's total budget, shared evenly by the failures that shrink (at most max_runs each):
  // a fixed share, counted over cached and fresh trials alike, so that which failures a small
  // budget leaves less shrunk depends neither on the shrinks' timing nor on what an earlier,
  // interrupted driver ran.
  auto shrinks = [&](const Failure& f) {
    const records::RunStatus status = f.firstRun().status;
    return !(f.check == kRunCompleted && (status == records::RunStatus::Timeout || status == records::RunStatus::Crashed));
  };
  long shrinking = 0;
  for (const Failure& f : failures) shrinking += shrinks(f) ? 1 : 0;
  const int cap = static_cast<int>(std::min<long>(s.shrink.max_runs, s.shrink.max_total_runs / std::max(1L, shrinking)));
  std::vector<char> ok(failures.size(), 0);
  std::vector<std::string> lost_by(failures.size());
  std::mutex error_m;
  std::exception_ptr error;
  // One thread per failure; the cache lets at most `jobs` trials run at once. Each shrink is
  // sequential, so its outcome does not depend on the others' timing. An exception in a thread
  // (an output that cannot be written) is carried to the caller.
  std::vector<std::thread> threads;
  auto joinAll = [&] {
    for (auto& t : threads) t.join();
  };
  for (size_t i = 0; i < failures.size(); ++i) {
    try {
      threads.emplace_back([&, i]() {
        try {
          const Failure& f = failures[i];
          // Timeouts are not shrunk (each trial could cost the whole timeout).
          if (!shrinks(f)) return;
          Shrinker sh(s, f, cache, cap);
          if (!sh.run()) {
            lost_by[i] = sh.lost_;
            return;
          }
          out[i] = sh.result(o.out_dir);
          ok[i] = 1;
          if (o.progress) {
            std::fprintf(stderr, "[sweep %s] shrunk %s %s: %s\n", s.name.c_str(), f.method.c_str(), f.check.c_str(),
                         out[i].command.c_str());
          }
        } catch (...) {
          std::lock_guard<std::mutex> lock(error_m);
          if (!error) error = std::current_exception();
        }
      });
    } catch (...) {  // no thread could be created: the ones running end first
      joinAll();
      throw;
    }
  }
  joinAll();
  if (error) std::rethrow_exception(error);
  for (size_t i = 0; i < failures.size(); ++i) {
    if (!lost_by[i].empty()) lost.push_back("shrinking " + failures[i].method + " " + failures[i].check + ": " + lost_by[i]);
  }
  // Failures that were not shrunk (interrupted, lost, or not shrinkable) keep their point.
  const std::vector<FailureRecord> plain = minimalFailures(s, records);
  for (size_t i = 0; i < out.size(); ++i) {
    if (!ok[i]) out[i] = plain[i];
  }
  return out;
}

}  // namespace lexdyn::sweep
