// `lexdyn-harness robot init` and `robot check` (docs/model.md, "Bringing your own robot"), run as
// a user runs them: every robot of the repository is drafted from its URDF (and SRDF), the drafted
// stand case passes and the reach case runs; bad input is refused with the file and element named,
// exit code 2, and nothing left in the output folder.
#include "../common/cli_test_utils.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
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
    {"quadruped_like", "models/quadruped_like/urdf/quadruped_like.urdf", "models/quadruped_like/srdf/quadruped_like.srdf", true, false},
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
    // A legged robot without two arms gets a base case instead; its first 2 s run.
    EXPECT_EQ(fs::is_regular_file(out + "/base.yaml"), r.name == "quadruped_like");
    if (fs::is_regular_file(out + "/base.yaml")) {
      harness("run " + out + "/base.yaml --out " + dir + "/base --quiet --duration 2", dir);
      const nlohmann::json s = nlohmann::json::parse(slurp(dir + "/base/summary.json"));
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
  const CliResult init = harness(
      "robot init " + kSrc + "/models/g1_like/urdf/g1_like.urdf --srdf " + kSrc + "/models/g1_like/srdf/g1_like.srdf --out " + out, dir);
  expectExit(init, 0,
             {"base: free_flyer (2 chains reach the ground below the root link (legs))",
              "foot LEFT_FOOT on link 'left_ankle_roll_link': 4 contact point(s)", "collision box", "arm LEFT: hand link",
              "posture 'standing' (the SRDF group state 'standing'", "mimic joints coupled to 'left_hand_thumb_0_joint'"});
  EXPECT_EQ(init.err.find("cannot hold the arm"), std::string::npos) << init.err;  // its shoulders hold the arms out
  const std::string data = slurp(out + "/g1_like.yaml");
  EXPECT_TRUE(
      containsAll(data, {"base: free_flyer", "friction_coefficient: 0.7", "mimic: {mode: coupled}",
                         "- {name: LEFT_SOLE, parent: left_ankle_roll_link", "- {name: LEFT_GRASP", "name: LEFT_FOOT", "frame: LEFT_SOLE",
                         "- {name: LEFT_FOOT_SENSOR, frame: LEFT_SOLE}", "standing:   # the SRDF group state"}));
  const std::string reach = slurp(out + "/reach.yaml");
  EXPECT_TRUE(containsAll(
      reach, {"- {name: left_hand, type: position, frame: LEFT_GRASP", "action: set_target, task: left_hand", "type: com_box",
              "sensor: LEFT_FOOT_SENSOR",
              "- {name: left_hand_reached, type: task_error, tasks: [left_hand], statistic: max, from_s: 15, to_s: 19.99, limit: 0.01}",
              "- {name: right_hand_reached, type: task_error, tasks: [right_hand], statistic: max, from_s: 15, to_s: 19.99, limit: 0.01}",
              "- {name: trunk_up, type: frame_height, frame:"}));
  // The grasp point is between the fingertips of the hand (g1_like's hand: three fingers, each
  // at the end of its own chain below the wrist).
  EXPECT_TRUE(containsAll(data, {"between the tips of the 3 fingers of the hand, link 'left_wrist_yaw_link'"})) << data;
  // The drafted robot checks: CoM above the soles, the joint table.
  const CliResult check = harness("robot check " + out + "/g1_like.yaml --png " + dir + "/g1.png", dir);
  expectExit(check, 0);
  EXPECT_TRUE(containsAll(check.out, {"robot g1_like", "mass 35.1", "inside its nearest edge", "left_knee_joint", "servo kp",
                                      "coupled mimic joints", "warnings (", "picture: " + dir + "/g1.png"}))
      << check.out;
  const std::string png = slurp(dir + "/g1.png");
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
}

// A shoulder whose effort limit cannot hold the arm stretched out level (as on a public 95 kg
// humanoid, whose drafted reach folds forward at the out-of-reach switch: docs/results.md, "A
// heavier humanoid") is a warning naming the joint, the torque it takes and its limit.
// Replaces the first `from` after the first `after` in `text`, as a user edits a description
// file; false (nothing changed) when either is missing.
bool replaceAfter(std::string& text, const std::string& after, const std::string& from, const std::string& to) {
  const size_t mark = text.find(after);
  const size_t at = mark == std::string::npos ? std::string::npos : text.find(from, mark);
  if (at == std::string::npos) return false;
  text.replace(at, from.size(), to);
  return true;
}

// A copy of models/g1_like in DIR/g1_like whose file REL (urdf/g1_like.urdf, srdf/g1_like.srdf)
// has `from` replaced by `to` once after `after` (a description package as a user edits it).
// Returns the package's folder.
std::string editedG1Like(const std::string& dir, const std::string& rel, const std::string& after, const std::string& from,
                         const std::string& to) {
  const std::string pkg = dir + "/g1_like";
  fs::remove_all(pkg);
  fs::copy(kSrc + "/models/g1_like", pkg, fs::copy_options::recursive);
  std::string text = slurp(pkg + "/" + rel);
  EXPECT_TRUE(replaceAfter(text, after, from, to)) << from;
  std::ofstream(pkg + "/" + rel) << text;
  return pkg;
}

TEST(RobotInit, AShoulderThatCannotHoldTheArmOutIsAWarning) {
  const std::string dir = scratch("weak_shoulder");
  const std::string pkg =
      editedG1Like(dir, "urdf/g1_like.urdf", "<joint name=\"left_shoulder_roll_joint\"", "effort=\"25\"", "effort=\"2\"");
  const CliResult init =
      harness("robot init " + pkg + "/urdf/g1_like.urdf --srdf " + pkg + "/srdf/g1_like.srdf --out " + dir + "/draft", dir);
  expectExit(init, 0,
             {"the left arm's joint 'left_shoulder_roll_joint' cannot hold the arm stretched out level: that takes about",
              "its effort limit is 2 N m", "A heavier humanoid"});
  EXPECT_EQ(init.err.find("right_shoulder_roll_joint' cannot hold"), std::string::npos) << init.err;
}

// An arm joint exactly at a limit in the posture (an elbow on its stop: the arm starts straight,
// and the drafted reach folds the robot) is moved 25 % of its range inside, with a warning; the
// CoM box of the reach keeps its faces 1.5 times its half extent inside the support's edge.
TEST(RobotInit, AnArmJointOnItsStopIsMovedInside) {
  const std::string dir = scratch("elbow_on_stop");
  const std::string pkg =
      editedG1Like(dir, "srdf/g1_like.srdf", "<joint name=\"left_elbow_joint\" value=", "value=\"0.9\"", "value=\"-1.0472\"");
  const CliResult init =
      harness("robot init " + pkg + "/urdf/g1_like.urdf --srdf " + pkg + "/srdf/g1_like.srdf --out " + dir + "/draft", dir);
  // -1.0472 + 0.25 * (2.0944 + 1.0472) = -0.2618
  expectExit(init, 0, {"left_elbow_joint: at its limit -1.0472", "taken as -0.2618 (25 % of its range inside)"});
  EXPECT_EQ(init.err.find("right_elbow_joint: at its limit"), std::string::npos) << init.err;
  const std::string data = slurp(dir + "/draft/g1_like.yaml");
  EXPECT_NE(data.find("left_elbow_joint: -0.2618"), std::string::npos) << data;
  EXPECT_TRUE(containsAll(slurp(dir + "/draft/reach.yaml"), {"each face at least 1.5 times that inside the support's edge"}));
}

// A COLLADA box (8 vertices, 12 triangles) of half extents `h` about `c`, in the file's
// coordinates, declaring `up` (Y_UP, Z_UP) as its up axis.
std::string colladaBox(const std::string& up, const std::array<double, 3>& c, const std::array<double, 3>& h) {
  std::ostringstream v;
  for (int k = 0; k < 8; ++k) {
    v << c[0] + ((k & 1) ? h[0] : -h[0]) << " " << c[1] + ((k & 2) ? h[1] : -h[1]) << " " << c[2] + ((k & 4) ? h[2] : -h[2]) << " ";
  }
  const char* tri = "0 1 3 0 3 2 4 6 7 4 7 5 0 4 5 0 5 1 2 3 7 2 7 6 0 2 6 0 6 4 1 5 7 1 7 3";
  return "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">\n"
         "<asset><unit meter=\"1\"/><up_axis>" +
         up +
         "</up_axis></asset>\n"
         "<library_geometries><geometry id=\"g\"><mesh><source id=\"p\"><float_array id=\"pa\" count=\"24\">" +
         v.str() +
         "</float_array><technique_common><accessor source=\"#pa\" count=\"8\" stride=\"3\"><param name=\"X\" type=\"float\"/>"
         "<param name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/></accessor></technique_common></source>"
         "<vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices><triangles count=\"12\">"
         "<input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>" +
         tri +
         "</p></triangles></mesh></geometry></library_geometries>\n"
         "<library_visual_scenes><visual_scene id=\"s\"><node id=\"n\"><instance_geometry url=\"#g\"/></node></visual_scene>"
         "</library_visual_scenes><scene><instance_visual_scene url=\"#s\"/></scene>\n</COLLADA>\n";
}

// COLLADA meshes that declare Y_UP: robot init turns them when the links' centres of mass say so
// (mesh_up_axis: file), and takes them as written (as ROS's tools do) when the centres of mass
// agree with that.
TEST(RobotInit, AColladaUpAxisIsAppliedWhenTheLinksSayItIsMeant) {
  const std::string dir = scratch("up_axis");
  fs::create_directories(dir + "/meshes");
  // Each link 0.4 m long along its z; the file writes the box along its y (Y_UP: y is up).
  std::ofstream(dir + "/meshes/link.dae") << colladaBox("Y_UP", {0.0, 0.2, 0.0}, {0.03, 0.2, 0.03});
  auto urdf = [&](const std::string& com) {
    std::string u = "<?xml version=\"1.0\"?>\n<robot name=\"stick\">\n  <link name=\"world\"/>\n";
    const char* names[] = {"a", "b", "c"};
    for (int k = 0; k < 3; ++k) {
      const std::string n = names[k], parent = k == 0 ? "world" : names[k - 1];
      u += "  <joint name=\"j" + n + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" + n +
           "\"/>"
           "<origin xyz=\"0 0 " +
           std::string(k == 0 ? "0" : "0.4") +
           "\"/><axis xyz=\"0 1 0\"/><limit lower=\"-2\" upper=\"2\" effort=\"100\" velocity=\"2\"/></joint>\n"
           "  <link name=\"" +
           n + "\"><inertial><origin xyz=\"" + com +
           "\"/><mass value=\"1\"/>"
           "<inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.001\"/></inertial>"
           "<collision><geometry><mesh filename=\"meshes/link.dae\"/></geometry></collision></link>\n";
    }
    return u + "</robot>\n";
  };
  std::ofstream(dir + "/turned.urdf") << urdf("0 0 0.2");   // the mass along z: the file's y is the link's z
  std::ofstream(dir + "/written.urdf") << urdf("0 0.2 0");  // the mass along y: as written
  const CliResult t = harness("robot init " + dir + "/turned.urdf --out " + dir + "/t", dir);
  expectExit(t, 0,
             {"meshes: of the COLLADA files, 1 declare Y_UP",
              "lie 0.0 cm on average from their meshes' centres with the up axis applied, 28.3 cm as written (3 meshes): turned to z up"});
  EXPECT_TRUE(containsAll(slurp(dir + "/t/stick.yaml"), {"mesh_up_axis: file ", "(file: COLLADA meshes turned by their <up_axis>)"}));
  const CliResult w = harness("robot init " + dir + "/written.urdf --out " + dir + "/w", dir);
  expectExit(w, 0, {"meshes: of the COLLADA files, 1 declare Y_UP", "taken as written"});
  EXPECT_TRUE(containsAll(slurp(dir + "/w/stick.yaml"), {"mesh_up_axis: ignore ", "(ignore: as ROS's tools read them)"}));
  // robot check reads the data file's choice: the stick stands 1.2 m tall turned, 0.06 m as written.
  const CliResult ct = harness("robot check " + dir + "/t/stick.yaml --png -", dir);
  expectExit(ct, 0);
  EXPECT_TRUE(containsAll(ct.out, {"height 1.2 m"})) << ct.out;
  const CliResult cw = harness("robot check " + dir + "/w/stick.yaml --png -", dir);
  expectExit(cw, 0);
  EXPECT_TRUE(containsAll(cw.out, {"height 0.86 m"})) << cw.out;
  // The mesh conversion of the replay does the same.
  expectExit(harness("robot mesh " + dir + "/meshes/link.dae --out " + dir + "/turned.stl --up-axis file", dir), 0);
  expectExit(harness("robot mesh " + dir + "/meshes/link.dae --out " + dir + "/written.stl", dir), 0);
  EXPECT_NE(slurp(dir + "/turned.stl"), slurp(dir + "/written.stl"));
}

// A posture that tilts both feet (the ankles 0.05 rad off half-sitting's): robot init stands the
// robot flat on them with its base tilted, robot check shows the same, and the drafted stand's
// equilibrium starts from the level soles and passes. An SRDF state naming a joint the URDF
// lacks is an error, or dropped with --srdf-skip-unknown.
TEST(RobotInit, APostureThatTiltsTheFeetStandsOnThemFlat) {
  const std::string dir = scratch("tilted");
  std::string srdf = slurp(kSrc + "/models/hrp2kai_like/hrp2kai_like.srdf");
  for (const std::string j : {"RLEG_JOINT4", "LLEG_JOINT4"}) {
    const std::string from = "<joint name=\"" + j + "\" value=\"-0.4189\"/>";
    ASSERT_NE(srdf.find(from), std::string::npos);
    srdf.replace(srdf.find(from), from.size(), "<joint name=\"" + j + "\" value=\"-0.3689\"/>");
  }
  std::ofstream(dir + "/tilted.srdf") << srdf;
  const std::string urdf = kSrc + "/models/hrp2kai_like/hrp2kai_like.urdf";
  const CliResult init = harness("robot init " + urdf + " --srdf " + dir + "/tilted.srdf --out " + dir + "/draft", dir);
  expectExit(init, 0,
             {"the posture tilts the feet by 2.86 deg from their zero-configuration attitude: the robot is turned to stand them flat",
              "centre of mass", "inside the support polygon's nearest edge"});
  const CliResult check = harness("robot check " + dir + "/draft/hrp2kai_like.yaml --png -", dir);
  expectExit(check, 0);
  EXPECT_TRUE(containsAll(check.out, {"the base is turned by 2.86 deg so that the feet stand flat", "forward: +x"})) << check.out;
  EXPECT_EQ(check.out.find("apart in height"), std::string::npos) << check.out;  // the soles are flat
  const CliResult stand = harness("run " + dir + "/draft/stand.yaml --out " + dir + "/stand --quiet", dir);
  expectExit(stand, 0, {"completed"});
  // An SRDF of another version of the robot: a joint it does not have.
  std::string other = srdf;
  other.replace(other.find("<joint name=\"HEAD_JOINT1\" value="), 0, "<joint name=\"HEAD_JOINT2\" value=\"0\"/>\n    ");
  std::ofstream(dir + "/other.srdf") << other;
  expectExit(harness("robot init " + urdf + " --srdf " + dir + "/other.srdf --out " + dir + "/other", dir), 2,
             {"other.srdf:", "names joint 'HEAD_JOINT2', which the URDF does not have", "--srdf-skip-unknown"});
  EXPECT_FALSE(fs::exists(dir + "/other"));
  const CliResult skip = harness("robot init " + urdf + " --srdf " + dir + "/other.srdf --srdf-skip-unknown --out " + dir + "/other", dir);
  expectExit(skip, 0, {"dropped HEAD_JOINT2 (not a joint of the URDF; --srdf-skip-unknown)"});
}

// An SRDF in the conventions of MoveIt configurations: one group state per limb under the same
// name. They are merged into one posture; a state of one leg, a lifted foot and a stretched arm
// are warned about; --mimic locked and --package-path are written into the data file and used.
TEST(RobotInit, PerGroupSrdfStatesMergeAndPostureProblemsAreWarned) {
  const std::string dir = scratch("per_group");
  const std::string urdf = kSrc + "/models/hrp2kai_like/hrp2kai_like.urdf";
  const std::string full = slurp(kSrc + "/models/hrp2kai_like/hrp2kai_like.srdf");
  // The half-sitting values by joint.
  std::vector<std::pair<std::string, std::string>> values;
  for (size_t at = full.find("<joint name=\""); at != std::string::npos; at = full.find("<joint name=\"", at + 1)) {
    const size_t n0 = at + 13, n1 = full.find('"', n0);
    const size_t v0 = full.find("value=\"", n1);
    if (v0 == std::string::npos || v0 > full.find('>', n1)) continue;  // a group's member, not a state's value
    values.emplace_back(full.substr(n0, n1 - n0), full.substr(v0 + 7, full.find('"', v0 + 7) - v0 - 7));
  }
  ASSERT_GT(values.size(), 24u);
  auto state = [&](const std::string& name, const std::string& group, const std::string& prefix,
                   const std::map<std::string, std::string>& change = {}) {
    std::string t = "  <group_state name=\"" + name + "\" group=\"" + group + "\">\n";
    for (const auto& [j, v] : values) {
      if (j.rfind(prefix, 0) != 0) continue;
      t += "    <joint name=\"" + j + "\" value=\"" + (change.count(j) ? change.at(j) : v) + "\"/>\n";
    }
    return t + "  </group_state>\n";
  };
  const std::string head = full.substr(0, full.find("  <group_state"));
  std::string srdf = head + state("ready", "right_leg", "RLEG") + state("ready", "left_leg", "LLEG") + state("ready", "right_arm", "RARM") +
                     state("ready", "left_arm", "LARM") +
                     // A state of the right leg alone, straight.
                     state("one_leg", "right_leg", "RLEG", {{"RLEG_JOINT2", "0"}, {"RLEG_JOINT3", "0"}, {"RLEG_JOINT4", "0"}}) +
                     // The right knee bent 0.1 rad further than half-sitting: that foot lifts.
                     state("lifted", "right_leg", "RLEG", {{"RLEG_JOINT3", "0.9727"}}) + state("lifted", "left_leg", "LLEG") +
                     state("lifted", "right_arm", "RARM") + state("lifted", "left_arm", "LARM") +
                     // Both legs half-sitting, the arms stretched down (elbows straight, 1 mrad off their
                     // stops at 0: an elbow on its stop would be moved inside, AnArmJointOnItsStopIsMovedInside).
                     state("arms_straight", "right_leg", "RLEG") + state("arms_straight", "left_leg", "LLEG") +
                     state("arms_straight", "right_arm", "RARM", {{"RARM_JOINT0", "0"}, {"RARM_JOINT1", "0"}, {"RARM_JOINT3", "-0.001"}}) +
                     state("arms_straight", "left_arm", "LARM", {{"LARM_JOINT0", "0"}, {"LARM_JOINT1", "0"}, {"LARM_JOINT3", "-0.001"}}) +
                     "</robot>\n";
  std::ofstream(dir + "/r.srdf") << srdf;
  const CliResult init = harness("robot init " + urdf + " --srdf " + dir + "/r.srdf --out " + dir + "/ready", dir);
  expectExit(init, 0,
             {"SRDF state 'ready' of group 'left_leg'", "merged with the one of group 'right_leg'", "6 more joint(s)", "posture 'ready'"});
  EXPECT_EQ(init.err.find("near a singularity"), std::string::npos) << init.err;
  EXPECT_EQ(init.err.find("above the lowest foot"), std::string::npos) << init.err;
  EXPECT_TRUE(containsAll(slurp(dir + "/ready/hrp2kai_like.yaml"), {"ready:"}));
  expectExit(harness("run " + dir + "/ready/stand.yaml --out " + dir + "/ready_stand --quiet", dir), 0, {"completed"});
  // A state of one leg: the other joints at 0.
  const CliResult one = harness("robot init " + urdf + " --srdf " + dir + "/r.srdf --posture one_leg --out " + dir + "/one", dir);
  expectExit(one, 0, {"posture 'one_leg' (the SRDF's) gives 6 of the", "the others are at 0: is it a state of one group only?"});
  // A foot in the air: warned by init and by robot check, whose support polygon leaves it out.
  const CliResult lifted = harness("robot init " + urdf + " --srdf " + dir + "/r.srdf --posture lifted --out " + dir + "/lifted", dir);
  expectExit(lifted, 0,
             {"posture 'lifted': foot on link 'RLEG_LINK5' is", "mm above the lowest foot in the posture: the robot does not stand on it"});
  const CliResult lifted_check = harness("robot check " + dir + "/lifted/hrp2kai_like.yaml --png -", dir);
  expectExit(lifted_check, 0, {});
  EXPECT_TRUE(containsAll(lifted_check.out,
                          {"contact point(s) more than 2 mm above the lowest: in the air, left out", "foot on link 'RLEG_LINK5' is"}))
      << lifted_check.out;
  // Joint names under a namespace prefix (a multi-robot configuration's 'hrp/RLEG_JOINT0'):
  // matched without it, noted once.
  std::string prefixed = state("ready", "right_leg", "RLEG") + state("ready", "left_leg", "LLEG") + state("ready", "right_arm", "RARM") +
                         state("ready", "left_arm", "LARM");
  for (size_t at = prefixed.find("<joint name=\""); at != std::string::npos; at = prefixed.find("<joint name=\"", at + 1)) {
    prefixed.insert(at + 13, "hrp/");
  }
  std::ofstream(dir + "/prefixed.srdf") << head + prefixed + "</robot>\n";
  const CliResult pre = harness("robot init " + urdf + " --srdf " + dir + "/prefixed.srdf --out " + dir + "/prefixed", dir);
  expectExit(pre, 0,
             {"SRDF joint names with the prefix 'hrp/' (e.g. 'hrp/RLEG_JOINT0', line", "matched to the URDF's joints without it",
              "posture 'ready'"});
  // The same joint values as the unprefixed states (the lines after the posture's comment).
  auto postureValues = [](const std::string& data) {
    const size_t p = data.find("postures:");
    if (p == std::string::npos) return std::string();
    std::string v = data.substr(data.find('\n', data.find('\n', p) + 1));  // after "postures:" and "  ready:   # ..."
    // Up to the first line indented less than a joint's value (the next posture, key or comment).
    for (size_t k = v.find('\n', 1); k != std::string::npos; k = v.find('\n', k + 1)) {
      if (v.compare(k + 1, 4, "    ") != 0) return v.substr(0, k);
    }
    return v;
  };
  const std::string values_prefixed = postureValues(slurp(dir + "/prefixed/hrp2kai_like.yaml"));
  EXPECT_GT(values_prefixed.size(), 200u);
  EXPECT_EQ(values_prefixed, postureValues(slurp(dir + "/ready/hrp2kai_like.yaml")));
  // Straight elbows: both arms near a singularity.
  const CliResult straight =
      harness("robot init " + urdf + " --srdf " + dir + "/r.srdf --posture arms_straight --out " + dir + "/straight", dir);
  expectExit(straight, 0, {"posture 'arms_straight': the right arm is near a singularity", "the left arm is near a singularity"});
  // The mimic mode and the package path go into the data file; the data file's package path,
  // relative to it, finds the meshes.
  const std::string pkg = dir + "/pkgs/g1_like_description";
  fs::create_directories(dir + "/pkgs");
  fs::copy(kSrc + "/models/g1_like", pkg, fs::copy_options::recursive);
  fs::create_directories(dir + "/alone");
  fs::copy_file(kSrc + "/models/g1_like/urdf/g1_like.urdf", dir + "/alone/g1_like.urdf");
  const std::string srdf_g1 = kSrc + "/models/g1_like/srdf/g1_like.srdf";
  const CliResult without = harness("robot check " + dir + "/alone/g1_like.urdf --png -", dir);
  EXPECT_TRUE(containsAll(without.out + without.err, {"package 'g1_like_description' not found"})) << without.out << without.err;
  const CliResult g1 = harness("robot init " + dir + "/alone/g1_like.urdf --srdf " + srdf_g1 + " --package-path " + dir +
                                   "/pkgs --mimic locked --out " + dir + "/g1",
                               dir);
  expectExit(g1, 0, {"posture 'standing'"});
  const std::string g1_data = slurp(dir + "/g1/g1_like.yaml");
  EXPECT_TRUE(containsAll(g1_data, {"mimic: {mode: locked, posture: standing}", "package_path: ['../pkgs']"})) << g1_data;
  const CliResult g1_check = harness("robot check " + dir + "/g1/g1_like.yaml --png -", dir);
  expectExit(g1_check, 0, {});
  EXPECT_TRUE(containsAll(g1_check.out, {"locked joints"})) << g1_check.out;
  EXPECT_EQ((g1_check.out + g1_check.err).find("not found"), std::string::npos) << g1_check.out << g1_check.err;
  EXPECT_EQ(g1_check.out.find("coupled mimic joints"), std::string::npos) << g1_check.out;
  expectExit(harness("run " + dir + "/g1/stand.yaml --out " + dir + "/g1_stand --quiet", dir), 0, {"completed"});
}

// A dual-arm robot on a fixed base (here the humanoid welded at its waist): both hands reach.
TEST(RobotInit, AFixedBaseWithTwoArmsGetsAReachOfBothHands) {
  const std::string dir = scratch("dual_arm");
  const CliResult init = harness("robot init " + kSrc + "/models/hrp2kai_like/hrp2kai_like.urdf --srdf " + kSrc +
                                     "/models/hrp2kai_like/hrp2kai_like.srdf --base fixed --out " + dir + "/draft",
                                 dir);
  expectExit(init, 0, {"base: fixed", "wrote " + dir + "/draft/reach.yaml"});
  const std::string reach = slurp(dir + "/draft/reach.yaml");
  EXPECT_TRUE(containsAll(reach, {"Fixed base; the hands", "- {name: left_hand, type: position", "- {name: right_hand, type: position",
                                  "left_hand_reached", "right_hand_reached"}))
      << reach;
  harness("run " + dir + "/draft/reach.yaml --out " + dir + "/reach --quiet --duration 2", dir);
  const nlohmann::json s = nlohmann::json::parse(slurp(dir + "/reach/summary.json"));
  EXPECT_EQ(s["status"], "completed") << s.dump(2);
}

// A quadruped on ball feet (models/quadruped_like: the Mini Cheetah's figures): robot init
// drafts a base case; each foot of one point is a point contact (3 rows), and the base moves to
// its target and tilts. Held as contacts of 6 rows (the frame's pose) the base cannot move.
TEST(RobotInit, AQuadrupedOnPointFeetMovesItsBase) {
  const std::string dir = scratch("quadruped");
  const std::string m = kSrc + "/models/quadruped_like/";
  const CliResult init =
      harness("robot init " + m + "urdf/quadruped_like.urdf --srdf " + m + "srdf/quadruped_like.srdf --out " + dir + "/draft", dir);
  expectExit(init, 0, {"foot FRONT_LEFT_FOOT on link 'fl_shank': 1 contact point(s)", "wrote " + dir + "/draft/base.yaml"});
  EXPECT_FALSE(fs::exists(dir + "/draft/reach.yaml"));
  // Ball feet: the collision sphere's centre and radius (the simulator rolls it).
  EXPECT_TRUE(containsAll(slurp(dir + "/draft/quadruped_like.yaml"), {"radius: 0.02", "points: [[0, 0, 0.02]]"}));
  const CliResult check = harness("robot check " + dir + "/draft/quadruped_like.yaml --png -", dir);
  EXPECT_TRUE(containsAll(check.out, {"(balls of radius 0.02 m, where they touch)", "support polygon: 4 corners"})) << check.out;
  const std::string base = slurp(dir + "/draft/base.yaml");
  EXPECT_TRUE(containsAll(base, {"- {name: FRONT_LEFT_FOOT, surface: FRONT_LEFT_FOOT",
                                 "- {name: base_position, type: position, frame: base", "action: set_target, task: base_orientation",
                                 "action: set_target, task: base_position", "- {name: base_reached", "- {name: base_tilted"}))
      << base;
  // The whole case (40 s) passes: the base to its target (by 6 s), tilted (by 14 s), then held
  // out of reach; the feet's friction ratios are judged about the ground's normal (the wrenches
  // of a point contact are in the world's axes: in the sole frames, which turn with the
  // shanks, the legs' stretch looked like slipping, a ratio of 1.29).
  const CliResult run = harness("run " + dir + "/draft/base.yaml --out " + dir + "/base --quiet", dir);
  EXPECT_EQ(run.code, 0) << run.err;
  nlohmann::json s = nlohmann::json::parse(slurp(dir + "/base/summary.json"));
  std::map<std::string, nlohmann::json> checks;
  for (const auto& c : s["checks"]) checks[c["name"]] = c;
  ASSERT_TRUE(checks.count("base_reached") && checks.count("base_tilted")) << s["checks"].dump(1);
  EXPECT_TRUE(checks["base_reached"]["passed"].get<bool>()) << checks["base_reached"].dump();
  EXPECT_TRUE(checks["base_tilted"]["passed"].get<bool>()) << checks["base_tilted"].dump();
  EXPECT_LT(checks["feet_held"]["value"].get<double>(), 1e-3);
  // On four feet: one foot lifted by 15 % of the base's height and put back (the base first over
  // the other three); the whole case passes and the foot carries load again.
  const CliResult lift = harness("run " + dir + "/draft/lift_foot.yaml --out " + dir + "/lift --quiet", dir);
  EXPECT_EQ(lift.code, 0) << lift.err;
  s = nlohmann::json::parse(slurp(dir + "/lift/summary.json"));
  checks.clear();
  for (const auto& c : s["checks"]) checks[c["name"]] = c;
  for (const char* n : {"base_shifted", "foot_lifted", "foot_down", "front_left_foot_reloaded"}) {
    ASSERT_TRUE(checks.count(n)) << n;
    EXPECT_TRUE(checks[n]["passed"].get<bool>()) << checks[n].dump();
  }
  // The same feet as contacts of 6 rows: the feet's frames cannot turn, the base stays.
  std::string six;
  for (const char* f : {"FRONT_LEFT_FOOT", "FRONT_RIGHT_FOOT", "HIND_LEFT_FOOT", "HIND_RIGHT_FOOT"}) {
    six += std::string(" --set controller.contacts[") + f + "].dims=6";
  }
  const CliResult held = harness("run " + dir + "/draft/base.yaml --duration 7" + six + " --out " + dir + "/held --quiet", dir);
  EXPECT_EQ(held.code, 1) << held.err;
  s = nlohmann::json::parse(slurp(dir + "/held/summary.json"));
  for (const auto& c : s["checks"]) {
    if (c["name"] == "base_reached") {
      EXPECT_FALSE(c["passed"].get<bool>());
      EXPECT_GT(c["value"].get<double>(), 0.9 * 0.0443) << c.dump();  // where it started: 10 % of the 0.30 m height, three ways
    }
  }
  // Bad input: dims other than 3 or 6; a point contact of several points; a normal on a point contact.
  expectExit(
      harness("run " + dir + "/draft/base.yaml --duration 1 --set controller.contacts[FRONT_LEFT_FOOT].dims=4 --out " + dir + "/bad1", dir),
      2, {"dims", "expected 3 (a point contact: its position held) or 6 (the frame's pose held)"});
  EXPECT_FALSE(fs::exists(dir + "/bad1/summary.json") && nlohmann::json::parse(slurp(dir + "/bad1/summary.json"))["status"] == "completed");
  // A ball of negative radius; a point contact on a frame the robot does not have.
  std::string bad_data = slurp(dir + "/draft/quadruped_like.yaml");
  bad_data.replace(bad_data.find("radius: 0.02"), 12, "radius: -0.02");
  std::ofstream(dir + "/draft/bad_radius.yaml") << bad_data;
  const CliResult neg = harness("robot check " + dir + "/draft/bad_radius.yaml --png -", dir);
  EXPECT_EQ(neg.code, 2) << neg.err;
  EXPECT_TRUE(containsAll(neg.err, {"bad_radius.yaml:", "radius", "expected a number in [0, 1] m, found -0.02"})) << neg.err;
  std::string bad_case = slurp(dir + "/draft/base.yaml");
  bad_case.replace(bad_case.find("surface: FRONT_LEFT_FOOT,"), 25, "frame: NO_SUCH_FRAME, points: [[0, 0, 0]],");
  std::ofstream(dir + "/draft/bad_frame.yaml") << bad_case;
  expectExit(harness("run " + dir + "/draft/bad_frame.yaml --duration 1 --out " + dir + "/bad4", dir), 2,
             {"bad_frame.yaml:", "NO_SUCH_FRAME"});
  expectExit(
      harness("run " + kSrc + "/cases/exp1.yaml --duration 1 --set controller.contacts[RIGHT_FOOT].dims=3 --out " + dir + "/bad2", dir), 2,
      {"dims 3 is a point contact: it needs exactly one point (this contact has 4)"});
  expectExit(harness("run " + dir + "/draft/base.yaml --duration 1 --set controller.contacts[FRONT_LEFT_FOOT].normal=[0,0,1] --out " + dir +
                         "/bad3",
                     dir),
             2, {"a point contact (dims 3) takes the ground's normal"});
}

// A quadruped's drafted zero posture (no SRDF): straight legs (the model's knees at 0) bend to
// 85 % of their reach with the feet under the hips and the knees towards the centre; knees whose
// range excludes 0 (clamped inside it, every foot forward of its hip: the centre of mass over
// one pair of feet) are brought back under the hips. Either way the drafted cases pass with the
// controller's default contact margins (a minimum normal force on every foot).
TEST(RobotInit, AQuadrupedsZeroPostureStandsOnFeetUnderItsHips) {
  const std::string dir = scratch("quadruped_zero");
  const std::string urdf = kSrc + "/models/quadruped_like/urdf/quadruped_like.urdf";
  CliResult init = harness("robot init " + urdf + " --out " + dir + "/straight", dir);
  expectExit(init, 0,
             {"fl_knee: 0 put FRONT_LEFT_FOOT's leg at 100 % of its reach; taken as",
              "(the foot under the hip, the leg at 85 % of its reach)", "hr_knee: 0 put HIND_RIGHT_FOOT's leg at 100 % of its reach"});
  // The knees towards the centre: the front ones bend one way, the hind ones the other.
  auto value = [](const std::string& data, const std::string& joint) {
    const size_t at = data.find("    " + joint + ": ");
    EXPECT_NE(at, std::string::npos) << joint;
    return at == std::string::npos ? 0.0 : std::stod(data.substr(at + joint.size() + 6));
  };
  std::string data = slurp(dir + "/straight/quadruped_like.yaml");
  EXPECT_LT(value(data, "fl_knee") * value(data, "hl_knee"), -0.5) << data;
  EXPECT_NEAR(value(data, "fl_knee"), value(data, "fr_knee"), 1e-9);
  EXPECT_EQ(harness("run " + dir + "/straight/base.yaml --out " + dir + "/straight_base --quiet", dir).code, 0);
  EXPECT_EQ(harness("run " + dir + "/straight/lift_foot.yaml --out " + dir + "/straight_lift --quiet", dir).code, 0);
  EXPECT_TRUE(nlohmann::json::parse(slurp(dir + "/straight_base/summary.json"))["start_warnings"].empty());
  // A minimum normal force above what a foot carries at rest (a quarter of the weight) is
  // warned at the start, on the console and in summary.json.
  const CliResult heavy =
      harness("run " + dir + "/straight/base.yaml --duration 0.05 --set 'controller.contact_margins={min_normal_N: 30}' --out " + dir +
                  "/min_normal --quiet",
              dir);
  EXPECT_TRUE(
      containsAll(heavy.err, {"warning: contact FRONT_LEFT_FOOT carries", "N at rest, less than the plan's minimum normal force 30 N"}))
      << heavy.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir + "/min_normal/summary.json"))["start_warnings"].size(), 4u);

  // Knees from 0.5 rad: clamped at 0.71, every foot behind its hip.
  fs::create_directories(dir + "/bent");
  std::string u = slurp(urdf);
  for (size_t at = u.find("<joint name=\""); at != std::string::npos; at = u.find("<joint name=\"", at + 1)) {
    const size_t end = u.find("</joint>", at);
    if (u.substr(at, 24).find("_knee") == std::string::npos) continue;
    const size_t lim = u.find("lower=\"-2.6\"", at);
    ASSERT_LT(lim, end);
    u.replace(lim, 12, "lower=\"0.5\"");
  }
  std::ofstream(dir + "/bent/q.urdf") << u;
  init = harness("robot init " + dir + "/bent/q.urdf --out " + dir + "/bent/draft", dir);
  expectExit(init, 0,
             {"fl_knee: 0 is outside [0.5, 2.6], taken as 0.71", "fl_hip: 0 put FRONT_LEFT_FOOT 0.127 m behind its hip",
              "fl_knee: 0.71 put FRONT_LEFT_FOOT 0.127 m behind its hip", "(the foot under the hip"});
  // The centre of mass in the middle of the support (6.6 cm inside the hind feet's edge in the
  // clamped posture).
  const std::string said = init.out + init.err;
  const size_t com = said.find("centre of mass ");
  ASSERT_NE(com, std::string::npos) << said;
  EXPECT_GT(std::stod(said.substr(com + 15)), 8.0) << said.substr(com, 80);
  data = slurp(dir + "/bent/draft/quadruped_like.yaml");
  EXPECT_GT(value(data, "fl_knee"), 0.71) << data;
  const CliResult check = harness("robot check " + dir + "/bent/draft/quadruped_like.yaml --png -", dir);
  EXPECT_EQ(check.code, 0) << check.err;
  EXPECT_EQ(harness("run " + dir + "/bent/draft/base.yaml --out " + dir + "/bent_base --quiet", dir).code, 0);
}

// Two conventions of other quadruped packages, on models/quadruped_like: box feet (4 cm) on legs of
// 3 joints are point contacts (a leg of 3 cannot hold a foot's orientation: held as poses, the
// four feet locked the base, which never moved), and a body turned half a turn in its root frame
// faces -x: the legs' names (fl_, hr_: two-letter leg names) tell left from right for four feet,
// so the foot of fl_shank is the front left one. Its drafted base case moves the base.
TEST(RobotInit, BoxFeetOnThreeJointLegsArePointsAndAQuadrupedFacingMinusXIsTurned) {
  const std::string dir = scratch("quadruped_box_turned");
  std::string u = slurp(kSrc + "/models/quadruped_like/urdf/quadruped_like.urdf");
  for (size_t at = u.find("<sphere radius=\"0.02\"/>"); at != std::string::npos; at = u.find("<sphere radius=\"0.02\"/>", at)) {
    u.replace(at, 23, "<box size=\"0.04 0.04 0.04\"/>");
  }
  ASSERT_TRUE(replaceAfter(u, "<joint name=\"base_to_trunk\"", "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>",
                           "<origin xyz=\"0 0 0\" rpy=\"0 0 3.141592653589793\"/>"));
  std::ofstream(dir + "/q.urdf") << u;
  const CliResult init = harness("robot init " + dir + "/q.urdf --out " + dir + "/draft", dir);
  expectExit(init, 0,
             {"foot FRONT_LEFT_FOOT on link 'fl_shank': 1 contact point(s) from the centre of the lowest",
              "(a point foot: its leg has 3 joints, too few to hold the foot's orientation)", "foot HIND_RIGHT_FOOT on link 'hr_shank'"});
  const CliResult check = harness("robot check " + dir + "/draft/quadruped_like.yaml --png -", dir);
  EXPECT_TRUE(containsAll(check.out, {"forward: -x"})) << check.out;
  const CliResult run = harness("run " + dir + "/draft/base.yaml --out " + dir + "/base --quiet", dir);
  EXPECT_EQ(run.code, 0) << run.err;
}

// What the feet-under-hips rule must leave alone, on variants of models/quadruped_like and
// models/g1_like: a pitch joint in the trunk (a spine between the front and the hind legs) is no
// leg's hip: it stays at 0 and the legs below it are bent as the others; hind knees that cannot
// bend leave every foot at its height (bending only the front legs would lift the front feet:
// the robot would stand on two); a humanoid's RL_/LL_ legs (right leg, left leg) turned half a
// turn keep their sides (RL_ is not a quadruped's rear left).
TEST(RobotInit, TheFeetUnderHipsRuleLeavesTrunksStiffLegsAndHumanoidsLegNamesAlone) {
  const std::string dir = scratch("feet_under_hips_limits");
  const std::string quad = slurp(kSrc + "/models/quadruped_like/urdf/quadruped_like.urdf");
  // A spine: the hind legs hang from a rear body behind a pitch joint at the trunk's origin.
  std::string spine = quad;
  const std::string rear =
      "  <joint name=\"spine\" type=\"revolute\"><parent link=\"trunk\"/><child link=\"rear\"/><origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>"
      "<axis xyz=\"0 1 0\"/><limit lower=\"-0.5\" upper=\"0.5\" effort=\"40\" velocity=\"10\"/></joint>\n"
      "  <link name=\"rear\"><inertial><origin xyz=\"-0.1 0 0\"/><mass value=\"0.5\"/>"
      "<inertia ixx=\"1e-3\" ixy=\"0\" ixz=\"0\" iyy=\"1e-3\" iyz=\"0\" izz=\"1e-3\"/></inertial></link>\n";
  spine.insert(spine.find("  <joint name=\"hl_abad\""), rear);
  for (const char* leg : {"<joint name=\"hl_abad\"", "<joint name=\"hr_abad\""})
    ASSERT_TRUE(replaceAfter(spine, leg, "<parent link=\"trunk\"/>", "<parent link=\"rear\"/>")) << leg;
  std::ofstream(dir + "/spine.urdf") << spine;
  const CliResult s = harness("robot init " + dir + "/spine.urdf --out " + dir + "/spine", dir);
  expectExit(s, 0, {"hl_knee: 0 put HIND_LEFT_FOOT's leg at 100 % of its reach", "fl_knee: 0 put FRONT_LEFT_FOOT's leg"});
  EXPECT_EQ((s.out + s.err).find("spine: 0 put"), std::string::npos) << s.out + s.err;
  const std::string spine_data = slurp(dir + "/spine/quadruped_like.yaml");
  EXPECT_NE(spine_data.find("    spine: 0\n"), std::string::npos) << spine_data;
  EXPECT_EQ(harness("run " + dir + "/spine/base.yaml --duration 10 --out " + dir + "/spine_base --quiet", dir).code, 0);

  // Hind knees that cannot bend: no leg is bent, the four feet stay on the ground.
  std::string stiff = quad;
  for (const char* knee : {"<joint name=\"hl_knee\"", "<joint name=\"hr_knee\""})
    ASSERT_TRUE(replaceAfter(stiff, knee, "lower=\"-2.6\" upper=\"2.6\"", "lower=\"-0.05\" upper=\"0.05\"")) << knee;
  std::ofstream(dir + "/stiff.urdf") << stiff;
  const CliResult k = harness("robot init " + dir + "/stiff.urdf --out " + dir + "/stiff", dir);
  expectExit(k, 0, {"foot FRONT_LEFT_FOOT on link 'fl_shank'", "foot HIND_RIGHT_FOOT on link 'hr_shank'"});
  EXPECT_EQ((k.out + k.err).find("fl_knee: 0 put"), std::string::npos) << k.out + k.err;

  // A humanoid's legs named LL_ and RL_, its body turned half a turn in the root frame.
  std::string hum = slurp(kSrc + "/models/g1_like/urdf/g1_like.urdf");
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"left_", "LL_"}, {"right_", "RL_"}}) {
    for (size_t at = hum.find(from); at != std::string::npos; at = hum.find(from, at + to.size())) hum.replace(at, from.size(), to);
  }
  ASSERT_TRUE(replaceAfter(hum, "<joint name=\"base_joint\"", "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>",
                           "<origin xyz=\"0 0 0\" rpy=\"0 0 3.141592653589793\"/>"));
  fs::create_directories(dir + "/hum/urdf");
  std::ofstream(dir + "/hum/urdf/g1_like.urdf") << hum;
  fs::copy(kSrc + "/models/g1_like/package.xml", dir + "/hum/package.xml");
  fs::create_directories(dir + "/hum/meshes");
  for (const auto& e : fs::directory_iterator(kSrc + "/models/g1_like/meshes")) {  // renamed as the URDF names them
    std::string name = e.path().filename().string();
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"left_", "LL_"}, {"right_", "RL_"}}) {
      if (name.rfind(from, 0) == 0) name = to + name.substr(from.size());
    }
    fs::copy(e.path(), dir + "/hum/meshes/" + name);
  }
  const CliResult h = harness("robot init " + dir + "/hum/urdf/g1_like.urdf --out " + dir + "/hum/draft", dir);
  expectExit(h, 0, {"foot LEFT_FOOT on link 'LL_ankle_roll_link'", "foot RIGHT_FOOT on link 'RL_ankle_roll_link'"});
  const CliResult hc = harness("robot check " + dir + "/hum/draft/g1_like.yaml --png -", dir);
  EXPECT_TRUE(containsAll(hc.out, {"forward: -x"})) << hc.out;
}

// robot check on a case file and on a URDF alone; a fixed-base robot whose posture its servos
// cannot hold is told so.
TEST(RobotCheck, ReadsCasesAndUrdfs) {
  const std::string dir = scratch("check");
  const CliResult c = harness("robot check " + kSrc + "/cases/exp1.yaml --png -", dir);
  expectExit(c, 0);
  EXPECT_TRUE(containsAll(
      c.out, {"robot hrp2kai_like", "posture 'half_sitting'", "RIGHT_FOOT", "support polygon: ", "inside its nearest edge", "RARM_JOINT3"}))
      << c.out;
  const CliResult u = harness("robot check " + kSrc + "/models/panda_like/urdf/panda_like.urdf --png -", dir);
  expectExit(u, 0);
  EXPECT_TRUE(containsAll(u.out, {"robot panda_like", "data: (none: the URDF alone)", "panda_joint4", "coupled mimic joints",
                                  "panda_finger_joint2       = 1 x panda_finger_joint1"}))
      << u.out;
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
  expectExit(mesh, 2,
             {"pkg/urdf/panda_like.urdf:", "mesh 'package://panda_like_description/meshes/", "not found", "which has no file meshes/",
              "the package is there without the file; --allow-missing-meshes"});
  EXPECT_EQ(mesh.err.find("--package-path"), std::string::npos) << mesh.err;  // the package was found
  EXPECT_FALSE(fs::exists(out));
  // An SRDF naming a joint the URDF lacks.
  std::ofstream(dir + "/bad.srdf") << "<?xml version=\"1.0\"?>\n<robot name=\"panda_like\">\n  <group_state name=\"ready\" group=\"arm\">\n"
                                      "    <joint name=\"panda_joint9\" value=\"0.1\"/>\n  </group_state>\n</robot>\n";
  const CliResult srdf =
      harness("robot init " + kSrc + "/models/panda_like/urdf/panda_like.urdf --srdf " + dir + "/bad.srdf --out " + out, dir);
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
  expectExit(harness("robot init " + kSrc + "/models/point_mass/point_mass.urdf --out " + out, dir), 2,
             {"exists and is not an empty folder"});
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
  for (const std::string& extra :
       {std::string(""), std::string(" --duration 5"), std::string(" --set controller.tasks[position].gains.kp=2")}) {
    SCOPED_TRACE(extra);
    expectExit(harness("run " + dir + "/case.yaml --out " + dir + "/out --quiet" + extra, dir), 2,
               {"point_mass.urdf:", "link 'mass': mass must be > 0, found -1"});
  }
}

}  // namespace
