// Case overrides (--set PATH=VALUE), the effective case, and the model and posture
// perturbations (docs/cases.md, "Overrides" and "Perturbations").
#include "harness/cases/case_file.hpp"
#include "harness/cases/runner.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "case_test_utils.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace lexdyn::cases {
namespace {

using namespace testing;  // case_test_utils.hpp

std::string src(const std::string& rel) { return std::string(LEXDYN_SOURCE_DIR) + "/" + rel; }

CaseSpec withSets(const std::string& file, const std::vector<std::string>& sets) {
  std::vector<Override> o;
  for (const auto& s : sets) o.push_back(parseOverride(s));
  return loadCase(src(file), o);
}

std::string errorOf(const std::string& file, const std::vector<std::string>& sets) {
  return inputErrorOf([&] { withSets(file, sets); });
}

const TaskSpec& task(const CaseSpec& c, const std::string& name) {
  return c.controller.lexdyn.tasks[static_cast<size_t>(c.controller.lexdyn.findTask(name))];
}

TEST(CaseOverrides, ParseSplitsAtTheFirstEqualsSign) {
  const Override o = parseOverride("a.b=x=y");
  EXPECT_EQ(o.path, "a.b");
  EXPECT_EQ(o.value, "x=y");
  EXPECT_EQ(o.label, "--set a.b=x=y");
  EXPECT_THROW(parseOverride("no-equals"), InputError);
  EXPECT_THROW(parseOverride("=1"), InputError);
  EXPECT_THROW(parseOverride("a= "), InputError);
}

TEST(CaseOverrides, ElementsByNameOrIndexInAnySpelling) {
  const CaseSpec base = loadCase(src("cases/exp1.yaml"));
  EXPECT_DOUBLE_EQ(task(base, "right_hand").paramsAs<tasks::PositionParams>().gains.kp, 0.3);
  for (const char* path : {"controller.tasks.right_hand.gains.kp", "controller.tasks[right_hand].gains.kp", "controller.tasks[9].gains.kp",
                           "controller.tasks.9.gains.kp"}) {
    const CaseSpec c = withSets("cases/exp1.yaml", {std::string(path) + "=0.7"});
    EXPECT_DOUBLE_EQ(task(c, "right_hand").paramsAs<tasks::PositionParams>().gains.kp, 0.7) << path;
    EXPECT_DOUBLE_EQ(task(c, "left_hand").paramsAs<tasks::PositionParams>().gains.kp, 0.3) << path;
  }
  // One element of a vector, a whole vector, a check's limit, a gain group by its pattern.
  const CaseSpec c = withSets("cases/exp1.yaml", {"controller.tasks[left_hand].target[1]=0.6", "events[0].value=[0.5, -1.5, 1.8]",
                                                  "checks[upright].min_m=0.4", "sim.servo.gains[*ARM_JOINT7].kp=150"});
  EXPECT_DOUBLE_EQ((*task(c, "left_hand").paramsAs<tasks::PositionParams>().target)[1], 0.6);
  EXPECT_DOUBLE_EQ(c.events[0].value[1], -1.5);
  EXPECT_DOUBLE_EQ(c.checks[2].limit, 0.4);
  EXPECT_DOUBLE_EQ(c.sim.servo.kp[23], 150.0);  // RARM_JOINT7
  EXPECT_EQ(c.overrides.size(), 4u);
}

TEST(CaseOverrides, ValidKeysTheFileLeavesOutCanBeSet) {
  const CaseSpec c = withSets("cases/exp1.yaml", {"sim.integrator.rtol=1e-5", "initial_state.joints.RARM_JOINT0=0.1",
                                                  "controller.method_params.bfgs.nu_dt2=1e-10", "controller.params.sr1=true"});
  EXPECT_DOUBLE_EQ(c.sim.integrator.rtol, 1e-5);
  ASSERT_EQ(c.initial_state.joints.size(), 1u);
  EXPECT_DOUBLE_EQ(c.initial_state.joints[0].second, 0.1);
  EXPECT_DOUBLE_EQ(c.controller.lexdyn.params.nu_dt2, 1e-10);  // bfgs is the case's method
  EXPECT_TRUE(c.controller.lexdyn.params.sr1);
}

// Overrides in a section that an earlier override created (the point mass's case has no
// controller.solver): each key is checked against the keys read there, a misspelt one still names
// the nearest valid paths.
TEST(CaseOverrides, SeveralKeysOfASectionAnOverrideCreated) {
  const CaseSpec c = withSets(
      "cases/pointmass-damping.yaml",
      {"controller.solver.spanning_stages=false", "controller.solver.lazy_snapshots=false", "controller.solver.max_iterations=77"});
  EXPECT_FALSE(c.controller.lexdyn.params.solver.spanning_stages);
  EXPECT_FALSE(c.controller.lexdyn.params.solver.lazy_snapshots);
  EXPECT_EQ(c.controller.lexdyn.params.solver.max_iterations, 77);
  // The controller's defaults take spanning stages of any rows and structured ones; a case turns
  // them off.
  EXPECT_TRUE(c.controller.lexdyn.params.solver.spanning_any_rows);
  EXPECT_TRUE(c.controller.lexdyn.params.solver.spanning_structured);
  const CaseSpec off = withSets("cases/pointmass-damping.yaml",
                                {"controller.solver.spanning_any_rows=false", "controller.solver.spanning_structured=false"});
  EXPECT_FALSE(off.controller.lexdyn.params.solver.spanning_any_rows);
  EXPECT_FALSE(off.controller.lexdyn.params.solver.spanning_structured);
  EXPECT_TRUE(off.controller.lexdyn.params.solver.spanning_stages);
  EXPECT_TRUE(containsAll(
      errorOf("cases/pointmass-damping.yaml", {"controller.solver.spanning_stages=false", "controller.solver.lazy_snapshotz=false"}),
      {"no key 'lazy_snapshotz'", "nearest valid paths: controller.solver.lazy_snapshots"}));
}

TEST(CaseOverrides, AWrongPathNamesTheNearestValidPaths) {
  EXPECT_TRUE(containsAll(
      errorOf("cases/exp1.yaml", {"controller.tasks.right_hand.gainz.kp=1"}),
      {"--set controller.tasks.right_hand.gainz.kp=1", "no key 'gainz'", "nearest valid paths: controller.tasks[right_hand].gains.kp"}));
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"controller.tasks.rihgt_hand.gains.kp=1"}),
                          {"no element named 'rihgt_hand'", "nearest valid paths: controller.tasks[right_hand].gains.kp"}));
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"checks[3].limit=2"}), {"nearest valid paths: checks[torques].limit_fraction"}));
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"durration_s=1"}), {"nearest valid paths: duration_s"}));
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"checks.99.limit=2"}), {"has 20 elements, no element 99"}));
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"duration_s.x=1"}), {"'duration_s' is a value"}));
  // Below a key being created nothing can be checked at once; the reader says what it allows.
  EXPECT_TRUE(
      containsAll(errorOf("cases/exp1.yaml", {"sim.integrator.rtoll=1e-5"}), {"--set sim.integrator.rtoll=1e-5", "allowed here: rtol"}));
}

TEST(CaseOverrides, ABadValueIsReportedAtTheOverride) {
  std::string e = errorOf("cases/exp1.yaml", {"controller.tasks.right_hand.gains.kp=-1"});
  EXPECT_EQ(e.rfind("--set controller.tasks.right_hand.gains.kp=-1: expected a number >= 0", 0), 0u) << e;
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"controller.tasks.right_hand.target=[1, 2]"}),
                          {"--set controller.tasks.right_hand.target=[1, 2]: expected 3 numbers, found 2"}));
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"duration_s=[1"}), {"not valid YAML"}));
  // A structured value: the error names the override and the place inside it.
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"controller.tasks.right_hand.gains={kp: -2}"}),
                          {"--set controller.tasks.right_hand.gains={kp: -2} (controller.tasks[right_hand].gains.kp)"}));
  // An error elsewhere keeps its file line.
  EXPECT_TRUE(containsAll(errorOf("cases/exp1.yaml", {"controller.method=gn", "controller.levels=[]"}), {"--set controller.levels=[]"}));
}

TEST(CaseOverrides, StopAtCutsTheRunButKeepsTheScenario) {
  const CaseSpec c = withSets("cases/exp1.yaml", {"stop_at_s=2.5"});
  EXPECT_DOUBLE_EQ(c.duration_s, 2.5);
  EXPECT_EQ(c.events.size(), 2u);  // at 30 s: never reached, still validated
  EXPECT_NE(errorOf("cases/exp1.yaml", {"stop_at_s=0.001"}).find("at least one control period"), std::string::npos);
  // duration_s itself still must cover the events.
  EXPECT_NE(errorOf("cases/exp1.yaml", {"duration_s=10"}).find("event after the end of the run"), std::string::npos);
}

TEST(CaseOverrides, TheEffectiveCaseReproducesTheRunBitForBit) {
  const std::string dir = outputDir("case_overrides_effective");
  // (Without the wall-time channels, which differ from run to run.)
  const std::vector<std::string> sets = {"controller.params.damping=0.6", "controller.tasks[position].gains.kp=2", "stop_at_s=3",
                                         "trace.timings=false"};
  CaseSpec c = withSets("cases/pointmass-damping.yaml", sets);
  overrideMethod(c, "wls", "test");
  RunOptions o;
  o.progress = false;
  o.out_dir = dir + "/a";
  const RunSummary a = runCase(c, o);
  ASSERT_EQ(a.status, lexdyn::records::RunStatus::Completed);
  // The run wrote its effective case; it loads on its own (relative paths to its folder) and
  // gives the same trace.
  ASSERT_TRUE(std::filesystem::is_regular_file(a.case_path));
  std::string text;
  {
    std::ifstream in(a.case_path);
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  EXPECT_NE(text.find("#   --set controller.params.damping=0.6"), std::string::npos) << text;
  // The model's path relative to the effective case's folder when the two share a top-level
  // folder (a build directory inside the checkout), else absolute (one elsewhere, /tmp/b).
  const std::filesystem::path model = std::filesystem::weakly_canonical(src("models/point_mass/point_mass.urdf"));
  const std::filesystem::path folder = std::filesystem::weakly_canonical(dir + "/a");
  const bool shared = *std::next(model.begin()) == *std::next(folder.begin());
  const std::string urdf = shared ? std::filesystem::relative(model, folder).string() : model.string();
  EXPECT_NE(text.find("urdf: " + urdf), std::string::npos) << urdf << "\n" << text;
  CaseSpec again = loadCase(a.case_path);
  overrideMethod(again, "wls", "test");
  EXPECT_DOUBLE_EQ(again.duration_s, 3.0);
  o.out_dir = dir + "/b";
  const RunSummary b = runCase(again, o);
  auto body = [](const std::string& path) {
    std::ifstream in(path);
    std::string line, out;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;  // the header names the case file
      out += line + "\n";
    }
    return out;
  };
  const std::string ta = body(a.trace_path), tb = body(b.trace_path);
  EXPECT_GT(ta.size(), 1000u);
  EXPECT_TRUE(ta == tb) << "the traces differ";
  // Without a destination the paths are absolute.
  const std::string abs = effectiveCaseText(c, "");
  EXPECT_NE(abs.find("urdf: " + std::filesystem::absolute(src("models/point_mass/point_mass.urdf")).lexically_normal().string()),
            std::string::npos);
}

TEST(CaseOverrides, PosturePerturbationIsSeededSmallAndWithinLimits) {
  auto q0 = [](const std::vector<std::string>& sets) {
    const CaseSpec c = withSets("cases/exp1.yaml", sets);
    const model::RobotModel m = model::RobotModel::fromFiles(c.urdf_path, c.data_path);
    return std::make_pair(initialJointPositions(c, m.description()), m.posture("half_sitting"));
  };
  const auto [nominal, posture] = q0({});
  EXPECT_TRUE(nominal == posture);
  const auto [a, p1] = q0({"initial_state.perturbation={seed: 7, amplitude_rad: 0.01, joints: [\"*ARM*\"]}"});
  const auto [b, p2] = q0({"initial_state.perturbation={seed: 7, amplitude_rad: 0.01, joints: [\"*ARM*\"]}"});
  const auto [c, p3] = q0({"initial_state.perturbation={seed: 8, amplitude_rad: 0.01, joints: [\"*ARM*\"]}"});
  EXPECT_TRUE(a == b);  // the seed alone decides
  EXPECT_FALSE(a == c);
  const Eigen::VectorXd d = a - posture;
  EXPECT_LE(d.cwiseAbs().maxCoeff(), 0.01);
  EXPECT_GT(d.cwiseAbs().maxCoeff(), 0.001);
  EXPECT_EQ(d.head(16).cwiseAbs().maxCoeff(), 0.0);  // legs, chest, head untouched
  EXPECT_GT(d.tail(16).cwiseAbs().minCoeff(), 0.0);  // every arm joint moved
  EXPECT_NE(errorOf("cases/exp1.yaml", {"initial_state.perturbation={seed: 1, amplitude_rad: 2}"}).find("amplitude <= 0.5"),
            std::string::npos);
}

TEST(CaseOverrides, TheSimulatedRobotCarriesTheModelPerturbation) {
  const CaseSpec c = withSets(
      "cases/exp1.yaml", {"sim.model={mass_scale: [{match: \"RARM_*\", scale: 2}], com_offset_m: [{match: WAIST, offset: [0.01, 0, 0]}]}"});
  const model::RobotDescription nominal = model::loadRobotDescription(c.urdf_path, c.data_path);
  const model::RobotDescription d = simulatedRobot(c);
  double arm = 0.0;
  for (size_t i = 0; i < d.links.size(); ++i) {
    const bool right_arm = d.links[i].name.rfind("RARM_", 0) == 0;
    EXPECT_DOUBLE_EQ(d.links[i].mass, nominal.links[i].mass * (right_arm ? 2.0 : 1.0)) << d.links[i].name;
    EXPECT_TRUE(d.links[i].inertia.isApprox(nominal.links[i].inertia * (right_arm ? 2.0 : 1.0))) << d.links[i].name;
    if (right_arm) arm += nominal.links[i].mass;
  }
  EXPECT_GT(arm, 1.0);
  EXPECT_NEAR(d.totalMass(), nominal.totalMass() + arm, 1e-12);
  EXPECT_DOUBLE_EQ(d.links[0].com.x(), nominal.links[0].com.x() + 0.01);
  EXPECT_NE(errorOf("cases/exp1.yaml", {"sim.model={mass_scale: [{match: NOPE, scale: 2}]}"}).find("matches no link"), std::string::npos);
  EXPECT_NE(errorOf("cases/exp1.yaml", {"sim.model={mass_scale: [{match: WAIST, scale: 0}]}"}).find("> 0"), std::string::npos);
  // The servo gain scales.
  const CaseSpec s = withSets("cases/exp1.yaml", {"sim.servo.kp_scale=0.5", "sim.servo.kd_scale=2"});
  const CaseSpec n = loadCase(src("cases/exp1.yaml"));
  EXPECT_TRUE(s.sim.servo.kp.isApprox(0.5 * n.sim.servo.kp));
  EXPECT_TRUE(s.sim.servo.kd.isApprox(2.0 * n.sim.servo.kd));
}

}  // namespace
}  // namespace lexdyn::cases
