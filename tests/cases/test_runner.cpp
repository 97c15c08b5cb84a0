// The case runner: the stand acceptance case and its static-equilibrium start, bit-identical
// reruns, failure and interruption handling (the trace so far is kept), checks on a stored
// trace, grasp events; the two solvers of the Newton systems agree.
#include "harness/cases/runner.hpp"
#include "harness/checks/trace.hpp"
#include "case_test_utils.hpp"
#include "lexdyn/common/error.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace lexdyn::cases {
namespace {

using namespace testing;  // case_test_utils.hpp

std::string src(const std::string& rel) { return std::string(LEXDYN_SOURCE_DIR) + "/" + rel; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

RunSummary run(const CaseSpec& spec, const std::string& dir, const std::atomic<bool>* interrupt = nullptr) {
  RunOptions o;
  o.out_dir = dir;
  o.progress = false;
  o.interrupt = interrupt;
  return runCase(spec, o);
}

// A copy of a repository case with a shorter duration, robot paths made absolute.
std::string shortenedCopy(const std::string& rel, double duration_s, const std::string& dir) {
  std::string text = slurp(src(rel));
  const size_t d = text.find("duration_s: 10.0");
  EXPECT_NE(d, std::string::npos);
  text.replace(d, 16, "duration_s: " + std::to_string(duration_s));
  for (size_t p = text.find("../models/"); p != std::string::npos; p = text.find("../models/")) {
    text.replace(p, 10, src("models/"));
  }
  const std::string path = dir + "/case.yaml";
  std::ofstream(path) << text;
  return path;
}

TEST(Runner, StandCaseHoldsHalfSittingAndPassesItsChecks) {
  const std::string dir = outputDir("runner_stand");
  const CaseSpec spec = loadCase(src("cases/stand.yaml"));
  const RunSummary s = run(spec, dir);
  EXPECT_EQ(s.status, lexdyn::records::RunStatus::Completed);
  EXPECT_DOUBLE_EQ(s.simulated_s, 10.0);
  EXPECT_EQ(s.ticks, 2000);
  ASSERT_EQ(s.checks.size(), 3u);
  for (const auto& c : s.checks) EXPECT_TRUE(c.passed) << c.name << " value " << c.value << " limit " << c.limit;
  EXPECT_EQ(exitCode(s), 0);
  // Files: the trace header records the model, integrator, compiler, flags and versions.
  const checks::TraceTable t = checks::readTrace(dir + "/trace.csv");
  for (const char* key : {"model", "integrator", "contact", "servo", "compiler", "cxx_flags", "eigen", "simbody", "sundials", "urdfdom",
                          "yaml_cpp", "robot_weight_N"}) {
    EXPECT_NE(checks::findMetadata(t.metadata, key), nullptr) << key;
  }
  EXPECT_EQ(t.rows.size(), 2001u);
  EXPECT_EQ(t.rows.back()[0], 10.0);
  const nlohmann::json j = nlohmann::json::parse(slurp(dir + "/summary.json"));
  EXPECT_EQ(j["status"], "completed");
  EXPECT_EQ(j["simulated_s"], 10.0);
  EXPECT_GT(j["wall_s"].get<double>(), 0.0);
  EXPECT_GT(j["realtime_factor"].get<double>(), 0.0);
  ASSERT_EQ(j["checks"].size(), 3u);
  for (const auto& c : j["checks"]) {
    for (const char* key : {"name", "passed", "value", "limit"}) EXPECT_TRUE(c.contains(key)) << key;
  }
  // The checks give the same answers on the stored trace.
  const auto stored = checks::runChecks(spec.checks, t);
  for (size_t i = 0; i < stored.size(); ++i) {
    EXPECT_EQ(stored[i].value, s.checks[i].value) << stored[i].name;
    EXPECT_EQ(stored[i].passed, s.checks[i].passed);
  }
}

TEST(Runner, StandStartsInStaticEquilibrium) {
  // The stand case's initial state: contact forces = m g at t = 0, recorded in the trace header.
  const std::string dir = outputDir("runner_stand_start");
  const CaseSpec spec = loadCase(shortenedCopy("cases/stand.yaml", 0.1, dir));
  ASSERT_EQ(spec.initial_state.settle, sim::Settle::StaticEquilibrium);
  ASSERT_EQ(run(spec, dir + "/out").status, lexdyn::records::RunStatus::Completed);
  const checks::TraceTable t = checks::readTrace(dir + "/out/trace.csv");
  const std::string* weight = checks::findMetadata(t.metadata, checks::kWeightMetadata);
  const std::string* init = checks::findMetadata(t.metadata, "initial_state");
  ASSERT_NE(weight, nullptr);
  ASSERT_NE(init, nullptr);
  EXPECT_NE(init->find("settle static_equilibrium"), std::string::npos) << *init;
  const double W = std::stod(*weight);
  const size_t r = static_cast<size_t>(t.column("contact.RIGHT_FOOT.fz")), l = static_cast<size_t>(t.column("contact.LEFT_FOOT.fz"));
  EXPECT_EQ(t.rows[0][0], 0.0);
  EXPECT_NEAR(t.rows[0][r] + t.rows[0][l], W, 1e-9 * W);
}

TEST(Runner, NoStaticEquilibriumIsAnInputErrorAndNothingRuns) {
  const std::string dir = outputDir("runner_no_equilibrium");
  auto sections = minimalCase(0.2);
  const std::string models = src("models/hrp2kai_like/");
  sections["b_robot"] = "robot:\n  urdf: " + models + "hrp2kai_like.urdf\n  data: " + testing::dataFileWithOneLegPosture(dir) + "\n";
  sections["d_initial"] = "initial_state:\n  posture: one_leg\n";
  const std::string path = writeCase(dir, sections);
  const CaseSpec spec = loadCase(path);
  try {
    run(spec, dir + "/out");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("initial_state"), std::string::npos) << msg;
    EXPECT_NE(msg.find("no stable static equilibrium"), std::string::npos) << msg;
    EXPECT_NE(msg.find("one_leg"), std::string::npos) << msg;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/trace.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/trace.csv.partial"));
}

TEST(Runner, RerunsAreBitIdentical) {
  const std::string base = outputDir("runner_determinism");
  const CaseSpec spec = loadCase(shortenedCopy("cases/squat_sway.yaml", 1.5, base));
  const RunSummary a = run(spec, base + "/a");
  const RunSummary b = run(spec, base + "/b");
  ASSERT_EQ(a.status, lexdyn::records::RunStatus::Completed);
  const std::string ta = slurp(base + "/a/trace.csv"), tb = slurp(base + "/b/trace.csv");
  EXPECT_GT(ta.size(), 100000u);
  EXPECT_TRUE(ta == tb) << "traces differ";
  EXPECT_EQ(a.integrator.steps, b.integrator.steps);
  EXPECT_EQ(a.integrator.rhs_evals, b.integrator.rhs_evals);
}

// The largest differences between two traces of one case: joint positions, joint torques, WAIST
// position.
struct TraceDifference {
  double q = 0.0, tau = 0.0, waist = 0.0;
};
TraceDifference largestDifference(const checks::TraceTable& a, const checks::TraceTable& b) {
  TraceDifference d;
  EXPECT_EQ(a.names, b.names);
  EXPECT_EQ(a.rows.size(), b.rows.size());
  if (a.names != b.names || a.rows.size() != b.rows.size()) return {1e300, 1e300, 1e300};
  for (size_t c = 0; c < a.names.size(); ++c) {
    const std::string& n = a.names[c];
    double* worst = n.rfind("q.", 0) == 0 ? &d.q : n.rfind("tau.", 0) == 0 ? &d.tau : n.rfind("frame.WAIST.", 0) == 0 ? &d.waist : nullptr;
    if (!worst) continue;
    for (size_t k = 0; k < a.rows.size(); ++k) *worst = std::max(*worst, std::abs(a.rows[k][c] - b.rows[k][c]));
  }
  return d;
}

// Runs `spec` into base/<first>, then `spec` changed by `change` into base/<second>, and reads
// both traces back.
struct TwoRuns {
  RunSummary a, b;
  checks::TraceTable ta, tb;
};
template <class Change>
TwoRuns runTwoWays(CaseSpec spec, const std::string& base, const std::string& first, const std::string& second, Change change) {
  TwoRuns r;
  r.a = run(spec, base + "/" + first);
  change(spec);
  r.b = run(spec, base + "/" + second);
  if (r.a.status == lexdyn::records::RunStatus::Completed && r.b.status == lexdyn::records::RunStatus::Completed) {
    r.ta = checks::readTrace(base + "/" + first + "/trace.csv");
    r.tb = checks::readTrace(base + "/" + second + "/trace.csv");
  }
  return r;
}

// sim.integrator.linear_solver: SUNDIALS' dense LU and our block elimination solve the same
// Newton systems, so the runs differ by rounding only, amplified by the integrator at its
// tolerances and by the stiff friction to the size of the integrator's own error against a tight
// reference (docs/simulator.md, "Integrator"); the limits are a few times the figures seen.
TEST(Runner, TheTwoNewtonSystemSolversAgree) {
  const std::string base = outputDir("runner_linear_solver");
  CaseSpec spec = loadCase(shortenedCopy("cases/squat_sway.yaml", 0.5, base));
  ASSERT_EQ(spec.sim.integrator.linear_solver, sim::LinearSolver::BlockElimination);  // the default
  const TwoRuns r =
      runTwoWays(spec, base, "block", "dense", [](CaseSpec& s) { s.sim.integrator.linear_solver = sim::LinearSolver::DenseLU; });
  ASSERT_EQ(r.a.status, lexdyn::records::RunStatus::Completed);
  ASSERT_EQ(r.b.status, lexdyn::records::RunStatus::Completed);
  EXPECT_EQ(r.b.integrator.lin_full_setups, 0);
  EXPECT_EQ(checks::findMetadata(r.ta.metadata, "integrator")->find("linear_solver"), std::string::npos);
  EXPECT_NE(checks::findMetadata(r.tb.metadata, "integrator")->find("linear_solver dense_lu"), std::string::npos);
  const TraceDifference d = largestDifference(r.ta, r.tb);
  EXPECT_LT(d.q, 1e-4) << "joint positions";     // 2.4e-5 rad
  EXPECT_LT(d.tau, 5.0) << "joint torques";      // 1.7 N m, at the friction transient of t = 0.32 s
  EXPECT_LT(d.waist, 1e-4) << "WAIST position";  // 1.2e-5 m
  EXPECT_GT(d.q + d.tau, 0.0);                   // really two different solvers
}

// sim.integrator.jacobian: the Jacobian of the applied forces instead of CVODE's difference
// quotients. The runs differ by the integrator's rounding (limits as above), no right-hand side
// is spent on Jacobians, and the integrator's other work grows by at most 20 %: a wrong friction
// or servo damping makes the Newton iterations fail and CVODE take many more steps. 2 s of
// squat_sway: the friction transient at 0.32 s and the squat.
TEST(Runner, TheAppliedForcesJacobianAgreesWithoutDifferenceQuotients) {
  const std::string base = outputDir("runner_jacobian");
  CaseSpec spec = loadCase(shortenedCopy("cases/squat_sway.yaml", 2.0, base));
  ASSERT_EQ(spec.sim.integrator.jacobian, sim::IntegratorJacobian::AppliedForces);  // the default
  spec.sim.integrator.jacobian = sim::IntegratorJacobian::DifferenceQuotient;
  const TwoRuns r =
      runTwoWays(spec, base, "dq", "forces", [](CaseSpec& s) { s.sim.integrator.jacobian = sim::IntegratorJacobian::AppliedForces; });
  ASSERT_EQ(r.a.status, lexdyn::records::RunStatus::Completed);
  ASSERT_EQ(r.b.status, lexdyn::records::RunStatus::Completed);
  const RunSummary& a = r.a;
  const RunSummary& b = r.b;
  EXPECT_GT(a.integrator.jac_rhs_evals, 0);
  EXPECT_EQ(b.integrator.jac_rhs_evals, 0);
  EXPECT_GT(b.integrator.jac_evals, 0);
  // 665 / 715 steps, 821 / 883 right-hand sides, 16 / 7 convergence failures here; a flipped
  // friction damping or no servo damping gives 10^5-10^6 steps.
  EXPECT_LE(b.integrator.steps, a.integrator.steps + a.integrator.steps / 5);
  EXPECT_LE(b.integrator.nonlin_conv_fails, a.integrator.nonlin_conv_fails + 10);
  EXPECT_LE(b.integrator.rhs_evals, a.integrator.rhs_evals + a.integrator.rhs_evals / 5);
  EXPECT_NE(checks::findMetadata(r.ta.metadata, "integrator")->find("difference-quotient Jacobian"), std::string::npos);
  EXPECT_NE(checks::findMetadata(r.tb.metadata, "integrator")->find("Jacobian of the applied forces"), std::string::npos);
  const TraceDifference d = largestDifference(r.ta, r.tb);
  EXPECT_LT(d.q, 1e-4) << "joint positions";     // 3.0e-5 rad
  EXPECT_LT(d.tau, 5.0) << "joint torques";      // 1.6 N m
  EXPECT_LT(d.waist, 1e-4) << "WAIST position";  // 1.7e-5 m
  EXPECT_GT(d.q + d.tau, 0.0);
}

TEST(Runner, IntegratorFailureKeepsTheTraceAndReportsTheStatus) {
  const std::string dir = outputDir("runner_failure");
  auto sections = minimalCase();
  sections["f_sim"] += "  integrator: {max_steps_per_tick: 2}\n";
  const CaseSpec spec = loadCase(writeCase(dir, sections));
  const RunSummary s = run(spec, dir + "/out");
  EXPECT_EQ(s.status, lexdyn::records::RunStatus::IntegratorFailure);
  EXPECT_NE(s.message.find("too_much_work"), std::string::npos) << s.message;
  EXPECT_EQ(exitCode(s), kExitRunFailure);
  EXPECT_LT(s.simulated_s, 0.005);
  const checks::TraceTable t = checks::readTrace(dir + "/out/trace.csv");
  EXPECT_GE(t.rows.size(), 1u);
  // The trace says by itself that the run failed, and why.
  EXPECT_FALSE(t.complete());
  EXPECT_EQ(t.end_status, lexdyn::records::RunStatus::IntegratorFailure);
  EXPECT_NE(t.end_message.find("too_much_work"), std::string::npos) << t.end_message;
  const nlohmann::json j = nlohmann::json::parse(slurp(dir + "/out/summary.json"));
  EXPECT_EQ(j["status"], "integrator_failure");
}

TEST(Runner, InterruptionStopsAfterATickAndKeepsTheTrace) {
  const std::string dir = outputDir("runner_interrupt");
  const CaseSpec spec = loadCase(writeCase(dir, minimalCase()));
  std::atomic<bool> stop{true};
  const RunSummary s = run(spec, dir + "/out", &stop);
  EXPECT_EQ(s.status, lexdyn::records::RunStatus::Interrupted);
  EXPECT_EQ(exitCode(s), 130);  // the signal unknown: SIGINT's code
  const checks::TraceTable t = checks::readTrace(dir + "/out/trace.csv");
  EXPECT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.end_status, lexdyn::records::RunStatus::Interrupted);
  EXPECT_NE(t.end_message.find("interrupted at t = 0 s"), std::string::npos) << t.end_message;
}

TEST(Runner, ProgressLinesGoToStderrOnly) {
  const std::string dir = outputDir("runner_progress");
  const CaseSpec spec = loadCase(writeCase(dir, minimalCase(0.05)));
  RunOptions o;
  o.out_dir = dir + "/a";
  o.progress = true;
  o.progress_interval_s = 0.0;  // a line after every tick
  ::testing::internal::CaptureStderr();
  const RunSummary a = runCase(spec, o);
  const std::string err = ::testing::internal::GetCapturedStderr();
  ASSERT_EQ(a.status, lexdyn::records::RunStatus::Completed);
  size_t lines = 0;
  for (size_t p = err.find("real time, about"); p != std::string::npos; p = err.find("real time, about", p + 1)) ++lines;
  EXPECT_EQ(lines, 10u) << err;
  EXPECT_NE(err.find("[minimal] t = 0.05 / 0.05 s"), std::string::npos) << err;
  // The trace does not depend on the progress output.
  o.out_dir = dir + "/b";
  o.progress = false;
  ASSERT_EQ(runCase(spec, o).status, lexdyn::records::RunStatus::Completed);
  EXPECT_EQ(slurp(dir + "/a/trace.csv"), slurp(dir + "/b/trace.csv"));
}

TEST(Runner, AFailedCheckGivesExitCodeOne) {
  const std::string dir = outputDir("runner_failed_check");
  auto sections = minimalCase(0.2);
  sections["h_checks"] = "checks:\n  - {name: tall, type: frame_height, frame: WAIST, min_m: 2.0}\n";
  const RunSummary s = run(loadCase(writeCase(dir, sections)), dir + "/out");
  EXPECT_EQ(s.status, lexdyn::records::RunStatus::Completed);
  ASSERT_EQ(s.checks.size(), 1u);
  EXPECT_FALSE(s.checks[0].passed);
  EXPECT_NEAR(s.checks[0].value, 0.774, 0.01);
  EXPECT_EQ(exitCode(s), 1);
}

TEST(Runner, GraspEventsSwitchTheContactAtTheirTimes) {
  const std::string dir = outputDir("runner_grasp");
  auto sections = minimalCase(0.4);
  sections["f_sim"] +=
      "  grasps:\n    - {name: left, frame: LGRASP, stiffness_N_per_m: 2e4, damping_Ns_per_m: 400,"
      " rot_stiffness_Nm_per_rad: 500, rot_damping_Nms_per_rad: 10}\n";
  sections["e_controller"] +=
      "events:\n  - {at_s: 0.1, action: grasp_on, grasp: left}\n"
      "  - {at_s: 0.3, action: grasp_off, grasp: left}\n";
  const RunSummary s = run(loadCase(writeCase(dir, sections)), dir + "/out");
  ASSERT_EQ(s.status, lexdyn::records::RunStatus::Completed);
  const checks::TraceTable t = checks::readTrace(dir + "/out/trace.csv");
  const int c = t.column("grasp.left.active");
  ASSERT_GE(c, 0);
  for (const auto& row : t.rows) {
    // A row holds the state at its time; the event at t applies to the step from t on.
    const double expected = (row[0] > 0.1 + 1e-9 && row[0] <= 0.3 + 1e-9) ? 1.0 : 0.0;
    EXPECT_EQ(row[static_cast<size_t>(c)], expected) << "t = " << row[0];
  }
}

}  // namespace
}  // namespace lexdyn::cases
