// The sweep driver on a real sweep (cases/sweeps/pointmass-damping.yaml, the sec. V-A point
// mass over the damping mu and the gain kp): one record per point, resumption after SIGKILL
// giving the same records as an uninterrupted run, a hang recorded as that run's failure (its
// timeout; a process killed from outside is run again, tests/faults), and the shrinker finding the failure boundary known in closed form
// (eq. 51: the acceleration-domain PD overshoots by exp(-pi/mu) for every kp).
#include "harness/records/sweep_record.hpp"
#include "harness/records/sweep_summary.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kHarness = std::string(LEXDYN_BINARY_DIR) + "/bin/lexdyn-harness";
const std::string kSweep = std::string(LEXDYN_SOURCE_DIR) + "/cases/sweeps/pointmass-damping.yaml";

std::string dirFor(const std::string& name) {
  const fs::path p = fs::path(LEXDYN_BINARY_DIR) / "test_output" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

int run(const std::string& args, const std::string& log) {
  const int status = std::system((kHarness + " " + args + " > " + log + " 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// results.jsonl without the wall times (the only figures allowed to differ between runs).
std::string withoutWallTimes(const std::string& path) {
  std::istringstream in(readText(path));
  std::string line, out;
  while (std::getline(in, line)) {
    json j = json::parse(line);
    for (auto& [m, r] : j["runs"].items()) r.erase("wall_s");
    out += j.dump() + "\n";
  }
  return out;
}

// The keys of the table that follows `title` in docs/file-formats.md (the first cell's `names`).
std::set<std::string> documentedKeys(const std::string& title) {
  const std::string doc = readText(std::string(LEXDYN_SOURCE_DIR) + "/docs/file-formats.md");
  const size_t from = doc.find(title);
  EXPECT_NE(from, std::string::npos) << title;
  std::set<std::string> keys;
  std::istringstream lines(doc.substr(from == std::string::npos ? doc.size() : from));
  bool in_table = false;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("|", 0) != 0) {
      if (in_table) break;
      continue;
    }
    in_table = true;
    if (line.rfind("| `", 0) != 0) continue;
    const std::string first = line.substr(2, line.find(" |", 2) - 2);  // "`a`, `b`"
    for (size_t p = first.find('`'); p != std::string::npos; p = first.find('`', first.find('`', p + 1) + 1))
      keys.insert(first.substr(p + 1, first.find('`', p + 1) - p - 1));
  }
  return keys;
}

// `j`'s keys are the table's: `absent` are documented but not in this file; with `extra`, they
// are keys the file holds beyond the table.
void expectDocumentedKeys(const std::string& title, const json& j, const std::set<std::string>& absent, bool extra = false) {
  std::set<std::string> documented = documentedKeys(title);
  std::set<std::string> written;
  for (auto it = j.begin(); it != j.end(); ++it) written.insert(it.key());
  if (extra) documented.insert(absent.begin(), absent.end());
  for (const auto& k : written)
    EXPECT_TRUE(documented.count(k)) << title << ": the file's key '" << k << "' is not in docs/file-formats.md";
  for (const auto& k : documented) {
    if (!extra && absent.count(k)) continue;
    EXPECT_TRUE(written.count(k)) << title << ": docs/file-formats.md documents '" << k << "', which the file does not hold";
  }
}

// The first time the closed-form response of eq. 51 (x0 = 1, kp, mu) goes past the target by more
// than `limit`.
double firstOvershootTime(double mu, double kp, double limit) {
  const double z = 1.0 / std::sqrt(1.0 + mu * mu), w = std::sqrt(kp / (1.0 + mu * mu)), wd = w * std::sqrt(1.0 - z * z);
  for (double t = 0.0; t < 60.0; t += 1e-4) {
    const double e = std::exp(-z * w * t) * (std::cos(wd * t) + z / std::sqrt(1.0 - z * z) * std::sin(wd * t));
    if (-e > limit) return t;
  }
  return NAN;
}

TEST(SweepDriver, RecordsResumptionAfterAKillAndTheShrunkBoundary) {
  const std::string dir = dirFor("sweep_driver");
  const std::string a = dir + "/a", b = dir + "/b";
  // A: uninterrupted, two processes.
  ASSERT_EQ(run("sweep run " + kSweep + " --out " + a + " -j 2 --db " + dir + "/db.jsonl", dir + "/a.log"), 1) << readText(dir + "/a.log");
  // One record per point, in index order, each with both methods and a reproducer command.
  std::istringstream in(readText(a + "/results.jsonl"));
  std::string line;
  long n = 0;
  while (std::getline(in, line)) {
    const json r = json::parse(line);
    // The records layer reads the line the driver wrote and writes it again byte for byte.
    std::string why;
    const auto typed = lexdyn::records::sweepPointFromJson(r, why);
    ASSERT_TRUE(typed.has_value()) << why;
    EXPECT_EQ(lexdyn::records::toJson(*typed).dump(), line);
    EXPECT_EQ(r["point"].get<long>(), n);
    for (const char* m : {"wls", "bfgs"}) {
      const json& run = r["runs"][m];
      EXPECT_EQ(run["status"], "completed");
      EXPECT_EQ(run["checks"].size(), 2u);
      EXPECT_NE(run["reproduce"].get<std::string>().find("lexdyn-harness run "), std::string::npos);
      EXPECT_NE(run["rerun"].get<std::string>().find("--index " + std::to_string(n)), std::string::npos);
    }
    // The velocity domain never overshoots; the acceleration domain does above mu = 0.4548.
    const double mu = std::stod(r["values"]["controller.params.damping"].get<std::string>());
    EXPECT_TRUE(r["runs"]["bfgs"]["checks"][0]["passed"].get<bool>());
    if (std::abs(mu - 0.4548) > 0.05) {
      EXPECT_EQ(r["runs"]["wls"]["checks"][0]["passed"].get<bool>(), mu < 0.4548) << "mu " << mu;
    }
    ++n;
  }
  EXPECT_EQ(n, 12);
  const json sa = json::parse(readText(a + "/summary.json"));
  EXPECT_EQ(sa["format"], lexdyn::records::kSweepSummaryFormat);
  EXPECT_EQ(sa["points"], 12);
  EXPECT_EQ(sa["completed"], 12);
  EXPECT_GT(sa["failed_points"].get<int>(), 0);

  // The shrunk failure: kp back at its simplest value, mu just above pi / ln(1000), the
  // duration just past the first overshoot of 1e-3 (closed form) within the shrink's resolution.
  ASSERT_EQ(sa["failures"].size(), 1u) << sa["failures"].dump(1);
  const json& f = sa["failures"][0];
  EXPECT_EQ(f["method"], "wls");
  EXPECT_EQ(f["check"], "no_overshoot");
  EXPECT_TRUE(f["shrunk"].get<bool>());
  EXPECT_FALSE(f["values"].contains("controller.tasks[position].gains.kp")) << f.dump(1);
  const double mu = std::stod(f["values"]["controller.params.damping"].get<std::string>());
  const double mu_boundary = M_PI / std::log(1000.0);  // 0.4548
  // Bisection from the simplest value 0 toward the failing one (<= 2), 7 steps: within 2 / 2^7.
  EXPECT_GE(mu, mu_boundary - 0.01) << f.dump(1);
  EXPECT_LE(mu, mu_boundary + 2.0 / 128.0 + 0.01) << f.dump(1);
  const double t_first = firstOvershootTime(mu, 1.0, 1e-3);
  const double d = f["duration_s"].get<double>();
  EXPECT_GE(d, t_first - 0.1) << "closed form " << t_first;
  EXPECT_LE(d, t_first + 0.5 + 0.1) << "closed form " << t_first;  // min_duration_s 0.5
  // Its case file reproduces it on its own.
  ASSERT_TRUE(fs::is_regular_file(a + "/" + f["case_file"].get<std::string>()));
  EXPECT_EQ(run("run " + a + "/" + f["case_file"].get<std::string>() + " --out " + dir + "/repro --quiet", dir + "/repro.log"), 1);
  const json rs = json::parse(readText(dir + "/repro/summary.json"));
  EXPECT_FALSE(rs["checks"][0]["passed"].get<bool>());
  EXPECT_EQ(rs["checks"][0]["name"], "no_overshoot");

  // B: killed (SIGKILL) part way, then the same command again: the same records.
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl(kHarness.c_str(), kHarness.c_str(), "sweep", "run", kSweep.c_str(), "--out", b.c_str(), "-j", "2", "--no-db", "--quiet",
          (char*)nullptr);
    _exit(127);
  }
  // Wait until some points are done, then kill the driver.
  for (int k = 0; k < 400; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    if (fs::exists(b + "/points") && std::distance(fs::directory_iterator(b + "/points"), fs::directory_iterator()) >= 3) break;
  }
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  const long done_before = std::distance(fs::directory_iterator(b + "/points"), fs::directory_iterator());
  EXPECT_LT(done_before, 12) << "the driver finished before it was killed";
  EXPECT_FALSE(fs::exists(b + "/results.jsonl"));
  // Merging what is there: the summary of the points done, exit code 3 (incomplete).
  EXPECT_EQ(run("sweep merge " + kSweep + " --out " + b + " --no-shrink --no-db", dir + "/b-merge.log"), 3)
      << readText(dir + "/b-merge.log");
  EXPECT_NE(readText(dir + "/b-merge.log").find("points have no result yet"), std::string::npos) << readText(dir + "/b-merge.log");
  ASSERT_EQ(run("sweep run " + kSweep + " --out " + b + " -j 2 --no-db", dir + "/b.log"), 1) << readText(dir + "/b.log");
  EXPECT_NE(readText(dir + "/b.log").find("runs done"), std::string::npos);
  EXPECT_EQ(withoutWallTimes(a + "/results.jsonl"), withoutWallTimes(b + "/results.jsonl"));
  const json sb = json::parse(readText(b + "/summary.json"));
  EXPECT_EQ(sa["failures"], sb["failures"]);
  EXPECT_EQ(sa["checks"], sb["checks"]);

  // C: the failure database: the shrunk failure is replayed first, and still fails.
  ASSERT_EQ(run("sweep run " + kSweep + " --out " + dir + "/c --points 2 --no-shrink --db " + dir + "/db.jsonl", dir + "/c.log"), 1)
      << readText(dir + "/c.log");
  const json replay = json::parse(readText(dir + "/c/replays.jsonl"));
  EXPECT_EQ(replay["format"], lexdyn::records::kSweepReplayFormat);
  EXPECT_EQ(replay["check"], "no_overshoot");
  // The database holds A's shrunk failure, then C's own (unshrunk), each once, as entries of this
  // format (B ran without the database).
  const std::string db = readText(dir + "/db.jsonl");
  const json sc = json::parse(readText(dir + "/c/summary.json"));
  ASSERT_EQ(std::count(db.begin(), db.end(), '\n'), 1 + static_cast<long>(sc["failures"].size())) << db;
  std::string why;
  const auto entry = lexdyn::records::sweepFailureFromJson(json::parse(db.substr(0, db.find('\n'))), why);
  ASSERT_TRUE(entry.has_value()) << why;
  EXPECT_EQ(entry->sweep, "pointmass-damping");
  EXPECT_EQ(entry->check, "no_overshoot");
  EXPECT_EQ(entry->values, (std::map<std::string, std::string>{{"controller.params.damping", f["values"]["controller.params.damping"]}}));
  EXPECT_TRUE(replay["still_fails"].get<bool>());
  EXPECT_NE(readText(dir + "/c.log").find("replayed 1 earlier failure(s)"), std::string::npos);

  // docs/file-formats.md's tables are the keys these files hold, no more and no fewer.
  const json point = json::parse(readText(a + "/points/000000.json"));
  expectDocumentedKeys("**Sweep point**", point, {});
  expectDocumentedKeys("**Sweep run**", point["runs"]["wls"], {});
  expectDocumentedKeys("**Sweep run**", json::parse(readText(a + "/runs/000000/wls/result.json")), {"reproduce", "rerun"});
  expectDocumentedKeys("**Sweep summary**", sa, {});
  expectDocumentedKeys("**Failure database entry**", json::parse(db.substr(0, db.find('\n'))), {});
  std::set<std::string> entry_keys = documentedKeys("**Failure database entry**");
  entry_keys.erase("format");
  expectDocumentedKeys("**Replay**", replay, entry_keys, true);
}

// The total shrink budget is shared evenly by the failures: with two failures of WLS and
// max_total_runs 6, each shrink counts exactly 3 trials and says its budget ended, and the
// shrunk failures are the same with one process or two (whatever the shrinks' timing).
TEST(SweepDriver, TheTotalShrinkBudgetIsSharedEvenly) {
  const std::string dir = dirFor("sweep_budget");
  std::string text = readText(kSweep);
  text.replace(text.find("base: ../pointmass-damping.yaml"), 31,
               "base: " + std::string(LEXDYN_SOURCE_DIR) + "/cases/pointmass-damping.yaml");
  text.replace(text.find("sampling: {points: 12}"), 22, "sampling: {points: 4}");
  text.replace(text.find("checks: [no_overshoot, controller_ok]"), 37, "checks: [no_overshoot, closed_form_eq49, controller_ok]");
  text.replace(text.find("shrink: {max_runs: 30,"), 22, "shrink: {max_runs: 30, max_total_runs: 6,");
  const std::string file = dir + "/budget.yaml";
  std::ofstream(file) << text;
  std::string failures[2];
  for (int k = 0; k < 2; ++k) {
    const std::string out = dir + "/j" + std::to_string(k + 1);
    ASSERT_EQ(run("sweep run " + file + " --out " + out + " -j " + std::to_string(k + 1), out + ".log"), 1) << readText(out + ".log");
    json summary = json::parse(readText(out + "/summary.json"));
    ASSERT_EQ(summary["failures"].size(), 2u) << summary.dump(1);
    for (auto& f : summary["failures"]) {
      EXPECT_EQ(f["method"], "wls");
      EXPECT_EQ(f["runs"].get<int>(), 3) << f.dump(1);
      EXPECT_TRUE(f["budget_exhausted"].get<bool>()) << f.dump(1);
      f.erase("wall_s");
    }
    failures[k] = summary["failures"].dump();
  }
  EXPECT_EQ(failures[0], failures[1]);
}

TEST(SweepDriver, AHangIsThatRunsRecordedFailure) {
  // A run that overruns its timeout is killed and recorded; the sweep goes on.
  const std::string dir = dirFor("sweep_driver_timeout");
  ASSERT_EQ(run("sweep run " + kSweep + " --out " + dir + "/out --points 1 --timeout 0.05 --no-db --no-shrink", dir + "/log"), 1)
      << readText(dir + "/log");
  const json r = json::parse(readText(dir + "/out/results.jsonl"));
  EXPECT_EQ(r["runs"]["wls"]["status"], "timeout");
  EXPECT_EQ(r["runs"]["bfgs"]["status"], "timeout");
  const json s = json::parse(readText(dir + "/out/summary.json"));
  EXPECT_EQ(s["failed_points"], 1);
  EXPECT_EQ(s["checks"][0]["check"], "run_completed");
  EXPECT_EQ(s["checks"][0]["passed"], 0);
  // A stored point record holding a number beyond the double range is damaged: removed with a
  // warning and made again, the sweep goes on.
  std::string point = readText(dir + "/out/points/000000.json");
  const size_t wall = point.find("\"wall_s\":");
  ASSERT_NE(wall, std::string::npos);
  point.replace(wall, point.find(',', wall) - wall, "\"wall_s\":1e999");
  std::ofstream(dir + "/out/points/000000.json") << point;
  ASSERT_EQ(run("sweep run " + kSweep + " --out " + dir + "/out --points 1 --timeout 0.05 --no-db --no-shrink", dir + "/log3"), 1)
      << readText(dir + "/log3");
  EXPECT_NE(readText(dir + "/log3").find("000000.json: damaged: "), std::string::npos) << readText(dir + "/log3");
  // Another sweep in the same folder is refused (its results would mix).
  std::string other = readText(kSweep);
  other.replace(other.find("base: ../pointmass-damping.yaml"), 31,
                "base: " + std::string(LEXDYN_SOURCE_DIR) + "/cases/pointmass-damping.yaml");
  std::ofstream(dir + "/other.yaml") << other << "# changed\n";
  EXPECT_EQ(run("sweep run " + dir + "/other.yaml --out " + dir + "/out --no-db", dir + "/log2"), 2);
  EXPECT_NE(readText(dir + "/log2").find("holds the results of another version"), std::string::npos) << readText(dir + "/log2");
}

}  // namespace
