// `lexdyn-harness robot init` and `robot check` (docs/model.md, "Bringing your own robot"), run as
// a user runs them: every robot of the repository is drafted from its URDF (and SRDF), the drafted
// stand case passes and the reach case runs; bad input is refused with the file and element named,
// exit code 2, and nothing left in the output folder.
#include "../common/cli_test_utils.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using lexdyn::testing::CliResult;
using lexdyn::testing::containsAll;
using lexdyn::testing::expectExit;
using lexdyn::testing::harness;
using lexdyn::testing::slurp;

const std::string kSrc = LEXDYN_SOURCE_DIR;

std::string outDir(const std::string& name) {
  const fs::path p = fs::path(LEXDYN_BINARY_DIR) / "test_output" / "robot_cli" / name;
  fs::remove_all(p);
  fs::create_directories(p.parent_path());
  return p.string();
}

// A scratch folder for a test's files (created, emptied).
std::string scratch(const std::string& name) {
  const std::string d = outDir(name);
  fs::create_directories(d);
  return d;
}

struct RepoRobot {
  std::string name, urdf, srdf;
  bool stand_passes = true;  // the drafted stand holds the posture
  bool reach = false;        // a reach case is drafted (two arms on legs, or one fixed-base arm)
};

const std::vector<RepoRobot> kRobots = {
    {"hrp2kai_like", "models/hrp2kai_like/hrp2kai_like.urdf", "models/hrp2kai_like/hrp2kai_like.srdf", true, true},
    {"g1_like", "models/g1_like/urdf/g1_like.urdf", "models/g1_like/srdf/g1_like.srdf", true, true},
    {"panda_like", "models/panda_like/urdf/panda_like.urdf", "models/panda_like/srdf/panda_like.srdf", true, true},
    {"arm_7dof", "models/arm_7dof/arm_7dof.urdf", "", true, true},
    {"planar_3r", "models/planar_3r/planar_3r.urdf", "", true, true},
    {"point_mass", "models/point_mass/point_mass.urdf", "", true, false},
};

TEST(RobotInit, EveryRepositoryRobotIsDraftedAndItsCasesRun) {
  for (const RepoRobot& r : kRobots) {
    SCOPED_TRACE(r.name);
    const std::string dir = scratch(r.name + "_run");
    const std::string out = dir + "/draft";
    const CliResult init =
        harness("robot init " + kSrc + "/" + r.urdf + " --out " + out + (r.srdf.empty() ? "" : " --srdf " + kSrc + "/" + r.srdf), dir);
    expectExit(init, 0, {"robot init:", "wrote " + out + "/stand.yaml"});
    ASSERT_TRUE(fs::is_regular_file(out + "/stand.yaml"));
    const std::string data = slurp(out + "/" + r.name + ".yaml");
    EXPECT_TRUE(containsAll(data, {"format: lexdyn-robot-data/1", "robot: " + r.name, "servo_gains:", "# guessed:"}));
    EXPECT_EQ(fs::is_regular_file(out + "/reach.yaml"), r.reach);
    // The stand case passes as drafted.
    const CliResult stand = harness("run " + out + "/stand.yaml --out " + dir + "/stand --quiet", dir);
    expectExit(stand, r.stand_passes ? 0 : 1, {"completed"});
    if (r.reach) {
      // The reach case runs (its first 2 s: the full runs are the goldens of the drafted cases).
      harness("run " + out + "/reach.yaml --out " + dir + "/reach --quiet --duration 2", dir);
      const nlohmann::json s = nlohmann::json::parse(slurp(dir + "/reach/summary.json"));
      EXPECT_EQ(s["status"], "completed") << s.dump(2);
    }
  }
}

// The draft of a humanoid in the conventions of a description package: feet from the collision
// boxes under the feet, hands at the ends of the arms, the SRDF's posture, sized servos, each
// guess with its source.
TEST(RobotInit, AHumanoidsDraftComesFromItsGeometry) {
  const std::string dir = scratch("g1_like_draft");
  const std::string out = dir + "/draft";
  const CliResult init = harness("robot init " + kSrc + "/models/g1_like/urdf/g1_like.urdf --srdf " + kSrc +
                                     "/models/g1_like/srdf/g1_like.srdf --out " + out,
                                 dir);
  expectExit(init, 0, {"base: free_flyer (2 chains reach the ground below the root link (legs))",
                       "foot LEFT_FOOT on link 'left_ankle_roll_link': 4 contact point(s)", "collision box",
                       "arm LEFT: hand link", "posture 'standing' (the SRDF group state 'standing'", "mimic joints coupled to 'left_hand_thumb_0_joint'"});
  const std::string data = slurp(out + "/g1_like.yaml");
  EXPECT_TRUE(containsAll(data, {"base: free_flyer", "friction_coefficient: 0.7", "mimic: {mode: coupled}",
                                 "- {name: LEFT_SOLE, parent: left_ankle_roll_link", "- {name: LEFT_GRASP", "name: LEFT_FOOT",
                                 "frame: LEFT_SOLE", "- {name: LEFT_FOOT_SENSOR, frame: LEFT_SOLE}", "standing:   # the SRDF group state"}));
  const std::string reach = slurp(out + "/reach.yaml");
  EXPECT_TRUE(containsAll(reach, {"- {name: left_hand, type: position, frame: LEFT_GRASP", "action: set_target, task: left_hand",
                                  "type: com_box", "sensor: LEFT_FOOT_SENSOR"}));
  // The drafted robot checks: CoM above the soles, the joint table.
  const CliResult check = harness("robot check " + out + "/g1_like.yaml --png " + dir + "/g1.png", dir);
  expectExit(check, 0);
  EXPECT_TRUE(containsAll(check.out, {"robot g1_like", "mass 35.1", "inside its nearest edge", "left_knee_joint", "servo kp",
                                      "locked joints", "warnings (", "picture: " + dir + "/g1.png"}))
      << check.out;
  const std::string png = slurp(dir + "/g1.png");
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
}

// robot check on a case file and on a URDF alone; a fixed-base robot whose posture its servos
// cannot hold is told so.
TEST(RobotCheck, ReadsCasesAndUrdfs) {
  const std::string dir = scratch("check");
  const CliResult c = harness("robot check " + kSrc + "/cases/exp1.yaml --png -", dir);
  expectExit(c, 0);
  EXPECT_TRUE(containsAll(c.out, {"robot hrp2kai_like", "posture 'half_sitting'", "RIGHT_FOOT", "support polygon: ",
                                  "inside its nearest edge", "RARM_JOINT3"}))
      << c.out;
  const CliResult u = harness("robot check " + kSrc + "/models/panda_like/urdf/panda_like.urdf --png -", dir);
  expectExit(u, 0);
  EXPECT_TRUE(containsAll(u.out, {"robot panda_like", "data: (none: the URDF alone)", "panda_joint4", "locked joints"})) << u.out;
}

// What the user gets wrong: one clear error (exit code 2), naming the file and the element, and
// nothing in the output folder.
TEST(RobotInit, BadInputIsRefusedAndLeavesNothing) {
  const std::string dir = scratch("bad");
  const std::string out = dir + "/draft";
  // A URDF that does not parse.
  std::ofstream(dir + "/broken.urdf") << "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n";
  expectExit(harness("robot init " + dir + "/broken.urdf --out " + out, dir), 2, {"broken.urdf:", "XML syntax error"});
  EXPECT_FALSE(fs::exists(out));
  // A mesh that is not there: the file, the line, the link and the URI.
  std::string urdf = slurp(kSrc + "/models/panda_like/urdf/panda_like.urdf");
  const std::string uri = "package://panda_like_description/meshes/";
  ASSERT_NE(urdf.find(uri), std::string::npos);
  fs::create_directories(dir + "/pkg/urdf");
  std::ofstream(dir + "/pkg/package.xml") << "<package><name>panda_like_description</name></package>";
  std::ofstream(dir + "/pkg/urdf/panda_like.urdf") << urdf;
  const CliResult mesh = harness("robot init " + dir + "/pkg/urdf/panda_like.urdf --out " + out, dir);
  expectExit(mesh, 2, {"pkg/urdf/panda_like.urdf:", "mesh 'package://panda_like_description/meshes/", "not found",
                       "which has no file meshes/", "--allow-missing-meshes"});
  EXPECT_FALSE(fs::exists(out));
  // An SRDF naming a joint the URDF lacks.
  std::ofstream(dir + "/bad.srdf") << "<?xml version=\"1.0\"?>\n<robot name=\"panda_like\">\n  <group_state name=\"ready\" group=\"arm\">\n"
                                      "    <joint name=\"panda_joint9\" value=\"0.1\"/>\n  </group_state>\n</robot>\n";
  const CliResult srdf = harness("robot init " + kSrc + "/models/panda_like/urdf/panda_like.urdf --srdf " + dir + "/bad.srdf --out " + out, dir);
  expectExit(srdf, 2, {"bad.srdf:4", "group state 'ready' names joint 'panda_joint9', which the URDF does not have"});
  EXPECT_FALSE(fs::exists(out));
  // A xacro file.
  std::ofstream(dir + "/r.urdf.xacro") << "<?xml version=\"1.0\"?>\n<robot name=\"r\" xmlns:xacro=\"http://www.ros.org/wiki/xacro\">\n"
                                          "  <xacro:include filename=\"x.xacro\"/>\n</robot>\n";
  expectExit(harness("robot init " + dir + "/r.urdf.xacro --out " + out, dir), 2, {"r.urdf.xacro:3", "expand it first"});
  EXPECT_FALSE(fs::exists(out));
  // An output folder that is not empty is never overwritten.
  fs::create_directories(out);
  std::ofstream(out + "/mine.txt") << "keep";
  expectExit(harness("robot init " + kSrc + "/models/point_mass/point_mass.urdf --out " + out, dir), 2, {"exists and is not an empty folder"});
  EXPECT_EQ(slurp(out + "/mine.txt"), "keep");
  EXPECT_FALSE(fs::exists(out + "/stand.yaml"));
  expectExit(harness("robot init " + kSrc + "/models/point_mass/point_mass.urdf --out " + dir + "/x --base floating", dir), 2,
             {"--base", "expected free_flyer or fixed"});
}

// Overrides (--duration, --set) never hide the robot files' own error.
TEST(RobotFiles, OverridesDoNotMaskTheRobotFilesError) {
  const std::string dir = scratch("mask");
  std::string urdf = slurp(kSrc + "/models/point_mass/point_mass.urdf");
  const size_t at = urdf.find("<mass value=\"1\"/>");
  ASSERT_NE(at, std::string::npos);
  urdf.replace(at, 17, "<mass value=\"-1\"/>");
  std::ofstream(dir + "/point_mass.urdf") << urdf;
  fs::copy_file(kSrc + "/models/point_mass/point_mass.yaml", dir + "/point_mass.yaml");
  std::string c = slurp(kSrc + "/cases/pointmass-damping.yaml");
  c.replace(c.find("../models/point_mass/point_mass.urdf"), 36, "point_mass.urdf");
  c.replace(c.find("../models/point_mass/point_mass.yaml"), 36, "point_mass.yaml");
  std::ofstream(dir + "/case.yaml") << c;
  for (const std::string& extra : {std::string(""), std::string(" --duration 5"), std::string(" --set controller.tasks[position].gains.kp=2")}) {
    SCOPED_TRACE(extra);
    expectExit(harness("run " + dir + "/case.yaml --out " + dir + "/out --quiet" + extra, dir), 2,
               {"point_mass.urdf:", "link 'mass': mass must be > 0, found -1"});
  }
}

}  // namespace
