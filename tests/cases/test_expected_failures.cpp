// A case's expected failures (docs/cases.md, "Expected failures"): what the loader refuses, how a
// run's outcome is matched against the entry, the exit code, and the point mass's WLS run, which
// fails as cases/pointmass-damping.yaml says it does (and fails plainly without the entry).
#include "harness/cases/case_file.hpp"
#include "harness/cases/runner.hpp"
#include "lexdyn/common/error.hpp"
#include "case_test_utils.hpp"

#include "../common/cli_test_utils.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <fstream>

namespace lexdyn::cases {
namespace {

using testing::outputDir;

const std::string kPointMass = std::string(LEXDYN_SOURCE_DIR) + "/cases/pointmass-damping.yaml";

// cases/pointmass-damping.yaml with its robot paths made absolute and `expected_failures`
// replaced by `entries` (YAML flow text; empty: the key removed), written to a fresh directory.
std::string pointMassWith(const std::string& dir_name, const std::string& entries) {
  YAML::Node doc = YAML::LoadFile(kPointMass);
  const std::string models = std::string(LEXDYN_SOURCE_DIR) + "/models/point_mass/";
  doc["robot"]["urdf"] = models + "point_mass.urdf";
  doc["robot"]["data"] = models + "point_mass.yaml";
  doc.remove("expected_failures");
  if (!entries.empty()) doc["expected_failures"] = YAML::Load(entries);
  const std::string path = outputDir(dir_name) + "/case.yaml";
  std::ofstream(path) << YAML::Dump(doc) << "\n";
  return path;
}

std::string loadError(const std::string& entries) {
  try {
    loadCase(pointMassWith("expected_failures_errors", entries));
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(ExpectedFailures, TheRepositoryCasesDeclareTheirs) {
  const CaseSpec pm = loadCase(kPointMass);
  const ExpectedFailure* x = expectedFailureFor(pm, "wls");
  ASSERT_NE(x, nullptr);
  EXPECT_EQ(x->status, lexdyn::records::RunStatus::Completed);
  EXPECT_EQ(x->checks, (std::vector<std::string>{"closed_form_eq49", "no_overshoot"}));  // sorted
  EXPECT_FALSE(x->reason.empty());
  EXPECT_EQ(expectedFailureFor(pm, "gn"), nullptr);
  const CaseSpec instant = loadCase(std::string(LEXDYN_SOURCE_DIR) + "/cases/exp2-instant.yaml");
  ASSERT_NE(expectedFailureFor(instant, "wls"), nullptr);
  EXPECT_EQ(expectedFailureFor(instant, "wls")->status, lexdyn::records::RunStatus::ControllerFailure);
}

TEST(ExpectedFailures, BadEntriesAreErrorsNamingTheKey) {
  const std::string ok = "[{method: wls, checks: [no_overshoot], reason: overshoot}]";
  EXPECT_EQ(loadError(ok), "<no error>");
  EXPECT_NE(loadError("[{method: nope, checks: [no_overshoot], reason: r}]").find("expected_failures[0].method"), std::string::npos);
  EXPECT_NE(loadError("[{checks: [no_overshoot], reason: r}]").find("method"), std::string::npos);
  EXPECT_NE(loadError("[{method: wls, checks: [nope], reason: r}]").find("unknown check 'nope'"), std::string::npos);
  EXPECT_NE(loadError("[{method: gn, checks: [closed_form_eq51], reason: r}]").find("does not apply to method gn"), std::string::npos);
  EXPECT_NE(loadError("[{method: wls, checks: [no_overshoot, no_overshoot], reason: r}]").find("listed twice"), std::string::npos);
  EXPECT_NE(loadError("[{method: wls, reason: r}]").find("expected a failure"), std::string::npos);
  EXPECT_NE(loadError("[{method: wls, checks: [no_overshoot]}]").find("reason"), std::string::npos);
  EXPECT_NE(loadError("[{method: wls, status: internal_error, reason: r}]").find("status"), std::string::npos);
  EXPECT_NE(loadError("[{method: wls, checks: [no_overshoot], reason: r}, {method: wls, status: controller_failure, reason: r}]")
                .find("a second entry for method wls"),
            std::string::npos);
  EXPECT_NE(loadError("[{method: wls, checks: [no_overshoot], reason: r, extra: 1}]").find("extra"), std::string::npos);
}

checks::CheckResult result(const std::string& name, bool passed, bool decides = true) {
  checks::CheckResult r;
  r.name = name;
  r.passed = passed;
  r.decides = decides;
  return r;
}

TEST(ExpectedFailures, TheOutcomeMustMatchExactly) {
  ExpectedFailure x;
  x.checks = {"a", "b"};
  x.reason = "r";
  const std::vector<checks::CheckResult> as_expected = {result("a", false), result("b", false), result("c", true),
                                                        result("t", false, false)};  // a wall-clock check: no verdict
  EXPECT_TRUE(expectationMismatches(x, lexdyn::records::RunStatus::Completed, as_expected).empty());
  EXPECT_EQ(expectationMismatches(x, lexdyn::records::RunStatus::Completed, {result("a", false), result("b", false), result("c", false)}),
            (std::vector<std::string>{"c failed (not expected)"}));
  EXPECT_EQ(expectationMismatches(x, lexdyn::records::RunStatus::Completed, {result("a", false), result("b", true)}),
            (std::vector<std::string>{"b passed (expected to fail)"}));
  EXPECT_EQ(expectationMismatches(x, lexdyn::records::RunStatus::Completed, {result("a", false)}),
            (std::vector<std::string>{"b was not evaluated (expected to fail)"}));
  EXPECT_EQ(expectationMismatches(x, lexdyn::records::RunStatus::ControllerFailure, as_expected),
            (std::vector<std::string>{"status controller_failure (expected completed)"}));
}

TEST(ExpectedFailures, ExitCodes) {
  RunSummary s;
  s.status = lexdyn::records::RunStatus::Completed;
  s.all_checks_passed = false;
  EXPECT_EQ(exitCode(s), kExitCheckFailed);  // no entry: a failure
  s.expected_failure.emplace();
  s.expected_failure->checks = {"a"};
  EXPECT_EQ(exitCode(s), kExitPass);  // failed as expected
  s.expectation_mismatches = {"b failed (not expected)"};
  EXPECT_EQ(exitCode(s), kExitCheckFailed);
  s.status = lexdyn::records::RunStatus::ControllerFailure;  // another run failure than the one expected (completed)
  EXPECT_EQ(exitCode(s), kExitRunFailure);
  s.expected_failure->status = lexdyn::records::RunStatus::ControllerFailure;
  s.expectation_mismatches = {"a passed (expected to fail)"};
  EXPECT_EQ(exitCode(s), kExitCheckFailed);  // the expected status, a check differs
  s.expectation_mismatches.clear();
  EXPECT_EQ(exitCode(s), kExitPass);
  s.status = lexdyn::records::RunStatus::Interrupted;
  s.signal = 15;
  EXPECT_EQ(exitCode(s), kExitInterrupted + 15);  // an interruption is never expected
  s.status = lexdyn::records::RunStatus::InternalError;
  EXPECT_EQ(exitCode(s), kExitRunFailure);
}

RunSummary runWls(const std::string& path, const std::string& dir) {
  CaseSpec spec = loadCase(path);
  overrideMethod(spec, "wls", "test");
  spec.duration_s = 10.0;
  RunOptions o;
  o.out_dir = outputDir(dir);
  o.progress = false;
  return runCase(spec, o);
}

// The point mass in the acceleration domain overshoots (Fig. 1): the case expects it.
TEST(ExpectedFailures, ThePointMassWlsRunFailsAsItsCaseSays) {
  const RunSummary declared = runWls(kPointMass, "expected_failures_pm");
  EXPECT_FALSE(declared.all_checks_passed);
  ASSERT_TRUE(declared.expected_failure.has_value());
  EXPECT_TRUE(declared.expectation_mismatches.empty()) << declared.expectation_mismatches.front();
  EXPECT_EQ(exitCode(declared), kExitPass);
  std::ifstream in(declared.summary_path);
  const std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"expected_failure\""), std::string::npos);
  EXPECT_NE(json.find("\"met\": true"), std::string::npos);

  const RunSummary plain = runWls(pointMassWith("expected_failures_plain", ""), "expected_failures_pm_plain");
  EXPECT_FALSE(plain.expected_failure.has_value());
  EXPECT_EQ(exitCode(plain), kExitCheckFailed);

  // Expecting only one of the two failures: the other is reported and the run fails.
  const RunSummary partial = runWls(pointMassWith("expected_failures_partial", "[{method: wls, checks: [no_overshoot], reason: r}]"),
                                    "expected_failures_pm_partial");
  EXPECT_EQ(partial.expectation_mismatches, (std::vector<std::string>{"closed_form_eq49 failed (not expected)"}));
  EXPECT_EQ(exitCode(partial), kExitCheckFailed);
}

// `check` on the stored trace of such a run judges it as `run` did: exit 0 when it failed exactly
// as declared, 1 with the mismatch otherwise.
TEST(ExpectedFailures, CheckJudgesAStoredTraceAsRunDid) {
  const std::string dir = outputDir("expected_failures_check");
  const std::string declared =
      pointMassWith("expected_failures_check_case", "[{method: wls, checks: [closed_form_eq49, no_overshoot], reason: r}]");
  lexdyn::testing::CliResult r =
      lexdyn::testing::harness("run " + declared + " --method wls --duration 10 --out " + dir + "/out --quiet", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  r = lexdyn::testing::harness("check " + dir + "/out/trace.csv --case " + declared, dir);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("expected failure, as the case says"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("xfail no_overshoot"), std::string::npos) << r.err;
  const std::string partial = pointMassWith("expected_failures_check_partial", "[{method: wls, checks: [no_overshoot], reason: r}]");
  r = lexdyn::testing::harness("check " + dir + "/out/trace.csv --case " + partial, dir);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("NOT the expected failure"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("closed_form_eq49 failed (not expected)"), std::string::npos) << r.err;
  // A run cut short by --duration: judged as cut short from the trace itself.
  r = lexdyn::testing::harness("run " + declared + " --method wls --duration 3 --out " + dir + "/short --quiet", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  r = lexdyn::testing::harness("check " + dir + "/short/trace.csv --case " + declared, dir);
  EXPECT_EQ(r.code, 0) << r.err;
  const std::string plain = pointMassWith("expected_failures_check_plain", "");
  EXPECT_EQ(lexdyn::testing::harness("check " + dir + "/out/trace.csv --case " + plain, dir).code, 1);
}

}  // namespace
}  // namespace lexdyn::cases
