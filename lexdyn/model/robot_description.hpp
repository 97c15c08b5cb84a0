// The validated description of a robot: a URDF (read with urdfdom) plus the robot's data file
// (YAML: base type, extra frames, contact surfaces, force sensors, self-collision capsules and
// pairs, named postures, friction coefficient). Format and conventions: docs/model.md.
//
// Everything here is plain data in SI units. Loading checks the files thoroughly and throws
// lexdyn::InputError naming the file, the line and the element for anything inconsistent:
// missing links, bad joint references, zero or negative mass, non-positive-definite or
// physically impossible inertia, unknown frame/link/joint/capsule names, values out of range.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <utility>
#include <vector>

namespace lexdyn::model {

enum class BaseType { Fixed, FreeFlyer };
enum class JointType { Revolute, Prismatic };

/// A rigid body of the model: one URDF link, plus the links attached to it by fixed joints
/// (their mass is lumped into it and they become frames).
struct LinkDescription {
  std::string name;
  int parent_joint = -1;        ///< index into RobotDescription::joints; -1 for the root
  double mass = 0.0;            ///< kg
  Eigen::Vector3d com = Eigen::Vector3d::Zero();              ///< in the link frame, m
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();          ///< about the CoM, link axes, kg m^2
  std::vector<std::string> merged_links;                      ///< fixed-joint children lumped in
};

/// An actuated one-degree-of-freedom joint. Joint i moves links[i + 1] (tree order).
struct JointDescription {
  std::string name;
  JointType type = JointType::Revolute;
  int parent_link = -1;  ///< index into RobotDescription::links
  int child_link = -1;
  /// Placement of the joint frame in the parent link frame at q = 0. The child link frame
  /// coincides with the joint frame rotated (revolute) or translated (prismatic) by q about /
  /// along `axis`.
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit vector in the joint frame
  double lower = 0.0, upper = 0.0;                  ///< rad or m (+-inf for continuous joints)
  double velocity_limit = 0.0;                      ///< rad/s or m/s
  double effort_limit = 0.0;                        ///< Nm or N
  int urdf_line = 0;
};

/// A named frame rigidly attached to a link. Every link is a frame (identity placement); the
/// data file adds more (soles, sensors, grasp frames); links merged by fixed joints are frames.
struct FrameDescription {
  std::string name;
  int link = -1;
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();  ///< frame in its link frame
};

/// A planar contact surface: points (in the surface frame) that may touch the ground.
struct ContactSurfaceDescription {
  std::string name;
  int frame = -1;
  std::vector<Eigen::Vector3d> points;
};

/// A 6-axis force/torque sensor. It reports the sum of the external contact wrenches applied to
/// the link it is attached to, expressed in its frame, about its origin.
struct ForceSensorDescription {
  std::string name;
  int frame = -1;
};

/// A capsule (segment p0-p1 in the link frame, swept by a sphere of `radius`).
struct CapsuleDescription {
  std::string name;
  int link = -1;
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero(), p1 = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

struct CollisionPairDescription {
  int capsule_a = -1, capsule_b = -1;
};

struct RobotDescription {
  std::string name;
  std::string urdf_path, data_path;
  BaseType base = BaseType::FreeFlyer;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< m/s^2, world frame
  double friction_coefficient = 0.0;

  /// Bodies in tree order: links[0] is the root; depth-first pre-order, siblings in the order
  /// their joints appear in the URDF file.
  std::vector<LinkDescription> links;
  /// Actuated joints; joints[i] moves links[i + 1]. This is the model's joint order.
  std::vector<JointDescription> joints;
  std::vector<FrameDescription> frames;
  std::vector<ContactSurfaceDescription> contact_surfaces;
  std::vector<ForceSensorDescription> force_sensors;
  std::vector<CapsuleDescription> capsules;
  std::vector<CollisionPairDescription> collision_pairs;
  double collision_interaction_distance = 0.05;  ///< m
  double collision_safety_distance = 0.01;       ///< m
  /// Named joint postures (model joint order), e.g. "half_sitting".
  std::vector<std::pair<std::string, Eigen::VectorXd>> postures;

  int findLink(const std::string& name) const;   ///< -1 when absent
  int findJoint(const std::string& name) const;  ///< -1 when absent
  int findFrame(const std::string& name) const;  ///< -1 when absent
  int findCapsule(const std::string& name) const;
  /// Like findJoint / findFrame, but throw lexdyn::InputError listing the known names when absent
  /// (the URDF for joints, the data file for frames and postures).
  int jointIndex(const std::string& name) const;
  int frameIndex(const std::string& name) const;
  const Eigen::VectorXd& posture(const std::string& name) const;
  double totalMass() const;
};

/// Reads and validates a URDF file and its data file. Throws lexdyn::InputError.
RobotDescription loadRobotDescription(const std::string& urdf_path, const std::string& data_path);

/// Same, from text (used by tests); the names are used in messages only.
RobotDescription parseRobotDescription(const std::string& urdf_text, const std::string& urdf_name,
                                       const std::string& data_text, const std::string& data_name);

/// Rotation from URDF roll-pitch-yaw (fixed axes X, then Y, then Z: R = Rz(yaw) Ry(pitch) Rx(roll)).
Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy);

}  // namespace lexdyn::model
