// Loading of URDF + data files: structure, joint order, mass lumping, and the error messages
// for malformed or inconsistent files (each must name the file, the line and the element).
#include "lexdyn/common/error.hpp"
#include "lexdyn/model/robot_description.hpp"
#include "model_test_utils.hpp"
#include "../common/expect_text.hpp"

#include <gtest/gtest.h>

#include <regex>

namespace lexdyn::model {
namespace {

using lexdyn::testing::containsAll;
using lexdyn::testing::inputErrorOf;
using testing::sourcePath;

// A two-link chain whose pieces the tests below replace.
struct UrdfParts {
  std::string link1_inertial =
      R"(<inertial><origin xyz="0 0 0.1"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>)";
  std::string joint1_parent = "base";
  std::string joint1_type = "revolute";
  std::string joint1_limit = R"(<limit lower="-1" upper="1" velocity="2" effort="10"/>)";
  std::string extra;

  std::string text() const {
    return std::string("<?xml version=\"1.0\"?>\n") +                  // line 1
           "<robot name=\"chain\">\n" +                                // line 2
           "  <link name=\"base\"/>\n" +                               // line 3
           "  <link name=\"link1\">" + link1_inertial + "</link>\n" +  // line 4
           "  <joint name=\"j1\" type=\"" + joint1_type + "\">\n" +    // line 5
           "    <parent link=\"" + joint1_parent + "\"/>\n" +          // line 6
           "    <child link=\"link1\"/>\n" +                           // line 7
           "    <axis xyz=\"0 1 0\"/>\n" + "    " + joint1_limit + "\n" + "  </joint>\n" + extra + "</robot>\n";
  }
};

const char* kData = "format: lexdyn-robot-data/1\nrobot: chain\nbase: fixed\n";

LoadOptions strictOptions() {
  LoadOptions o;
  o.strict = true;
  return o;
}

std::string errorOf(const std::string& urdf, const std::string& data) {
  return inputErrorOf([&] { parseRobotDescription(urdf, "chain.urdf", data, "chain.yaml"); });
}

// The error of the chain whose link1 has this <inertial> element.
std::string errorWithInertial(const std::string& inertial) {
  UrdfParts p;
  p.link1_inertial = inertial;
  return errorOf(p.text(), kData);
}

// An <inertial> element (no origin) of this mass and these attributes of <inertia>.
std::string inertial(const std::string& mass, const std::string& inertia = R"(ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01")") {
  return "<inertial><mass value=\"" + mass + "\"/><inertia " + inertia + "/></inertial>";
}

TEST(RobotDescription, ValidChainLoads) {
  const RobotDescription d = parseRobotDescription(UrdfParts().text(), "chain.urdf", kData, "chain.yaml");
  ASSERT_EQ(d.links.size(), 2u);
  ASSERT_EQ(d.joints.size(), 1u);
  EXPECT_EQ(d.joints[0].name, "j1");
  EXPECT_EQ(d.joints[0].child_link, 1);
  EXPECT_DOUBLE_EQ(d.links[1].mass, 1.0);
  EXPECT_TRUE(d.links[1].com.isApprox(Eigen::Vector3d(0, 0, 0.1)));
}

TEST(RobotDescription, MissingParentLinkNamesFileLineAndLink) {
  UrdfParts p;
  p.joint1_parent = "nowhere";
  EXPECT_TRUE(containsAll(errorOf(p.text(), kData), {"chain.urdf:6", "'nowhere'", "j1"}));
}

// A moving link without mass and nothing with mass after it: the joint moves nothing the
// dynamics sees. It is locked like a fixed joint, with a warning; strict mode refuses it.
TEST(RobotDescription, ZeroMassIsLockedOrAnErrorInStrictMode) {
  UrdfParts p;
  p.link1_inertial = inertial("0");
  const RobotDescription d = parseRobotDescription(p.text(), "chain.urdf", kData, "chain.yaml");
  EXPECT_EQ(d.joints.size(), 0u);
  ASSERT_EQ(d.locked_joints.size(), 1u);
  EXPECT_EQ(d.locked_joints[0].reason, "massless");
  EXPECT_TRUE(containsAll(d.warnings.back(), {"('j1') move only massless links: locked"}));
  EXPECT_TRUE(containsAll(inputErrorOf([&] { parseRobotDescription(p.text(), "chain.urdf", kData, "chain.yaml", strictOptions()); }),
                          {"chain.urdf:4", "link 'link1': mass must be > 0, found 0 (a moving body"}));
}

TEST(RobotDescription, NegativeMassIsAnError) { EXPECT_TRUE(containsAll(errorWithInertial(inertial("-2")), {"chain.urdf:4", "found -2"})); }

TEST(RobotDescription, MissingInertialIsAnErrorInStrictMode) {
  UrdfParts p;
  p.link1_inertial = "";
  EXPECT_TRUE(containsAll(inputErrorOf([&] { parseRobotDescription(p.text(), "chain.urdf", kData, "chain.yaml", strictOptions()); }),
                          {"chain.urdf:4", "link 'link1' has no <inertial>"}));
}

TEST(RobotDescription, NonPositiveDefiniteInertiaIsAnError) {
  // Principal moments -0.01, 0.01, 0.03: far beyond rounding noise.
  const std::string inertia = R"(ixx="0.01" ixy="0.02" ixz="0" iyy="0.01" iyz="0" izz="0.01")";
  EXPECT_TRUE(containsAll(errorWithInertial(inertial("1", inertia)),
                          {"chain.urdf:4", "body 'link1'", "not physically possible", "negative principal moment"}));
}

TEST(RobotDescription, ImpossibleInertiaIsAnError) {
  const std::string inertia = R"(ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.05")";  // positive definite but Ixx + Iyy < Izz
  EXPECT_TRUE(containsAll(errorWithInertial(inertial("1", inertia)), {"triangle inequality"}));
}

TEST(RobotDescription, UnsupportedJointTypeIsAnError) {
  UrdfParts p;
  p.joint1_type = "planar";
  EXPECT_TRUE(containsAll(errorOf(p.text(), kData), {"chain.urdf:5", "not supported"}));
  // A floating joint is read only from a massless root to a free-flyer base.
  p.joint1_type = "floating";
  EXPECT_TRUE(containsAll(errorOf(p.text(), kData), {"chain.urdf:5", "floating joint", "base: free_flyer"}));
}

TEST(RobotDescription, BadLimitsAreErrors) {
  UrdfParts p;
  p.joint1_limit = R"(<limit lower="1" upper="-1" velocity="2" effort="10"/>)";
  EXPECT_NE(errorOf(p.text(), kData).find("lower < upper"), std::string::npos);
  p.joint1_limit = R"(<limit lower="-1" upper="1" velocity="2" effort="-3"/>)";
  EXPECT_NE(errorOf(p.text(), kData).find("effort limit must be > 0, found -3"), std::string::npos);
  // effort="0" is "unspecified" in URDF packages: refused only in strict mode (below).
  p.joint1_limit = R"(<limit lower="-1" upper="1" velocity="2" effort="0"/>)";
  EXPECT_TRUE(containsAll(inputErrorOf([&] { parseRobotDescription(p.text(), "chain.urdf", kData, "chain.yaml", strictOptions()); }),
                          {"effort limit is unspecified", "strict mode"}));
}

// A cycle of joints detached from the tree (found by fuzzing: tests/fuzz/corpus/urdf) leaves one
// root, so the root count did not see it; urdfdom then built a cycle of shared pointers (a leak
// under AddressSanitizer). It is refused before urdfdom, naming the joint.
TEST(RobotDescription, ADetachedCycleOfJointsIsAnError) {
  UrdfParts p;
  p.extra =
      "  <link name=\"a\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" "
      "izz=\"0.01\"/></inertial></link>\n"
      "  <link name=\"b\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" "
      "izz=\"0.01\"/></inertial></link>\n"
      "  <joint name=\"ja\" type=\"fixed\"><parent link=\"b\"/><child link=\"a\"/></joint>\n"
      "  <joint name=\"jb\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>\n";
  EXPECT_TRUE(
      containsAll(errorOf(p.text(), kData), {"chain.urdf:13: link 'a' is not connected to the root link 'base'", "joints form a cycle"}));
}

TEST(RobotDescription, TwoRootsIsAnError) {
  UrdfParts p;
  p.extra = "  <link name=\"orphan\"/>\n";
  EXPECT_TRUE(containsAll(errorOf(p.text(), kData), {"exactly one root", "orphan"}));
}

TEST(RobotDescription, XmlSyntaxErrorNamesTheLine) {
  EXPECT_TRUE(containsAll(errorOf("<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n  <link name=\"a\">\n</robot>\n", kData),
                          {"chain.urdf:", "XML syntax error"}));
}

TEST(RobotDescription, DataFileErrorsNameFileLineAndKey) {
  const std::string urdf = UrdfParts().text();
  // Unknown frame parent.
  EXPECT_TRUE(containsAll(errorOf(urdf, std::string(kData) + "frames:\n  - {name: f, parent: link9}\n"),
                          {"chain.yaml:5: frames[0].parent", "'link9'"}));
  // Unknown key.
  EXPECT_TRUE(containsAll(errorOf(urdf, std::string(kData) + "colour: red\n"), {"chain.yaml:4: colour", "unknown key"}));
  // Wrong type.
  EXPECT_TRUE(containsAll(errorOf(urdf, std::string(kData) + "frames:\n  - {name: f, parent: link1, xyz: [0, 0]}\n"), {"frames[0].xyz"}));
  EXPECT_TRUE(containsAll(errorOf(urdf, std::string(kData) + "gravity: [0, 0, \"-9.81\"]\n"), {"gravity[2]"}));
  // Robot name mismatch.
  EXPECT_TRUE(containsAll(errorOf(urdf, "format: lexdyn-robot-data/1\nrobot: other\nbase: fixed\n"), {"chain.yaml:2: robot"}));
  // Unknown joint and out-of-range value in a posture; incomplete posture.
  EXPECT_TRUE(containsAll(errorOf(urdf, std::string(kData) + "postures:\n  p: {j9: 0}\n"), {"postures.p.j9"}));
  EXPECT_TRUE(containsAll(errorOf(urdf, std::string(kData) + "postures:\n  p: {j1: 2.5}\n"), {"outside the joint limits"}));
  EXPECT_TRUE(containsAll(errorOf(urdf, std::string(kData) + "postures:\n  p: {}\n"), {"missing: j1"}));
  // Unknown capsule in a pair; capsules on the same link.
  EXPECT_TRUE(
      containsAll(errorOf(urdf, std::string(kData) + "capsules:\n  - {name: c1, parent: link1, p0: [0,0,0], p1: [0,0,1], radius: 0.1}\n"
                                                     "collision_pairs:\n  interaction_distance: 0.05\n  safety_distance: 0.01\n"
                                                     "  pairs: [[c1, c2]]\n"),
                  {"collision_pairs.pairs[0][1]", "'c2'"}));
  // Missing base.
  EXPECT_TRUE(containsAll(errorOf(urdf, "format: lexdyn-robot-data/1\nrobot: chain\n"), {"'base'"}));
  // Negative radius.
  EXPECT_TRUE(
      containsAll(errorOf(urdf, std::string(kData) + "capsules:\n  - {name: c1, parent: link1, p0: [0,0,0], p1: [0,0,1], radius: -0.1}\n"),
                  {"capsules[0].radius"}));
}

TEST(RobotDescription, MissingFilesAreNamed) {
  EXPECT_TRUE(containsAll(inputErrorOf([] { loadRobotDescription("/nonexistent/robot.urdf", "/nonexistent/robot.yaml"); }),
                          {"/nonexistent/robot.urdf"}));
}

TEST(RobotDescription, HumanoidJointOrderFollowsTheFile) {
  const RobotDescription d =
      loadRobotDescription(sourcePath("models/hrp2kai_like/hrp2kai_like.urdf"), sourcePath("models/hrp2kai_like/hrp2kai_like.yaml"));
  ASSERT_EQ(d.joints.size(), 32u);
  const std::vector<std::string> expected_prefix = {"RLEG_JOINT0", "RLEG_JOINT1", "RLEG_JOINT2", "RLEG_JOINT3",
                                                    "RLEG_JOINT4", "RLEG_JOINT5", "LLEG_JOINT0"};
  for (size_t i = 0; i < expected_prefix.size(); ++i) EXPECT_EQ(d.joints[i].name, expected_prefix[i]);
  EXPECT_EQ(d.joints[12].name, "CHEST_JOINT0");
  EXPECT_EQ(d.joints[14].name, "HEAD_JOINT0");
  EXPECT_EQ(d.joints[16].name, "RARM_JOINT0");
  EXPECT_EQ(d.joints[24].name, "LARM_JOINT0");
  EXPECT_EQ(d.joints[31].name, "LARM_JOINT7");
  // Parents precede children.
  for (const auto& j : d.joints) EXPECT_LT(j.parent_link, j.child_link);
  EXPECT_EQ(d.contact_surfaces.size(), 2u);
  EXPECT_EQ(d.force_sensors.size(), 4u);
  EXPECT_EQ(d.collision_pairs.size(), 16u);
  EXPECT_DOUBLE_EQ(d.friction_coefficient, 0.7);
  // Left limits mirror the right ones for roll and yaw axes.
  const auto& r1 = d.joints[static_cast<size_t>(d.findJoint("RLEG_JOINT1"))];
  const auto& l1 = d.joints[static_cast<size_t>(d.findJoint("LLEG_JOINT1"))];
  EXPECT_DOUBLE_EQ(l1.lower, -r1.upper);
  EXPECT_DOUBLE_EQ(l1.upper, -r1.lower);
}

TEST(RobotDescription, FixedJointsAreMergedWithLumpedMass) {
  const RobotDescription d = loadRobotDescription(sourcePath("tests/data/model/merged.urdf"), sourcePath("tests/data/model/merged.yaml"));
  ASSERT_EQ(d.joints.size(), 2u);  // hinge, wrist
  ASSERT_EQ(d.links.size(), 3u);   // base, arm(+tip+sensor), slider
  const LinkDescription& arm = d.links[1];
  EXPECT_DOUBLE_EQ(arm.mass, 3.0);
  ASSERT_EQ(arm.merged_links.size(), 2u);
  // CoM: (2 * (0.1,0,0) + 1 * X_tip * (0,0,0.05)) / 3.
  const Eigen::Isometry3d X_tip = Eigen::Translation3d(0.4, 0.1, 0) * Eigen::Isometry3d(rotationFromRpy({0, 0.5, 0.2}));
  const Eigen::Vector3d c_tip = X_tip * Eigen::Vector3d(0, 0, 0.05);
  const Eigen::Vector3d com = (2.0 * Eigen::Vector3d(0.1, 0, 0) + 1.0 * c_tip) / 3.0;
  EXPECT_TRUE(arm.com.isApprox(com, 1e-12));
  // Inertia about the combined CoM, by the parallel-axis theorem written out.
  Eigen::Matrix3d I1;
  I1 << 0.01, 0.001, 0, 0.001, 0.02, 0, 0, 0, 0.02;
  const Eigen::Matrix3d I2 = X_tip.linear() * Eigen::Vector3d(0.003, 0.004, 0.005).asDiagonal() * X_tip.linear().transpose();
  auto pa = [](double m, const Eigen::Vector3d& r) {
    return Eigen::Matrix3d(m * (r.dot(r) * Eigen::Matrix3d::Identity() - r * r.transpose()));
  };
  const Eigen::Matrix3d I = I1 + pa(2.0, Eigen::Vector3d(0.1, 0, 0) - com) + I2 + pa(1.0, c_tip - com);
  EXPECT_TRUE(arm.inertia.isApprox(I, 1e-12));
  // The wrist joint hangs from the merged tip: its origin is composed.
  const JointDescription& wrist = d.joints[1];
  EXPECT_EQ(wrist.parent_link, 1);
  EXPECT_TRUE(wrist.origin.translation().isApprox(X_tip * Eigen::Vector3d(0.05, 0, 0), 1e-12));
  // Frames: the merged links and the data-file frame on the massless sensor link.
  const int probe = d.findFrame("probe");
  ASSERT_GE(probe, 0);
  EXPECT_EQ(d.frames[static_cast<size_t>(probe)].link, 1);
  EXPECT_TRUE(d.frames[static_cast<size_t>(probe)].placement.translation().isApprox(X_tip * Eigen::Vector3d(0.01, 0, 0.1), 1e-12));
}

}  // namespace
}  // namespace lexdyn::model
