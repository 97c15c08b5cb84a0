// Trace files (round trip, partial file on interruption) and the checks on synthetic traces
// whose answers are known.
#include "harness/checks/checks.hpp"
#include "harness/checks/trace.hpp"
#include "lexdyn/common/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

namespace lexdyn::checks {
namespace {

namespace fs = std::filesystem;

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

// A synthetic trace: WAIST moves 1 mm in x after 2 s, foot point p1 slides 0.3 mm, the
// vertical forces sum to the weight except a 1 % dip at t = 3 s, HEAD sinks from 1.5 m to 0.7 m.
TraceTable synthetic() {
  TraceTable t;
  t.metadata = {{kWeightMetadata, "600"}};
  t.names = {"t", frameChannel("WAIST", 'x'), frameChannel("WAIST", 'y'), frameChannel("WAIST", 'z'),
             contactForceChannel("R"), contactForceChannel("L"), contactPointChannel("R", 0, 'x'),
             contactPointChannel("R", 0, 'y'), contactPointChannel("R", 1, 'x'), contactPointChannel("R", 1, 'y'),
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
  specs[0] = {"drift", "frame_drift", "WAIST", {}, 0.5, 0.002, "test"};
  specs[1] = {"drift_tight", "frame_drift", "WAIST", {}, 0.5, 0.0005, "test"};
  specs[2] = {"balance", "force_balance", "", {"R", "L"}, 0.0, 0.0101, "test"};
  specs[3] = {"slip", "contact_slip", "", {"R"}, 0.0, 0.0005, "test"};
  specs[4] = {"slip_late", "contact_slip", "", {"R"}, 2.5, 0.0001, "test"};
  specs[5] = {"height", "frame_height", "HEAD", {}, 0.0, 0.75, "test"};
  const std::vector<CheckResult> r = runChecks(specs, t);
  ASSERT_EQ(r.size(), 6u);
  EXPECT_NEAR(r[0].value, 0.001, 1e-15);
  EXPECT_TRUE(r[0].passed);
  EXPECT_FALSE(r[1].passed);
  EXPECT_NEAR(r[2].value, 0.01, 1e-12);  // (600 - 594) / 600
  EXPECT_TRUE(r[2].passed);
  EXPECT_NEAR(r[3].value, 0.0003, 1e-12);
  EXPECT_TRUE(r[3].passed);
  EXPECT_NEAR(r[4].value, 0.0, 1e-15);   // measured from its own start at 2.5 s
  EXPECT_TRUE(r[4].passed);
  EXPECT_NEAR(r[5].value, 0.7, 1e-12);
  EXPECT_FALSE(r[5].passed);  // went below 0.75 m
}

TEST(Checks, NoRowsAfterFromIsAFailureNotAPass) {
  const TraceTable t = synthetic();
  const std::vector<CheckResult> r = runChecks({{"late", "frame_drift", "WAIST", {}, 100.0, 1.0, "test"}}, t);
  EXPECT_FALSE(r[0].passed);
  EXPECT_TRUE(std::isnan(r[0].value));
}

TEST(Checks, MissingChannelsAndMetadataAreInputErrors) {
  TraceTable t = synthetic();
  EXPECT_THROW(runChecks({{"x", "frame_drift", "FOOT", {}, 0.0, 1.0, "case.yaml:3"}}, t), InputError);
  t.metadata.clear();
  EXPECT_THROW(runChecks({{"x", "force_balance", "", {"R"}, 0.0, 1.0, "case.yaml:4"}}, t), InputError);
}

}  // namespace
}  // namespace lexdyn::checks
