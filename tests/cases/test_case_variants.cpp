// Case variants are full copies of their base case (a case file is self-contained data), so this
// test keeps them in step: each variant must equal its base except for the keys listed here.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <set>
#include <string>
#include <vector>

namespace {

const std::string kCases = std::string(LEXDYN_SOURCE_DIR) + "/cases/";

// Paths (a.b.c, list entries by index) where the two documents differ.
void diff(const YAML::Node& a, const YAML::Node& b, const std::string& path, std::vector<std::string>& out) {
  if (a.Type() != b.Type()) {
    out.push_back(path);
    return;
  }
  if (a.IsMap()) {
    std::set<std::string> keys;
    for (const auto& kv : a) keys.insert(kv.first.as<std::string>());
    for (const auto& kv : b) keys.insert(kv.first.as<std::string>());
    for (const std::string& k : keys) {
      const std::string p = path.empty() ? k : path + "." + k;
      if (!a[k] || !b[k])
        out.push_back(p);
      else
        diff(a[k], b[k], p, out);
    }
  } else if (a.IsSequence()) {
    if (a.size() != b.size()) {
      out.push_back(path);
      return;
    }
    for (std::size_t i = 0; i < a.size(); ++i) diff(a[i], b[i], path + "[" + std::to_string(i) + "]", out);
  } else if (a.IsScalar() && a.Scalar() != b.Scalar()) {
    out.push_back(path);
  }
}

std::vector<std::string> differences(const std::string& base, const std::string& variant) {
  std::vector<std::string> out;
  diff(YAML::LoadFile(kCases + base), YAML::LoadFile(kCases + variant), "", out);
  return out;
}

// exp1's documented outcomes (`expected_failures`, the comparisons' `expected_to_fail`) are its
// own: each variant documents its own or none.
TEST(CaseVariants, Exp1GnIsExp1WithPureGaussNewton) {
  EXPECT_EQ(differences("exp1.yaml", "exp1-gn.yaml"),
            (std::vector<std::string>{"comparisons[0].expected_to_fail", "comparisons[1].expected_to_fail", "controller.method",
                                      "description", "expected_failures", "name"}));
}

TEST(CaseVariants, Exp1WlsWeakIsExp1WithThePostureWeight1e6) {
  EXPECT_EQ(differences("exp1.yaml", "exp1-wls-weak.yaml"),
            (std::vector<std::string>{"comparisons[0].expected_to_fail", "comparisons[1].expected_to_fail", "controller.method",
                                      "controller.wls_levels[1].weights.posture", "description", "expected_failures", "name"}));
  EXPECT_EQ(YAML::LoadFile(kCases + "exp1-wls-weak.yaml")["controller"]["wls_levels"][1]["weights"]["posture"].as<double>(), 1e-6);
}

TEST(CaseVariants, Exp1WlsUnbiasedIsExp1WithTheRegulariserWeight1e7) {
  EXPECT_EQ(differences("exp1.yaml", "exp1-wls-unbiased.yaml"),
            (std::vector<std::string>{"comparisons[0].expected_to_fail", "comparisons[1].expected_to_fail", "controller.method",
                                      "controller.wls_levels[1].weights.wrench", "description", "expected_failures", "name"}));
  EXPECT_EQ(YAML::LoadFile(kCases + "exp1-wls-unbiased.yaml")["controller"]["wls_levels"][1]["weights"]["wrench"].as<double>(), 1e-7);
}

TEST(CaseVariants, Exp1Kp1IsExp1WithThePapersHandGains) {
  EXPECT_EQ(differences("exp1.yaml", "exp1-kp1.yaml"),
            (std::vector<std::string>{"comparisons[0].expected_to_fail", "comparisons[1].expected_to_fail", "controller.tasks[9].gains.kp",
                                      "controller.tasks[10].gains.kp", "description", "expected_failures", "name"}));
  const YAML::Node tasks = YAML::LoadFile(kCases + "exp1-kp1.yaml")["controller"]["tasks"];
  for (int i : {9, 10}) EXPECT_EQ(tasks[i]["gains"]["kp"].as<double>(), 1.0) << tasks[i]["name"].as<std::string>();
}

TEST(CaseVariants, Exp2InstantIsExp2WithTheBoxChangedAtOnce) {
  EXPECT_EQ(differences("exp2.yaml", "exp2-instant.yaml"),
            (std::vector<std::string>{"description", "events[1].ramp_s", "events[2].ramp_s", "expected_failures", "name"}));
}

// The 90 kg humanoid with TALOS's upper-body limits runs hrp2kai_heavy's exp1 unchanged but for
// its robot, its length (the fold ends the runs) and the first reach's settling window.
TEST(CaseVariants, HrpKaiWeakExp1IsHrpKaiHeavyExp1OnTheWeakRobot) {
  const std::vector<std::string> d = differences("hrp2kai_heavy/exp1.yaml", "hrp2kai_weak/exp1.yaml");
  std::vector<std::string> expected = {"description", "duration_s", "expected_failures", "name", "robot.data", "robot.urdf"};
  const YAML::Node checks = YAML::LoadFile(kCases + "hrp2kai_weak/exp1.yaml")["checks"];
  for (std::size_t i = 0; i < checks.size(); ++i) {
    if (checks[i]["name"].as<std::string>() != "hands_settled") continue;
    expected.insert(expected.begin(), {"checks[" + std::to_string(i) + "].from_s", "checks[" + std::to_string(i) + "].to_s"});
  }
  EXPECT_EQ(d, expected);
}

// The comparison can fail: a changed value is reported at its path.
TEST(CaseVariants, TheComparisonNamesEveryDifferingPath) {
  const YAML::Node a = YAML::Load("{x: 1, y: [1, {z: 2}], w: 3}");
  const YAML::Node b = YAML::Load("{x: 1, y: [1, {z: 3}], v: 3}");
  std::vector<std::string> out;
  diff(a, b, "", out);
  EXPECT_EQ(out, (std::vector<std::string>{"v", "w", "y[1].z"}));
}

}  // namespace
