// lexdyn-harness exit codes (docs/architecture.md, "Errors and exit codes"): 0 all checks passed,
// 1 a check failed, 2 bad input (with a message naming the file and the key path), 3 a run
// failure, 130 / 143 interrupted; traces carry their end mark.
#include "case_test_utils.hpp"
#include "../common/cli_test_utils.hpp"
#include "harness/checks/trace.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <sys/wait.h>

namespace lexdyn::cases {
namespace {

using namespace testing;  // case_test_utils.hpp

using namespace lexdyn::testing;  // the command-line test helpers

// `run CASE --out DIR/OUT --quiet`.
CliResult runQuiet(const std::string& c, const std::string& dir, const std::string& out) {
  return harness("run " + c + " --out " + dir + "/" + out + " --quiet", dir);
}

// The minimal case (0.2 s) with the simulator's integrator settings `integrator`, written in `dir`.
std::string caseWithIntegrator(const std::string& dir, const std::string& integrator) {
  auto s = minimalCase(0.2);
  s["f_sim"] += "  integrator: " + integrator + "\n";
  return writeCase(dir, s);
}

// Runs the case `c` twice, in two processes: both complete and write the same trace, byte for
// byte, of more than `min_bytes`.
void expectIdenticalTracesOfTwoRuns(const std::string& c, const std::string& dir, size_t min_bytes, const std::string& what) {
  ASSERT_EQ(runQuiet(c, dir, "a").code, 0);
  ASSERT_EQ(runQuiet(c, dir, "b").code, 0);
  const std::string a = slurp(dir + "/a/trace.csv"), b = slurp(dir + "/b/trace.csv");
  EXPECT_GT(a.size(), min_bytes);
  EXPECT_TRUE(a == b) << what << " of two processes differ";
}

TEST(HarnessCli, ExitCodeZeroWhenEveryCheckPasses) {
  const std::string dir = outputDir("cli_ok");
  const std::string c = writeCase(dir, minimalCase(0.2));
  const CliResult r = runQuiet(c, dir, "out");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/trace.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/summary.json"));
  // The stored trace can be checked again.
  EXPECT_EQ(harness("check " + c + " " + dir + "/out/trace.csv", dir).code, 0);
}

TEST(HarnessCli, ExitCodeOneWhenACheckFails) {
  const std::string dir = outputDir("cli_fail");
  auto s = minimalCase(0.2);
  s["h_checks"] = "checks:\n  - {name: tall, type: frame_height, frame: WAIST, min_m: 2.0}\n";
  const CliResult r = runQuiet(writeCase(dir, s), dir, "out");
  expectExit(r, 1, {"FAIL"});
}

TEST(HarnessCli, ExitCodeTwoOnBadInputNamingFileAndKey) {
  const std::string dir = outputDir("cli_bad");
  const std::string c = caseWithIntegrator(dir, "{rtol: fast}");
  CliResult r = runQuiet(c, dir, "out");
  expectExit(r, 2, {c, "sim.integrator.rtol"});
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/trace.csv"));
  r = harness("run " + dir + "/missing.yaml --out " + dir + "/out", dir);
  expectExit(r, 2, {"missing.yaml"});
  r = harness("run", dir);  // missing arguments
  EXPECT_EQ(r.code, 2);
  // A posture without a static equilibrium on the feet: bad input, nothing simulated.
  auto s = minimalCase(0.2);
  const std::string models = std::string(LEXDYN_SOURCE_DIR) + "/models/hrp2kai_like/";
  s["b_robot"] = "robot:\n  urdf: " + models + "hrp2kai_like.urdf\n  data: " + testing::dataFileWithOneLegPosture(dir) + "\n";
  s["d_initial"] = "initial_state:\n  posture: one_leg\n  settle: static_equilibrium\n";
  const std::string c2 = writeCase(dir, s, "one_leg_case.yaml");
  r = runQuiet(c2, dir, "out2");
  expectExit(r, 2, {c2 + ":8: initial_state.settle"});
  EXPECT_FALSE(std::filesystem::exists(dir + "/out2/trace.csv"));
}

TEST(HarnessCli, SigintStopsTheRunAndKeepsTraceAndSummary) {
  // A 100 s run (several seconds of wall time), interrupted as soon as it has started writing.
  const std::string dir = outputDir("cli_sigint");
  const std::string c = writeCase(dir, minimalCase(100.0));
  const std::string out = dir + "/out";
  EXPECT_EQ(harnessRunSignalled(c, out, dir, "INT", "0.05"), 130);
  ASSERT_TRUE(std::filesystem::exists(out + "/summary.json"));
  ASSERT_TRUE(std::filesystem::exists(out + "/trace.csv"));
  EXPECT_FALSE(std::filesystem::exists(out + "/trace.csv.partial"));
  const std::string summary = slurp(out + "/summary.json");
  EXPECT_NE(summary.find("\"status\": \"interrupted\""), std::string::npos) << summary;
  // The trace is marked as interrupted by itself: separated from its summary it is not taken for
  // a complete run. Its checks can be run again (on the rows it holds) but do not pass.
  const checks::TraceTable t = checks::readTrace(out + "/trace.csv");
  EXPECT_EQ(t.end_status, lexdyn::records::RunStatus::Interrupted);
  EXPECT_NE(t.end_message.find("interrupted by SIGINT at t = "), std::string::npos) << t.end_message;
  const CliResult r = harness("check " + c + " " + out + "/trace.csv", dir);
  expectExit(r, 1, {" rows, t = 0 .. "});
  EXPECT_NE(r.err.find("is not the trace of a complete run (the run did not complete: interrupted"), std::string::npos) << r.err;
}

TEST(HarnessCli, AKilledRunLeavesItsPartialTraceAndNoOldOutputs) {
  // Outputs of an earlier run in the same directory, then a run killed with SIGKILL: only the
  // new run's partial trace is left, readable by `check`.
  const std::string dir = outputDir("cli_sigkill");
  const std::string c = writeCase(dir, minimalCase(100.0));
  const std::string out = dir + "/out";
  std::filesystem::create_directories(out);
  std::ofstream(out + "/summary.json") << "{\"status\": \"completed\"}\n";
  std::ofstream(out + "/trace.csv") << "# case: old\nt\n0\n";
  // Killed once the trace holds more than 600 kB: at least the first 200 rows (one flush, t >= 1 s).
  EXPECT_EQ(runAndSignal(binPath("lexdyn-harness") + " run " + c + " --out " + out + " --quiet 2> " + dir + "/stderr.txt",
                         "[ $(stat -c %s " + out + "/trace.csv.partial 2>/dev/null || echo 0) -ge 600000 ]", "KILL", dir + "/code"),
            128 + 9);
  EXPECT_FALSE(std::filesystem::exists(out + "/summary.json"));
  EXPECT_FALSE(std::filesystem::exists(out + "/trace.csv"));
  ASSERT_TRUE(std::filesystem::exists(out + "/trace.csv.partial"));
  const CliResult r = harness("check " + c + " " + out + "/trace.csv.partial", dir);
  EXPECT_EQ(r.code, 1) << r.err;  // the checks run on its rows, but a cut trace never passes
  EXPECT_NE(r.err.find("partial trace"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no end mark: the run was killed"), std::string::npos) << r.err;
}

TEST(HarnessCli, CheckWarnsWhenTheTraceIsOfAnotherCase) {
  const std::string dir = outputDir("cli_other_case");
  auto s = minimalCase(0.25);
  const std::string a = writeCase(dir, s, "a.yaml");
  s["a_name"] = "name: other\n";
  const std::string b = writeCase(dir, s, "b.yaml");
  ASSERT_EQ(runQuiet(a, dir, "out").code, 0);
  const CliResult r = harness("check " + b + " " + dir + "/out/trace.csv", dir);
  EXPECT_NE(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("'minimal', not of 'other'"), std::string::npos) << r.err;
  EXPECT_EQ(harness("check " + a + " " + dir + "/out/trace.csv", dir).err.find("warning"), std::string::npos);
}

TEST(HarnessCli, TwoProcessesWriteIdenticalTraces) {
  const std::string dir = outputDir("cli_determinism");
  auto s = minimalCase(0.5);
  s["e_controller"] =
      "controller:\n  type: posture_servo\n  posture: half_sitting\n  motions:\n"
      "    - {joints: [RLEG_JOINT3, LLEG_JOINT3], amplitude: 0.4, period_s: 1.0, waveform: raised_cosine}\n"
      "    - {joints: [RARM_JOINT0], amplitude: 0.5, period_s: 1.0}\n";
  s["h_checks"] = "checks:\n  - {name: upright, type: frame_height, frame: WAIST, min_m: 0.5}\n";
  const std::string c = writeCase(dir, s);
  expectIdenticalTracesOfTwoRuns(c, dir, 10000u, "traces");
}

TEST(HarnessCli, ControllerCaseMethodOverrideCheckAndCompare) {
  const std::string dir = outputDir("cli_controller");
  auto s = testing::minimalLexdynCase(0.2);
  s["i_comparisons"] =
      "comparisons:\n  - {name: bfgs_vs_wls, type: method_comparison, tasks: [right_hand],"
      " statistic: final, better: bfgs, worse: wls, margin: 10.0}\n";
  const std::string c = writeCase(dir, s);
  CliResult r = runQuiet(c, dir, "bfgs");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("[minimal bfgs] completed"), std::string::npos) << r.err;
  r = harness("run " + c + " --out " + dir + "/wls --method wls --duration 0.1 --quiet", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("[minimal wls] completed: 0.100 s simulated"), std::string::npos) << r.err;
  EXPECT_EQ(harness("run " + c + " --out " + dir + "/x --method newton --quiet", dir).code, 2);
  // check: TRACE --case CASE, the case from the trace's header, and the older order.
  EXPECT_EQ(harness("check " + dir + "/wls/trace.csv --case " + c, dir).code, 0);
  r = harness("check " + dir + "/wls/trace.csv", dir);
  expectExit(r, 0, {"[minimal wls]"});
  EXPECT_EQ(harness("check " + c + " " + dir + "/bfgs/trace.csv", dir).code, 0);
  // compare: one trace per method; a missing method is a failed comparison.
  r = harness("compare --case " + c + " " + dir + "/bfgs/trace.csv " + dir + "/wls/trace.csv", dir);
  expectExit(r, 0, {"ok   bfgs_vs_wls"});
  r = harness("compare --case " + c + " " + dir + "/bfgs/trace.csv", dir);
  expectExit(r, 1, {"needs traces of methods bfgs and wls"});
}

TEST(HarnessCli, TwoProcessesWriteIdenticalControllerTraces) {
  const std::string dir = outputDir("cli_controller_determinism");
  auto s = testing::minimalLexdynCase(0.3, "bfgs");
  s["g_trace"] = "trace:\n  frames: [WAIST]\n  timings: false\n";
  const std::string c = writeCase(dir, s);
  expectIdenticalTracesOfTwoRuns(c, dir, 50000u, "controller traces");
}

TEST(HarnessCli, GoldenUpdateThenCheckAndAMismatchNamesTimeAndChannel) {
  const std::string dir = outputDir("cli_golden");
  const std::string c = writeCase(dir, testing::minimalLexdynCase(0.3));
  std::filesystem::create_directories(dir + "/golden");
  const std::string manifest = dir + "/golden/manifest.yaml";
  std::ofstream(manifest) << "format: lexdyn-golden-manifest/1\n"
                             "tolerance: {abs: 1.0e-9, rel: 1.0e-9}\n"
                             "channels: [\"t\", \"q.*\", \"task.*\", \"solver.*\"]\n"
                             "entries:\n  - {case: ../case.yaml, methods: [bfgs, wls], duration_s: 0.2, every_n_ticks: 4}\n";
  const std::string g = " --manifest " + manifest + " --work " + dir + "/work";
  CliResult r = harness("golden check" + g, dir);
  EXPECT_EQ(r.code, 1) << r.err;  // nothing generated yet
  EXPECT_NE(r.err.find("MISSING minimal.bfgs"), std::string::npos) << r.err;
  r = harness("golden update" + g, dir);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(std::filesystem::exists(dir + "/golden/minimal.bfgs.csv"));
  ASSERT_TRUE(std::filesystem::exists(dir + "/golden/minimal.wls.csv"));
  r = harness("golden check" + g, dir);
  expectExit(r, 0, {"golden check: 2 of 2 match"});
  // Tamper with one value of the bfgs golden: q.RARM_JOINT0 at its row t = 0.1 s.
  const checks::TraceTable t = checks::readTrace(dir + "/golden/minimal.bfgs.csv");
  std::ifstream in(dir + "/golden/minimal.bfgs.csv");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const int col = t.column("q.RARM_JOINT0");
  ASSERT_GE(col, 0);
  size_t row = 0;
  while (row < t.rows.size() && std::abs(t.rows[row][0] - 0.1) > 1e-9) ++row;
  ASSERT_LT(row, t.rows.size());
  // Find that row's line (rows follow the header and the channel line, in order).
  size_t pos = text.find("\nt,");
  pos = text.find('\n', pos + 1);
  for (size_t k = 0; k < row; ++k) pos = text.find('\n', pos + 1);
  size_t start = pos + 1;
  for (int k = 0; k < col; ++k) start = text.find(',', start) + 1;
  const size_t end = text.find_first_of(",\n", start);
  text.replace(start, end - start, "0.5");
  std::ofstream(dir + "/golden/minimal.bfgs.csv") << text;
  r = harness("golden check" + g, dir);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("FAIL minimal.bfgs: MISMATCH: first divergence at t = 0.1 s in channel q.RARM_JOINT0 (golden 0.5"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("ok   minimal.wls"), std::string::npos) << r.err;
  EXPECT_EQ(harness("golden check --only minimal.wls" + g, dir).code, 0);
  // The wls golden cut at a line end (its end mark gone) is named as cut, not as a row count.
  {
    std::ifstream win(dir + "/golden/minimal.wls.csv");
    std::string w((std::istreambuf_iterator<char>(win)), std::istreambuf_iterator<char>());
    win.close();
    std::ofstream(dir + "/golden/minimal.wls.csv") << w.substr(0, w.rfind("# end:"));
    r = harness("golden check --only minimal.wls" + g, dir);
    expectExit(r, 1, {"FAIL minimal.wls", "no end mark", "cut"});
  }
  EXPECT_EQ(harness("golden check --only minimal.gn" + g, dir).code, 2);  // not in the manifest
  std::ofstream(dir + "/golden/bad.yaml") << "format: lexdyn-golden-manifest/1\nentries: [{case: ../case.yaml}]\n";
  r = harness("golden check --manifest " + dir + "/golden/bad.yaml", dir);
  expectExit(r, 2, {"bad.yaml:2: entries[0]: missing required key 'methods'"});
}

// A run failure (here the integrator's step limit) exits 3; its trace says so by itself, and
// `check` on it does not pass.
TEST(HarnessCliExitCodes, RunFailureIsThreeAndTheTraceSaysWhy) {
  const std::string dir = outputDir("cli_run_failure");
  const std::string c = caseWithIntegrator(dir, "{max_steps_per_tick: 2}");
  CliResult r = runQuiet(c, dir, "out");
  expectExit(r, 3, {"integrator_failure"});
  r = harness("check " + dir + "/out/trace.csv --case " + c, dir);
  expectExit(r, 1, {"(the run did not complete: integrator_failure"});
}

TEST(HarnessCliExitCodes, SigtermIs143) {
  const std::string dir = outputDir("cli_sigterm");
  const std::string c = writeCase(dir, minimalCase(100.0));
  const std::string out = dir + "/out";
  EXPECT_EQ(harnessRunSignalled(c, out, dir, "TERM", "0.05"), 143);
  const checks::TraceTable t = checks::readTrace(out + "/trace.csv");
  EXPECT_EQ(t.end_status, lexdyn::records::RunStatus::Interrupted);
  EXPECT_NE(t.end_message.find("interrupted by SIGTERM"), std::string::npos) << t.end_message;
}

// tick_time is a wall-clock measurement: reported and labelled, a verdict only when asked for.
TEST(HarnessCliExitCodes, WallClockChecksDecideOnlyWhenAskedFor) {
  const std::string dir = outputDir("cli_wall_clock");
  auto s = testing::minimalLexdynCase(0.05);
  s["h_checks"] += "  - {name: impossible_budget, type: tick_time, timer: tick, percentile: 50, limit_us: 0.001}\n";
  const std::string c = writeCase(dir, s);
  CliResult r = runQuiet(c, dir, "out");
  expectExit(r, 0, {"info impossible_budget", "machine-dependent, reported only"});
  const std::string summary = slurp(dir + "/out/summary.json");
  EXPECT_NE(summary.find("\"machine_dependent\": true"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"decides\": false"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"all_checks_passed\": true"), std::string::npos) << summary;
  r = harness("run " + c + " --out " + dir + "/out2 --quiet --wall-clock-checks", dir);
  expectExit(r, 1, {"FAIL impossible_budget"});
  // The same on the stored trace.
  EXPECT_EQ(harness("check " + dir + "/out/trace.csv --case " + c, dir).code, 0);
  EXPECT_EQ(harness("check " + dir + "/out/trace.csv --case " + c + " --wall-clock-checks", dir).code, 1);
}

}  // namespace
}  // namespace lexdyn::cases
