// The lexdyn controller in the closed loop (harness/cases/lexdyn_driver.cpp): a short controller
// case writes the documented channels and summary, reruns bit-identically, applies its events at
// their ticks (targets, contacts with their simulator grasps, swings, trajectories), stops on a
// controller failure keeping the trace, and its checks give the same result on the stored trace.
#include "harness/cases/runner.hpp"
#include "case_test_utils.hpp"
#include "lexdyn/common/error.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <fstream>
#include <sstream>

namespace lexdyn::cases {
namespace {

using namespace testing;  // case_test_utils.hpp

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

RunSummary run(const CaseSpec& spec, const std::string& dir) {
  RunOptions o;
  o.out_dir = dir;
  o.progress = false;
  return runCase(spec, o);
}

double at(const checks::TraceTable& t, size_t row, const std::string& channel) {
  const int c = t.column(channel);
  EXPECT_GE(c, 0) << channel;
  return c < 0 ? NAN : t.rows[row][static_cast<size_t>(c)];
}

TEST(ControllerRunner, EveryMethodRunsAndWritesTheControllerChannelsAndSummary) {
  for (const char* method : {"bfgs", "ah", "gn", "wls"}) {
    const std::string dir = outputDir(std::string("ctl_runner_") + method);
    CaseSpec spec = loadCase(writeCase(dir, minimalLexdynCase(0.2)));
    overrideMethod(spec, method, "test");
    const RunSummary s = run(spec, dir + "/out");
    EXPECT_EQ(s.status, lexdyn::records::RunStatus::Completed) << method << ": " << s.message;
    EXPECT_EQ(s.method, method);
    const checks::TraceTable t = checks::readTrace(dir + "/out/trace.csv");
    ASSERT_EQ(t.rows.size(), 41u);  // t = 0 .. 0.2 s
    EXPECT_EQ(*checks::findMetadata(t.metadata, "method"), method);
    for (const char* c : {"ctrl.status",
                          "solver.status",
                          "solver.iterations",
                          "time.tick_us",
                          "time.solver_us",
                          "task.right_hand.error",
                          "task.right_hand.active",
                          "task.right_hand.engaged",
                          "cmd.q.RLEG_JOINT3",
                          "cmd.qd.RLEG_JOINT3",
                          "cmd.tau.RLEG_JOINT3",
                          "tau.RLEG_JOINT3",
                          "ctrl_contact.RIGHT_FOOT.active",
                          "wrench.RIGHT_FOOT.fz",
                          "wrench_sensed.RIGHT_FOOT.fz",
                          "wrench.POLE.fx",
                          "wrench_sensed.POLE.tz",
                          "target.right_hand.x",
                          "target.com_box.lower_x",
                          "com.x"}) {
      EXPECT_GE(t.column(c), 0) << c << " (" << method << ")";
    }
    const bool wls = std::string(method) == "wls";
    EXPECT_EQ(t.column("level.hands.augmented") >= 0, !wls) << method;
    EXPECT_EQ(t.column("level.objective.violation") >= 0, wls) << method;
    // The size of the Newton rows against J^T J: a value on the augmented rows only (NaN else).
    if (!wls) {
      for (size_t row = 0; row < t.rows.size(); ++row) {
        const bool aug = at(t, row, "level.hands.augmented") != 0.0;
        for (const char* c : {"level.hands.second_order_ratio", "level.hands.curvature_ratio"})
          EXPECT_EQ(std::isnan(at(t, row, c)), !aug) << c << " row " << row << " (" << method << ")";
      }
    }
    EXPECT_EQ(t.column("task.posture.error") >= 0, wls) << method;  // only the method's tasks
    EXPECT_EQ(t.column("task.velocity.error") >= 0, !wls) << method;
    // At rest in the static equilibrium, the feet carry the weight in the controller's plan and
    // in the sensors, in the same axes (the contact frames) and about the same points.
    const double fz = at(t, 0, "wrench.RIGHT_FOOT.fz") + at(t, 0, "wrench.LEFT_FOOT.fz");
    const double fz_sensed = at(t, 0, "wrench_sensed.RIGHT_FOOT.fz") + at(t, 0, "wrench_sensed.LEFT_FOOT.fz");
    EXPECT_NEAR(fz, 637.65, 0.05 * 637.65) << method;
    EXPECT_NEAR(fz_sensed, 637.65, 0.05) << method;
    // The sole's normal force equals the simulator's vertical contact force (the sole is level
    // to a few mrad).
    EXPECT_NEAR(at(t, 0, "wrench_sensed.RIGHT_FOOT.fz"), at(t, 0, "contact.RIGHT_FOOT.fz"), 0.05) << method;
    EXPECT_EQ(at(t, 0, "ctrl_contact.POLE.active"), 0.0);
    EXPECT_EQ(at(t, 0, "target.right_hand.y"), -0.4);
    // summary.json
    const nlohmann::json j = nlohmann::json::parse(slurp(dir + "/out/summary.json"));
    EXPECT_EQ(j["method"], method);
    ASSERT_TRUE(j.contains("tasks"));
    EXPECT_GT(j["tasks"]["right_hand"]["final_error"].get<double>(), 0.0);
    EXPECT_GT(j["tasks"]["right_hand"]["mean_error"].get<double>(), j["tasks"]["right_hand"]["final_error"].get<double>());
    EXPECT_GE(j["solver"]["peak_iterations"].get<int>(), 1);
    for (const char* timer : {"model", "tasks", "hessian", "solver", "tick"}) {
      const auto& tm = j["timing_us"][timer];
      EXPECT_LE(tm["median"].get<double>(), tm["p99"].get<double>()) << timer;
      EXPECT_LE(tm["p99"].get<double>(), tm["max"].get<double>()) << timer;
    }
    EXPECT_EQ(j["controller"]["ticks"].get<long>(), 41);
    EXPECT_EQ(j["checks"].size(), 1u);
  }
}

TEST(ControllerRunner, RerunsAreBitIdentical) {
  const std::string dir = outputDir("ctl_runner_determinism");
  auto sections = minimalLexdynCase(0.3, "ah");
  sections["g_trace"] = "trace:\n  frames: [WAIST]\n  timings: false\n";
  const CaseSpec spec = loadCase(writeCase(dir, sections));
  ASSERT_EQ(run(spec, dir + "/a").status, lexdyn::records::RunStatus::Completed);
  ASSERT_EQ(run(spec, dir + "/b").status, lexdyn::records::RunStatus::Completed);
  const std::string a = slurp(dir + "/a/trace.csv"), b = slurp(dir + "/b/trace.csv");
  EXPECT_GT(a.size(), 50000u);
  EXPECT_TRUE(a == b) << "traces differ";
  // With the wall-time channels every other channel is still identical.
  sections["g_trace"] = "trace:\n  frames: [WAIST]\n";
  const CaseSpec timed = loadCase(writeCase(dir, sections));
  ASSERT_EQ(run(timed, dir + "/c").status, lexdyn::records::RunStatus::Completed);
  const checks::TraceTable ta = checks::readTrace(dir + "/a/trace.csv"), tc = checks::readTrace(dir + "/c/trace.csv");
  ASSERT_EQ(ta.rows.size(), tc.rows.size());
  EXPECT_GE(tc.column("time.tick_us"), 0);
  EXPECT_LT(ta.column("time.tick_us"), 0);
  for (size_t i = 0; i < ta.names.size(); ++i) {
    const int c = tc.column(ta.names[i]);
    ASSERT_GE(c, 0) << ta.names[i];
    for (size_t r = 0; r < ta.rows.size(); ++r) {
      const double x = ta.rows[r][i], y = tc.rows[r][static_cast<size_t>(c)];
      // nan (a ratio channel on a tick without Newton rows) equals nan here.
      if (std::isnan(x) && std::isnan(y)) continue;
      ASSERT_EQ(x, y) << ta.names[i] << " row " << r;
    }
  }
}

TEST(ControllerRunner, EventsApplyAtTheirTicks) {
  const std::string dir = outputDir("ctl_runner_events");
  std::ofstream(dir + "/path.csv") << "t,x,y,z\n0,0.2,-0.4,0.8\n0.1,0.3,-0.4,0.8\n0.2,0.3,-0.3,0.9\n";
  auto sections = minimalLexdynCase(0.5);
  sections["g_events"] = R"(events:
  - {at_s: 0.1, action: set_target, task: right_hand, value: [0.35, -0.45, 0.95]}
  - {at_s: 0.1, action: add_contact, contact: POLE}
  - {at_s: 0.2, action: set_target, task: com_box, lower: [-0.04, -0.1, -.inf], upper: [0.04, 0.1, .inf]}
  - {at_s: 0.25, action: swing, task: left_hand, from: [0.2, 0.3, 0.7], to: [0.3, 0.5, 0.9], period_s: 0.4}
  - {at_s: 0.3, action: target_trajectory, task: right_hand, file: path.csv, moving_average_s: 0.05}
  - {at_s: 0.4, action: remove_contact, contact: POLE}
)";
  const CaseSpec spec = loadCase(writeCase(dir, sections));
  const RunSummary s = run(spec, dir + "/out");
  ASSERT_EQ(s.status, lexdyn::records::RunStatus::Completed) << s.message;
  const checks::TraceTable t = checks::readTrace(dir + "/out/trace.csv");
  // An event applies at the first tick at or after its time; its target generator starts there.
  auto tickAt = [&](double at_s) -> double {
    for (const auto& row : t.rows) {
      if (row[0] >= at_s - 1e-9) return row[0];
    }
    return std::numeric_limits<double>::quiet_NaN();
  };
  const double swing_start = tickAt(0.25), path_start = tickAt(0.3);
  const TargetTrajectory path = TargetTrajectory::fromCsv(dir + "/path.csv", 0.05, false);
  Swing swing;
  swing.from = Eigen::Vector3d(0.2, 0.3, 0.7);
  swing.to = Eigen::Vector3d(0.3, 0.5, 0.9);
  swing.period_s = 0.4;
  for (size_t r = 0; r < t.rows.size(); ++r) {
    const double time = t.rows[r][0];
    // Controller channels show the tick at the row's time, after that time's events.
    const bool pole = time >= 0.1 - 1e-9 && time < 0.4 - 1e-9;
    EXPECT_EQ(at(t, r, "ctrl_contact.POLE.active"), pole ? 1.0 : 0.0) << time;
    // Simulator channels show the state at the row's time: the grasp acts from the event on.
    const bool grasp = time > 0.1 + 1e-9 && time <= 0.4 + 1e-9;
    EXPECT_EQ(at(t, r, "grasp.left.active"), grasp ? 1.0 : 0.0) << time;
    Eigen::Vector3d rh(at(t, r, "target.right_hand.x"), at(t, r, "target.right_hand.y"), at(t, r, "target.right_hand.z"));
    if (time < 0.1 - 1e-9) {
      EXPECT_EQ(rh, Eigen::Vector3d(0.3, -0.4, 0.9)) << time;
    } else if (time < 0.3 - 1e-9) {
      EXPECT_EQ(rh, Eigen::Vector3d(0.35, -0.45, 0.95)) << time;
    } else {
      EXPECT_EQ(rh, path.at(time - path_start)) << time;
    }
    EXPECT_EQ(at(t, r, "target.com_box.lower_x"), time < 0.2 - 1e-9 ? -0.03 : -0.04) << time;
    if (time >= 0.25 - 1e-9) {
      const Eigen::Vector3d lh(at(t, r, "target.left_hand.x"), at(t, r, "target.left_hand.y"), at(t, r, "target.left_hand.z"));
      EXPECT_EQ(lh, swing.at(time - swing_start)) << time;
    }
  }
  // The pole contact carries a force in the plan while held (sensed through the grasp).
  size_t row = 30;  // t = 0.15 s
  EXPECT_NEAR(t.rows[row][0], 0.15, 1e-12);
  EXPECT_EQ(at(t, row, "grasp.left.active"), 1.0);
}

TEST(ControllerRunner, ControllerFailureStopsTheRunKeepingTheTrace) {
  // Two contradicting joint targets in the WLS hard level: infeasible at the first tick.
  const std::string dir = outputDir("ctl_runner_failure");
  auto sections = minimalLexdynCase(0.3, "wls");
  std::string ctl = lexdynController("wls",
                                     "    - {name: head_a, type: joint_position, joints: [HEAD_JOINT0], target: [0.3]}\n"
                                     "    - {name: head_b, type: joint_position, joints: [HEAD_JOINT0], target: [-0.3]}\n");
  const std::string from = "{name: hard, tasks: [joint_limits,";
  ctl.replace(ctl.find(from), from.size(), "{name: hard, tasks: [head_a, head_b, joint_limits,");
  sections["e_controller"] = ctl;
  const CaseSpec spec = loadCase(writeCase(dir, sections));
  const RunSummary s = run(spec, dir + "/out");
  EXPECT_EQ(s.status, lexdyn::records::RunStatus::ControllerFailure);
  EXPECT_NE(s.message.find("controller_failure: infeasible at t = 0 s"), std::string::npos) << s.message;
  EXPECT_EQ(exitCode(s), kExitRunFailure);
  const checks::TraceTable t = checks::readTrace(dir + "/out/trace.csv");
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.end_status, lexdyn::records::RunStatus::ControllerFailure);
  EXPECT_NE(t.end_message.find("infeasible at t = 0 s"), std::string::npos) << t.end_message;
  EXPECT_EQ(at(t, 0, "ctrl.status"), 3.0);  // infeasible (ctrl_status_codes)
  const nlohmann::json j = nlohmann::json::parse(slurp(dir + "/out/summary.json"));
  EXPECT_EQ(j["status"], "controller_failure");
  EXPECT_EQ(j["controller"]["status_counts"]["infeasible"].get<long>(), 1);
}

// The divergence guard (docs/cases.md, "Divergence guard"): exp1 with an upper body four times
// heavier in the simulator than in the controller's model sinks away from its plan; the guard
// ends the run with status `diverged` while the robot still stands (the waist above 0.7 m),
// keeping the trace. Without the guard the same run goes on until the robot has collapsed (the
// waist at 0.15 m) and the integrator fails.
TEST(ControllerRunner, DivergenceGuardStopsARunThatLeavesItsPlan) {
  const std::string exp1 = std::string(LEXDYN_SOURCE_DIR) + "/cases/exp1.yaml";
  const std::vector<Override> heavy = {{"sim.model", "{mass_scale: [{match: \"CHEST*\", scale: 4}, {match: \"*ARM*\", scale: 4}]}", ""},
                                       {"stop_at_s", "5", ""}};
  const std::string dir = outputDir("ctl_runner_diverged");
  const RunSummary s = run(loadCase(exp1, heavy), dir + "/on");
  EXPECT_EQ(s.status, lexdyn::records::RunStatus::Diverged) << s.message;
  EXPECT_NE(s.message.find("from the plan's position (limit 0.25 m, divergence_guard.position_m)"), std::string::npos) << s.message;
  EXPECT_EQ(exitCode(s), kExitRunFailure);
  EXPECT_LT(s.simulated_s, 3.0);
  const checks::TraceTable t = checks::readTrace(dir + "/on/trace.csv");
  EXPECT_EQ(t.end_status, lexdyn::records::RunStatus::Diverged);
  EXPECT_EQ(t.end_message, s.message);
  double lowest = INFINITY;
  for (size_t r = 0; r < t.rows.size(); ++r) lowest = std::min(lowest, at(t, r, "frame.WAIST.z"));
  EXPECT_GT(lowest, 0.7);
  EXPECT_NEAR(at(t, t.rows.size() - 1, "t"), s.simulated_s, 1e-12);
  std::vector<Override> off = heavy;
  off.push_back({"controller.divergence_guard", "off", ""});
  const RunSummary s_off = run(loadCase(exp1, off), dir + "/off");
  EXPECT_NE(s_off.status, lexdyn::records::RunStatus::Diverged);
  EXPECT_GT(s_off.simulated_s, s.simulated_s);
  const checks::TraceTable t_off = checks::readTrace(dir + "/off/trace.csv");
  lowest = INFINITY;
  for (size_t r = 0; r < t_off.rows.size(); ++r) lowest = std::min(lowest, at(t_off, r, "frame.WAIST.z"));
  EXPECT_LT(lowest, 0.3);
}

// Each criterion of the guard, driven by a threshold no healthy run meets, names its key.
TEST(ControllerRunner, DivergenceGuardCriteriaNameTheirThresholds) {
  const std::string exp1 = std::string(LEXDYN_SOURCE_DIR) + "/cases/exp1.yaml";
  struct Case {
    const char* guard;
    const char* message;
    double before_s;  // the run stops before this time
  };
  for (const Case& c :
       {Case{"{angle_rad: 1.0e-9}", "from the plan's position (limit 1e-09, divergence_guard.angle_rad)", 0.1},
        Case{"{contact_lost_fraction: 0.9, contact_lost_s: 0.2}", "but the simulated robot has left it since t = 0 s", 0.25},
        Case{"{torque_factor: 1.0, angle_rad: 10}", "", 0.0}, Case{"{task_error: 0.01}", "task right_hand has an error of", 0.01}}) {
    const std::string dir = outputDir("ctl_runner_guard");
    const RunSummary s = run(loadCase(exp1, {{"controller.divergence_guard", c.guard, ""}, {"stop_at_s", "1", ""}}), dir);
    if (*c.message == 0) {
      // The plan keeps its torques within their limits (the torque_limits level): a factor of 1
      // never fires on a healthy run.
      EXPECT_EQ(s.status, lexdyn::records::RunStatus::Completed) << c.guard << ": " << s.message;
      continue;
    }
    EXPECT_EQ(s.status, lexdyn::records::RunStatus::Diverged) << c.guard;
    EXPECT_NE(s.message.find(c.message), std::string::npos) << c.guard << ": " << s.message;
    EXPECT_LT(s.simulated_s, c.before_s) << c.guard;
  }
}

TEST(ControllerRunner, StoredTraceChecksEqualTheLiveOnes) {
  const std::string dir = outputDir("ctl_runner_checks");
  auto sections = minimalLexdynCase(0.3);
  sections["h_checks"] = R"(checks:
  - {name: hands, type: task_error, tasks: [right_hand, left_hand], statistic: mean, limit: 1.0}
  - {name: torques, type: torque_limits, limit_fraction: 0.5}
  - {name: unilateral, type: contact_unilateral, contact: LEFT_FOOT, source: sensed, min_N: 100}
  - {name: cone, type: contact_friction, contact: RIGHT_FOOT}
  - {name: cop, type: contact_cop, contact: RIGHT_FOOT, source: sensed, limit_m: -0.01}
  - {name: match, type: contact_wrench_match, contact: RIGHT_FOOT, limit_N: 50}
  - {name: acc, type: joint_acceleration_sign_changes, dead_band_rad_per_s2: 0.1, limit_per_s: 10}
  - {name: hf, type: joint_velocity_hf_energy, cutoff_hz: 10, limit_rad2_per_s2: 1}
  - {name: rate, type: task_error_rate_sign_changes, task: right_hand, limit_per_s: 5}
  - {name: status, type: controller_status}
  - {name: peak, type: active_set_peak, limit_iterations: 30}
  - {name: aug, type: augmented_fraction, level: hands, max_fraction: 1.0, methods: [bfgs, ah, gn]}
  - {name: tick, type: tick_time, timer: tick, percentile: 50, limit_us: 1.0e6}
)";
  const CaseSpec spec = loadCase(writeCase(dir, sections));
  const RunSummary s = run(spec, dir + "/out");
  ASSERT_EQ(s.status, lexdyn::records::RunStatus::Completed);
  ASSERT_EQ(s.checks.size(), 13u);
  const std::vector<checks::CheckResult> stored = checks::runChecks(spec.checks, checks::readTrace(dir + "/out/trace.csv"));
  ASSERT_EQ(stored.size(), s.checks.size());
  for (size_t i = 0; i < stored.size(); ++i) {
    EXPECT_EQ(stored[i].name, s.checks[i].name);
    EXPECT_TRUE(stored[i].value == s.checks[i].value || (std::isnan(stored[i].value) && std::isnan(s.checks[i].value)))
        << stored[i].name << ": " << stored[i].value << " vs " << s.checks[i].value;
    EXPECT_EQ(stored[i].passed, s.checks[i].passed) << stored[i].name;
    EXPECT_EQ(stored[i].detail, s.checks[i].detail) << stored[i].name;
  }
  // At rest-like conditions over 0.3 s these hold (values, not just pass/fail, are sane).
  for (const auto& c : s.checks) {
    if (c.name == "unilateral") {
      EXPECT_GT(c.value, 250.0);
    }
    if (c.name == "status") {
      EXPECT_EQ(c.value, 0.0);
    }
  }
  // With --method wls the check restricted to the velocity methods is skipped.
  CaseSpec wls = spec;
  overrideMethod(wls, "wls", "test");
  const RunSummary w = run(wls, dir + "/wls");
  EXPECT_EQ(w.checks.size(), 12u);
  ASSERT_EQ(w.skipped_checks.size(), 1u);
  EXPECT_EQ(w.skipped_checks[0].name, "aug");
  EXPECT_NE(w.skipped_checks[0].reason.find("restricted to other methods"), std::string::npos) << w.skipped_checks[0].reason;
}

}  // namespace
}  // namespace lexdyn::cases
