// Trace files (round trip, partial file on interruption) and the checks on synthetic traces
// whose answers are known.
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

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace lexdyn::checks {
namespace {

namespace fs = std::filesystem;
using testing::kFail;
using testing::kNoValue;
using testing::kPass;

CheckSpec legacy(const std::string& name, const std::string& type, const std::string& frame, const std::vector<std::string>& surfaces,
                 double from_s, double limit, const std::string& where) {
  CheckSpec s;
  s.name = name;
  s.type = type;
  if (frame.empty())
    s.params = SurfacesParams{surfaces};
  else
    s.params = FrameParams{frame};
  s.from_s = from_s;
  s.limit = limit;
  s.where = where;
  return s;
}

std::string tempDir(const std::string& name) {
  const fs::path p = fs::path(LEXDYN_BINARY_DIR) / "test_output" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

TEST(Trace, RoundTripIsBitExactAndRenamedOnFinish) {
  const std::string dir = tempDir("trace_roundtrip");
  TraceSchema schema;
  schema.add("t");
  schema.add("a.b");
  schema.add("c");
  const std::string path = dir + "/trace.csv";
  const double rows[3][3] = {{0.0, 0.1, -1e-300}, {0.005, 1.0 / 3.0, 123456789.123456789}, {0.01, -0.0, 6.02214076e23}};
  {
    TraceWriter w(path, schema, {{"case", "unit test"}, {"robot_weight_N", "637.65"}}, 2);
    for (const auto& r : rows) w.write(r);
    EXPECT_TRUE(fs::exists(path + ".partial"));
    EXPECT_FALSE(fs::exists(path));
    w.finish();
  }
  EXPECT_FALSE(fs::exists(path + ".partial"));
  const TraceTable t = readTrace(path);
  ASSERT_EQ(t.names, schema.names());
  ASSERT_EQ(t.rows.size(), 3u);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(t.rows[static_cast<size_t>(i)][static_cast<size_t>(j)], rows[i][j]);
  ASSERT_NE(findMetadata(t.metadata, "case"), nullptr);
  EXPECT_EQ(*findMetadata(t.metadata, "case"), "unit test");
}

// The writer reuses a channel's text when its value keeps the same bits from one row to the
// next: every line must still be each value's own shortest form, whether repeated, changed by
// the sign of a zero only, or not a number.
TEST(Trace, RepeatedValuesAreWrittenAsTheirOwnShortestForm) {
  const std::string dir = tempDir("trace_repeats");
  TraceSchema schema;
  for (const char* name : {"a", "b", "c", "d"}) schema.add(name);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::vector<double>> rows = {{0.0, 1.5, nan, -2.2250738585072014e-308},
                                                 {0.0, 1.5, nan, -2.2250738585072014e-308},
                                                 {-0.0, 1.5000000000000002, 1.0, 1e+22},
                                                 {-0.0, 1.5, 1.0, 100000.0},
                                                 {0.0, 1.5, nan, 100000.0}};
  const std::string path = dir + "/trace.csv";
  {
    TraceWriter w(path, schema, {}, 1);
    for (const auto& r : rows) w.write(r.data());
    w.finish();
  }
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> data;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') data.push_back(line);
  }
  ASSERT_EQ(data.size(), rows.size() + 1);  // the names, then the rows
  for (size_t i = 0; i < rows.size(); ++i) {
    std::string expected;
    for (size_t j = 0; j < rows[i].size(); ++j) {
      char buf[32];
      const auto r = std::to_chars(buf, buf + sizeof buf, rows[i][j]);
      expected += std::string(buf, r.ptr) + (j + 1 < rows[i].size() ? "," : "");
    }
    EXPECT_EQ(data[i + 1], expected) << "row " << i;
  }
  EXPECT_EQ(data[4], "-0,1.5,1,1e+05");
}

TEST(Trace, UnfinishedWriterLeavesThePartialFileWithFlushedRows) {
  const std::string dir = tempDir("trace_partial");
  TraceSchema schema;
  schema.add("t");
  const std::string path = dir + "/trace.csv";
  {
    TraceWriter w(path, schema, {}, 1);
    const double r = 1.5;
    w.write(&r);
    // Flushed after every row: readable while the writer is still open.
    EXPECT_EQ(readTrace(path + ".partial").rows.size(), 1u);
  }  // destroyed without finish(), e.g. by an exception
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(readTrace(path + ".partial").rows.size(), 1u);
}

TEST(Trace, ACutLastRowIsDroppedFromAPartialTraceOnly) {
  // A killed run can stop in the middle of a row (the writer's buffer is flushed when full).
  const std::string dir = tempDir("trace_cut");
  const std::string text = "# a: b\nt,x\n0,1\n0.005,2\n0.01,3";  // no newline after the last row
  std::ofstream(dir + "/trace.csv.partial") << text;
  const TraceTable t = readTrace(dir + "/trace.csv.partial");
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[1][1], 2.0);
  std::ofstream(dir + "/trace.csv") << text;
  try {
    readTrace(dir + "/trace.csv");
    FAIL() << "a finished trace with a cut last line must be an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("trace.csv:5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no newline"), std::string::npos) << e.what();
  }
  // A complete last line (with its newline) is kept in both.
  std::ofstream(dir + "/whole.csv.partial") << text << "\n";
  EXPECT_EQ(readTrace(dir + "/whole.csv.partial").rows.size(), 3u);
}

// A trace says by itself whether its run completed: the writer's end mark, read back; a trace
// without it (a cut .partial file, or not written by a finished run) is not complete.
TEST(Trace, TheEndMarkSaysWhetherTheRunCompleted) {
  const std::string dir = tempDir("trace_end_mark");
  TraceSchema schema;
  schema.add("t");
  const double r0 = 0.0, r1 = 0.005;
  {
    TraceWriter w(dir + "/done.csv", schema, {}, 1);
    w.write(&r0);
    w.finish();
  }
  TraceTable t = readTrace(dir + "/done.csv");
  EXPECT_TRUE(t.complete());
  EXPECT_EQ(t.end_status, lexdyn::records::RunStatus::Completed);
  {
    TraceWriter w(dir + "/stopped.csv", schema, {}, 1);
    w.write(&r0);
    w.write(&r1);
    w.finish(lexdyn::records::RunStatus::IntegratorFailure, "CVODE stopped\nat t = 0.005 s");
  }
  t = readTrace(dir + "/stopped.csv");
  EXPECT_FALSE(t.complete());
  EXPECT_EQ(t.end_status, lexdyn::records::RunStatus::IntegratorFailure);
  EXPECT_EQ(t.end_message, "CVODE stopped at t = 0.005 s");  // newlines become spaces
  EXPECT_NE(t.completeness().find("the run did not complete: integrator_failure (CVODE stopped"), std::string::npos);
  std::ofstream(dir + "/cut.csv.partial") << "t\n0\n0.005\n";
  t = readTrace(dir + "/cut.csv.partial");
  EXPECT_FALSE(t.complete());
  EXPECT_NE(t.completeness().find("no end mark"), std::string::npos);
  // Nothing may follow the mark, and no header line may follow the channel names.
  std::ofstream(dir + "/after.csv") << "t\n0\n# end: completed\n0.005\n";
  EXPECT_THROW(readTrace(dir + "/after.csv"), InputError);
  std::ofstream(dir + "/header.csv") << "t\n0\n# case: x\n";
  EXPECT_THROW(readTrace(dir + "/header.csv"), InputError);
}

// The time channel orders every row a check sees: it must be finite, >= 0, strictly increasing,
// on the header's tick grid (but for a failed run's last state) and within its duration.
TEST(Trace, TheTimeChannelIsValidated) {
  const std::string dir = tempDir("trace_time");
  const std::string head = "# control_period_s: 0.005\n# duration_s: 0.02\nt,x\n";
  auto error = [&](const std::string& rows) {
    std::ofstream(dir + "/t.csv") << head << rows;
    try {
      readTrace(dir + "/t.csv");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error("0,1\n0.005,2\n0.01,3\n# end: completed\n"), "");
  EXPECT_NE(error("0,1\nnan,2\n").find("t.csv:5: time 't': expected a finite time >= 0 s, found nan"), std::string::npos);
  EXPECT_NE(error("0,1\n0.01,2\n0.005,3\n").find("t.csv:6: time 't': rows must be in strictly increasing time"), std::string::npos);
  EXPECT_NE(error("0,1\n0.005,2\n0.005,3\n").find("strictly increasing"), std::string::npos);
  EXPECT_NE(error("0,1\n1e9,2\n").find("1e9 s is beyond the header's duration"), std::string::npos);
  EXPECT_NE(error("0,1\n0.0051,2\n0.01,3\n").find("t.csv:5: time 't': not a tick of the header's control period"), std::string::npos);
  // The last state of a failed run may fall between ticks; of a completed run it may not.
  EXPECT_EQ(error("0,1\n0.005,2\n0.0061,3\n# end: integrator_failure: CVODE stopped\n"), "");
  EXPECT_NE(error("0,1\n0.005,2\n0.0061,3\n# end: completed\n").find("the last row is not a tick"), std::string::npos);
  // Values as the writer writes them: no hexadecimal, no spaces, nothing out of range.
  EXPECT_NE(error("0,0x10\n").find("not a number: '0x10'"), std::string::npos);
  EXPECT_NE(error("0, 1\n").find("not a number: ' 1'"), std::string::npos);
  EXPECT_NE(error("0,1e999\n").find("not a number: '1e999'"), std::string::npos);
  EXPECT_EQ(error("0,nan\n0.005,-inf\n"), "");
}

TEST(Trace, MalformedFilesAreErrorsWithLineNumbers) {
  const std::string dir = tempDir("trace_bad");
  const std::string path = dir + "/bad.csv";
  std::ofstream(path) << "# a: b\nt,x\n0,1\n0.005,oops\n";
  try {
    readTrace(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'x'"), std::string::npos) << e.what();
  }
}

TEST(Trace, DuplicateOrInvalidChannelNamesAreInputErrors) {
  // Checks rebuild a schema from the names: a malformed header must be an input error, not an abort.
  const std::string dir = tempDir("trace_bad_names");
  std::ofstream(dir + "/dup.csv") << "# a: b\nt,x,x\n0,1,2\n";
  try {
    readTrace(dir + "/dup.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("dup.csv:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("duplicate channel name 'x'"), std::string::npos) << e.what();
  }
  std::ofstream(dir + "/empty.csv") << "t,,y\n0,1,2\n";
  EXPECT_THROW(readTrace(dir + "/empty.csv"), InputError);
}

// A synthetic trace: WAIST moves 1 mm in x after 2 s, foot point p1 slides 0.3 mm, the
// vertical forces sum to the weight except a 1 % dip at t = 3 s, HEAD sinks from 1.5 m to 0.7 m.
TraceTable synthetic() {
  TraceTable t;
  t.metadata = {{kWeightMetadata, "600"}};
  t.names = {"t",
             frameChannel("WAIST", 'x'),
             frameChannel("WAIST", 'y'),
             frameChannel("WAIST", 'z'),
             contactForceChannel("R"),
             contactForceChannel("L"),
             contactPointChannel("R", 0, 'x'),
             contactPointChannel("R", 0, 'y'),
             contactPointChannel("R", 1, 'x'),
             contactPointChannel("R", 1, 'y'),
             frameChannel("HEAD", 'z')};
  for (int k = 0; k <= 400; ++k) {
    const double time = 0.01 * k;
    const double wx = time > 2.0 ? 0.001 : 0.0;
    const double fr = (k == 300) ? 294.0 : 300.0;
    const double slide = time > 1.0 ? 0.0003 * std::min(1.0, time - 1.0) : 0.0;
    t.rows.push_back({time, wx, 0.0, 0.8, fr, 300.0, 0.1, 0.2, 0.3 + slide, 0.2, 1.5 - 0.2 * time});
  }
  return t;
}

TEST(Checks, KnownValuesOnASyntheticTrace) {
  const TraceTable t = synthetic();
  std::vector<CheckSpec> specs(6);
  specs[0] = legacy("drift", "frame_drift", "WAIST", {}, 0.5, 0.002, "test");
  specs[1] = legacy("drift_tight", "frame_drift", "WAIST", {}, 0.5, 0.0005, "test");
  specs[2] = legacy("balance", "force_balance", "", {"R", "L"}, 0.0, 0.0101, "test");
  specs[3] = legacy("slip", "contact_slip", "", {"R"}, 0.0, 0.0005, "test");
  specs[4] = legacy("slip_late", "contact_slip", "", {"R"}, 2.5, 0.0001, "test");
  specs[5] = legacy("height", "frame_height", "HEAD", {}, 0.0, 0.75, "test");
  const std::vector<CheckResult> r = runChecks(specs, t);
  ASSERT_EQ(r.size(), 6u);
  EXPECT_NEAR(r[0].value, 0.001, 1e-15);
  EXPECT_TRUE(r[0].passed);
  EXPECT_FALSE(r[1].passed);
  EXPECT_NEAR(r[2].value, 0.01, 1e-12);  // (600 - 594) / 600
  EXPECT_TRUE(r[2].passed);
  EXPECT_NEAR(r[3].value, 0.0003, 1e-12);
  EXPECT_TRUE(r[3].passed);
  EXPECT_NEAR(r[4].value, 0.0, 1e-15);  // measured from its own start at 2.5 s
  EXPECT_TRUE(r[4].passed);
  EXPECT_NEAR(r[5].value, 0.7, 1e-12);
  EXPECT_FALSE(r[5].passed);  // went below 0.75 m
}

TEST(Checks, NoRowsAfterFromIsAFailureNotAPass) {
  const TraceTable t = synthetic();
  const std::vector<CheckResult> r = runChecks({legacy("late", "frame_drift", "WAIST", {}, 100.0, 1.0, "test")}, t);
  EXPECT_FALSE(r[0].passed);
  EXPECT_TRUE(std::isnan(r[0].value));
}

TEST(Checks, MissingChannelsAndMetadataAreInputErrors) {
  TraceTable t = synthetic();
  EXPECT_THROW(runChecks({legacy("x", "frame_drift", "FOOT", {}, 0.0, 1.0, "case.yaml:3")}, t), InputError);
  t.metadata.clear();
  EXPECT_THROW(runChecks({legacy("x", "force_balance", "", {"R"}, 0.0, 1.0, "case.yaml:4")}, t), InputError);
}

}  // namespace
}  // namespace lexdyn::checks

// --- Controller checks (harness/checks/*_checks.cpp) on a synthetic trace ---------

namespace lexdyn::checks {
namespace {

// 401 rows, t = 0 .. 4 s every 0.01 s, channels with known answers.
TraceTable controllerTrace() {
  TraceTable t;
  t.metadata = {{"method", "bfgs"}};
  t.names = {"t", "task.a.error", "task.b.error", "task.c.error", "tau.J1", "cmd.tau.J1", "ctrl_contact.C.active"};
  for (const char* p : {"wrench.C.", "wrench_sensed.C."}) {
    for (const char* c : {"fx", "fy", "fz", "tx", "ty", "tz"}) t.names.push_back(std::string(p) + c);
  }
  for (const char* n :
       {"qd.J1", "qd.J2", "cmd.qd.J1", "cmd.qd.J2", "ctrl.status", "solver.iterations", "level.L.augmented", "time.tick_us"}) {
    t.names.push_back(n);
  }
  for (int k = 0; k <= 400; ++k) {
    const double time = 0.01 * k;
    const bool active = time >= 1.0 - 1e-9 && time <= 3.0 + 1e-9;
    std::vector<double> r = {
        time, 1.0 - 0.1 * time, 0.5, 1.0 + 0.5 * std::sin(M_PI * time), 50.0 * std::sin(time), k == 200 ? 60.0 : 10.0, active ? 1.0 : 0.0};
    // Computed: f = (30, 40, 100), torque (5, -2, 0): CoP (0.02, 0.05). Inactive rows: garbage.
    const double cw[6] = {30, 40, 100, 5, -2, 0};
    const double sensed_fz = time < 2.0 - 1e-9 ? 90.0 : 110.0;
    for (int i = 0; i < 6; ++i) r.push_back(active ? cw[i] : -1000.0);
    for (int i = 0; i < 6; ++i) r.push_back(active ? (i == 2 ? sensed_fz : cw[i]) : -1000.0);
    r.push_back(std::sin(2.0 * M_PI * 2.1 * time));   // qd.J1: acceleration sign changes
    r.push_back(0.1 * time);                          // qd.J2: constant acceleration
    r.push_back(std::sin(2.0 * M_PI * 20.0 * time));  // cmd.qd.J1: 20 Hz
    r.push_back(std::sin(2.0 * M_PI * 0.5 * time));   // cmd.qd.J2: 0.5 Hz
    r.push_back(k == 300 ? 3.0 : (k % 50 == 0 ? 1.0 : 0.0));
    r.push_back(k == 250 ? 17.0 : 1.0);
    r.push_back(time >= 3.0 - 1e-9 ? 1.0 : 0.0);
    r.push_back(static_cast<double>(k));
    t.rows.push_back(r);
  }
  return t;
}

CheckSpec spec(const std::string& type, double limit) {
  CheckSpec s;
  s.name = type;
  s.type = type;
  s.limit = limit;
  s.where = "test";
  return s;
}

CheckResult one(const CheckSpec& s) { return testing::runOne(s, controllerTrace()); }

/// testing::expectOutcome on controllerTrace().
CheckResult expectOne(const CheckSpec& s, testing::Expected value, testing::Verdict verdict,
                      std::initializer_list<std::string> detail = {}) {
  return testing::expectOutcome(s, controllerTrace(), value, verdict, detail);
}

TEST(ControllerChecks, TaskErrorStatistics) {
  CheckSpec s = spec("task_error", 1.2);
  auto& sp = s.params.emplace<TaskErrorParams>();
  sp.tasks = {"a", "b"};
  sp.statistic = "final";
  expectOne(s, {1.1, 1e-12}, kPass);
  sp.statistic = "max";
  expectOne(s, {1.5, 1e-12}, kFail);
  sp.statistic = "mean";  // time average of 1.5 - 0.1 t over [0, 4]
  EXPECT_NEAR(one(s).value, 1.3, 1e-12);
  s.from_s = 2.0;
  s.to_s = 3.0;  // 1.5 - 0.25
  EXPECT_NEAR(one(s).value, 1.25, 1e-12);
}

TEST(ControllerChecks, TorqueLimits) {
  CheckSpec s = spec("torque_limits", 0.55);
  auto& sp = s.params.emplace<TorqueLimitsParams>();
  sp.joints = {"J1"};
  sp.joint_limits = {100.0};
  sp.source = "applied";
  expectOne(s, {0.5, 1e-4}, kPass);  // 50 sin(t) peaks near t = pi / 2
  sp.source = "both";
  expectOne(s, {0.6, 1e-12}, kFail, {"commanded torque of J1 60"});  // commanded 60 N m at t = 2
  s.limit = 0.6;                                                     // on the limit passes
  EXPECT_TRUE(one(s).passed);
}

TEST(ControllerChecks, ContactWrenches) {
  CheckSpec s = spec("contact_unilateral", 95.0);
  auto& sp = s.params.emplace<ContactParams>();
  sp.contact = "C";
  sp.source = "computed";
  expectOne(s, 100.0, kPass);  // inactive rows (-1000) are skipped
  sp.source = "sensed";
  expectOne(s, 90.0, kFail);
  CheckSpec f = spec("contact_friction", 1.0);
  auto& fp = f.params.emplace<ContactFrictionParams>();
  fp.contact = "C";
  fp.source = "computed";
  fp.friction = 0.7;
  fp.min_normal_N = 1.0;
  EXPECT_NEAR(one(f).value, 50.0 / 70.0, 1e-12);
  fp.friction = 0.4;
  expectOne(f, {50.0 / 40.0, 1e-12}, kFail);
  CheckSpec c = spec("contact_cop", 0.0);
  auto& cp = c.params.emplace<ContactCopParams>();
  cp.contact = "C";
  cp.source = "computed";
  cp.min_normal_N = 1.0;
  cp.polygon = {{-0.1, -0.1}, {0.1, -0.1}, {0.1, 0.1}, {-0.1, 0.1}};
  expectOne(c, {-0.05, 1e-12}, kPass);  // CoP (0.02, 0.05): 5 cm inside the y = 0.1 edge
  cp.polygon = {{-0.1, -0.1}, {0.1, -0.1}, {0.1, 0.03}, {-0.1, 0.03}};
  expectOne(c, {0.02, 1e-12}, kFail);  // 2 cm outside
  CheckSpec m = spec("contact_wrench_match", 9.0);
  auto& mp = m.params.emplace<WrenchMatchParams>();
  mp.contact = "C";
  mp.component = "force";
  mp.statistic = "rms";
  expectOne(m, {10.0, 1e-12}, kFail);
  mp.component = "torque";
  EXPECT_EQ(one(m).value, 0.0);
}

TEST(ControllerChecks, Oscillation) {
  CheckSpec a = spec("joint_acceleration_sign_changes", 4.0);
  auto& ap = testing::measuredJoints<JointSignChangesParams>(a, {"J1", "J2"});
  ap.dead_band = 1e-6;
  // cos(2 pi 2.1 t) changes sign at (2n + 1) / 8.4 s: 17 times between the first and the last
  // velocity difference (t = 0.005 .. 3.995 s), over 4 s.
  expectOne(a, {17.0 / 4.0, 1e-12}, kFail, {"J1: 17"});
  ap.joints = {"J2"};
  EXPECT_EQ(one(a).value, 0.0);
  CheckSpec h = spec("joint_velocity_hf_energy", 0.1);
  auto& hp = h.params.emplace<JointHfEnergyParams>();
  hp.joints = {"J1"};
  hp.source = "commanded";
  hp.cutoff_hz = 5.0;
  // A unit 20 Hz sine passes the 5 Hz high-pass almost unchanged: mean square ~ 1/2.
  expectOne(h, {0.5, 0.03}, kFail);
  hp.joints = {"J2"};  // 0.5 Hz: attenuated by about (0.5 / 5)^4
  EXPECT_LT(one(h).value, 1e-3);
  hp.cutoff_hz = 60.0;  // above the trace's Nyquist frequency (50 Hz)
  expectOne(h, kNoValue, kFail);
  CheckSpec e = spec("task_error_rate_sign_changes", 0.5);
  auto& ep = e.params.emplace<TaskErrorRateParams>();
  ep.task = "c";
  ep.dead_band = 1e-6;
  expectOne(e, {1.0, 1e-12}, kFail);  // 1 + sin(pi t)/2 turns at t = 0.5, 1.5, 2.5, 3.5
  ep.task = "a";
  EXPECT_EQ(one(e).value, 0.0);
}

TEST(ControllerChecks, Health) {
  CheckSpec s = spec("controller_status", 0.0);
  auto& sp = s.params.emplace<ControllerStatusParams>();
  sp.allowed = {"ok", "solver_stopped_early"};
  expectOne(s, 1.0, kFail, {"first at t = 3 s (infeasible)"});
  sp.allowed = {"ok"};
  EXPECT_EQ(one(s).value, 9.0);  // 8 rows stopped early besides
  CheckSpec p = spec("active_set_peak", 17.0);
  expectOne(p, 17.0, kPass);
  CheckSpec a = spec("augmented_fraction", 0.2);
  auto& ap = a.params.emplace<AugmentedFractionParams>();
  ap.level = "L";
  expectOne(a, {101.0 / 401.0, 1e-15}, kFail);
  CheckSpec t = spec("tick_time", 300.0);
  auto& tp = t.params.emplace<TickTimeParams>();
  tp.timer = "tick";
  tp.percentile = 50.0;
  EXPECT_EQ(one(t).value, 200.0);
  tp.percentile = 100.0;
  expectOne(t, 400.0, kFail);
}

TEST(ControllerChecks, MethodFilterAndComparisons) {
  CheckSpec s = spec("active_set_peak", 100.0);
  s.methods = {"wls"};
  EXPECT_TRUE(runChecks({s}, controllerTrace()).empty());  // a bfgs trace
  s.methods = {"wls", "bfgs"};
  EXPECT_EQ(runChecks({s}, controllerTrace()).size(), 1u);
  TraceTable bfgs = controllerTrace(), wls = controllerTrace();
  wls.metadata = {{"method", "wls"}};
  for (auto& row : wls.rows) row[1] += 0.2;  // task a worse by 0.2
  ComparisonSpec c;
  c.name = "cmp";
  c.tasks = {"a"};
  c.statistic = "final";
  c.better = "bfgs";
  c.worse = "wls";
  CheckResult r = compareMethods(c, bfgs, wls);
  EXPECT_NEAR(r.value, -0.2, 1e-12);
  EXPECT_TRUE(r.passed);
  c.better = "wls";
  c.worse = "bfgs";
  r = compareMethods(c, wls, bfgs);
  EXPECT_NEAR(r.value, 0.2, 1e-12);
  EXPECT_FALSE(r.passed);
  EXPECT_THROW(compareMethods(c, bfgs, wls), InputError);  // the traces' methods do not match
}

TEST(ControllerChecks, MissingChannelsAreInputErrors) {
  CheckSpec s = spec("task_error", 1.0);
  auto& sp = s.params.emplace<TaskErrorParams>();
  sp.tasks = {"nope"};
  sp.statistic = "final";
  s.where = "case.yaml:9";
  try {
    one(s);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("case.yaml:9: check 'task_error' needs trace channel 'task.nope.error'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lexdyn::checks
