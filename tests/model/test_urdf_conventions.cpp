// URDFs as description packages ship them (docs/model.md, "Loading and validation"): the loader
// reads them the way urdfdom, ROS and Pinocchio do, says what it assumed, lists every problem of
// a file at once, and keeps the older rules in strict mode. Each convention below was refused by
// the loader before it followed URDF's own semantics.
#include "lexdyn/common/error.hpp"
#include "lexdyn/model/inertia.hpp"
#include "lexdyn/model/resource_path.hpp"
#include "lexdyn/model/robot_description.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "../common/expect_text.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace lexdyn::model {
namespace {

using lexdyn::testing::containsAll;
using lexdyn::testing::inputErrorOf;
namespace fs = std::filesystem;

const char* kValidInertia = R"(ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01")";

std::string inertial(const std::string& mass, const std::string& inertia = kValidInertia, const std::string& xyz = "0 0 0") {
  return "<inertial><origin xyz=\"" + xyz + "\"/><mass value=\"" + mass + "\"/><inertia " + inertia + "/></inertial>";
}

// A small legged robot written the way exporters and description packages write one. Each piece
// can be replaced by a test.
struct RosStyleRobot {
  std::string base_link = "<link name=\"base_link\"/>";    // the massless ROS base frame
  std::string base_joint_extra = "<axis xyz=\"0 0 0\"/>";  // CAD exporters write it on fixed joints
  std::string imu_inertial = inertial("0.05", R"(ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0")");
  std::string hip_limit = R"(<limit lower="-1" upper="1" effort="0" velocity="0"/>)";
  // Principal moments 0.01, 0.01, 0.020001 (the triangle inequality violated by 1e-6) and an
  // off-diagonal of CAD rounding.
  std::string thigh_inertia = R"(ixx="0.01" ixy="1e-22" ixz="0" iyy="0.01" iyz="0" izz="0.020001")";
  std::string finger_joint_type = "revolute";
  std::string finger_mimic = "<mimic joint=\"knee\" multiplier=\"0.5\" offset=\"0.1\"/>";
  std::string shank_inertial = inertial("1.5", kValidInertia, "0 0 -0.15");
  std::string finger_inertial = inertial("0.1", kValidInertia, "0 0 -0.02");
  std::string data_extra;

  std::string urdf() const {
    return std::string("<?xml version=\"1.0\"?>\n") + "<robot name=\"ros_style\">\n" +  // 2
           "  " + base_link + "\n" +                                                    // 3
           "  <joint name=\"base_to_pelvis\" type=\"fixed\"><parent link=\"base_link\"/><child link=\"pelvis\"/>"
           "<origin xyz=\"0 0 0.1\"/>" +
           base_joint_extra + "</joint>\n" +                           // 4
           "  <link name=\"pelvis\">" + inertial("5") + "</link>\n" +  // 5
           "  <joint name=\"imu_joint\" type=\"fixed\"><parent link=\"pelvis\"/><child link=\"imu_link\"/>"
           "<origin xyz=\"0.1 0 0\"/><limit lower=\"0\" upper=\"0\"/></joint>\n" +  // 6
           "  <link name=\"imu_link\">" +
           imu_inertial + "</link>\n" +  // 7
           "  <joint name=\"hip\" type=\"revolute\"><parent link=\"pelvis\"/><child link=\"thigh\"/>"
           "<origin xyz=\"0 0 -0.1\"/><axis xyz=\"0 1 0\"/>" +
           hip_limit + "</joint>\n" +                                                             // 8
           "  <link name=\"thigh\">" + inertial("2", thigh_inertia, "0 0 -0.15") + "</link>\n" +  // 9
           "  <joint name=\"knee\" type=\"continuous\"><parent link=\"thigh\"/><child link=\"shank\"/>"
           "<origin xyz=\"0 0 -0.3\"/><axis xyz=\"0 1 0\"/></joint>\n" +  // 10
           "  <link name=\"shank\">" +
           shank_inertial +
           "<collision><origin xyz=\"0 0 -0.3\"/><geometry><sphere radius=\"0.02\"/></geometry></collision></link>\n" +  // 11
           "  <joint name=\"finger\" type=\"" + finger_joint_type +
           "\"><parent link=\"shank\"/><child link=\"finger_link\"/>"
           "<origin xyz=\"0 0.05 0\"/><axis xyz=\"1 0 0\"/><limit lower=\"0\" upper=\"0.5\" effort=\"1\" velocity=\"1\"/>" +
           finger_mimic + "</joint>\n" +                                      // 12
           "  <link name=\"finger_link\">" + finger_inertial + "</link>\n" +  // 13
           "  <joint name=\"cover_joint\" type=\"fixed\"><parent link=\"shank\"/><child link=\"cover\"/>"
           "<mimic joint=\"knee\"/></joint>\n" +  // 14
           "  <link name=\"cover\"/>\n" +         // 15
           "</robot>\n";
  }
  std::string data() const { return "format: lexdyn-robot-data/1\nrobot: ros_style\nbase: free_flyer\n" + data_extra; }
  RobotDescription load(const LoadOptions& o = {}) const { return parseRobotDescription(urdf(), "ros.urdf", data(), "ros.yaml", o); }
};

LoadOptions strict() {
  LoadOptions o;
  o.strict = true;
  return o;
}

std::string allWarnings(const RobotDescription& d) {
  std::string s;
  for (const auto& w : d.warnings) s += w + "\n";
  return s;
}

TEST(UrdfConventions, APackageStyleRobotLoadsWithItsWarnings) {
  const RosStyleRobot r;
  const RobotDescription d = r.load();
  // Bodies: base_link + pelvis + imu_link lumped; thigh; shank + cover; finger_link, moved by the
  // coupled mimic joint 'finger'.
  ASSERT_EQ(d.links.size(), 4u);
  ASSERT_EQ(d.joints.size(), 2u);
  EXPECT_EQ(d.joints[0].name, "hip");
  EXPECT_EQ(d.joints[1].name, "knee");
  EXPECT_EQ(d.links[0].name, "base_link");
  EXPECT_DOUBLE_EQ(d.links[0].mass, 5.05);
  EXPECT_DOUBLE_EQ(d.links[2].mass, 1.5);
  EXPECT_EQ(d.links[3].name, "finger_link");
  EXPECT_EQ(d.links[3].parent_joint, -1);
  EXPECT_EQ(d.parentBody(3), 2);
  ASSERT_EQ(d.coupled_joints.size(), 1u);
  const CoupledJointDescription& c = d.coupled_joints[0];
  EXPECT_EQ(c.name, "finger");
  EXPECT_EQ(c.master, 1);
  EXPECT_DOUBLE_EQ(c.multiplier, 0.5);
  EXPECT_DOUBLE_EQ(c.offset, 0.1);
  EXPECT_EQ(d.links[3].parent_coupled, 0);
  const std::string w = allWarnings(d);
  // A fixed joint's <limit> and <mimic> are noted; an <axis xyz="0 0 0"/> (what exporters write
  // on every fixed joint) is not.
  EXPECT_TRUE(containsAll(w, {"2 fixed joints ('imu_joint', 'cover_joint')", "ignored"})) << w;
  EXPECT_EQ(w.find("'base_to_pelvis'"), std::string::npos) << w;
  EXPECT_TRUE(containsAll(w, {"ros.urdf:7", "link 'imu_link'", "zero inertia", "point mass"})) << w;
  EXPECT_TRUE(containsAll(w, {"ros.urdf:9", "body 'thigh'", "rounding noise", "projected"})) << w;
  EXPECT_TRUE(containsAll(w, {"'hip'", "effort limit is unspecified", "unlimited"})) << w;
  EXPECT_TRUE(containsAll(w, {"velocity limit is unspecified"})) << w;
  EXPECT_TRUE(containsAll(
      w, {"ros.urdf:12", "mimic joints coupled to 'knee' (q its coordinate): 'finger' = 0.5 q + 0.1", "`mimic: {mode: locked}`"}))
      << w;
  EXPECT_TRUE(containsAll(w, {"'cover_joint')", "<mimic>", "ignored"})) << w;
  // The finger's limits [0, 0.5] narrow its master's range: 0.5 q + 0.1 in [0, 0.5].
  EXPECT_TRUE(containsAll(w, {"ros.urdf:12", "the range of 'knee' is narrowed", "to [-0.2, 0.8]"})) << w;
  EXPECT_DOUBLE_EQ(d.joints[1].lower, -0.2);
  EXPECT_DOUBLE_EQ(d.joints[1].upper, 0.8);
  EXPECT_FALSE(d.joints[1].continuous);
  // What was assumed.
  EXPECT_TRUE(std::isinf(d.joints[0].effort_limit));
  EXPECT_TRUE(std::isinf(d.joints[0].velocity_limit));
  ASSERT_EQ(d.mimics.size(), 1u);
  EXPECT_EQ(d.mimics[0].mode, MimicMode::Coupled);
  // The point mass is lumped exactly: the base's CoM moves towards it.
  EXPECT_NEAR(d.links[0].com.x(), 0.05 * 0.1 / 5.05, 1e-15);
  // The thigh's inertia is physical after the projection, and within 1e-6 of the file's.
  const InertiaCheck ci = checkInertia(d.links[1].inertia);
  EXPECT_EQ(ci.kind, InertiaClass::Valid);
  EXPECT_NEAR(d.links[1].inertia(2, 2), 0.020001, 1e-6);
  // The controller's model builds from it, in the independent coordinates.
  const RobotModel m(d);
  EXPECT_EQ(m.nv(), 8);
  EXPECT_TRUE(m.hasCoupledJoints());
}

// Locked instead of coupled: the data file's `mimic: {mode: locked}` holds the finger at the
// default posture's value and lumps its link into the shank.
TEST(UrdfConventions, LockedMimicsAreLumpedIntoTheirParent) {
  RosStyleRobot r;
  r.data_extra = "mimic: {mode: locked}\n";
  const RobotDescription d = r.load();
  ASSERT_EQ(d.links.size(), 3u);
  EXPECT_TRUE(d.coupled_joints.empty());
  EXPECT_DOUBLE_EQ(d.links[2].mass, 1.6);
  ASSERT_EQ(d.mimics.size(), 1u);
  EXPECT_EQ(d.mimics[0].mode, MimicMode::Locked);
  EXPECT_DOUBLE_EQ(d.mimics[0].locked_value, 0.1);
  EXPECT_TRUE(std::isinf(d.joints[1].lower) && d.joints[1].continuous);
  const std::string w = allWarnings(d);
  EXPECT_TRUE(containsAll(w, {"ros.urdf:12", "mimic joints of 'knee': 'finger' (x 0.5 + 0.1: locked at 0.1)"})) << w;
  EXPECT_FALSE(RobotModel(d).hasCoupledJoints());
}

TEST(UrdfConventions, StrictModeKeepsTheOlderRulesAndListsEveryProblem) {
  const std::string e = inputErrorOf([] { RosStyleRobot().load(strict()); });
  EXPECT_TRUE(containsAll(
      e, {"ros.urdf: ", "problems:", "ros.urdf:4: fixed joint 'base_to_pelvis' has <axis>",
          "ros.urdf:6: fixed joint 'imu_joint' has <limit>", "ros.urdf:14: fixed joint 'cover_joint' has <mimic>",
          "link 'imu_link': inertia is zero (mass 0.05 kg)", "link 'thigh': inertia is not physically possible",
          "mimic joints coupled to 'knee'", "link 'base_link' has no <inertial>", "effort limit is unspecified", "strict mode"}))
      << e;
}

TEST(UrdfConventions, EveryProblemOfAFileIsListedInOnePass) {
  RosStyleRobot r;
  r.thigh_inertia = R"(ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="nan")";
  r.hip_limit = R"(<limit lower="-1" upper="1" effort="abc" velocity="1"/>)";
  std::string u = r.urdf();
  u.replace(u.find("<origin xyz=\"0 0 0.1\"/>"), 23, "<origin xyz=\"0 0\"/>");
  const std::string e = inputErrorOf([&] { parseRobotDescription(u, "ros.urdf", r.data(), "ros.yaml"); });
  EXPECT_TRUE(containsAll(e, {"3 problems:", "ros.urdf:4: joint 'base_to_pelvis': <origin xyz=\"0 0\">: expected 3 numbers",
                              "ros.urdf:9: link 'thigh': <inertia izz=\"nan\">: expected finite numbers",
                              "ros.urdf:8: joint 'hip': <limit effort=\"abc\">: expected finite numbers"}))
      << e;
  // In file order.
  EXPECT_LT(e.find("ros.urdf:4:"), e.find("ros.urdf:8:")) << e;
  EXPECT_LT(e.find("ros.urdf:8:"), e.find("ros.urdf:9:")) << e;
}

TEST(UrdfConventions, DataFileProblemsAreListedWithTheUrdfs) {
  RosStyleRobot r;
  r.thigh_inertia = R"(ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="-1")";
  r.data_extra = "frames:\n  - {name: f, parent: nowhere}\nforce_sensors:\n  - {name: s, frame: nothing}\n";
  const std::string e = inputErrorOf([&] { r.load(); });
  EXPECT_TRUE(containsAll(e, {"ros.urdf: 4 problems in ros.urdf and ros.yaml:", "body 'thigh'", "ros.yaml:5: frames[0].parent",
                              "ros.yaml:7: force_sensors[0].frame"}))
      << e;
}

TEST(UrdfConventions, TheDataFileFillsUnspecifiedLimitsAndLocksMimicsAtAPosture) {
  RosStyleRobot r;
  r.data_extra =
      "joint_limits:\n  hip: {effort: 40, velocity: 3}\n  knee: {effort: 20, velocity: 5}\n"
      "mimic: {mode: locked, posture: bent}\n"
      "postures:\n  bent: {hip: 0.2, knee: 0.6}\n";
  const RobotDescription d = r.load();
  EXPECT_DOUBLE_EQ(d.joints[0].effort_limit, 40.0);
  EXPECT_DOUBLE_EQ(d.joints[0].velocity_limit, 3.0);
  ASSERT_EQ(d.mimics.size(), 1u);
  EXPECT_DOUBLE_EQ(d.mimics[0].locked_value, 0.5 * 0.6 + 0.1);
  const std::string w = allWarnings(d);
  EXPECT_EQ(w.find("effort limit is unspecified"), std::string::npos) << w;
  EXPECT_TRUE(containsAll(w, {"locked at 0.4", "'knee' at 0.6 in posture 'bent'"})) << w;
  // A posture locks: it does not go with coupled mimic joints (the error names the key).
  r.data_extra = "mimic: {mode: coupled, posture: bent}\npostures:\n  bent: {hip: 0.2, knee: 0.6}\n";
  EXPECT_TRUE(containsAll(inputErrorOf([&] { r.load(); }), {"ros.yaml:4: mimic.posture", "mode: locked"}));
  // Coupled mimic joints are not model joints: their limits are their master's.
  r.data_extra = "joint_limits:\n  finger: {effort: 2}\n";
  EXPECT_TRUE(containsAll(inputErrorOf([&] { r.load(); }), {"ros.yaml:5", "'finger' is a mimic joint coupled to its master"}));
}

// A small arm whose gripper fingers are mimic joints, for the coupled mimic joints' edge cases.
// `fingers` are the mimic joints' lines: each a joint from 'palm' with a link of its own.
std::string gripperUrdf(const std::string& fingers,
                        const std::string& grip_limit = R"(<limit lower="-1" upper="1" effort="5" velocity="2"/>)") {
  return std::string("<?xml version=\"1.0\"?>\n<robot name=\"gripper\">\n<link name=\"world\"/>\n") +
         "<joint name=\"grip\" type=\"revolute\"><parent link=\"world\"/><child link=\"palm\"/><axis xyz=\"0 0 1\"/>" + grip_limit +
         "</joint>\n" + "<link name=\"palm\">" + inertial("0.5", kValidInertia, "0.05 0 0") + "</link>\n" + fingers + "</robot>\n";
}
std::string finger(const std::string& name, const std::string& mimic,
                   const std::string& limit = R"(<limit lower="-2" upper="2" effort="1" velocity="3"/>)",
                   const std::string& link_inertial = inertial("0.1", kValidInertia, "0.02 0 0")) {
  return "<joint name=\"" + name + "\" type=\"revolute\"><parent link=\"palm\"/><child link=\"" + name +
         "_link\"/><origin xyz=\"0.1 0 0\"/>"
         "<axis xyz=\"0 1 0\"/>" +
         limit + mimic + "</joint>\n<link name=\"" + name + "_link\">" + link_inertial + "</link>\n";
}
RobotDescription loadGripper(const std::string& urdf, const std::string& data_extra = "", const LoadOptions& o = {}) {
  return parseRobotDescription(urdf, "g.urdf", "format: lexdyn-robot-data/1\nrobot: gripper\nbase: fixed\n" + data_extra, "g.yaml", o);
}

TEST(UrdfConventions, CoupledMimicJointsEdgeCases) {
  // A cycle of two (a mimics b, b mimics a) is an error naming it, not a crash.
  std::string e = inputErrorOf([] { loadGripper(gripperUrdf(finger("a", "<mimic joint=\"b\"/>") + finger("b", "<mimic joint=\"a\"/>"))); });
  EXPECT_TRUE(containsAll(e, {"g.urdf:", "its <mimic> joints form a cycle ('a' -> 'b' -> 'a')"})) << e;
  // A chain into a cycle too.
  e = inputErrorOf([] {
    loadGripper(
        gripperUrdf(finger("a", "<mimic joint=\"b\"/>") + finger("b", "<mimic joint=\"c\"/>") + finger("c", "<mimic joint=\"b\"/>")));
  });
  EXPECT_TRUE(containsAll(e, {"form a cycle ('b' -> 'c' -> 'b')"})) << e;
  // A long chain composes to its independent master.
  std::string chain = finger("f0", "<mimic joint=\"grip\" multiplier=\"0.9\"/>");
  for (int k = 1; k < 40; ++k)
    chain += finger("f" + std::to_string(k), "<mimic joint=\"f" + std::to_string(k - 1) + "\" multiplier=\"1\"/>");
  const RobotDescription long_chain = loadGripper(gripperUrdf(chain));
  ASSERT_EQ(long_chain.coupled_joints.size(), 40u);
  for (const auto& c : long_chain.coupled_joints) {
    EXPECT_EQ(c.master, 0);
    EXPECT_DOUBLE_EQ(c.multiplier, 0.9);
  }
  // A coupled link that moves nothing about its axis (a point mass on it): the simulator's tree
  // would be singular; the error says so and how to go on.
  e = inputErrorOf([] {
    loadGripper(gripperUrdf(finger("a", "<mimic joint=\"grip\"/>", R"(<limit lower="-2" upper="2" effort="1" velocity="3"/>)",
                                   inertial("0.2", R"(ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0")"))));
  });
  EXPECT_TRUE(containsAll(e, {"mimic joint 'a' moves nothing with mass or inertia about its axis", "`mimic: {mode: locked}`"})) << e;
  // The master's range is narrowed to where the finger stays within its limits, and the data
  // file's joint_limits are narrowed the same way; the velocity limit too (|c| qdot <= its own).
  const std::string f = finger("a", "<mimic joint=\"grip\" multiplier=\"2\"/>", R"(<limit lower="-1" upper="1" effort="1" velocity="3"/>)");
  RobotDescription d = loadGripper(gripperUrdf(f));
  EXPECT_DOUBLE_EQ(d.joints[0].lower, -0.5);
  EXPECT_DOUBLE_EQ(d.joints[0].upper, 0.5);
  EXPECT_DOUBLE_EQ(d.joints[0].velocity_limit, 1.5);
  d = loadGripper(gripperUrdf(f), "joint_limits:\n  grip: {lower: -3, upper: 3, velocity: 10}\n");
  EXPECT_DOUBLE_EQ(d.joints[0].lower, -0.5);
  EXPECT_DOUBLE_EQ(d.joints[0].upper, 0.5);
  EXPECT_DOUBLE_EQ(d.joints[0].velocity_limit, 1.5);
  EXPECT_TRUE(containsAll(allWarnings(d), {"the range of 'grip' is narrowed from [-3, 3] to [-0.5, 0.5]",
                                           "the velocity limit of 'grip' is lowered from 10 to 1.5"}));
  // A posture outside the narrowed range is an error naming it; a mimic joint's value that its
  // master contradicts is a warning.
  e = inputErrorOf([&] { loadGripper(gripperUrdf(f), "postures:\n  open: {grip: 0.8}\n"); });
  EXPECT_TRUE(containsAll(e, {"posture 'open': 'grip' at 0.8 puts its mimic joint 'a' at 1.6, outside its limits [-1, 1]"})) << e;
  d = loadGripper(gripperUrdf(f), "postures:\n  half: {grip: 0.2, a: 0.3}\n");
  EXPECT_TRUE(containsAll(allWarnings(d), {"posture 'half': mimic joint 'a' at 0.3 is not where its master puts it (2 x grip 0.2 = 0.4)"}));
  // Limits written for the other sign of the multiplier (as a gripper package ships them): they
  // contradict the coupling and are ignored with a warning; strict mode refuses them.
  const std::string g =
      finger("a", "<mimic joint=\"grip\" multiplier=\"-1\"/>", R"(<limit lower="0" upper="0.9" effort="1" velocity="3"/>)");
  d = loadGripper(gripperUrdf(g, R"(<limit lower="0" upper="0.8" effort="5" velocity="2"/>)"));
  EXPECT_DOUBLE_EQ(d.joints[0].lower, 0.0);
  EXPECT_DOUBLE_EQ(d.joints[0].upper, 0.8);
  EXPECT_TRUE(containsAll(allWarnings(d),
                          {"its limits [0, 0.9] leave its master no range within [0, 0.8]", "contradict the coupling and are ignored"}));
  EXPECT_TRUE(containsAll(
      inputErrorOf([&] { loadGripper(gripperUrdf(g, R"(<limit lower="0" upper="0.8" effort="5" velocity="2"/>)"), "", strict()); }),
      {"contradict the coupling", "refused in strict mode"}));
  // lower="0" upper="0" (a CAD exporter's "not set"): no position limits; strict refuses it.
  d = loadGripper(gripperUrdf("", R"(<limit lower="0" upper="0" effort="5" velocity="2"/>)"));
  EXPECT_TRUE(std::isinf(d.joints[0].lower) && std::isinf(d.joints[0].upper));
  EXPECT_TRUE(containsAll(allWarnings(d), {"without lower and upper, or with both 0 ('grip')"}));
  EXPECT_TRUE(containsAll(
      inputErrorOf([&] { loadGripper(gripperUrdf("", R"(<limit lower="0" upper="0" effort="5" velocity="2"/>)"), "", strict()); }),
      {"expected limit lower < upper, found lower=0 upper=0"}));
}

TEST(UrdfConventions, AMimicOfAnUnknownJointIsAnError) {
  RosStyleRobot r;
  std::string u = r.urdf();
  u.replace(u.find("<mimic joint=\"knee\" multiplier"), 19, "<mimic joint=\"kne\"");
  const std::string e = inputErrorOf([&] { parseRobotDescription(u, "ros.urdf", r.data(), "ros.yaml"); });
  EXPECT_TRUE(containsAll(e, {"ros.urdf:12", "joint 'finger'", "<mimic joint=\"kne\">", "names no joint"})) << e;
}

// A floating base without mass of its own is fine when the robot hanging from it has mass (the
// base's 6 x 6 block of M is the whole robot's inertia); a robot with none is refused.
TEST(UrdfConventions, AFreeFlyerRobotNeedsMassSomewhere) {
  RosStyleRobot r;
  std::string u = r.urdf();
  u.replace(u.find("<link name=\"pelvis\">"), std::string("<link name=\"pelvis\">").size() + inertial("5").size(),
            "<link name=\"pelvis\">");
  u.replace(u.find("<link name=\"imu_link\">"), std::string("<link name=\"imu_link\">").size() + r.imu_inertial.size(),
            "<link name=\"imu_link\">");
  const RobotDescription d = parseRobotDescription(u, "ros.urdf", r.data(), "ros.yaml");
  EXPECT_EQ(d.links[0].mass, 0.0);
  EXPECT_GT(d.totalMass(), 3.0);
  const std::string e = inputErrorOf(
      [&] { parseRobotDescription("<robot name=\"ros_style\"><link name=\"a\"/></robot>", "one.urdf", r.data(), "ros.yaml"); });
  EXPECT_TRUE(containsAll(e, {"one.urdf", "free-flyer robot (base 'a') has no mass"})) << e;
}

// A hand whose finger links are all massless: its joints move nothing the dynamics sees; they
// are locked like fixed joints (a warning; strict mode refuses).
TEST(UrdfConventions, JointsOfMasslessLinksAreLocked) {
  RosStyleRobot r;
  r.finger_mimic = "";
  r.finger_inertial = "";
  const RobotDescription d = r.load();
  EXPECT_EQ(d.joints.size(), 2u);
  EXPECT_TRUE(containsAll(allWarnings(d), {"1 moving joint(s) ('finger') move only massless links: locked"}));
  EXPECT_TRUE(containsAll(inputErrorOf([&] { r.load(strict()); }), {"ros.urdf:13", "link 'finger_link' has no <inertial>"}));
}

TEST(UrdfConventions, AFloatingJointFromAWorldLinkMakesItsChildTheBase) {
  RosStyleRobot r;
  std::string u = r.urdf();
  u.replace(u.find("type=\"fixed\"><parent link=\"base_link\"/>"), 12, "type=\"floating\"");
  const RobotDescription d = parseRobotDescription(u, "ros.urdf", r.data(), "ros.yaml");
  EXPECT_EQ(d.links[0].name, "pelvis");
  EXPECT_EQ(d.urdf_root, "base_link");
  EXPECT_TRUE(containsAll(allWarnings(d), {"floating joint 'base_to_pelvis'", "'pelvis' is the free-flyer base"}));
}

TEST(UrdfConventions, XacroFilesAreRefusedWithWhatToDo) {
  const std::string xacro =
      "<?xml version=\"1.0\"?>\n<robot name=\"r\" xmlns:xacro=\"http://www.ros.org/wiki/xacro\">\n"
      "  <xacro:property name=\"l\" value=\"0.3\"/>\n  <link name=\"a\"/>\n</robot>\n";
  const std::string e = inputErrorOf([&] { parseRobotDescription(xacro, "r.urdf.xacro", "base: fixed\n", "r.yaml"); });
  EXPECT_TRUE(containsAll(e, {"r.urdf.xacro:3", "xacro file", "expand it first", "xacro r.urdf.xacro > robot.urdf"})) << e;
}

// A joint whose subtree has mass but no inertia about its axis (a point mass on the axis): M is
// singular; the error names the joint.
TEST(UrdfConventions, AJointThatMovesNothingIsNamed) {
  RosStyleRobot r;
  r.finger_joint_type = "fixed";
  r.finger_inertial = "";
  r.shank_inertial = inertial("1", R"(ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0")");
  const std::string e = inputErrorOf([&] { r.load(); });
  EXPECT_TRUE(containsAll(e, {"ros.urdf:10", "joint 'knee' moves nothing with mass or inertia about its axis", "'shank'"})) << e;
}

TEST(UrdfConventions, GeometryIsPlacedInItsBodysFrame) {
  RosStyleRobot r;
  r.finger_joint_type = "fixed";
  const RobotDescription d = r.load();
  ASSERT_EQ(d.geometries.size(), 1u);
  const GeometryDescription& g = d.geometries[0];
  EXPECT_EQ(g.type, GeometryType::Sphere);
  EXPECT_TRUE(g.collision);
  EXPECT_EQ(g.urdf_link, "shank");
  EXPECT_EQ(d.links[static_cast<size_t>(g.link)].name, "shank");
  EXPECT_DOUBLE_EQ(g.radius, 0.02);
  EXPECT_TRUE(g.placement.translation().isApprox(Eigen::Vector3d(0, 0, -0.3)));
}

TEST(UrdfConventions, InertiaNoiseIsProjectedAndImpossibleInertiasAreNot) {
  Eigen::Matrix3d I = Eigen::Vector3d(0.01, 0.01, 0.0201).asDiagonal();  // 0.5 % over the triangle
  EXPECT_EQ(checkInertia(I).kind, InertiaClass::Noise);
  const Eigen::Matrix3d P = projectInertia(I);
  EXPECT_EQ(checkInertia(P).kind, InertiaClass::Valid);
  EXPECT_NEAR(P(0, 0) + P(1, 1), P(2, 2), 1e-15);
  EXPECT_LT((P - I).norm(), 1e-4);
  I = Eigen::Vector3d(0.01, 0.01, 0.03).asDiagonal();  // 50 % over
  EXPECT_EQ(checkInertia(I).kind, InertiaClass::Impossible);
  I = Eigen::Vector3d(-1.3e-22, 1e-3, 1e-3).asDiagonal();  // a CAD export's -1.3e-22
  EXPECT_EQ(checkInertia(I).kind, InertiaClass::Valid);
  I = Eigen::Vector3d(-1e-6, 1e-3, 1e-3).asDiagonal();
  EXPECT_EQ(checkInertia(I).kind, InertiaClass::Noise);
  EXPECT_EQ(checkInertia(projectInertia(I)).kind, InertiaClass::Valid);
  EXPECT_EQ(checkInertia(Eigen::Matrix3d::Zero()).kind, InertiaClass::Zero);
}

// package:// URIs resolve through the URDF's own package, --package-path folders (by folder name
// or package.xml) and $ROS_PACKAGE_PATH; relative and file:// URIs against the URDF's folder.
TEST(UrdfConventions, MeshUrisResolveThroughThePackagePath) {
  const fs::path root = fs::path(LEXDYN_BINARY_DIR) / "test_output" / "urdf_conventions";
  fs::remove_all(root);
  fs::create_directories(root / "ws" / "src" / "my_robot_pkg" / "meshes");
  fs::create_directories(root / "ws" / "src" / "my_robot_pkg" / "urdf");
  fs::create_directories(root / "other" / "named_differently" / "meshes");
  std::ofstream(root / "ws" / "src" / "my_robot_pkg" / "package.xml") << "<package><name>my_robot_pkg</name></package>";
  std::ofstream(root / "ws" / "src" / "my_robot_pkg" / "meshes" / "foot.stl") << "solid x\nendsolid x\n";
  std::ofstream(root / "other" / "named_differently" / "package.xml") << "<package>\n  <name> hands_pkg </name>\n</package>";
  std::ofstream(root / "other" / "named_differently" / "meshes" / "hand.stl") << "solid x\nendsolid x\n";
  const std::string urdf = (root / "ws" / "src" / "my_robot_pkg" / "urdf" / "r.urdf").string();
  // The URDF's own package, found above it.
  EXPECT_EQ(resolveResource("package://my_robot_pkg/meshes/foot.stl", urdf, {}).path,
            (root / "ws" / "src" / "my_robot_pkg" / "meshes" / "foot.stl").string());
  // Another package through the search path, by its package.xml name, several levels down.
  EXPECT_EQ(resolveResource("package://hands_pkg/meshes/hand.stl", urdf, {root.string()}).path,
            (root / "other" / "named_differently" / "meshes" / "hand.stl").string());
  // Relative to the URDF, and file://.
  EXPECT_EQ(resolveResource("../meshes/foot.stl", urdf, {}).path, (root / "ws" / "src" / "my_robot_pkg" / "meshes" / "foot.stl").string());
  EXPECT_EQ(resolveResource("file://" + (root / "other" / "named_differently" / "meshes" / "hand.stl").string(), urdf, {}).path,
            (root / "other" / "named_differently" / "meshes" / "hand.stl").string());
  // Not found: says where it looked.
  const ResolvedResource miss = resolveResource("package://nope/m.stl", urdf, {});
  EXPECT_TRUE(miss.path.empty());
  EXPECT_TRUE(containsAll(miss.searched, {"package 'nope' not found", "--package-path"}));
}

}  // namespace
}  // namespace lexdyn::model
