// The checks on the lexdyn controller's channels (harness/checks/*_checks.cpp) on
// synthetic traces whose answers are computed by hand: every check type passes and fails where
// it should, and its detail names the time (and the joint, contact or status) of its value.
#include "harness/checks/checks.hpp"
#include "harness/checks/contact_checks.hpp"
#include "harness/checks/health_checks.hpp"
#include "harness/checks/joint_checks.hpp"
#include "harness/checks/sim_checks.hpp"
#include "harness/checks/task_checks.hpp"
#include "harness/checks/trace.hpp"
#include "lexdyn/common/error.hpp"
#include "check_test_utils.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace lexdyn::checks {
namespace {

using namespace testing;  // runOne, expectOutcome

using Fn = std::function<double(double)>;

/// A trace with channel t = k dt (k = 0..n-1) and the given channels as functions of t.
TraceTable makeTrace(const std::vector<std::pair<std::string, Fn>>& channels, double dt, int n, TraceMetadata md = {}) {
  TraceTable tr;
  tr.metadata = std::move(md);
  tr.names.push_back(kTimeChannel);
  for (const auto& c : channels) tr.names.push_back(c.first);
  for (int k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;  // as the runner computes tick times
    std::vector<double> row{t};
    for (const auto& c : channels) row.push_back(c.second(t));
    tr.rows.push_back(std::move(row));
  }
  return tr;
}

Fn constant(double v) {
  return [v](double) { return v; };
}

CheckSpec spec(const std::string& type, double limit) {
  CheckSpec s;
  s.name = type + "_check";
  s.type = type;
  s.limit = limit;
  s.where = "synthetic.yaml:1: checks[0]";
  return s;
}

// -------------------------------------------------------------------------------------------
// task_error

// Two tasks over t = 0 .. 2 s (dt 0.01): a = 1 - t/2 (linear to 0), b = 0.1 except a spike of
// 0.5 at t = 0.3 s.
TraceTable twoTasks() {
  return makeTrace({{taskChannel("a", "error"), [](double t) { return 1.0 - 0.5 * t; }},
                    {taskChannel("b", "error"), [](double t) { return std::abs(t - 0.3) < 1e-9 ? 0.5 : 0.1; }}},
                   0.01, 201);
}

// A task_error check of the tasks a and b.
CheckSpec taskErrorSpec(double limit, const std::string& statistic) {
  CheckSpec s = spec("task_error", limit);
  auto& sp = s.params.emplace<TaskErrorParams>();
  sp.tasks = {"a", "b"};
  sp.statistic = statistic;
  return s;
}

TEST(TaskErrorCheck, FinalMaxAndMeanOfTheSumOfNorms) {
  const TraceTable t = twoTasks();
  CheckSpec s = taskErrorSpec(0.1 + 1e-12, "final");
  auto& sp = s.paramsAs<TaskErrorParams>();
  expectOutcome(s, t, {0.1, 1e-15}, kPass, {"final of a + b, at t = 2 s"});  // a(2) = 0, b = 0.1
  s.limit = 0.09;
  EXPECT_FALSE(runOne(s, t).passed);

  sp.statistic = "max";
  s.limit = 1.5;
  expectOutcome(s, t, {1.0 - 0.15 + 0.5, 1e-15}, kPass, {"largest at t = 0.3 s"});  // the spike at 0.3 s beats t = 0 (1.1)
  s.limit = 1.3;
  EXPECT_FALSE(runOne(s, t).passed);

  // Time average (trapezoidal over the rows): a averages 0.5 over [0, 2]; b is 0.1 plus a
  // triangle of height 0.4 and base 0.02 s at the spike: 0.1 + 0.4 * 0.01 / 2.
  sp.statistic = "mean";
  s.limit = 1.0;
  expectOutcome(s, t, {0.5 + 0.1 + 0.004 / 2.0, 1e-12}, kPass, {"time average over t = 0 .. 2 s"});
  s.limit = 0.6;
  EXPECT_FALSE(runOne(s, t).passed);
}

TEST(TaskErrorCheck, WindowFromAndTo) {
  const TraceTable t = twoTasks();
  CheckSpec s = taskErrorSpec(1.0, "max");
  auto& sp = s.paramsAs<TaskErrorParams>();
  s.from_s = 0.5;  // after the spike: the largest is at 0.5 s, 0.75 + 0.1
  CheckResult r = expectOutcome(s, t, {0.85, 1e-15}, kEither, {"largest at t = 0.5 s"});
  sp.statistic = "final";
  s.to_s = 1.0;  // the last row of the window
  expectOutcome(s, t, {0.6, 1e-15}, kEither, {"at t = 1 s"});
  sp.statistic = "mean";  // a over [0.5, 1]: 0.625
  EXPECT_NEAR(runOne(s, t).value, 0.725, 1e-12);
  // A window without rows fails with no value.
  s.from_s = 5.0;
  s.to_s = 6.0;
  expectOutcome(s, t, kNoValue, kFail);
}

// range = max - min within the window: how much the error still moves (convergence).
TEST(TaskErrorCheck, RangeOfTheSumInTheWindow) {
  const TraceTable t = twoTasks();
  CheckSpec s = taskErrorSpec(0.26, "range");
  s.from_s = 1.5;  // a + b goes from 0.35 to 0.1 over [1.5, 2]
  expectOutcome(s, t, {0.25, 1e-12}, kPass, {"smallest 0.1 at t = 2 s"});
  s.limit = 0.24;
  EXPECT_FALSE(runOne(s, t).passed);
  s.from_s = 0.0;  // the spike at 0.3 s (0.85 + 0.5) is the largest: 1.35 - 0.1
  s.limit = 2.0;
  EXPECT_NEAR(runOne(s, t).value, 1.25, 1e-12);
}

TEST(TaskErrorCheck, NonFiniteErrorsFailAndMissingChannelsAreInputErrors) {
  TraceTable t = twoTasks();
  t.rows[100][1] = std::numeric_limits<double>::quiet_NaN();
  CheckSpec s = spec("task_error", 100.0);
  auto& sp = s.params.emplace<TaskErrorParams>();
  sp.tasks = {"a"};
  sp.statistic = "max";
  EXPECT_FALSE(runOne(s, t).passed);
  sp.tasks = {"c"};
  try {
    runOne(s, t);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "synthetic.yaml:1: checks[0]")) << e.what();
    EXPECT_TRUE(contains(e.what(), "task.c.error")) << e.what();
  }
}

// -------------------------------------------------------------------------------------------
// frame_height

TEST(FrameHeightCheck, LowestHeightInTheWindowAndItsTime) {
  // z dips to 0.4 m at t = 0.2 s, then stays at 0.8 m.
  const TraceTable t = makeTrace({{frameChannel("WAIST", 'z'), [](double t) { return std::abs(t - 0.2) < 1e-9 ? 0.4 : 0.8; }}}, 0.01, 101);
  CheckSpec s = spec("frame_height", 0.5);
  auto& sp = s.params.emplace<FrameParams>();
  sp.frame = "WAIST";
  expectOutcome(s, t, 0.4, kFail, {"lowest at t = 0.2"});
  s.from_s = 0.25;
  expectOutcome(s, t, 0.8, kPass);
  s.limit = 0.8;  // equality passes (min_m is the lowest allowed height)
  EXPECT_TRUE(runOne(s, t).passed);
}

// -------------------------------------------------------------------------------------------
// torque_limits

// Joints J1 (limit 10 N m) and J2 (limit 20 N m); applied torques tau.* and commanded cmd.tau.*.
TraceTable torques(double cmd_j2_at_05, double applied_j1_at_07) {
  return makeTrace({{"tau.J1", [=](double t) { return std::abs(t - 0.7) < 1e-9 ? applied_j1_at_07 : 2.0; }},
                    {"tau.J2", constant(-4.0)},
                    {"cmd.tau.J1", constant(1.0)},
                    {"cmd.tau.J2", [=](double t) { return std::abs(t - 0.5) < 1e-9 ? cmd_j2_at_05 : -3.0; }}},
                   0.01, 101);
}

CheckSpec torqueSpec(const std::string& source, double limit_fraction) {
  CheckSpec s = spec("torque_limits", limit_fraction);
  auto& sp = s.params.emplace<TorqueLimitsParams>();
  sp.source = source;
  sp.joints = {"J1", "J2"};
  sp.joint_limits = {10.0, 20.0};
  return s;
}

TEST(TorqueLimitsCheck, ATorqueExactlyAtItsLimitPassesDespiteRoundOff) {
  // The controller's torque: the limit times (1 + 6.7e-16), as dt tau / dt comes out of the
  // solver when the torque-limit row is active (the reported failure: margin -6.7e-16).
  const double at_limit = -20.0 * (1.0 + 6.7e-16);
  ASSERT_GT(std::abs(at_limit), 20.0);
  CheckResult r = runOne(torqueSpec("commanded", 1.0), torques(at_limit, 2.0));
  EXPECT_TRUE(r.passed) << r.detail;
  EXPECT_GT(r.value, 1.0);
  EXPECT_TRUE(contains(r.detail, "commanded torque of J2")) << r.detail;
  EXPECT_TRUE(contains(r.detail, "at t = 0.5 s")) << r.detail;
  // Exactly at the limit: value 1.
  r = runOne(torqueSpec("commanded", 1.0), torques(-20.0, 2.0));
  EXPECT_EQ(r.value, 1.0);
  EXPECT_TRUE(r.passed);
  // Beyond the round-off allowance (1e-9 of the limit): fails.
  r = runOne(torqueSpec("commanded", 1.0), torques(-20.0 * (1.0 + 1e-8), 2.0));
  EXPECT_FALSE(r.passed) << r.detail;
  // A limit fraction below 1: 0.5 of the effort, the margin is reported against it.
  r = runOne(torqueSpec("commanded", 0.5), torques(-12.0, 2.0));
  EXPECT_NEAR(r.value, 0.6, 1e-15);
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(contains(r.detail, "margin -0.1")) << r.detail;
}

TEST(TorqueLimitsCheck, SourceSelectsAppliedCommandedOrBoth) {
  // Applied J1 reaches 11 N m (> 10) at 0.7 s; commanded J2 reaches 25 N m (> 20) at 0.5 s.
  const TraceTable t = torques(25.0, 11.0);
  CheckResult applied = runOne(torqueSpec("applied", 1.0), t);
  EXPECT_NEAR(applied.value, 1.1, 1e-15);
  EXPECT_FALSE(applied.passed);
  EXPECT_TRUE(contains(applied.detail, "applied torque of J1")) << applied.detail;
  EXPECT_TRUE(contains(applied.detail, "at t = 0.7 s")) << applied.detail;
  CheckResult commanded = runOne(torqueSpec("commanded", 1.0), t);
  EXPECT_NEAR(commanded.value, 1.25, 1e-15);
  EXPECT_TRUE(contains(commanded.detail, "commanded torque of J2")) << commanded.detail;
  CheckResult both = runOne(torqueSpec("both", 1.0), t);
  EXPECT_NEAR(both.value, 1.25, 1e-15);
  EXPECT_FALSE(both.passed);
  // Within limits: applied J1 2 / 10 and J2 -4 / 20 are the largest (commanded: 1 / 10, -3 / 20).
  const CheckResult ok = runOne(torqueSpec("both", 1.0), torques(-3.0, 2.0));
  EXPECT_NEAR(ok.value, 0.2, 1e-15);
  EXPECT_TRUE(ok.passed);
  // Missing commanded channels: an input error for commanded, fine for applied.
  TraceTable no_cmd = makeTrace({{"tau.J1", constant(1.0)}, {"tau.J2", constant(1.0)}}, 0.01, 3);
  EXPECT_TRUE(runOne(torqueSpec("applied", 1.0), no_cmd).passed);
  EXPECT_THROW(runOne(torqueSpec("commanded", 1.0), no_cmd), InputError);
}

// -------------------------------------------------------------------------------------------
// Contact checks: contact C with computed wrench.C.* and sensed wrench_sensed.C.* (contact
// frame), ctrl_contact.C.active.

struct WrenchRow {
  double f[3], m[3];
};

/// Computed wrench = `computed(t)`, sensed = `sensed(t)`; the contact is active for
/// t in [0.1, 0.8] (dt 0.01, t = 0 .. 1).
TraceTable contactTrace(const std::function<WrenchRow(double)>& computed, const std::function<WrenchRow(double)>& sensed) {
  std::vector<std::pair<std::string, Fn>> ch;
  ch.emplace_back(contactActiveChannel("C"), [](double t) { return (t > 0.1 - 1e-9 && t < 0.8 + 1e-9) ? 1.0 : 0.0; });
  const char* comp[6] = {"fx", "fy", "fz", "tx", "ty", "tz"};
  for (int k = 0; k < 6; ++k) {
    ch.emplace_back(wrenchChannel("C", false, comp[k]), [=](double t) {
      const WrenchRow w = computed(t);
      return k < 3 ? w.f[k] : w.m[k - 3];
    });
  }
  for (int k = 0; k < 6; ++k) {
    ch.emplace_back(wrenchChannel("C", true, comp[k]), [=](double t) {
      const WrenchRow w = sensed(t);
      return k < 3 ? w.f[k] : w.m[k - 3];
    });
  }
  return makeTrace(ch, 0.01, 101);
}

bool at(double t, double s) { return std::abs(t - s) < 1e-9; }

/// A contact check of contact C (the params struct of its type).
CheckSpec contactSpec(const std::string& type, double limit, const std::string& source = "computed") {
  CheckSpec s = spec(type, limit);
  ContactParams c;
  c.contact = "C";
  c.source = source;
  if (type == "contact_friction")
    s.params = ContactFrictionParams{c, 0.0, 1.0};
  else if (type == "contact_cop")
    s.params = ContactCopParams{c, {}, 1.0};
  else if (type == "contact_wrench_match")
    s.params = WrenchMatchParams{c.contact};
  else
    s.params = c;
  return s;
}

TEST(ContactUnilateralCheck, LowestNormalForceWhileActive) {
  // Computed: 100 N, except -5 N at t = 0.05 (contact inactive: ignored) and 3 N at t = 0.4.
  // Sensed: 50 N, except -1e-14 N (round-off around zero of a 100 N wrench) at t = 0.3.
  const TraceTable t = contactTrace(
      [](double t) {
        const double fz = at(t, 0.05) ? -5.0 : (at(t, 0.4) ? 3.0 : 100.0);
        return WrenchRow{{1.0, 0.0, fz}, {0, 0, 0}};
      },
      [](double t) {
        return at(t, 0.3) ? WrenchRow{{100.0, 0.0, -1e-14}, {0, 0, 0}} : WrenchRow{{0.0, 0.0, 50.0}, {0, 0, 0}};
      });
  CheckResult r = runOne(contactSpec("contact_unilateral", 0.0), t);
  EXPECT_EQ(r.value, 3.0);
  EXPECT_TRUE(r.passed);
  EXPECT_TRUE(contains(r.detail, "lowest computed normal force at t = 0.4 s")) << r.detail;
  r = runOne(contactSpec("contact_unilateral", 5.0), t);
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(contains(r.detail, "first below 5 N at t = 0.4 s")) << r.detail;
  // Sensed: -1e-14 N with |f| = 100 N is round-off (allowance 1e-9 |f|): passes min_N 0.
  r = runOne(contactSpec("contact_unilateral", 0.0, "sensed"), t);
  EXPECT_EQ(r.value, -1e-14);
  EXPECT_TRUE(r.passed) << r.detail;
  EXPECT_TRUE(contains(r.detail, "sensed normal force at t = 0.3 s")) << r.detail;
  // A real pull (-1 N) fails.
  const TraceTable pull = contactTrace(
      [](double t) {
        return WrenchRow{{0, 0, at(t, 0.6) ? -1.0 : 10.0}, {0, 0, 0}};
      },
      [](double) {
        return WrenchRow{{0, 0, 1}, {0, 0, 0}};
      });
  r = runOne(contactSpec("contact_unilateral", 0.0), pull);
  EXPECT_EQ(r.value, -1.0);
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(contains(r.detail, "at t = 0.6 s")) << r.detail;
}

TEST(ContactUnilateralCheck, NormalDirectionAndNoActiveRows) {
  // Normal along -x of the contact frame (e.g. a wall): f_n = -fx.
  const TraceTable t = contactTrace(
      [](double) {
        return WrenchRow{{-20.0, 0.0, 7.0}, {0, 0, 0}};
      },
      [](double) {
        return WrenchRow{{0, 0, 0}, {0, 0, 0}};
      });
  CheckSpec s = contactSpec("contact_unilateral", 15.0);
  auto& sp = s.paramsAs<ContactParams>();
  sp.normal[0] = -1.0;
  sp.normal[2] = 0.0;
  CheckResult r = expectOutcome(s, t, 20.0, kPass);
  // Window without active rows: no data is a failure.
  s.from_s = 0.85;
  expectOutcome(s, t, kNoValue, kFail, {"no row with contact 'C' active"});
}

TEST(ContactFrictionCheck, RatioToTheConeWithRoundOffOnItsSurface) {
  const double mu = 0.5;
  // On the cone's surface at t = 0.2 (one generator of the pyramid carries the force, computed
  // in a rotated frame: tangential = mu fn times (1 + 2 eps)); 1.2 mu at t = 0.5 for the
  // sensed wrench; f_n = 0.5 N (below min_normal_N) with a large tangential force at t = 0.6.
  const TraceTable t = contactTrace(
      [=](double t) {
        if (at(t, 0.2)) return WrenchRow{{0.6 * mu * 100.0 * (1.0 + 4e-16), 0.8 * mu * 100.0, 100.0}, {0, 0, 0}};
        if (at(t, 0.6)) return WrenchRow{{5.0, 0.0, 0.5}, {0, 0, 0}};
        return WrenchRow{{10.0, 0.0, 100.0}, {0, 0, 0}};
      },
      [=](double t) {
        return WrenchRow{{at(t, 0.5) ? 1.2 * mu * 80.0 : 0.0, 0.0, 80.0}, {0, 0, 0}};
      });
  CheckSpec s = contactSpec("contact_friction", 1.0);
  auto& sp = s.paramsAs<ContactFrictionParams>();
  sp.friction = mu;
  sp.min_normal_N = 1.0;
  expectOutcome(s, t, {1.0, 1e-15}, kPass, {"largest computed ratio at t = 0.2 s", "1 rows with f_n below 1 N skipped"});
  s.limit = 0.9;
  EXPECT_FALSE(runOne(s, t).passed);
  // With no minimum normal force the 0.5 N row counts: ratio 5 / (0.5 * 0.5) = 20.
  s.limit = 1.0;
  sp.min_normal_N = 0.0;
  expectOutcome(s, t, {20.0, 1e-12}, kFail, {"at t = 0.6 s"});
  // Sensed: 1.2 at t = 0.5.
  sp.source = "sensed";
  expectOutcome(s, t, {1.2, 1e-12}, kFail, {"largest sensed ratio at t = 0.5 s"});
}

TEST(ContactCopCheck, SignedDistanceToTheSupportPolygon) {
  // Sole 0.2 x 0.1 m centred on the contact frame's origin. CoP = (-ty / fz, tx / fz).
  // Computed: centre except (0.08, 0.0) at t = 0.3 (2 cm inside the front edge) and on the
  // front edge with round-off at t = 0.6; sensed: 1 cm outside the side at t = 0.4.
  const double fz = 200.0;
  const TraceTable t = contactTrace(
      [=](double t) {
        double x = 0.0;
        if (at(t, 0.3)) x = 0.08;
        if (at(t, 0.6)) x = 0.1 * (1.0 + 3e-16);
        return WrenchRow{{0, 0, fz}, {0.0, -x * fz, 0.0}};
      },
      [=](double t) {
        const double y = at(t, 0.4) ? 0.06 : 0.0;
        return WrenchRow{{0, 0, fz}, {y * fz, 0.0, 0.0}};
      });
  CheckSpec s = contactSpec("contact_cop", 0.0);
  auto& sp = s.paramsAs<ContactCopParams>();
  sp.polygon = {{-0.1, -0.05}, {0.1, -0.05}, {0.1, 0.05}, {-0.1, 0.05}};
  sp.min_normal_N = 10.0;
  // On the edge; limit 0: the edge is allowed, round-off included.
  expectOutcome(s, t, {0.0, 1e-15}, kPass, {"computed CoP (0.1, 0) m in the contact frame at t = 0.6 s"});
  s.limit = -0.01;  // at least 1 cm inside: the edge fails
  EXPECT_FALSE(runOne(s, t).passed);
  // Without the edge row the worst is 2 cm inside the front edge (or 5 cm from the sides).
  s.to_s = 0.55;
  expectOutcome(s, t, {-0.02, 1e-15}, kPass, {"at t = 0.3 s"});
  // Sensed: 1 cm outside.
  s.to_s = std::numeric_limits<double>::infinity();
  s.limit = 0.0;
  sp.source = "sensed";
  expectOutcome(s, t, {0.01, 1e-15}, kFail, {"sensed CoP (0, 0.06)", "at t = 0.4 s"});
}

TEST(ContactWrenchMatchCheck, RmsAndMaxOfTheDifferenceWhileActive) {
  // Computed and sensed forces differ by (3, 4, 0) N (norm 5) at t = 0.5 and by 1 N in z
  // elsewhere; a 100 N difference while inactive (t = 0.9) is ignored. Torques differ by 0.2 N m
  // in x throughout.
  const TraceTable t = contactTrace(
      [](double t) {
        if (at(t, 0.5)) return WrenchRow{{3.0, 4.0, 50.0}, {0.2, 0, 0}};
        if (at(t, 0.9)) return WrenchRow{{100.0, 0.0, 50.0}, {0.2, 0, 0}};
        return WrenchRow{{0.0, 0.0, 51.0}, {0.2, 0, 0}};
      },
      [](double) {
        return WrenchRow{{0.0, 0.0, 50.0}, {0.0, 0, 0}};
      });
  CheckSpec s = contactSpec("contact_wrench_match", 5.0);
  auto& sp = s.paramsAs<WrenchMatchParams>();
  sp.component = "force";
  sp.statistic = "max";
  expectOutcome(s, t, {5.0, 1e-15}, kPass, {"over 71 rows", "largest 5 at t = 0.5 s"});  // <= limit; t = 0.1 .. 0.8
  s.limit = 4.9;
  EXPECT_FALSE(runOne(s, t).passed);
  sp.statistic = "rms";  // sqrt((70 * 1 + 25) / 71)
  s.limit = 1.5;
  expectOutcome(s, t, {std::sqrt(95.0 / 71.0), 1e-14}, kPass);
  s.limit = 1.1;
  EXPECT_FALSE(runOne(s, t).passed);
  sp.component = "torque";
  s.limit = 0.21;
  expectOutcome(s, t, {0.2, 1e-15}, kPass);
  s.limit = 0.19;
  EXPECT_FALSE(runOne(s, t).passed);
}

// -------------------------------------------------------------------------------------------
// Oscillation

TEST(JointAccelerationSignChangesCheck, CountsPerSecondOfTheWorstJoint) {
  // Velocities over t = 0 .. 2 s: J1 = sin(2 pi 2 t + 0.3) (acceleration changes sign 4 times a
  // second: 8 changes), J2 = 0.01 sin(2 pi 5 t + 0.3) (20 changes of amplitude 0.01 * 2 pi 5 =
  // 0.31 rad/s^2), J3 constant. The commanded velocities (cmd.qd.*) are smooth: J1 ramps.
  const double pi = M_PI;
  const TraceTable t = makeTrace({{"qd.J1", [=](double t) { return std::sin(2 * pi * 2 * t + 0.3); }},
                                  {"qd.J2", [=](double t) { return 0.01 * std::sin(2 * pi * 5 * t + 0.3); }},
                                  {"qd.J3", constant(0.5)},
                                  {"cmd.qd.J1", [](double t) { return 0.1 * t; }},
                                  {"cmd.qd.J2", constant(0.0)},
                                  {"cmd.qd.J3", constant(0.0)}},
                                 0.005, 401);
  CheckSpec s = spec("joint_acceleration_sign_changes", 10.0);
  auto& sp = measuredJoints<JointSignChangesParams>(s, {"J1", "J2", "J3"});
  CheckResult r =
      expectOutcome(s, t, {20.0 / 2.0, 1e-12}, kPass, {"J2: 20 sign changes of the measured acceleration over 2 s"});  // 10 <= 10
  s.limit = 9.0;
  EXPECT_FALSE(runOne(s, t).passed);
  // A dead band above J2's amplitude leaves J1's 8 changes.
  sp.dead_band = 0.5;
  r = expectOutcome(s, t, {4.0, 1e-12}, kEither, {"J1: 8 sign changes"});
  EXPECT_TRUE(r.passed);
  // From 1 s on: J1 has 4 changes over 1 s.
  s.from_s = 1.0;
  EXPECT_NEAR(runOne(s, t).value, 4.0, 1e-12);
  // Commanded velocities: none.
  s.from_s = 0.0;
  sp.source = "commanded";
  expectOutcome(s, t, 0.0, kEither, {"commanded acceleration"});
}

TEST(JointVelocityHfEnergyCheck, EnergyAboveTheCutoff) {
  // J1 = 0.2 sin(2 pi 40 t) (above the 5 Hz cut-off: mean square 0.02 passes the filter),
  // J2 = sin(2 pi 0.5 t) (below: attenuated by (0.5 / 5)^4 = 1e-4), J3 constant.
  const double pi = M_PI;
  const TraceTable t = makeTrace({{"qd.J1", [=](double t) { return 0.2 * std::sin(2 * pi * 40 * t); }},
                                  {"qd.J2", [=](double t) { return std::sin(2 * pi * 0.5 * t); }},
                                  {"qd.J3", constant(3.0)}},
                                 0.005, 801);
  CheckSpec s = spec("joint_velocity_hf_energy", 0.03);
  auto& sp = measuredJoints<JointHfEnergyParams>(s, {"J1", "J2", "J3"});
  sp.cutoff_hz = 5.0;
  s.from_s = 1.0;  // after the filter's transient
  CheckResult r = runOne(s, t);
  // Butterworth gain at 40 Hz with fc = 5 Hz (bilinear, prewarped): |H|^2 = r^4 / (1 + r^4),
  // r = tan(pi 40 h) / tan(pi 5 h); J2 contributes about 0.5 * 1e-4.
  const double h = 0.005, ratio = std::tan(pi * 40 * h) / std::tan(pi * 5 * h);
  const double expected = 0.02 * std::pow(ratio, 4) / (1.0 + std::pow(ratio, 4));
  EXPECT_NEAR(r.value, expected, 0.01 * expected + 1e-4);
  EXPECT_TRUE(r.passed);
  EXPECT_TRUE(contains(r.detail, "largest share J1")) << r.detail;
  s.limit = 0.015;
  EXPECT_FALSE(runOne(s, t).passed);
  // Without J1: the slow sine and the constant stay below 1e-4.
  sp.joints = {"J2", "J3"};
  s.limit = 1e-4;
  r = runOne(s, t);
  EXPECT_LT(r.value, 1e-4);
  EXPECT_GT(r.value, 1e-6);
  EXPECT_TRUE(r.passed);
  sp.joints = {"J3"};
  EXPECT_EQ(runOne(s, t).value, 0.0);
  // A cut-off at or above the trace's Nyquist frequency (100 Hz) cannot be evaluated: failed, no value.
  sp.cutoff_hz = 100.0;
  expectOutcome(s, t, kNoValue, kFail, {"Nyquist"});
}

TEST(JointVelocityHfEnergyCheck, ARowAtAnotherSpacingIsLeftOut) {
  // The runner's last row (end of a run between two ticks) has another spacing.
  TraceTable t = makeTrace({{"qd.J1", constant(1.0)}}, 0.005, 201);
  t.rows.push_back({1.0025, 50.0});  // would be a huge step for the filter
  CheckSpec s = spec("joint_velocity_hf_energy", 1e-12);
  auto& sp = measuredJoints<JointHfEnergyParams>(s, {"J1"});
  sp.cutoff_hz = 5.0;
  const CheckResult r = expectOutcome(s, t, 0.0, kPass, {"1 rows at another spacing left out"});
}

TEST(TaskErrorRateSignChangesCheck, OscillatingErrorNorm) {
  // |e| = 1 + 0.1 sin(2 pi 1.5 t + 0.2) over 0 .. 2 s: d|e|/dt changes sign 3 times a second
  // (6 changes), with a rate of amplitude 0.1 * 2 pi 1.5 = 0.94 /s.
  const TraceTable t =
      makeTrace({{taskChannel("hand", "error"), [](double t) { return 1.0 + 0.1 * std::sin(2 * M_PI * 1.5 * t + 0.2); }}}, 0.005, 401);
  CheckSpec s = spec("task_error_rate_sign_changes", 3.0);
  auto& sp = s.params.emplace<TaskErrorRateParams>();
  sp.task = "hand";
  expectOutcome(s, t, {3.0, 1e-12}, kPass, {"6 sign changes of d/dt |e| of hand over 2 s"});
  s.limit = 2.9;
  EXPECT_FALSE(runOne(s, t).passed);
  sp.dead_band = 1.0;  // above the rate's amplitude: no sign at all
  EXPECT_EQ(runOne(s, t).value, 0.0);
  sp.task = "foot";  // not recorded
  EXPECT_THROW(runOne(s, t), InputError);
}

// -------------------------------------------------------------------------------------------
// PD response against the closed form (sec. V-A), overshoot

// |e| of a unit-mass PD x'' + kv x' + kp x = 0 from x(0) = 2, x'(0) = 0, by the exact solution:
// critically damped (kp 1, kv 2): 2 (1 + t) e^-t; under-damped (kp 0.5, kv 1): see below.
double critical(double t) { return 2.0 * (1.0 + t) * std::exp(-t); }
double underDamped(double t) {  // delta 0.5, wd 0.5: 2 e^{-t/2} (cos(t/2) + sin(t/2))
  return 2.0 * std::exp(-0.5 * t) * (std::cos(0.5 * t) + std::sin(0.5 * t));
}

// The task and the gains of the response a task_error_closed_form check compares with.
void setResponse(TaskClosedFormParams& sp, const std::string& task, double kp, double kv) {
  sp.task = task;
  sp.kp = kp;
  sp.kv = kv;
}

// A task_error_closed_form check of the task p with kp = 1, kv = 2 (critically damped).
CheckSpec closedFormSpec(double limit) {
  CheckSpec s = spec("task_error_closed_form", limit);
  setResponse(s.params.emplace<TaskClosedFormParams>(), "p", 1.0, 2.0);
  return s;
}

TEST(TaskErrorClosedFormCheck, MatchesTheCriticallyDampedResponseOfEq49) {
  const TraceTable t = makeTrace({{taskChannel("p", "error"), [](double t) { return critical(t); }},
                                  {taskChannel("q", "error"), [](double t) { return std::abs(underDamped(t)); }},
                                  {taskChannel("r", "error"), [](double t) { return critical(t) + (at(t, 3.0) ? 0.04 : 0.0); }}},
                                 0.01, 1001);
  CheckSpec s = closedFormSpec(1e-12);
  auto& sp = s.paramsAs<TaskClosedFormParams>();
  CheckResult r = runOne(s, t);
  EXPECT_LT(r.value, 1e-14);
  EXPECT_TRUE(r.passed) << r.detail;
  EXPECT_TRUE(contains(r.detail, "e0 2 at t = 0 s; kp 1, kv 2, damping ratio 1")) << r.detail;
  // A bump of 0.04 at t = 3 s: 2 % of the initial error, reported at its time.
  sp.task = "r";
  s.limit = 0.019;
  expectOutcome(s, t, {0.02, 1e-12}, kFail, {"largest at t = 3 s"});
  // The under-damped response (|x| after its zero crossing) is far from eq. 49 but is the
  // closed form with its own gains (eq. 51 for kp 1, kv 2, mu 1).
  sp.task = "q";
  s.limit = 0.01;
  r = runOne(s, t);
  EXPECT_GT(r.value, 0.05);
  EXPECT_FALSE(r.passed);
  sp.kp = 0.5;
  sp.kv = 1.0;
  r = runOne(s, t);
  EXPECT_LT(r.value, 1e-13);
  EXPECT_TRUE(r.passed);
  EXPECT_TRUE(contains(r.detail, "damping ratio 0.707107")) << r.detail;
  // Over-damped gains (kv 3): the response is slower than eq. 49.
  setResponse(sp, "p", 1.0, 3.0);
  EXPECT_GT(runOne(s, t).value, 0.05);
  // Eq. 49 with w = sqrt(kp) = 3 (kv = 6): (1 + 3 t) e^{-3 t}, and over-damped kp 1, kv 2.5:
  // roots -0.5 and -2, x = (4 e^{-t/2} - e^{-2 t}) / 3.
  const TraceTable u =
      makeTrace({{taskChannel("w3", "error"), [](double t) { return (1.0 + 3.0 * t) * std::exp(-3.0 * t); }},
                 {taskChannel("over", "error"), [](double t) { return (4.0 * std::exp(-0.5 * t) - std::exp(-2.0 * t)) / 3.0; }}},
                0.01, 501);
  setResponse(sp, "w3", 9.0, 6.0);
  s.limit = 1e-12;
  EXPECT_TRUE(runOne(s, u).passed) << runOne(s, u).detail;
  sp.kv = 5.0;
  EXPECT_FALSE(runOne(s, u).passed);
  setResponse(sp, "over", 1.0, 2.5);
  EXPECT_TRUE(runOne(s, u).passed) << runOne(s, u).detail;
  // Under-damped kp 1, kv 1 against an independent solution: RK4 on x'' = -kv x' - kp x
  // (step 1e-4 s, error ~1e-16), |x| sampled every 0.01 s.
  std::vector<double> xs;
  double x = 1.0, v = 0.0;
  const double h = 1e-4;
  auto acc = [](double x_, double v_) { return -v_ - x_; };
  for (int k = 0; k <= 100000; ++k) {
    if (k % 100 == 0) xs.push_back(std::abs(x));
    const double k1x = v, k1v = acc(x, v);
    const double k2x = v + 0.5 * h * k1v, k2v = acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
    const double k3x = v + 0.5 * h * k2v, k3v = acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
    const double k4x = v + h * k3v, k4v = acc(x + h * k3x, v + h * k3v);
    x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
  }
  const TraceTable rk =
      makeTrace({{taskChannel("u", "error"), [&](double t) { return xs[static_cast<size_t>(std::lround(t * 100.0))]; }}}, 0.01, 1001);
  setResponse(sp, "u", 1.0, 1.0);
  s.limit = 1e-10;
  EXPECT_TRUE(runOne(s, rk).passed) << runOne(s, rk).detail;
}

TEST(TaskErrorClosedFormCheck, TheWindowStartsTheResponse) {
  // The error is 2 until t = 1 s (target not yet moved), then the critically damped response.
  const TraceTable t =
      makeTrace({{taskChannel("p", "error"), [](double t) { return t < 1.0 - 1e-9 ? 2.0 : critical(t - 1.0); }}}, 0.01, 601);
  CheckSpec s = closedFormSpec(1e-9);
  EXPECT_FALSE(runOne(s, t).passed);  // from t = 0 the held error is not the response
  s.from_s = 1.0;
  CheckResult r = runOne(s, t);
  EXPECT_LT(r.value, 1e-12);
  EXPECT_TRUE(r.passed);
  EXPECT_TRUE(contains(r.detail, "e0 2 at t = 1 s")) << r.detail;
  // No initial error: nothing to compare, a failure without a value.
  const TraceTable zero = makeTrace({{taskChannel("p", "error"), constant(0.0)}}, 0.01, 11);
  s.from_s = 0.0;
  expectOutcome(s, zero, kNoValue, kFail);
}

TEST(TaskOvershootCheck, LargestRiseAboveTheRunningMinimum) {
  const TraceTable t = makeTrace({{taskChannel("mono", "error"), [](double t) { return critical(t); }},
                                  {taskChannel("over", "error"), [](double t) { return std::abs(underDamped(t)); }}},
                                 0.01, 2001);
  CheckSpec s = spec("task_overshoot", 1e-3);
  auto& sp = s.params.emplace<TaskOvershootParams>();
  sp.task = "mono";
  CheckResult r = expectOutcome(s, t, 0.0, kPass, {"the error never rises"});
  // Under-damped, damping ratio 1/sqrt(2): x = 2 e^{-t/2} (cos + sin)(t/2) crosses 0 at
  // t = 3 pi / 2 and reaches its most negative value at t = 2 pi: -2 e^{-pi} (4.3 % of x0).
  sp.task = "over";
  r = runOne(s, t);
  const double expected = std::exp(-M_PI);
  EXPECT_NEAR(r.value, expected, 2e-4);  // the sampled minimum is near, not at, the zero crossing
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(contains(r.detail, "largest rise at t = 6.28 s")) << r.detail;
  EXPECT_TRUE(contains(r.detail, "at t = 4.71 s")) << r.detail;  // the minimum, 3 pi / 2
  s.limit = 0.05;
  EXPECT_TRUE(runOne(s, t).passed);
  // From the window's start: after 7 s the under-damped response decays towards its second
  // zero crossing (at 7 pi / 2 = 11 s) and rises again to its next extremum (4 pi = 12.6 s).
  s.from_s = 7.0;
  r = runOne(s, t);
  EXPECT_GT(r.value, 0.0);
  EXPECT_TRUE(contains(r.detail, "e0")) << r.detail;
}

// -------------------------------------------------------------------------------------------
// Controller health

TEST(ControllerStatusCheck, CountsRowsWithStatusesNotAllowed) {
  // Codes (controllerStatusNames): 0 ok, 1 solver_stopped_early, 2 solver_iteration_limit,
  // 3 infeasible. Rows: ok, stopped early at 0.1, iteration limit at 0.3 and 0.4, infeasible at 0.9.
  const TraceTable t = makeTrace({{kControllerStatusChannel,
                                   [](double t) {
                                     if (at(t, 0.1)) return 1.0;
                                     if (at(t, 0.3) || at(t, 0.4)) return 2.0;
                                     if (at(t, 0.9)) return 3.0;
                                     return 0.0;
                                   }}},
                                 0.1, 11);
  ASSERT_EQ(controllerStatusNames()[2], "solver_iteration_limit");
  CheckSpec s = spec("controller_status", 0.0);
  auto& sp = s.params.emplace<ControllerStatusParams>();
  sp.allowed = {"ok", "solver_stopped_early"};
  expectOutcome(s, t, 3.0, kFail, {"first at t = 0.3 s (solver_iteration_limit)", "infeasible 1", "ok 7"});
  s.limit = 3.0;  // limit_count
  EXPECT_TRUE(runOne(s, t).passed);
  s.limit = 0.0;
  sp.allowed = {"ok", "solver_stopped_early", "solver_iteration_limit", "infeasible"};
  expectOutcome(s, t, 0.0, kPass);
  sp.allowed = {"ok"};
  s.to_s = 0.2;
  expectOutcome(s, t, 1.0, kEither, {"first at t = 0.1 s (solver_stopped_early)"});
  // A code outside the list is never allowed.
  TraceTable bad = t;
  bad.rows[5][1] = 17.0;
  s.to_s = std::numeric_limits<double>::infinity();
  sp.allowed = {"ok", "solver_stopped_early", "solver_iteration_limit", "infeasible", "non_finite"};
  expectOutcome(s, bad, 1.0, kEither, {"invalid(17)"});
  sp.allowed = {"fine"};
  EXPECT_THROW(runOne(s, t), InputError);
}

TEST(ActiveSetPeakCheck, LargestIterationCountAndItsTime) {
  const TraceTable t =
      makeTrace({{kSolverIterationsChannel, [](double t) { return at(t, 0.7) ? 31.0 : (at(t, 0.2) ? 12.0 : 2.0); }}}, 0.1, 11);
  CheckSpec s = spec("active_set_peak", 30.0);
  expectOutcome(s, t, 31.0, kFail, {"at t = 0.7 s"});
  s.limit = 31.0;
  EXPECT_TRUE(runOne(s, t).passed);
  s.to_s = 0.5;
  expectOutcome(s, t, 12.0, kEither, {"at t = 0.2 s"});
}

TEST(FactorizationPeakCheck, LargestStageCountAndItsTime) {
  const TraceTable t = makeTrace({{kSolverFactorizationsChannel, [](double t) { return at(t, 0.4) ? 194.0 : 9.0; }}}, 0.1, 11);
  CheckSpec s = spec("factorization_peak", 450.0);
  CheckResult r = expectOutcome(s, t, 194.0, kPass);
  EXPECT_FALSE(r.machine_dependent);
  EXPECT_TRUE(contains(r.detail, "at t = 0.4 s")) << r.detail;
  s.limit = 100.0;
  EXPECT_FALSE(runOne(s, t).passed);
  s.to_s = 0.3;
  EXPECT_EQ(runOne(s, t).value, 9.0);
}

TEST(AugmentedFractionCheck, FractionOfRowsAndTheMethodsFilter) {
  // Level "hands" augmented from t = 0.6 s: 5 of 11 rows (0.6 .. 1.0).
  const TraceTable t = makeTrace({{levelChannel("hands", "augmented"), [](double t) { return t > 0.55 ? 1.0 : 0.0; }}}, 0.1, 11,
                                 {{kMethodMetadata, "bfgs"}});
  CheckSpec s = spec("augmented_fraction", 0.5);
  auto& sp = s.params.emplace<AugmentedFractionParams>();
  sp.level = "hands";
  CheckResult r = expectOutcome(s, t, {5.0 / 11.0, 1e-15}, kPass, {"5 of 11 rows, first at t = 0.6 s"});
  s.limit = 0.4;
  EXPECT_FALSE(runOne(s, t).passed);
  s.limit = 0.0;
  s.to_s = 0.5;
  r = expectOutcome(s, t, 0.0, kPass);
  EXPECT_EQ(r.detail, "0 of 6 rows");
  // methods: the check applies to the listed methods only; runChecks leaves it out for others.
  s.methods = {"bfgs", "ah"};
  EXPECT_EQ(runChecks({s}, t).size(), 1u);
  TraceTable wls = t;
  wls.metadata = {{kMethodMetadata, "wls"}};
  EXPECT_TRUE(runChecks({s}, wls).empty());
  EXPECT_TRUE(appliesTo(s, "ah"));
  EXPECT_FALSE(appliesTo(s, "gn"));
  s.methods.clear();
  EXPECT_TRUE(appliesTo(s, "gn"));
  EXPECT_EQ(runChecks({s}, wls).size(), 1u);
}

TEST(TickTimeCheck, NearestRankPercentiles) {
  // Tick times 1 .. 100 us in a scrambled order.
  const TraceTable t = makeTrace({{timerChannel("tick"),
                                   [](double t) {
                                     const int k = static_cast<int>(std::lround(t * 100.0));
                                     return static_cast<double>((k * 37) % 100 + 1);
                                   }}},
                                 0.01, 100);
  CheckSpec s = spec("tick_time", 99.0);
  auto& sp = s.params.emplace<TickTimeParams>();
  sp.timer = "tick";
  sp.percentile = 99.0;
  CheckResult r = expectOutcome(s, t, 99.0, kPass, {"p99 of tick time over 100 ticks (max 100 us"});
  // A wall-clock measurement: labelled, and a verdict only when asked for.
  EXPECT_TRUE(r.machine_dependent);
  EXPECT_FALSE(r.decides);
  s.limit = 98.5;
  EXPECT_FALSE(runOne(s, t).passed);
  EXPECT_TRUE(allPassed(runChecks({s}, t)));
  EXPECT_FALSE(allPassed(runChecks({s}, t, true)));
  EXPECT_TRUE(runChecks({s}, t, true)[0].decides);
  sp.percentile = 50.0;
  EXPECT_EQ(runOne(s, t).value, 50.0);
  sp.percentile = 100.0;
  EXPECT_EQ(runOne(s, t).value, 100.0);
  sp.percentile = 0.5;  // rank ceil(0.5) = 1
  EXPECT_EQ(runOne(s, t).value, 1.0);
  sp.timer = "solver";
  EXPECT_THROW(runOne(s, t), InputError);
}

// -------------------------------------------------------------------------------------------
// method_comparison

TEST(MethodComparison, DifferenceOfTheStatisticsOfTwoMethods) {
  auto trace = [](const std::string& method, double final_error) {
    return makeTrace(
        {{taskChannel("r", "error"), [=](double t) { return final_error + (1.0 - t); }}, {taskChannel("l", "error"), constant(0.5)}}, 0.01,
        101, {{kMethodMetadata, method}});
  };
  ComparisonSpec c;
  c.name = "bfgs_not_worse";
  c.tasks = {"r", "l"};
  c.statistic = "final";
  c.better = "bfgs";
  c.worse = "wls";
  c.where = "synthetic.yaml:9: comparisons[0]";
  CheckResult r = compareMethods(c, trace("bfgs", 1.0), trace("wls", 1.2));
  EXPECT_NEAR(r.value, -0.2, 1e-12);
  EXPECT_TRUE(r.passed);
  EXPECT_TRUE(contains(r.detail, "final bfgs 1.5, wls 1.7")) << r.detail;
  r = compareMethods(c, trace("bfgs", 1.3), trace("wls", 1.2));
  EXPECT_NEAR(r.value, 0.1, 1e-12);
  EXPECT_FALSE(r.passed);
  c.margin = 0.1 + 1e-12;
  EXPECT_TRUE(compareMethods(c, trace("bfgs", 1.3), trace("wls", 1.2)).passed);
  // Equal results pass with margin 0.
  c.margin = 0.0;
  EXPECT_TRUE(compareMethods(c, trace("bfgs", 1.2), trace("wls", 1.2)).passed);
  // mean over a window: the difference of the constants.
  c.statistic = "mean";
  c.from_s = 0.5;
  EXPECT_NEAR(compareMethods(c, trace("bfgs", 1.0), trace("wls", 1.25)).value, -0.25, 1e-12);
  // The traces must be of the named methods.
  EXPECT_THROW(compareMethods(c, trace("ah", 1.0), trace("wls", 1.2)), InputError);
  // An empty window fails.
  c.from_s = 10.0;
  r = compareMethods(c, trace("bfgs", 1.0), trace("wls", 1.2));
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(std::isnan(r.value));
}

}  // namespace
}  // namespace lexdyn::checks
