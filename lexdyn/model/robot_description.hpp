// The validated description of a robot: a URDF (read with urdfdom) plus the robot's data file
// (YAML: base type, extra frames, contact surfaces, force sensors, self-collision capsules and
// pairs, named postures, friction coefficient). Format and conventions: docs/model.md.
//
// Everything here is plain data in SI units. The URDF is read as the URDF ecosystem (urdfdom, ROS,
// Pinocchio) reads it: links merged by fixed joints are lumped before their mass properties are
// checked, a fixed joint's axis, limits and mimic mean nothing, unspecified limits are unlimited,
// rounding noise in an inertia is projected away, a <mimic> joint is locked or coupled (docs/model.md,
// "Loading and validation"); each such reading is a warning saying what was assumed (`warnings`),
// and an error with LoadOptions::strict. Loading checks the files thoroughly and throws one
// lexdyn::InputError listing every problem found, each naming the file, the line and the element:
// missing links, bad joint references, bodies without mass or with a physically impossible inertia,
// unknown frame/link/joint/capsule names, values out of range.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <utility>
#include <vector>

namespace lexdyn::model {

enum class BaseType { Fixed, FreeFlyer };
enum class JointType { Revolute, Prismatic };

/// How the robot files are read.
struct LoadOptions {
  /// The strict rules: everything lexdyn otherwise reads leniently with a warning (an axis or
  /// limits on a fixed joint, <mimic>, unspecified limits, inertia rounding noise, a massless link
  /// where a body needs mass before lumping) is an error.
  bool strict = false;
  /// Folders searched for package://NAME/... URIs (a package NAME is the folder NAME under one of
  /// them, or a folder below one of them whose package.xml names NAME), before $ROS_PACKAGE_PATH.
  std::vector<std::string> package_paths;
  bool use_ros_package_path = true;  ///< also search the folders of $ROS_PACKAGE_PATH
  /// A mesh file that cannot be found is an error (robot init and check read them) rather than a
  /// warning (the dynamics does not need it).
  bool require_meshes = false;
};

/// A rigid body of the model: one URDF link, plus the links attached to it by fixed joints
/// (their mass is lumped into it and they become frames).
struct LinkDescription {
  std::string name;
  int parent_joint = -1;                              ///< index into RobotDescription::joints; -1 for the root (and a coupled body)
  int parent_coupled = -1;                            ///< index into RobotDescription::coupled_joints for a body moved by one
  double mass = 0.0;                                  ///< kg
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      ///< in the link frame, m
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  ///< about the CoM, link axes, kg m^2
  std::vector<std::string> merged_links;              ///< fixed-joint children lumped in
  int urdf_line = 0;                                  ///< line of the URDF <link>
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
  double lower = 0.0, upper = 0.0;                  ///< rad or m (+-inf: none, e.g. continuous joints)
  double velocity_limit = 0.0;                      ///< rad/s or m/s (+inf: unspecified)
  double effort_limit = 0.0;                        ///< Nm or N (+inf: unspecified)
  bool continuous = false;                          ///< a URDF continuous joint
  int urdf_line = 0;
};

/// A named frame rigidly attached to a link. Every link is a frame (identity placement); the
/// data file adds more (soles, sensors, grasp frames); links merged by fixed joints are frames.
struct FrameDescription {
  std::string name;
  int link = -1;
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();  ///< frame in its link frame
  bool from_data_file = false;                                  ///< given by the data file's frames (not a URDF link)
};

/// A <visual> or <collision> shape of a link, placed in its body's frame.
enum class GeometryType { Box, Sphere, Cylinder, Mesh };
struct GeometryDescription {
  GeometryType type = GeometryType::Box;
  bool collision = false;                                       ///< a <collision> element (else <visual>)
  int link = -1;                                                ///< the body it moves with (index into links)
  std::string urdf_link;                                        ///< the URDF link that carries it (a merged link keeps its name)
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();  ///< shape frame in the body frame
  Eigen::Vector3d size = Eigen::Vector3d::Zero();               ///< box edge lengths, m
  double radius = 0.0;                                          ///< sphere, cylinder, m
  double length = 0.0;                                          ///< cylinder (along its z axis), m
  std::string mesh_uri;                                         ///< as written in the URDF
  std::string mesh_path;                                        ///< the file it resolves to; empty when it was not found
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();
  int urdf_line = 0;
};

/// A URDF <mimic> on a moving joint: q_joint = multiplier * q_master + offset. Locked: the joint is
/// held at `locked_value` (it becomes a fixed joint; its link is lumped into its parent). Coupled:
/// the joint keeps its body and moves with its master (RobotDescription::coupled_joints).
enum class MimicMode { Locked, Coupled };
struct MimicDescription {
  std::string joint, master;
  double multiplier = 1.0, offset = 0.0;
  MimicMode mode = MimicMode::Locked;
  double locked_value = 0.0;  ///< rad or m
  int urdf_line = 0;
};

/// A <mimic> joint coupled to its master: one body on a mobilizer of its own whose coordinate is
/// not independent, q = multiplier * q_master + offset (the master a model joint; a mimic of a
/// mimic is composed down to it). Not a model joint: the controller's model and the simulator
/// work in the independent coordinates (docs/model.md, "Mimic joints").
struct CoupledJointDescription {
  std::string name;
  JointType type = JointType::Revolute;
  int parent_link = -1, child_link = -1;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< joint frame in the parent body at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();           ///< unit, joint frame
  int master = -1;                                           ///< model joint index (RobotDescription::joints)
  double multiplier = 1.0, offset = 0.0;
  double lower = 0.0, upper = 0.0;  ///< its own limits (rad or m; +-inf: none)
  double velocity_limit = 0.0;      ///< its own (rad/s or m/s; inf: none)
  int urdf_line = 0;
};

/// A moving URDF joint the loader holds fixed: a locked mimic joint, or a joint that moves only
/// massless links. Its child link is lumped into its parent at `value`.
struct LockedJointDescription {
  std::string name;
  double value = 0.0;  ///< rad or m
  std::string reason;  ///< "mimic" or "massless"
};

/// Servo gains of the joints whose names match `match` (a glob: * and ?); later groups override
/// earlier ones (the data file's `servo_gains`, the cases' default).
struct ServoGainGroup {
  std::string match;
  double kp = 0.0;  ///< N m/rad or N/m
  double kd = 0.0;  ///< N m s/rad or N s/m
};

/// A planar contact surface: points (in the surface frame) that may touch the ground.
struct ContactSurfaceDescription {
  std::string name;
  int frame = -1;
  /// Corner points in the frame; with radius > 0 the centres of spheres of that radius (ball
  /// feet), which touch the ground at their lowest points.
  std::vector<Eigen::Vector3d> points;
  double radius = 0.0;  ///< m; 0: points
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
  /// The data file's servo gain groups (empty when it has none).
  std::vector<ServoGainGroup> servo_gains;
  /// Shapes of every link (bodies and merged links), in URDF order.
  std::vector<GeometryDescription> geometries;
  /// The URDF's <mimic> joints on moving joints, and what they became.
  std::vector<MimicDescription> mimics;
  /// Every moving URDF joint the loader holds fixed (mimics and joints of massless links).
  std::vector<LockedJointDescription> locked_joints;
  /// The coupled mimic joints, each moving its own body (LinkDescription::parent_coupled).
  std::vector<CoupledJointDescription> coupled_joints;
  /// What the loader assumed or repaired ("file:line: what"), in the order found.
  std::vector<std::string> warnings;
  std::string urdf_root;  ///< the URDF's root link (before a floating joint from a world link)
  /// The data file's `urdf` key: the URDF it was written for, relative to the data file (robot
  /// check reads it when given the data file alone); empty when absent.
  std::string data_urdf;
  /// The data file's `mesh_up_axis: file`: COLLADA meshes are turned by the <up_axis> they
  /// declare (robot init, robot check, the replay; the dynamics use no mesh). Default `ignore`:
  /// their coordinates as written, as ROS's tools read them.
  bool mesh_up_axis_from_file = false;
  bool strict = false;  ///< read with LoadOptions::strict

  int findLink(const std::string& name) const;   ///< -1 when absent
  int findJoint(const std::string& name) const;  ///< -1 when absent
  int findFrame(const std::string& name) const;  ///< -1 when absent
  int findCapsule(const std::string& name) const;
  /// The body that body b hangs from (through its joint or its coupled joint); -1 for the root.
  int parentBody(int b) const;
  /// The placement of body b's joint frame in its parent body at q = 0, and its axis and type.
  const Eigen::Isometry3d& jointOrigin(int b) const;
  /// Like findJoint / findFrame, but throw lexdyn::InputError listing the known names when absent
  /// (the URDF for joints, the data file for frames and postures).
  int jointIndex(const std::string& name) const;
  int frameIndex(const std::string& name) const;
  const Eigen::VectorXd& posture(const std::string& name) const;
  double totalMass() const;
};

/// Reads and validates a URDF file and its data file. Throws lexdyn::InputError (every problem of
/// the files in one message).
RobotDescription loadRobotDescription(const std::string& urdf_path, const std::string& data_path, const LoadOptions& options = {});

/// Same, from text (used by tests); the names are used in messages and to resolve relative mesh
/// URIs (relative to the URDF name's folder).
RobotDescription parseRobotDescription(const std::string& urdf_text, const std::string& urdf_name, const std::string& data_text,
                                       const std::string& data_name, const LoadOptions& options = {});

/// A URDF without a data file (robot init, robot check): links, joints, frames of the links,
/// geometry, mimic joints (coupled to their masters, as without a data file's `mimic`); no surfaces,
/// sensors or postures. `base` as given; `mimic`: Locked holds the mimic joints at their masters'
/// zero (clamped into their limits).
RobotDescription loadUrdfOnly(const std::string& urdf_path, BaseType base, const LoadOptions& options = {},
                              MimicMode mimic = MimicMode::Coupled);

/// Rotation from URDF roll-pitch-yaw (fixed axes X, then Y, then Z: R = Rz(yaw) Ry(pitch) Rx(roll)).
Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy);

}  // namespace lexdyn::model
