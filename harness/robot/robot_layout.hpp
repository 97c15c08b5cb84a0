// What a robot's description says about its body plan, read off the URDF's kinematics and
// geometry in a posture (the base at the origin, unrotated): which chains are legs and where
// their feet touch the ground, which are arms and where their hands are, and how heavy each
// joint's load is. `robot init` drafts a data file and cases from it; `robot check` shows it.
#pragma once

#include "lexdyn/common/problems.hpp"
#include "lexdyn/model/robot_description.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace lexdyn::robot {

struct MeshCache;

/// Where a guessed value came from, for the comment beside it in a drafted file.
struct Sourced {
  double value = 0.0;
  std::string source;
};

struct FootLayout {
  std::string surface;                                             ///< contact surface name (LEFT_FOOT, FRONT_LEFT_FOOT, ...)
  int body = -1;                                                   ///< the body that carries the sole
  std::string link;                                                ///< that body's link name
  Eigen::Isometry3d sole_in_body = Eigen::Isometry3d::Identity();  ///< the sole frame (z up in the posture)
  std::vector<Eigen::Vector3d> points;                             ///< contact points in the sole frame (z = 0)
  std::vector<Eigen::Vector3d> points_world;
  bool point_foot = false;  ///< one contact point (a sphere or a tip)
  double radius = 0.0;      ///< a point foot that is the bottom of a collision sphere: its radius
  std::string source;       ///< which geometry gave the points
};

struct ArmLayout {
  std::string side;   ///< "LEFT", "RIGHT" or "" (a single arm)
  int end_body = -1;  ///< the hand's body
  std::string end_link;
  int first_joint = -1;                                ///< where the arm leaves the trunk (model joint index)
  Eigen::Vector3d shoulder = Eigen::Vector3d::Zero();  ///< first joint's origin, world
  Eigen::Vector3d grasp_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d grasp_in_body = Eigen::Vector3d::Zero();
  double reach = 0.0;  ///< shoulder to grasp point along the chain, fully stretched, m
  std::string source;
};

/// Standard gravity (m/s^2), for the loads, servo sizes and contact forces robot init drafts.
inline constexpr double kGravity = 9.81;

struct JointLoad {
  double mass = 0.0;     ///< kg the joint holds (its subtree, or the rest of the robot for a leg joint)
  double lever = 0.0;    ///< m, from the joint to that mass's centre of mass
  double inertia = 0.0;  ///< kg m^2 (kg): the load's inertia about the joint
  std::string what;      ///< "its subtree (arm)", "the robot above it, shared by 2 feet"
};

struct ServoGains {
  double kp = 0.0, kd = 0.0;
  std::string source;  ///< the sizing, in words, for the comment
};

struct RobotLayout {
  Eigen::VectorXd posture;  ///< model joint order
  /// The base's orientation in the layout's world: the identity, or turned so that two feet that
  /// the posture tilts stand flat (the base at the origin either way).
  Eigen::Matrix3d base_rotation = Eigen::Matrix3d::Identity();
  std::vector<Eigen::Isometry3d> body_pose;  ///< world pose of every body in the posture
  double lowest_z = 0.0, highest_z = 0.0;    ///< of the geometry (or the bodies) in the posture
  double height = 0.0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  double mass = 0.0;
  bool legged = false;
  /// The robot's forward direction in the world (+x, or -x when the links' names put its left at -y).
  Eigen::Vector3d forward = Eigen::Vector3d::UnitX();
  std::string sides_from = "geometry";  ///< how left and right were told: "names" or "geometry"
  std::string base_reason;              ///< why free-flyer or fixed
  std::vector<FootLayout> feet;
  std::vector<ArmLayout> arms;
  std::vector<JointLoad> loads;  ///< per model joint
  /// The bounding points (world) of every geometry of the description (same order as
  /// RobotDescription::geometries; a mesh that could not be read has none).
  std::vector<std::vector<Eigen::Vector3d>> geometry_points;
  std::vector<std::string> notes;     ///< what could not be found, what was assumed
  std::vector<std::string> warnings;  ///< what is likely wrong (a foot in the air in the posture)
};

/// The layout in `posture` (model joint order). `legged_hint`: the base type the URDF implies
/// (a robot whose root is welded to the world has no legs). Geometry meshes are read (problems
/// record a mesh that cannot be read). Throws nothing for a robot without feet or arms: the
/// lists are empty and `notes` say so. `cache`: meshes already read (and kept for the next call).
RobotLayout analyseLayout(const model::RobotDescription& d, const Eigen::VectorXd& posture, ProblemList& problems,
                          MeshCache* cache = nullptr);

/// Servo gains sized for joint j (docs/model.md, "Servo gains"): kp = load torque m g r over a
/// static deflection of 5 mrad, at least effort / 0.5 rad; kd = max(4 dt kp, 1.4 sqrt(kp I)).
ServoGains sizeServo(const model::RobotDescription& d, const RobotLayout& layout, int joint, double control_period_s);

/// The support polygon (convex hull of the feet's points in the ground plane, counter-clockwise)
/// and the signed distance of a point to its edges (> 0 inside).
std::vector<Eigen::Vector2d> supportPolygon(const RobotLayout& layout);
double marginInPolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p);
std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points);

}  // namespace lexdyn::robot
