// Sweep files: parsing, validation before any run (file and field named), point values from
// (seed, index) alone, grids, overrides of a configuration.
#include "harness/sweep/sweep_file.hpp"
#include "lexdyn/common/error.hpp"
#include "../common/expect_text.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

namespace lexdyn::sweep {
namespace {

namespace fs = std::filesystem;
using lexdyn::testing::containsAll;
using lexdyn::testing::inputErrorOf;

std::string dirFor(const std::string& name) {
  const fs::path p = fs::path(LEXDYN_BINARY_DIR) / "test_output" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

// A sweep over the point mass with `body` after the common head.
std::string writeSweep(const std::string& dir, const std::string& body, const std::string& head_extra = "") {
  const std::string path = dir + "/sweep.yaml";
  std::ofstream out(path);
  out << "name: t\nbase: " << LEXDYN_SOURCE_DIR << "/cases/pointmass-damping.yaml\nmethods: [wls, bfgs]\nseed: 3\n" << head_extra << body;
  return path;
}

const char* kParams =
    "sampling: {points: 20}\n"
    "parameters:\n"
    "  - {path: controller.params.damping, range: [0.0, 2.0], simplest: 0}\n"
    "  - {name: kp, path: 'controller.tasks[position].gains.kp', range: [0.5, 2.0], scale: log}\n"
    "  - {path: 'controller.tasks[position].target', values: [[0, 0, 0], [0.5, 0, 0]]}\n"
    "  - {path: sim.servo.kp_scale, integers: [1, 3], simplest: 1}\n";

std::string errorOf(const std::string& body, const std::string& head_extra = "") {
  const std::string dir = dirFor("sweep_file_errors");
  const std::string path = writeSweep(dir, body, head_extra);
  return inputErrorOf([&] { loadSweep(path); });
}

TEST(SweepFile, TheCommittedSweepsLoad) {
  for (const auto& e : fs::directory_iterator(std::string(LEXDYN_SOURCE_DIR) + "/cases/sweeps")) {
    if (e.path().extension() != ".yaml") continue;
    SCOPED_TRACE(e.path().string());
    const SweepSpec s = loadSweep(e.path().string());
    EXPECT_GT(s.points, 0);
    EXPECT_FALSE(s.parameters.empty());
  }
}

TEST(SweepFile, PointValuesDependOnlyOnSeedAndIndex) {
  const std::string dir = dirFor("sweep_file_points");
  const SweepSpec s = loadSweep(writeSweep(dir, kParams));
  ASSERT_EQ(s.parameters.size(), 4u);
  EXPECT_EQ(s.parameters[0].simplest, "0");
  EXPECT_EQ(s.parameters[1].simplest, "1.0");  // the base case's value
  EXPECT_EQ(s.parameters[1].name, "kp");
  // Point 7 alone equals point 7 of the sequence; another seed gives other values.
  const Point p7 = pointAt(s, 7);
  for (long i = 0; i < 20; ++i) {
    const Point p = pointAt(s, i);
    if (i == 7) {
      EXPECT_EQ(p.values, p7.values);
    }
    double d = std::stod(p.values[0]), kp = std::stod(p.values[1]);
    EXPECT_GE(d, 0.0);
    EXPECT_LE(d, 2.0);
    EXPECT_GE(kp, 0.5);
    EXPECT_LE(kp, 2.0);
    EXPECT_TRUE(p.values[2] == "[0, 0, 0]" || p.values[2] == "[0.5, 0, 0]") << p.values[2];
    const int k = std::stoi(p.values[3]);
    EXPECT_TRUE(k >= 1 && k <= 3);
  }
  const SweepSpec other = loadSweep(writeSweep(dir, kParams, "description: the same seed\n"));
  EXPECT_EQ(pointAt(other, 7).values, p7.values);  // same seed
  std::ofstream(dir + "/s4.yaml") << "name: t\nbase: " << LEXDYN_SOURCE_DIR << "/cases/pointmass-damping.yaml\nmethods: [wls]\nseed: 4\n"
                                  << kParams;
  EXPECT_NE(loadSweep(dir + "/s4.yaml").parameters.size(), 0u);
  EXPECT_NE(pointAt(loadSweep(dir + "/s4.yaml"), 7).values, p7.values);
  // The overrides of a point: each parameter's paths; an empty value leaves the base's.
  const auto o = overridesOf(s, {"0.5", "", "[0.5, 0, 0]", "2"});
  ASSERT_EQ(o.size(), 3u);
  EXPECT_EQ(o[0].path, "controller.params.damping");
  EXPECT_EQ(o[1].value, "[0.5, 0, 0]");
}

TEST(SweepFile, GridsEnumerateEveryCombinationFirstParameterSlowest) {
  const std::string dir = dirFor("sweep_file_grid");
  const SweepSpec s = loadSweep(writeSweep(dir,
                                           "sampling: {grid: true}\n"
                                           "parameters:\n"
                                           "  - {path: controller.params.damping, range: [0.0, 1.0], steps: 3}\n"
                                           "  - {path: 'controller.tasks[position].gains.kp', values: [1, 2]}\n"));
  ASSERT_EQ(s.points, 6);
  std::set<std::vector<std::string>> seen;
  for (long i = 0; i < 6; ++i) seen.insert(pointAt(s, i).values);
  EXPECT_EQ(seen.size(), 6u);
  EXPECT_EQ(pointAt(s, 0).values, (std::vector<std::string>{"0", "1"}));
  EXPECT_EQ(pointAt(s, 1).values, (std::vector<std::string>{"0", "2"}));
  EXPECT_EQ(pointAt(s, 2).values, (std::vector<std::string>{"0.5", "1"}));
  EXPECT_EQ(pointAt(s, 5).values, (std::vector<std::string>{"1", "2"}));
}

TEST(SweepFile, BadSweepsAreRejectedBeforeAnyRunNamingFileAndField) {
  // An unknown parameter path: the nearest valid ones are named.
  EXPECT_TRUE(containsAll(errorOf("sampling: {points: 2}\nparameters:\n  - {path: controller.params.dampign, range: [0, 1]}\n"),
                          {"sweep.yaml:7: parameters[0]", "nearest valid paths: controller.params.damping"}));
  // An empty range, an empty set.
  EXPECT_TRUE(containsAll(errorOf("sampling: {points: 2}\nparameters:\n  - {path: controller.params.damping, range: [1, 1]}\n"),
                          {"parameters[0].range: expected [lo, hi] with lo < hi (an empty range)"}));
  EXPECT_TRUE(containsAll(errorOf("sampling: {points: 2}\nparameters:\n  - {path: controller.params.damping, values: []}\n"),
                          {"parameters[0].values: expected at least one value"}));
  // A value the case refuses (a negative damping) at one end of the range.
  EXPECT_TRUE(containsAll(errorOf("sampling: {points: 2}\nparameters:\n  - {path: controller.params.damping, range: [-1, 1]}\n"),
                          {"parameter 'controller.params.damping' = -1", "expected a number in [0, 1e+06], found -1"}));
  // A property that names no check, a comparison with a method the sweep does not run.
  EXPECT_TRUE(containsAll(errorOf(std::string(kParams) + "properties:\n  checks: [no_such_check]\n"),
                          {"properties.checks[0]: the base case has no check 'no_such_check' (checks: no_overshoot"}));
  EXPECT_TRUE(containsAll(errorOf(std::string(kParams) + "properties:\n  comparisons: [{name: c, type: method_comparison, tasks: "
                                                         "[position], statistic: final, better: gn, worse: wls}]\n"),
                          {"needs method gn, which the sweep does not run"}));
  // A base case that does not load.
  const std::string dir = dirFor("sweep_file_bad_base");
  std::ofstream(dir + "/broken.yaml") << "name: broken\n";
  std::ofstream(dir + "/s.yaml") << "name: t\nbase: broken.yaml\nmethods: [wls]\nseed: 1\n" << kParams;
  try {
    loadSweep(dir + "/s.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InputError& err) {
    EXPECT_TRUE(containsAll(err.what(), {"s.yaml:2: base: the base case does not load", "missing required key 'robot'"}));
  }
  // Unknown keys, a grid without steps, a method without a hierarchy.
  EXPECT_TRUE(containsAll(errorOf(std::string(kParams) + "shrinking: {}\n"), {"unknown key 'shrinking'"}));
  EXPECT_TRUE(containsAll(errorOf("sampling: {grid: true}\nparameters:\n  - {path: controller.params.damping, range: [0, 1]}\n"),
                          {"a grid needs steps for a range"}));
  EXPECT_TRUE(containsAll(errorOf(std::string(kParams), "description: x\nmethods: [bfgs]\n"), {"duplicate key 'methods'"}));
}

TEST(SweepFile, WallClockChecksAreNeverASweepsVerdict) {
  // Left out when the sweep takes all of the case's checks; refused when named.
  const std::string dir = dirFor("sweep_file_wall_clock");
  const std::string head = std::string("name: t\nbase: ") + LEXDYN_SOURCE_DIR + "/cases/exp1-gn.yaml\nmethods: [gn]\nseed: 1\n" +
                           "sampling: {points: 1}\nparameters:\n  - {path: 'controller.params.nu_dt2', range: [1.0e-16, 1.0e-8]}\n";
  std::ofstream(dir + "/all.yaml") << head;
  const SweepSpec all = loadSweep(dir + "/all.yaml");
  ASSERT_FALSE(all.checks.empty());
  for (const auto& name : all.checks) EXPECT_NE(name, "tick_time_p99");
  std::ofstream(dir + "/named.yaml") << head << "properties:\n  checks: [tick_time_p99]\n";
  try {
    loadSweep(dir + "/named.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InputError& err) {
    EXPECT_TRUE(
        containsAll(err.what(), {"named.yaml:9: properties.checks[0]: check 'tick_time_p99' is a wall-clock check (machine-dependent)"}));
  }
}

}  // namespace
}  // namespace lexdyn::sweep
