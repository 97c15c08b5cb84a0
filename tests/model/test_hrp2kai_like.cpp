// The HRP-2Kai-like model against the figures it was built from (models/hrp2kai_like/README.md,
// "Checks"): mass, height, span, half-sitting WAIST and CoM heights, shoulder height, reach.
// Every value is computed by forward kinematics of the loaded model.
#include "model_test_utils.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lexdyn::model {
namespace {

using testing::loadHumanoid;

class Humanoid : public ::testing::Test {
 protected:
  RobotModel model = loadHumanoid();
  ModelData data = model.createData();

  // Updates the model at `joints` with the base placed so that the lowest sole point is at z = 0.
  Configuration standOnGround(const Eigen::VectorXd& joints) {
    Configuration q = model.neutralConfiguration();
    q.joints = joints;
    const Eigen::VectorXd u = Eigen::VectorXd::Zero(model.nv());
    model.update(data, q, u);
    double zmin = 1e9;
    for (const auto& s : model.description().contact_surfaces) {
      for (const auto& p : s.points) zmin = std::min(zmin, model.pointPosition(data, s.frame, p).z());
    }
    q.base_position.z() -= zmin;
    model.update(data, q, u);
    return q;
  }
  double z(const std::string& frame) { return model.framePlacement(data, model.frameId(frame)).translation().z(); }
  Eigen::Vector3d pos(const std::string& frame) { return model.framePlacement(data, model.frameId(frame)).translation(); }
};

TEST_F(Humanoid, SizesAndMass) {
  EXPECT_EQ(model.numJoints(), 32);
  EXPECT_EQ(model.nv(), 38);
  EXPECT_TRUE(model.hasFreeFlyer());
  EXPECT_NEAR(model.totalMass(), 65.0, 1e-9);
}

TEST_F(Humanoid, ZeroPoseHeightIsPublished171) {
  standOnGround(Eigen::VectorXd::Zero(32));
  EXPECT_NEAR(z("WAIST"), 0.845, 1e-9);
  EXPECT_NEAR(z("HEAD_TOP"), 1.71, 1e-9);
}

TEST_F(Humanoid, ArmSpanIsPublished211) {
  Eigen::VectorXd j = Eigen::VectorXd::Zero(32);
  j[model.jointIndex("RARM_JOINT1")] = -M_PI / 2;  // arms raised sideways
  j[model.jointIndex("LARM_JOINT1")] = M_PI / 2;
  standOnGround(j);
  const double span = pos("LHAND_TIP").y() - pos("RHAND_TIP").y();
  EXPECT_NEAR(span, 2.110, 1e-9);
}

TEST_F(Humanoid, HalfSittingHeights) {
  standOnGround(model.posture("half_sitting"));
  // WAIST 0.776 m (published 0.773 m), CoM 0.879 m (published 0.87 m), shoulders 1.33 m.
  EXPECT_NEAR(z("WAIST"), 0.776, 0.0005);
  EXPECT_NEAR(model.centerOfMass(data).z(), 0.879, 0.0005);
  EXPECT_NEAR(z("RARM_LINK0"), 1.33, 0.005);
  EXPECT_NEAR(z("LARM_LINK0"), 1.33, 0.005);
  // Feet at y = -+0.105 m (published), soles flat, CoM between the feet.
  EXPECT_NEAR(pos("RSOLE").y(), -0.105, 1e-9);
  EXPECT_NEAR(pos("LSOLE").y(), 0.105, 1e-9);
  EXPECT_NEAR(z("RSOLE"), 0.0, 1e-9);
  const Eigen::Vector3d c = model.centerOfMass(data);
  EXPECT_LT(std::abs(c.x() - pos("RSOLE").x()), 0.108);
  EXPECT_NEAR(c.y(), 0.0, 1e-12);
  // No self-collision pair is closer than the safety distance in half-sitting.
  Eigen::RowVectorXd J(0);
  for (int p = 0; p < model.numCollisionPairs(); ++p) {
    EXPECT_GT(model.capsuleDistance(data, p, J).distance, model.description().collision_safety_distance) << p;
  }
}

TEST_F(Humanoid, ReachOfTheExperimentTargets) {
  // Shoulder-to-grasp-frame length with a straight arm: 0.30 + 0.30 + 0.15 = 0.75 m.
  standOnGround(model.posture("half_sitting"));
  Configuration q = standOnGround(model.posture("half_sitting"));
  for (const char* side : {"R", "L"}) {
    for (int k = 0; k < 7; ++k) q.joints[model.jointIndex(std::string(side) + "ARM_JOINT" + std::to_string(k))] = 0.0;
  }
  model.update(data, q, Eigen::VectorXd::Zero(model.nv()));
  const double reach = (pos("LGRASP") - pos("LARM_LINK0")).norm();
  EXPECT_NEAR(reach, 0.75, 1e-9);
  // In half-sitting: the pole and the first targets are within reach, the second targets not.
  q = standOnGround(model.posture("half_sitting"));
  const Eigen::Vector3d ls = pos("LARM_LINK0"), rs = pos("RARM_LINK0");
  EXPECT_LT((Eigen::Vector3d(0.5, 0.25, 1.0) - ls).norm(), reach);
  EXPECT_LT((Eigen::Vector3d(0.4, 0.5, 1.3) - ls).norm(), reach);
  EXPECT_LT((Eigen::Vector3d(0.4, -0.5, 1.3) - rs).norm(), reach);
  EXPECT_GT((Eigen::Vector3d(0.4, 2.0, 2.0) - ls).norm(), reach);
  EXPECT_GT((Eigen::Vector3d(0.4, -2.0, 2.0) - rs).norm(), reach);
}

}  // namespace
}  // namespace lexdyn::model
