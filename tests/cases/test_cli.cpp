// lexdyn-harness exit codes: 0 all checks passed, 1 a check failed, 2 bad input (with a message
// naming the file and the key path).
#include "case_test_utils.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace lexdyn::cases {
namespace {

using testing::minimalCase;
using testing::outputDir;
using testing::writeCase;

struct Result {
  int code = -1;
  std::string stderr_text;
};

Result harness(const std::string& args, const std::string& dir) {
  const std::string err = dir + "/stderr.txt";
  const std::string cmd = std::string(LEXDYN_BINARY_DIR) + "/bin/lexdyn-harness " + args + " 2> " + err;
  const int status = std::system(cmd.c_str());
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::ostringstream ss;
  ss << in.rdbuf();
  r.stderr_text = ss.str();
  return r;
}

TEST(HarnessCli, ExitCodeZeroWhenEveryCheckPasses) {
  const std::string dir = outputDir("cli_ok");
  const std::string c = writeCase(dir, minimalCase(0.2));
  const Result r = harness("run " + c + " --out " + dir + "/out --quiet", dir);
  EXPECT_EQ(r.code, 0) << r.stderr_text;
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/trace.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/summary.json"));
  // The stored trace can be checked again.
  EXPECT_EQ(harness("check " + c + " " + dir + "/out/trace.csv", dir).code, 0);
}

TEST(HarnessCli, ExitCodeOneWhenACheckFails) {
  const std::string dir = outputDir("cli_fail");
  auto s = minimalCase(0.2);
  s["h_checks"] = "checks:\n  - {name: tall, type: frame_height, frame: WAIST, min_m: 2.0}\n";
  const Result r = harness("run " + writeCase(dir, s) + " --out " + dir + "/out --quiet", dir);
  EXPECT_EQ(r.code, 1) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("FAIL"), std::string::npos) << r.stderr_text;
}

TEST(HarnessCli, ExitCodeTwoOnBadInputNamingFileAndKey) {
  const std::string dir = outputDir("cli_bad");
  auto s = minimalCase(0.2);
  s["f_sim"] += "  integrator: {rtol: fast}\n";
  const std::string c = writeCase(dir, s);
  Result r = harness("run " + c + " --out " + dir + "/out --quiet", dir);
  EXPECT_EQ(r.code, 2) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find(c), std::string::npos) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("sim.integrator.rtol"), std::string::npos) << r.stderr_text;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/trace.csv"));
  r = harness("run " + dir + "/missing.yaml --out " + dir + "/out", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.stderr_text.find("missing.yaml"), std::string::npos) << r.stderr_text;
  r = harness("run", dir);  // missing arguments
  EXPECT_EQ(r.code, 2);
}

TEST(HarnessCli, TwoProcessesWriteIdenticalTraces) {
  const std::string dir = outputDir("cli_determinism");
  auto s = minimalCase(0.5);
  s["e_controller"] = "controller:\n  type: posture_servo\n  posture: half_sitting\n  motions:\n"
                      "    - {joints: [RLEG_JOINT3, LLEG_JOINT3], amplitude: 0.4, period_s: 1.0, waveform: raised_cosine}\n"
                      "    - {joints: [RARM_JOINT0], amplitude: 0.5, period_s: 1.0}\n";
  s["h_checks"] = "checks:\n  - {name: upright, type: frame_height, frame: WAIST, min_m: 0.5}\n";
  const std::string c = writeCase(dir, s);
  ASSERT_EQ(harness("run " + c + " --out " + dir + "/a --quiet", dir).code, 0);
  ASSERT_EQ(harness("run " + c + " --out " + dir + "/b --quiet", dir).code, 0);
  auto slurp = [](const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  const std::string a = slurp(dir + "/a/trace.csv"), b = slurp(dir + "/b/trace.csv");
  EXPECT_GT(a.size(), 10000u);
  EXPECT_TRUE(a == b) << "traces of two processes differ";
}

}  // namespace
}  // namespace lexdyn::cases
