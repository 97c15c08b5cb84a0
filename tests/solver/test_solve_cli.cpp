// lexdyn-solve: output format, exit codes and bad-input messages.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace {

struct CliRun {
  int code = -1;
  std::string out, err;
};

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

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

CliRun run(const std::string& args) {
  const std::string o = tempDir() + "/stdout", e = tempDir() + "/stderr";
  const int st = std::system((kBin + " " + args + " >" + o + " 2>" + e).c_str());
  CliRun r;
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  r.out = slurp(o);
  r.err = slurp(e);
  return r;
}

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

TEST(SolveCli, MissingFileAndUsage) {
  EXPECT_EQ(run(tempDir() + "/does-not-exist.json").code, 2);
  EXPECT_EQ(run("").code, 2);
}

TEST(SolveCli, BenchReportsColdAndWarmStatistics) {
  const std::string a = writeFile("t0.json", kValid);
  const std::string b = writeFile("t1.json", kValid);
  const CliRun r = run("--bench " + a + " " + b);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["qr_unit_us"].get<double>(), 0.0);
  for (const char* k : {"cold", "warm"}) {
    for (const char* f : {"median_us", "p99_us", "max_us", "mean_iterations", "max_iterations", "iteration_limit_hits",
                          "median_qr_units", "p99_qr_units", "max_qr_units"}) {
      EXPECT_TRUE(j[k].contains(f)) << k << "." << f;
    }
  }
  EXPECT_EQ(j["cold"]["count"], 2);
  EXPECT_EQ(j["warm"]["count"], 1);
  EXPECT_EQ(j["warm"]["max_iterations"], 1);  // same problem: the previous active set is optimal
}

}  // namespace
