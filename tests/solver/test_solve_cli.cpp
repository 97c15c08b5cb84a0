// lexdyn-solve: output format, exit codes and bad-input messages.
#include "../common/cli_test_utils.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "lexdyn/solver/problem_io.hpp"
#include "lexdyn/solver/solver.hpp"
#include "reference.hpp"

namespace {

using CliRun = lexdyn::testing::CliResult;

const std::string kBin = std::string(LEXDYN_BINARY_DIR) + "/bin/lexdyn-solve";

std::string tempDir() {
  static std::string dir;
  if (dir.empty()) {
    char tmpl[] = "/tmp/lexdyn-solve-cli-XXXXXX";
    dir = mkdtemp(tmpl);
  }
  return dir;
}

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = tempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

using lexdyn::testing::slurp;

CliRun run(const std::string& args) { return lexdyn::testing::runCli(kBin + " " + args, tempDir()); }

const char* kValid = R"({"variables": 2, "levels": [
  {"name": "box", "A": [[1, 0], [0, 1]], "lower": [-1, -1], "upper": [1, 1]},
  {"name": "task", "A": [[1, 1]], "lower": [5], "upper": [5]}]})";

TEST(SolveCli, PrintsTheResultAsJson) {
  const CliRun r = run(writeFile("valid.json", kValid));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "solved");
  ASSERT_EQ(j["x"].size(), 2u);
  EXPECT_NEAR(j["x"][0].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(j["x"][1].get<double>(), 1.0, 1e-12);
  ASSERT_EQ(j["level_violation"].size(), 2u);
  EXPECT_NEAR(j["level_violation"][1].get<double>(), 3.0, 1e-12);  // relaxed, still exit 0
  EXPECT_GE(j["iterations"].get<int>(), 1);
  // Split coordinates (docs/solver.md) give the same answer; a negative index is bad input.
  const CliRun split = run("--split-from 1 " + writeFile("valid_split.json", kValid));
  ASSERT_EQ(split.code, 0) << split.err;
  const auto js = nlohmann::json::parse(split.out);
  EXPECT_NEAR(js["x"][0].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(js["x"][1].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(run("--split-from -3 " + writeFile("valid_split2.json", kValid)).code, 2);
}

TEST(SolveCli, MalformedJson) {
  const std::string f = writeFile("malformed.json", "{\"variables\": 2, \"levels\": [");
  const CliRun r = run(f);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(f), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("malformed JSON"), std::string::npos) << r.err;
}

TEST(SolveCli, WrongRowSizeNamesLevelAndRow) {
  const CliRun r = run(writeFile("size.json", R"({"variables": 2, "levels": [
    {"A": [[1, 0]], "lower": [0], "upper": [0]},
    {"A": [[1, 0], [1, 2, 3]], "lower": [0, 0], "upper": [1, 1]}]})"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("levels[1].A[1]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("expected 2 numbers"), std::string::npos) << r.err;
}

TEST(SolveCli, BoundsCountMismatch) {
  const CliRun r = run(writeFile("count.json", R"({"variables": 1, "levels": [
    {"A": [[1]], "lower": [0, 1], "upper": [0]}]})"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("levels[0].lower"), std::string::npos) << r.err;
}

TEST(SolveCli, LowerAboveUpperNamesTheRow) {
  const CliRun r = run(writeFile("order.json", R"({"variables": 1, "levels": [
    {"A": [[1], [2]], "lower": [0, 3], "upper": [1, 2]}]})"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("levels[0].row[1]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("greater than upper"), std::string::npos) << r.err;
}

TEST(SolveCli, NonFiniteEntriesOfA) {
  const CliRun inf = run(writeFile("inf.json", R"({"variables": 2, "levels": [
    {"A": [[1, 1e999]], "lower": [0], "upper": [1]}]})"));
  EXPECT_EQ(inf.code, 2);
  EXPECT_NE(inf.err.find("levels[0].A[0][1]"), std::string::npos) << inf.err;
  const CliRun nan = run(writeFile("nan.json", R"({"variables": 2, "levels": [
    {"A": [[1, "NaN"]], "lower": [0], "upper": [1]}]})"));
  EXPECT_EQ(nan.code, 2);
  EXPECT_NE(nan.err.find("levels[0].A[0][1]"), std::string::npos) << nan.err;
  const CliRun lit = run(writeFile("nanlit.json", R"({"variables": 2, "levels": [
    {"A": [[1, NaN]], "lower": [0], "upper": [1]}]})"));
  EXPECT_EQ(lit.code, 2);
}

TEST(SolveCli, UnknownKeys) {
  const CliRun top = run(writeFile("key1.json", R"({"variables": 1, "levels": [], "solver": 3})"));
  EXPECT_EQ(top.code, 2);
  EXPECT_NE(top.err.find("solver"), std::string::npos) << top.err;
  const CliRun lvl = run(writeFile("key2.json", R"({"variables": 1, "levels": [
    {"A": [[1]], "lower": [0], "upper": [0], "weight": 2}]})"));
  EXPECT_EQ(lvl.code, 2);
  EXPECT_NE(lvl.err.find("levels[0].weight"), std::string::npos) << lvl.err;
}

// A level's optional `columns` (its nonzero entries lie in its first columns): read and solved
// as declared, written back by problemToJson; a bad value and an entry past the declared columns
// are bad input naming the place.
TEST(SolveCli, LevelColumnsAreReadCheckedAndWritten) {
  const std::string declared = R"({"variables": 3, "levels": [
    {"name": "eq", "A": [[1, 1, 1]], "lower": [1], "upper": [1]},
    {"name": "first two", "A": [[1, -1, 0], [0, 1, 0]], "lower": [0, 0.25], "upper": [0, 0.25], "columns": 2}]})";
  const CliRun r = run(writeFile("columns.json", declared));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["x"][0].get<double>(), 0.25, 1e-14);
  EXPECT_NEAR(j["x"][2].get<double>(), 0.5, 1e-14);
  const lexdyn::solver::Problem p = lexdyn::solver::parseProblemFile(declared, "columns.json").problem;
  EXPECT_EQ(p.level(0).columns, -1);
  EXPECT_EQ(p.level(1).columns, 2);
  const lexdyn::solver::Problem back = lexdyn::solver::parseProblemFile(lexdyn::solver::problemToJson(p, nullptr), "back.json").problem;
  EXPECT_EQ(back.level(0).columns, -1);
  EXPECT_EQ(back.level(1).columns, 2);
  for (const auto& [columns, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"("two")", "levels[1].columns: expected an integer in 0 .. 3 (the number of variables), found \"two\""},
           {"4", "levels[1].columns: expected an integer in 0 .. 3 (the number of variables), found 4"},
           {"1", "levels[1] (\"first two\").A[0]: A[0][1] is -1, but the level declares its nonzero entries in its first 1 columns"}}) {
    std::string bad = declared;
    bad.replace(bad.find("\"columns\": 2"), 12, "\"columns\": " + columns);
    const CliRun b = run(writeFile("bad_columns.json", bad));
    EXPECT_EQ(b.code, 2) << columns;
    EXPECT_NE(b.err.find(expected), std::string::npos) << b.err;
  }
}

// A problem file's solver_options (a controller's dump carries them) are what lexdyn-solve runs
// by default, and the output says so; --default-options and single flags change them; a bad key
// or value is bad input naming it.
TEST(SolveCli, RunsTheSolverOptionsTheFileCarries) {
  const std::string with = std::string(kValid).substr(0, std::string(kValid).size() - 1) +
                           R"(, "solver_options": {"max_iterations": 1, "split_from_variable": 1}})";
  const std::string f = writeFile("with_options.json", with);
  CliRun r = run(f);
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["solver_options_from"], "the problem file");
  EXPECT_EQ(j["solver_options"]["max_iterations"], 1);
  EXPECT_EQ(j["solver_options"]["split_from_variable"], 1);
  EXPECT_EQ(j["solver_options"]["rank_tolerance"], 1e-9);  // not in the file: the default
  EXPECT_EQ(r.code, 3) << r.out;                           // one iteration is not enough here
  EXPECT_EQ(j["status"], "iteration_limit");
  r = run("--default-options " + f);
  EXPECT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["solver_options_from"], "the solver's defaults");
  EXPECT_EQ(j["solver_options"]["split_from_variable"], -1);
  r = run("--max-iterations 50 " + f);
  EXPECT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["solver_options"]["max_iterations"], 50);
  EXPECT_EQ(j["solver_options"]["split_from_variable"], 1);
  EXPECT_EQ(j["solver_options"]["spanning_any_rows"], false);
  EXPECT_EQ(j["solver_options"]["spanning_structured"], false);
  // Without spanning stages the two flags would do nothing: refused, naming the flag.
  r = run("--spanning-any-rows " + f);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--spanning-any-rows: needs spanning stages"), std::string::npos) << r.err;
  r = run("--bench --spanning-structured " + f + " " + f);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--spanning-structured: needs spanning stages"), std::string::npos) << r.err;
  r = run("--max-iterations 50 --spanning-stages --spanning-any-rows --spanning-structured " + f);
  EXPECT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["solver_options"]["spanning_stages"], true);
  EXPECT_EQ(j["solver_options"]["spanning_any_rows"], true);
  EXPECT_EQ(j["solver_options"]["spanning_structured"], true);
  j = nlohmann::json::parse(run(writeFile("without_options.json", kValid)).out);
  EXPECT_EQ(j["solver_options_from"], "the solver's defaults");
  r = run("--bench " + f + " " + f);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["solver_options_from"], "the first problem file");
  EXPECT_EQ(r.err.find("differ from the first file's"), std::string::npos) << r.err;
  // A file whose options differ from the first's: --bench says it runs the first's.
  const std::string without = writeFile("bench_without_options.json", kValid);
  r = run("--bench " + f + " " + without);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("bench_without_options.json: its solver options differ from the first file's; --bench runs the first's"),
            std::string::npos)
      << r.err;
  for (const auto& [options, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"({"rank_tol": 1})", "solver_options.rank_tol: unknown key (expected bland_after_degenerate_steps"},
           {R"({"rank_tolerance": "small"})", "solver_options.rank_tolerance: expected a number"},
           {R"({"rank_tolerance": 1})", "bad_options.json: solver_options.rank_tolerance: expected a number in (0, 0.01], found 1\n"},
           {R"({"spanning_stages": 1})", "solver_options.spanning_stages: expected true or false"},
           {R"({"spanning_any_rows": "yes"})", "solver_options.spanning_any_rows: expected true or false"},
           {R"({"spanning_structured": 0})", "solver_options.spanning_structured: expected true or false"},
           {R"({"last_level_projection": "sometimes"})", "expected \"auto\", \"never\" or \"always\""}}) {
    const std::string bad = std::string(kValid).substr(0, std::string(kValid).size() - 1) + R"(, "solver_options": )" + options + "}";
    const CliRun b = run(writeFile("bad_options.json", bad));
    EXPECT_EQ(b.code, 2) << options;
    EXPECT_NE(b.err.find(expected), std::string::npos) << b.err;
  }
}

TEST(SolveCli, MissingFileAndUsage) {
  EXPECT_EQ(run(tempDir() + "/does-not-exist.json").code, 2);
  EXPECT_EQ(run("").code, 2);
}

// `lexdyn-solve OPTIONS --bench` on `count` copies of the valid problem; exits 0, its JSON.
nlohmann::json benchOnCopies(const std::string& options, int count, CliRun* out = nullptr) {
  std::string files;
  for (int i = 0; i < count; ++i) files += " " + writeFile("copy" + std::to_string(i) + ".json", kValid);
  const CliRun r = run("--bench " + options + files);
  EXPECT_EQ(r.code, 0) << r.err;
  if (out) *out = r;
  return r.code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
}

// --repeats: each tick's best time over the repeats (tick_best_*) next to the pooled figures; the
// best of a tick is never above its pooled max, and its median never above the pooled max.
TEST(SolveCli, BenchReportsEachTicksBestOverTheRepeats) {
  const nlohmann::json j = benchOnCopies("--repeats 5", 4);
  for (const char* k : {"cold", "warm"}) {
    const nlohmann::json& s = j[k];
    for (const char* f :
         {"tick_best_median_us", "tick_best_p99_us", "tick_best_max_us", "tick_best_p99_qr_units", "tick_best_max_qr_units"}) {
      ASSERT_TRUE(s.contains(f) && s[f].is_number()) << k << "." << f << ": " << s.dump();
    }
    EXPECT_EQ(s["count"].get<int>(), std::string(k) == "cold" ? 20 : 15) << k;
    EXPECT_LE(s["tick_best_max_us"].get<double>(), s["max_us"].get<double>()) << k;
    EXPECT_LE(s["tick_best_median_us"].get<double>(), s["tick_best_max_us"].get<double>()) << k;
    EXPECT_GT(s["tick_best_median_us"].get<double>(), 0.0) << k;
  }
  // One file: no warm tick, the figures null.
  const nlohmann::json one = benchOnCopies("--repeats 2", 1);
  EXPECT_TRUE(one["warm"]["tick_best_max_us"].is_null()) << one.dump();
}

TEST(SolveCli, BenchReportsColdAndWarmStatistics) {
  const std::string a = writeFile("t0.json", kValid);
  const std::string b = writeFile("t1.json", kValid);
  const CliRun r = run("--bench " + a + " " + b);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["qr_unit_us"].get<double>(), 0.0);
  for (const char* k : {"cold", "warm"}) {
    for (const char* f : {"median_us", "p99_us", "max_us", "mean_iterations", "max_iterations", "iteration_limit_hits", "median_qr_units",
                          "p99_qr_units", "max_qr_units"}) {
      EXPECT_TRUE(j[k].contains(f)) << k << "." << f;
    }
  }
  EXPECT_EQ(j["cold"]["count"], 2);
  EXPECT_EQ(j["warm"]["count"], 1);
  EXPECT_EQ(j["warm"]["max_iterations"], 1);  // same problem: the previous active set is optimal
  EXPECT_EQ(j["repeats"], 1);
  EXPECT_EQ(j["warm"]["min_repeat_median_us"], j["warm"]["median_us"]);
}

TEST(SolveCli, BenchRepeatsReportTheMinimumOfTheMedians) {
  CliRun r;
  const auto j = benchOnCopies("--repeats 3", 3, &r);
  ASSERT_FALSE(j.empty());
  EXPECT_EQ(j["repeats"], 3);
  for (const char* k : {"cold", "warm"}) {
    // The smallest of the repeats' medians is positive and at most the pooled median (if every
    // repeat's median exceeded it, more than half of all the times would).
    const double minMedian = j[k]["min_repeat_median_us"].get<double>();
    EXPECT_GT(minMedian, 0.0) << k;
    EXPECT_LE(minMedian, j[k]["median_us"].get<double>() * (1.0 + 1e-12)) << k;
    EXPECT_DOUBLE_EQ(j[k]["min_repeat_median_qr_units"].get<double>(), minMedian / j["qr_unit_us"].get<double>()) << k;
  }
  EXPECT_EQ(j["cold"]["count"], 9);
  EXPECT_EQ(j["warm"]["count"], 6);  // each repeat starts cold: two warm ticks per repeat
  EXPECT_NE(r.err.find("repeat 3/3"), std::string::npos) << r.err;
}

TEST(SolveCli, BenchWarmOnlySkipsTheColdSolves) {
  const auto j = benchOnCopies("--warm-only", 2);
  ASSERT_FALSE(j.empty());
  EXPECT_FALSE(j.contains("cold"));
  EXPECT_EQ(j["warm"]["count"], 1);
  // A single file has no warm tick: no median to take the minimum of.
  const auto j1 = benchOnCopies("", 1);
  ASSERT_FALSE(j1.empty());
  EXPECT_EQ(j1["warm"]["count"], 0);
  for (const char* f : {"median_us", "p99_us", "max_us", "min_repeat_median_us", "mean_iterations"})
    EXPECT_TRUE(j1["warm"][f].is_null()) << f;  // no figure rather than zeros
  EXPECT_FALSE(j1["cold"]["min_repeat_median_us"].is_null());
}

// The rows of a --per-tick CSV, split on commas; a quoted field (RFC 4180) stays one field.
std::vector<std::vector<std::string>> csvRows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string cell;
  bool quoted = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    if (quoted) {
      if (ch == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (ch == '"') {
        quoted = false;
      } else {
        cell += ch;
      }
    } else if (ch == '"') {
      quoted = true;
    } else if (ch == ',') {
      row.push_back(cell);
      cell.clear();
    } else if (ch == '\n') {
      row.push_back(cell);
      rows.push_back(row);
      row.clear();
      cell.clear();
    } else {
      cell += ch;
    }
  }
  return rows;
}

// `lexdyn-solve --bench --repeats 3 --per-tick` on `files`: the CSV's rows against the library's
// Solver solving the same files the same way (cold, and warm along the chain, with the first
// file's options or the solver's defaults), field by field; the JSON's slowest tick and largest
// factorisation count against the rows. Returns the rows (header first).
std::vector<std::vector<std::string>> checkPerTick(const std::vector<std::string>& files) {
  const std::string csv = tempDir() + "/per_tick.csv";
  std::string args = "--bench --repeats 3 --per-tick " + csv;
  for (const std::string& f : files) args += " '" + f + "'";
  const CliRun r = run(args);
  EXPECT_EQ(r.code, 0) << r.err;
  if (r.code != 0) return {};
  const auto j = nlohmann::json::parse(r.out);
  const auto rows = csvRows(slurp(csv));
  EXPECT_EQ(rows.size(), files.size() + 1) << slurp(csv);
  if (rows.size() != files.size() + 1) return {};
  const std::vector<std::string>& head = rows[0];
  EXPECT_EQ(head.size(), 16u);
  auto col = [&](const std::string& name) {
    for (size_t c = 0; c < head.size(); ++c)
      if (head[c] == name) return c;
    ADD_FAILURE() << "no column " << name;
    return size_t{0};
  };
  std::vector<lexdyn::solver::Problem> problems;
  lexdyn::solver::Options options;
  for (const std::string& f : files) {
    lexdyn::solver::ProblemFile pf = lexdyn::solver::readProblemFile(f);
    if (problems.empty() && pf.options) options = *pf.options;
    problems.push_back(std::move(pf.problem));
    problems.back().detectBoundsLevel();
  }
  lexdyn::solver::Solver cold, warm;
  cold.setup(problems[0], options);
  warm.setup(problems[0], options);
  for (size_t t = 0; t < files.size(); ++t) {
    const std::vector<std::string>& row = rows[t + 1];
    EXPECT_EQ(row.size(), head.size()) << t;
    if (row.size() != head.size()) continue;
    EXPECT_EQ(row[col("tick")], std::to_string(t));
    EXPECT_EQ(row[col("file")], files[t]);
    const lexdyn::solver::Result rc = cold.solve(problems[t]);
    const lexdyn::solver::Result rw = t == 0 ? warm.solve(problems[0]) : warm.solve(problems[t], warm.result().active, warm.result().x);
    for (const auto& [kind, res] : {std::pair<std::string, const lexdyn::solver::Result*>{"cold", &rc}, {"warm", &rw}}) {
      const std::string k = kind + "_";
      if (kind == "warm" && t == 0) {
        // Tick 0 seeds the warm chain: no warm figures.
        for (const char* f : {"best_us", "iterations", "factorizations", "activations", "deactivations", "bound_change_restarts", "status"})
          EXPECT_TRUE(row[col(k + f)].empty()) << f;
        continue;
      }
      EXPECT_GT(std::stod(row[col(k + "best_us")]), 0.0) << kind << t;
      EXPECT_EQ(std::stoi(row[col(k + "iterations")]), res->iterations) << kind << t;
      EXPECT_EQ(std::stoi(row[col(k + "factorizations")]), res->factorizations) << kind << t;
      EXPECT_EQ(std::stoi(row[col(k + "activations")]), res->activations) << kind << t;
      EXPECT_EQ(std::stoi(row[col(k + "deactivations")]), res->deactivations) << kind << t;
      EXPECT_EQ(std::stoi(row[col(k + "bound_change_restarts")]), res->bound_change_restarts) << kind << t;
      EXPECT_EQ(row[col(k + "status")], lexdyn::solver::toString(res->status)) << kind << t;
    }
  }
  for (const char* k : {"cold", "warm"}) {
    int maxFact = 0;
    size_t slowest = 0;
    double slowestUs = -1.0;
    for (size_t t = 0; t < files.size(); ++t) {
      const std::string& us = rows[t + 1][col(std::string(k) + "_best_us")];
      if (us.empty()) continue;
      maxFact = std::max(maxFact, std::stoi(rows[t + 1][col(std::string(k) + "_factorizations")]));
      if (std::stod(us) > slowestUs) {
        slowestUs = std::stod(us);
        slowest = t;
      }
    }
    const nlohmann::json& s = j[k]["slowest_tick"];
    EXPECT_EQ(j[k]["max_factorizations"].get<int>(), maxFact) << k;
    EXPECT_EQ(s["tick"].get<size_t>(), slowest) << k;
    EXPECT_EQ(s["file"].get<std::string>(), files[slowest]) << k;
    EXPECT_EQ(s["iterations"].get<int>(), std::stoi(rows[slowest + 1][col(std::string(k) + "_iterations")])) << k;
    EXPECT_EQ(s["factorizations"].get<int>(), std::stoi(rows[slowest + 1][col(std::string(k) + "_factorizations")])) << k;
    EXPECT_NEAR(s["best_us"].get<double>(), slowestUs, 1e-3) << k;
    EXPECT_NEAR(j[k]["tick_best_max_us"].get<double>(), slowestUs, 1e-3) << k;
  }
  // With three ticks, the median of the cold solves' best times is the middle one.
  if (files.size() == 3) {
    std::vector<double> coldBest;
    for (size_t t = 0; t < 3; ++t) coldBest.push_back(std::stod(rows[t + 1][col("cold_best_us")]));
    std::sort(coldBest.begin(), coldBest.end());
    EXPECT_NEAR(j["cold"]["tick_best_median_us"].get<double>(), coldBest[1], 1e-3);
  }
  return rows;
}

// --per-tick: one row per tick, each solve's best time and its work, which is the solver's own
// (checkPerTick). Once on small problems whose warm starts change the active set, one file name
// holding a comma (quoted in the CSV); once on a controller-shaped problem with its split
// coordinates, whose cold solves restart after bound changes and release rows, so that every
// column of the work is nonzero somewhere.
TEST(SolveCli, BenchPerTickWritesEachTicksWorkNextToItsBestTime) {
  const std::string a = writeFile("pt0.json", kValid);
  const std::string b = writeFile("pt,1.json", R"({"variables": 2, "levels": [
    {"name": "box", "A": [[1, 0], [0, 1]], "lower": [-1, -1], "upper": [1, 1]},
    {"name": "task", "A": [[1, -1]], "lower": [0.5], "upper": [0.5]}]})");
  // Three names (the third the first's problem again): a slowest tick's file is its own.
  const auto small = checkPerTick({a, b, writeFile("pt2.json", kValid)});
  ASSERT_EQ(small.size(), 4u);
  for (size_t t = 2; t < 4; ++t) EXPECT_GT(std::stoi(small[t][10]), 1) << "warm iterations, tick " << t - 1;

  // The first controller-shaped seed whose cold solve restarts after a bound change and releases a
  // row; its second tick has the general levels' targets halved.
  lexdyn::solver::Options o;
  lexdyn::solver::Problem p;
  bool found = false;
  for (std::uint64_t seed = 1; seed < 400 && !found; ++seed) {
    o = lexdyn::solver::Options{};
    p = lexdyn::solver::test::controllerShapedProblem(seed, 12, 7, 8, o);
    lexdyn::solver::Solver s;
    s.setup(p, o);
    const lexdyn::solver::Result& r = s.solve(p);
    found = r.status == lexdyn::solver::Status::Solved && r.bound_change_restarts > 0 && r.deactivations > 0 &&
            r.activations != r.deactivations;
  }
  ASSERT_TRUE(found);
  lexdyn::solver::Problem q = p;
  for (int l = 0; l < q.levelCount(); ++l) {
    if (q.level(l).kind != lexdyn::solver::LevelKind::General) continue;
    q.level(l).lower *= 0.5;
    q.level(l).upper *= 0.5;
  }
  const std::string c0 = tempDir() + "/shaped0.json", c1 = tempDir() + "/shaped1.json", c2 = tempDir() + "/shaped2.json";
  lexdyn::solver::writeProblemJson(p, c0, &o);
  lexdyn::solver::writeProblemJson(q, c1, &o);
  lexdyn::solver::writeProblemJson(p, c2, &o);
  const auto shaped = checkPerTick({c0, c1, c2});
  ASSERT_EQ(shaped.size(), 4u);
  EXPECT_GT(std::stoi(shaped[1][7]), 0) << "cold restarts after a bound change";
  EXPECT_NE(shaped[1][5], shaped[1][6]) << "cold activations and deactivations";

  // --warm-only: every cold field empty. One file: no warm tick, so no slowest tick.
  const std::string csv = tempDir() + "/per_tick_warm.csv";
  const CliRun w = run("--bench --warm-only --per-tick " + csv + " " + a + " " + a);
  ASSERT_EQ(w.code, 0) << w.err;
  const auto wrows = csvRows(slurp(csv));
  ASSERT_EQ(wrows.size(), 3u);
  for (size_t t = 1; t < 3; ++t) {
    for (size_t c = 2; c < 9; ++c) EXPECT_TRUE(wrows[t][c].empty()) << t << " " << wrows[0][c];
    EXPECT_EQ(wrows[t][10].empty(), t == 1) << t;
  }
  const CliRun one = run("--bench --per-tick " + csv + " " + a);
  ASSERT_EQ(one.code, 0) << one.err;
  const auto jo = nlohmann::json::parse(one.out);
  EXPECT_TRUE(jo["warm"]["slowest_tick"].is_null() && jo["warm"]["max_factorizations"].is_null()) << jo.dump();
  EXPECT_EQ(jo["cold"]["slowest_tick"]["tick"], 0);

  // A path that cannot be written: bad input, found before anything is solved or printed.
  const CliRun bad = run("--bench --per-tick " + tempDir() + "/no-such-dir/t.csv " + a + " " + a);
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--per-tick: cannot write: No such file or directory"), std::string::npos) << bad.err;
  EXPECT_TRUE(bad.out.empty()) << bad.out;
  EXPECT_EQ(run("--bench --per-tick '' " + a).code, 2);
}

// --stage-times: the timed solves' factorisation time, level by level (the bounds level has no
// stage), counted over the same solves as the other figures; the figures themselves unchanged in
// kind (the solves are the same with the diagnostic).
TEST(SolveCli, BenchStageTimesSplitTheFactorisationByLevel) {
  // A bounds level, an equality level that the elimination takes (no stage of its own) and a
  // level of two rows.
  const char* three = R"({"variables": 3, "levels": [
    {"name": "box", "A": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "lower": [-1, -1, -1], "upper": [1, 1, 1]},
    {"name": "sum", "A": [[1, 1, 1]], "lower": [0.5], "upper": [0.5]},
    {"name": "task", "A": [[1, -1, 0], [0, 1, -1]], "lower": [2, -0.5], "upper": [2, 0.5]}]})";
  std::string files;
  for (int i = 0; i < 3; ++i) files += " " + writeFile("st" + std::to_string(i) + ".json", three);
  const CliRun r = run("--bench --repeats 2 --stage-times" + files);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("stage_times")) << j.dump();
  for (const char* k : {"cold", "warm"}) {
    const nlohmann::json& s = j["stage_times"][k];
    EXPECT_EQ(s["solves"], j[k]["count"]) << k;
    ASSERT_EQ(s["stages"].size(), 2u) << s.dump();
    EXPECT_EQ(s["stages"][0]["level"], "sum");
    EXPECT_EQ(s["stages"][0]["factorizations"], 0) << "eliminated, no stage";
    EXPECT_TRUE(s["stages"][0]["us_per_factorization"].is_null());
    const nlohmann::json& task = s["stages"][1];
    EXPECT_EQ(task["level"], "task");
    // One full factorisation per solve at least (each takes one active-set iteration or more).
    EXPECT_GE(task["factorizations"].get<long>(), j[k]["count"].get<long>()) << k;
    EXPECT_GE(s["passes"].get<long>(), task["factorizations"].get<long>()) << k;
    const double stage = task["us_per_solve"].get<double>();
    EXPECT_GT(stage, 0.0) << k;
    EXPECT_GE(s["factorization_us_per_solve"].get<double>(), stage) << k;
    EXPECT_GE(s["layout_us_per_solve"].get<double>(), 0.0) << k;
    EXPECT_GE(s["preparation_us_per_solve"].get<double>(), 0.0) << k;
    EXPECT_NEAR(task["us_per_factorization"].get<double>() * task["factorizations"].get<double>(), stage * s["solves"].get<double>(),
                1e-9 * stage * s["solves"].get<double>())
        << k;
  }
  const nlohmann::json w = benchOnCopies("--warm-only --stage-times", 2);
  ASSERT_TRUE(w.contains("stage_times"));
  EXPECT_FALSE(w["stage_times"].contains("cold"));
  EXPECT_EQ(w["stage_times"]["warm"]["solves"], 1);
  EXPECT_FALSE(benchOnCopies("", 2).contains("stage_times"));
}

TEST(SolveCli, RepeatsAndWarmOnlyNeedBench) {
  const std::string a = writeFile("n0.json", kValid);
  for (const std::string opt : {"--repeats 2", "--warm-only", "--per-tick x.csv", "--stage-times"}) {
    const CliRun r = run(opt + " " + a);
    EXPECT_EQ(r.code, 2) << opt;
    EXPECT_NE(r.err.find("need --bench"), std::string::npos) << r.err;
  }
  EXPECT_EQ(run("--bench --repeats 0 " + a).code, 2);
}

}  // namespace

// Exit codes (docs/architecture.md, "Errors and exit codes"): every code lexdyn-solve and
// lexdyn-solver-sweep give, from a real run of each.
namespace exit_codes {

// Runs `cmd` in the background and sends `sig` once `started` holds (a shell test), then waits.
int runAndSignal(const std::string& cmd, const std::string& started, const char* sig) {
  const std::string code = tempDir() + "/code";
  // `started` reads sig.err: the previous run's must not answer for this one (the signal would
  // then reach the shell before it starts the command).
  std::remove((tempDir() + "/sig.err").c_str());
  std::remove((tempDir() + "/sig.out").c_str());
  return lexdyn::testing::runAndSignal(cmd + " > " + tempDir() + "/sig.out 2> " + tempDir() + "/sig.err", started, sig, code);
}

const std::string kSweep = std::string(LEXDYN_BINARY_DIR) + "/bin/lexdyn-solver-sweep";

TEST(SolveCliExitCodes, SolverFailuresAreThree) {
  // The hard iteration cap leaves an iterate, not a solution.
  CliRun r = run("--max-iterations 1 " + std::string(LEXDYN_SOURCE_DIR) + "/tests/data/solver/example.json");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("status iteration_limit"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("\"status\":\"iteration_limit\""), std::string::npos) << r.out;  // the result is still printed
  // A coefficient of 1e-300 asks for x = 1e300: the violations overflow. Not optimal.
  r = run(writeFile("overflow.json", R"({"variables": 2, "levels": [{"A": [[1e-300, 0]], "lower": [1], "upper": [1]},
    {"A": [[1, 0], [0, 1]], "lower": [0, 0], "upper": [0, 0]}]})"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.out.find("\"status\":\"non_finite_result\""), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("\"reason\":\"optimal\""), std::string::npos) << r.out;
}

TEST(SolveCliExitCodes, InterruptedBenchIs130Or143) {
  // A thousand copies of a controller tick: loading them takes seconds, the signal comes first.
  const std::string link = tempDir() + "/t.json";
  std::remove(link.c_str());
  ASSERT_EQ(symlink((std::string(LEXDYN_SOURCE_DIR) + "/tests/data/solver/controller_tick_degenerate.json").c_str(), link.c_str()), 0);
  std::string files;
  for (int i = 0; i < 1000; ++i) files += " " + link;
  const std::string started = "grep -q loaded " + tempDir() + "/sig.err";
  EXPECT_EQ(runAndSignal(kBin + " --bench" + files, started, "INT"), 130);
  EXPECT_NE(slurp(tempDir() + "/sig.err").find("interrupted by SIGINT"), std::string::npos) << slurp(tempDir() + "/sig.err");
  EXPECT_EQ(runAndSignal(kBin + " --bench" + files, started, "TERM"), 143);
  EXPECT_NE(slurp(tempDir() + "/sig.err").find("interrupted by SIGTERM"), std::string::npos) << slurp(tempDir() + "/sig.err");
}

// The exact reference on a problem of 100 variables (a check ran past 15 minutes without a
// limit): the time limit and the work budget leave it undecided, not passed, and counted apart;
// without a limit,
// SIGINT stops it within the check and the sweep prints what it had (the unfinished problem not
// counted) and exits 130.
TEST(SolverSweepExitCodes, TheExactReferenceHasATimeLimitAndStopsOnASignal) {
  const std::string big = " --cases 1 --seed 5 --max-variables 100 --max-levels 50 --max-rows 100 --exact-every 1";
  const std::string out = tempDir() + "/sweep_big.out";
  EXPECT_EQ(lexdyn::testing::exitCode(std::system((kSweep + big + " --exact-time-limit 1 > " + out).c_str())), 0);
  EXPECT_TRUE(lexdyn::testing::containsAll(
      slurp(out), {"\"exact_checked\": 1", "\"exact_undecided\": 1", "\"exact_out_of_time\": 1", "\"failures\": 0"}))
      << slurp(out);
  // The work budget: the same verdict and figures on any machine (two runs: the same output but
  // for the seconds).
  std::string first;
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(lexdyn::testing::exitCode(std::system((kSweep + big + " --exact-work-limit 1000000 > " + out).c_str())), 0);
    std::string text = slurp(out);
    EXPECT_TRUE(lexdyn::testing::containsAll(text, {"\"exact_checked\": 1", "\"exact_undecided\": 1", "\"exact_out_of_work\": 1",
                                                    "\"exact_out_of_time\": 0", "\"failures\": 0"}))
        << text;
    text.erase(text.find("\"seconds\""), text.find(", \"interrupted\"") - text.find("\"seconds\""));
    if (k == 0) first = text;
    EXPECT_EQ(text, first);
  }
  EXPECT_EQ(runAndSignal(kSweep + big + " --exact-time-limit 0 --exact-work-limit 0", "sleep 1", "INT"), 130);
  EXPECT_TRUE(lexdyn::testing::containsAll(slurp(tempDir() + "/sig.out"), {"\"problems\": 0", "\"solved\": 0", "\"exact_checked\": 0",
                                                                           "\"certificate_failures\": 0", "\"interrupted\": true"}))
      << slurp(tempDir() + "/sig.out");
  EXPECT_EQ(lexdyn::testing::exitCode(std::system((kSweep + " --exact-time-limit -1 > " + out + " 2>&1").c_str())), 2);
}

// Controller-shaped problems (velocities, then forces with their bounds; split coordinates,
// declared velocity-only levels): each is solved cold and again warm with every second bound
// released, and both results are checked. The restarts after a bound change are taken (counted),
// split coordinates apply to some; a failure's rerun line and file carry the problem's own options.
TEST(SolverSweepExitCodes, ControllerShapedProblemsAreSolvedColdAndWarm) {
  const std::string out = tempDir() + "/sweep_cs.out", err = tempDir() + "/sweep_cs.err";
  auto sweep = [&](const std::string& args) {
    return lexdyn::testing::exitCode(std::system((kSweep + " " + args + " > " + out + " 2> " + err).c_str()));
  };
  ASSERT_EQ(sweep("--controller-shaped --cases 2000 --seed 1 --exact-every 50"), 0) << slurp(out) << slurp(err);
  const auto j = nlohmann::json::parse(slurp(out));
  EXPECT_EQ(j["failures"], 0);
  EXPECT_EQ(j["warm_checked"], 2000);
  EXPECT_EQ(j["exact_checked"], 80);  // every 50th problem, cold and warm
  EXPECT_GT(j["bound_change_restarts"].get<long>(), 1000);
  EXPECT_GT(j["split_applied"].get<long>(), 200);
  // The same problems with the restarts off: the same verdicts, no restart counted.
  ASSERT_EQ(sweep("--controller-shaped --cases 2000 --seed 1 --no-restart-after-bound-change"), 0) << slurp(out);
  EXPECT_EQ(nlohmann::json::parse(slurp(out))["bound_change_restarts"], 0);
  // A failure (a cap of one iteration) prints a rerun line with --controller-shaped and writes
  // the problem with its solver options.
  EXPECT_EQ(sweep("--controller-shaped --cases 20 --seed 1 --max-iterations 1 --write-failures " + tempDir() + "/cs_failures"), 1);
  const std::string o = slurp(out);
  const size_t at = o.find("rerun: lexdyn-solver-sweep --seed ");
  ASSERT_NE(at, std::string::npos) << o;
  const std::string rerun = o.substr(at + 7, o.find('\n', at) - at - 7);
  EXPECT_NE(rerun.find(" --controller-shaped"), std::string::npos) << rerun;
  const std::string seed = rerun.substr(std::string("lexdyn-solver-sweep --seed ").size(), rerun.find(" --cases") - 27);
  const lexdyn::solver::ProblemFile f = lexdyn::solver::readProblemFile(tempDir() + "/cs_failures/problem-" + seed + ".json");
  ASSERT_TRUE(f.options.has_value());
  EXPECT_GT(f.options->split_from_variable, 0);
  // --warm solves the default generator's problems warm as well.
  ASSERT_EQ(sweep("--warm --cases 500 --seed 3"), 0) << slurp(out);
  EXPECT_EQ(nlohmann::json::parse(slurp(out))["warm_checked"], 500);
  // It draws each problem's options itself: the option flags are refused, as is a single variable.
  EXPECT_EQ(sweep("--controller-shaped --spanning-stages --cases 1"), 2);
  EXPECT_NE(slurp(err).find("--controller-shaped"), std::string::npos) << slurp(err);
  EXPECT_EQ(sweep("--controller-shaped --spanning-any-rows --cases 1"), 2);
  EXPECT_EQ(sweep("--spanning-any-rows --cases 1"), 2);  // without --spanning-stages
  EXPECT_NE(slurp(err).find("need --spanning-stages"), std::string::npos) << slurp(err);
  EXPECT_EQ(sweep("--controller-shaped --spanning-structured --cases 1"), 2);
  EXPECT_EQ(sweep("--controller-shaped --max-variables 1 --cases 1"), 2);
}

TEST(SolverSweepExitCodes, ZeroOneTwoAndInterruption) {
  const std::string out = tempDir() + "/sweep.out", err = tempDir() + "/sweep.err";
  auto sweep = [&](const std::string& args) {
    return lexdyn::testing::exitCode(std::system((kSweep + " " + args + " > " + out + " 2> " + err).c_str()));
  };
  EXPECT_EQ(sweep("--cases 200 --seed 3"), 0) << slurp(err);
  EXPECT_NE(slurp(out).find("\"failures\": 0"), std::string::npos) << slurp(out);
  // A cap of one iteration: results that are not optimal are failures, each with its rerun line.
  EXPECT_EQ(sweep("--cases 50 --seed 3 --max-iterations 1 --write-failures " + tempDir() + "/failures"), 1);
  const std::string o = slurp(out);
  EXPECT_NE(o.find("hard iteration cap hit"), std::string::npos) << o;
  const size_t at = o.find("rerun: lexdyn-solver-sweep --seed ");
  ASSERT_NE(at, std::string::npos) << o;
  // The printed command reruns that problem alone, with the same outcome.
  const std::string rerun = o.substr(at + 7, o.find('\n', at) - at - 7);
  EXPECT_EQ(sweep(rerun.substr(std::string("lexdyn-solver-sweep").size())), 1) << rerun;
  EXPECT_NE(slurp(out).find("\"problems\": 1, \"solved\": 1, \"failures\": 1"), std::string::npos) << slurp(out);
  EXPECT_NE(o.find("lexdyn-solve --details " + tempDir() + "/failures/problem-"), std::string::npos) << o;
  // Bad options: 2 (--max-variables 0 divided by zero: SIGFPE).
  EXPECT_EQ(sweep("--max-variables 0"), 2);
  EXPECT_NE(slurp(err).find("--max-variables"), std::string::npos) << slurp(err);
  EXPECT_EQ(sweep("--write-failures /proc/forbidden/dir --cases 1"), 2);
  // Interrupted: the summary of the problems done so far, 130 / 143.
  // (The handler's summary line tells its exit from a kill by the signal, which the shell also
  // reports as 128 + the signal.)
  EXPECT_EQ(runAndSignal(kSweep + " --cases 100000000", "sleep 0.3", "INT"), 130);
  EXPECT_NE(slurp(tempDir() + "/sig.out").find("\"interrupted\": true"), std::string::npos) << slurp(tempDir() + "/sig.out");
  EXPECT_EQ(runAndSignal(kSweep + " --cases 100000000", "sleep 0.3", "TERM"), 143);
  EXPECT_NE(slurp(tempDir() + "/sig.out").find("\"interrupted\": true"), std::string::npos) << slurp(tempDir() + "/sig.out");
}

}  // namespace exit_codes
