// The simulator's own multibody system: a Simbody matter subsystem built from a
// RobotDescription by the simulator's code, not by lexdyn::model's. The controller's model and
// the simulator share the URDF and data-file reading (RobotDescription) and nothing after it,
// so that a conversion bug (an inertia shifted wrongly, a joint axis or frame mixed up, an index
// map off by one) cannot reach both the "true" dynamics and the controller unnoticed:
// tests/sim/test_model_vs_simulator.cpp compares the two on random states (docs/simulator.md,
// "The simulator's multibody system").
//
// Coordinates (the integrated state, docs/simulator.md "State and time"):
//   q = [body-fixed X-Y-Z Euler angles of the base (3); base link origin in world (3); joints]
//       for a free-flyer (nq = 6 + nj), q = joints for a fixed base;
//   u = [omega_world (3); v_base_origin_world (3); qdot_joints] (free-flyer), u = qdot_joints.
// Joints are in RobotDescription order. Simbody's own q and u numbering is mapped explicitly.
//
// Model / State split as in lexdyn::model: a Multibody is immutable after construction; every
// per-state result and the applied-force workspace live in a MultibodyState created (and
// sized) once by createState(). The "Simbody operator" queries (massMatrix, biasForces,
// frameJacobian, systemCenterOfMass) allocate temporaries and serve verification.
//
// This header includes no Simbody header.
#pragma once

#include "lexdyn/model/robot_description.hpp"
#include "lexdyn/model/robot_model.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

namespace lexdyn::sim {

/// Body kinematics at a state, world frame, one column / entry per body (description link order).
struct BodyKinematics {
  std::vector<Eigen::Matrix3d> R;  ///< R_world_body
  Eigen::Matrix3Xd p;              ///< body frame origin
  Eigen::Matrix3Xd com;            ///< body centre of mass
  Eigen::Matrix3Xd omega;          ///< angular velocity
  Eigen::Matrix3Xd v;              ///< velocity of the body frame origin
};

class Multibody;

/// Per-state workspace of a Multibody: Simbody state, body kinematics, applied forces.
class MultibodyState {
 public:
  MultibodyState(MultibodyState&&) noexcept;
  MultibodyState& operator=(MultibodyState&&) noexcept;
  ~MultibodyState();
  const BodyKinematics& bodies() const;

 private:
  friend class Multibody;
  struct Impl;
  explicit MultibodyState(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

class Multibody {
 public:
  explicit Multibody(model::RobotDescription description);
  Multibody(Multibody&&) noexcept;
  Multibody& operator=(Multibody&&) noexcept;
  ~Multibody();

  // ----- the robot (from its description) ------------------------------------------------
  const model::RobotDescription& description() const;
  const std::string& name() const;
  bool hasFreeFlyer() const;
  int numBodies() const;
  int numJoints() const;
  int nq() const;  ///< size of the coordinates q
  int nv() const;  ///< size of the speeds u
  double totalMass() const;
  const Eigen::Vector3d& gravity() const;
  const std::vector<std::string>& jointNames() const;
  const Eigen::VectorXd& jointTorqueLimits() const;
  int jointIndex(const std::string& name) const;          ///< throws InputError when absent
  model::FrameId frameId(const std::string& name) const;  ///< throws InputError when absent
  const Eigen::VectorXd& posture(const std::string& name) const;
  model::Configuration neutralConfiguration() const;  ///< identity base at the origin, joints 0

  /// q (nq) of a configuration: Euler angles by model::eulerXYZFromRotation.
  void coordinates(const model::Configuration& c, double* q) const;
  /// The configuration of q (nq); `c.joints` must be sized.
  void configuration(const double* q, model::Configuration& c) const;

  // ----- per state ----------------------------------------------------------------------
  MultibodyState createState() const;
  /// Sets q (nq) and u (nv), realizes Simbody's Velocity stage and fills the body kinematics.
  void setState(MultibodyState& s, const double* q, const double* u) const;
  /// As setState, with the same body kinematics to the bit, but Simbody's state realized through
  /// Position only: the body velocities come from the system Jacobian (J u) instead of the
  /// Velocity stage, whose velocity-dependent dynamics terms are not computed. For observations;
  /// coordinateRates(), accelerations(), netForce() and biasForces() need setState.
  void setKinematicState(MultibodyState& s, const double* q, const double* u) const;
  /// qdot = N(q) u at the state (Euler-angle rates, base velocity, joint rates), nq entries.
  void coordinateRates(const MultibodyState& s, double* qdot) const;

  Eigen::Isometry3d bodyPlacement(const MultibodyState& s, int body) const;
  Eigen::Isometry3d framePlacement(const MultibodyState& s, model::FrameId f) const;
  /// Centre of mass: body masses and centres accumulated from the leaves to the root.
  Eigen::Vector3d centerOfMass(const MultibodyState& s) const;

  // ----- applied forces and dynamics (in the state's force workspace) ---------------------
  void clearForces(MultibodyState& s) const;
  /// Adds a force on a body: the torque about the body frame's origin and the force (world).
  void addBodyForce(MultibodyState& s, int body, const Eigen::Vector3d& torque_about_origin, const Eigen::Vector3d& force) const;
  void setJointForce(MultibodyState& s, int joint, double tau) const;
  /// udot (nv) from the applied forces: Simbody's articulated-body forward dynamics.
  void accelerations(MultibodyState& s, double* udot) const;
  /// The net generalized force at rest-accelerations udot = 0: applied forces minus the
  /// velocity-dependent inertial terms (nv), from Simbody's inverse dynamics. At u = 0 it is
  /// zero exactly at a static equilibrium.
  void netForce(MultibodyState& s, double* f) const;

  // ----- for the integrator's Jacobian (docs/simulator.md, "Integrator") -------------------
  /// Jacobian (6 x nv, world, rows [linear; angular]) of the point r_body (body frame) of a
  /// body: its velocity and the body's angular velocity are J u. calcFrameJacobian.
  void pointJacobian(MultibodyState& s, int body, const Eigen::Vector3d& r_body, Eigen::Ref<Eigen::MatrixXd> J) const;
  /// M(q)^-1 (nv x nv): calcMInv.
  void inverseMassMatrix(MultibodyState& s, Eigen::Ref<Eigen::MatrixXd> Minv) const;
  /// N(q) (nq x nv) of qdot = N(q) u: multiplyByN, one column per speed.
  void rateMatrix(MultibodyState& s, Eigen::Ref<Eigen::MatrixXd> N) const;

  // ----- Simbody's operators at the state (allocate; for verification) ---------------------
  /// Joint-space inertia matrix (nv x nv), calcM.
  void massMatrix(const MultibodyState& s, Eigen::Ref<Eigen::MatrixXd> M) const;
  /// Coriolis, centrifugal and gravity forces (nv): calcResidualForceIgnoringConstraints at
  /// udot = 0 with gravity applied at every body's centre of mass, so M udot + N = tau.
  void biasForces(const MultibodyState& s, Eigen::Ref<Eigen::VectorXd> N) const;
  /// calcFrameJacobian of a frame's origin (6 x nv), rows reordered to [linear; angular].
  void frameJacobian(const MultibodyState& s, model::FrameId f, Eigen::Ref<Eigen::MatrixXd> J) const;
  /// calcSystemMassCenterLocationInGround.
  Eigen::Vector3d systemCenterOfMass(const MultibodyState& s) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lexdyn::sim
