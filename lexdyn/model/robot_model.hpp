// The controller's robot model: a URDF + data file (robot_description.hpp) turned into a Simbody
// matter subsystem, with the per-tick queries a whole-body controller needs. No simulator here.
//
// Conventions (docs/model.md):
//  - Configuration: base pose (rotation R_world_base, position of the base link frame origin in
//    world) + joint positions in model joint order (RobotDescription::joints).
//  - Velocity u (size nv): free-flyer  u = [omega_world(3); v_base_origin_world(3); qdot_joints]
//    (nv = 6 + nj); fixed base u = qdot_joints. These are Simbody's generalized speeds. They are
//    also the rates of the paper's base Euler angles re-zeroed at every tick (R = Rx Ry Rz(theta)
//    R_k, theta = 0 at the tick): the Euler-rate matrix is the identity at theta = 0.
//  - M, N and every Jacobian are with respect to u; M udot + N(q, u) = S^T tau + sum J^T f.
//  - Jacobian rows are [linear; angular], in the world frame: J u = [v_point_world; omega_world].
//    Jdot*u biases are the classical accelerations of the same rows at udot = 0.
//
// Model / Data split: RobotModel is immutable after loading; every per-tick result is written
// into a ModelData created once by createData() or into caller-provided outputs. update() and
// every query below are allocation-free (checked by tests/model/test_model_allocation.cpp);
// the "Reference" queries call Simbody's own O(n) operators, allocate, and serve verification.
#pragma once

#include "lexdyn/model/robot_description.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

namespace lexdyn::model {

using FrameId = int;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Configuration q. For a fixed base, base_rotation/base_position are ignored (identity/zero).
struct Configuration {
  Eigen::Matrix3d base_rotation = Eigen::Matrix3d::Identity();  ///< R_world_base
  Eigen::Vector3d base_position = Eigen::Vector3d::Zero();      ///< base link origin, world, m
  Eigen::VectorXd joints;                                       ///< model joint order, rad / m
};

/// Kind of a degree of freedom (column of u). The free-flyer's angular dofs are revolute about
/// the world axes through the base origin, its linear dofs prismatic along the world axes.
enum class DofType { Revolute, Prismatic };

/// The kinematic tree, for analytic derivatives (e.g. Hessians) built on top of the model.
/// Bodies are in tree order (parents before children); body 0 is the base.
struct KinematicTree {
  struct Body {
    std::string name;
    int parent = -1;                                    ///< parent body, -1 for the base
    double mass = 0.0;                                  ///< kg
    Eigen::Vector3d com = Eigen::Vector3d::Zero();      ///< in the body frame
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  ///< about the CoM, body axes
    double subtree_mass = 0.0;                          ///< mass of the body and all its descendants
    std::vector<int> dofs;                              ///< dofs of this body's own mobilizer
    std::vector<int> ancestor_dofs;                     ///< every dof that moves this body, from the ground outwards
  };
  struct Dof {
    DofType type = DofType::Revolute;
    int body = -1;    ///< body whose mobilizer this dof belongs to
    int parent = -1;  ///< nearest dof inboard of this one along the chain to the ground (-1: none)
    int joint = -1;   ///< model joint index, -1 for the free-flyer's dofs
  };
  std::vector<Body> bodies;
  std::vector<Dof> dofs;
  /// Free-flyer chain from the ground: dofs 3, 4, 5 (translations x, y, z), then 0, 1, 2
  /// (rotations about x, y, z). With the re-zeroed Euler angles R = Rx(t0) Ry(t1) Rz(t2) R_k the
  /// x rotation is inboard of y, y inboard of z, and the translations inboard of all rotations.
  bool dofMovesBody(int dof, int body) const;
};

/// One self-collision pair evaluation.
struct CapsuleDistance {
  double distance = 0.0;                              ///< surface distance, m (< 0: penetration)
  Eigen::Vector3d point_a = Eigen::Vector3d::Zero();  ///< witness point on segment a (world)
  Eigen::Vector3d point_b = Eigen::Vector3d::Zero();  ///< witness point on segment b (world)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, from b towards a
};

class RobotModel;

namespace detail {
// The Simbody side of RobotModel and ModelData (lexdyn/model/detail/model_impl.hpp, internal).
struct RobotModelImpl;
struct ModelDataImpl;
}  // namespace detail

/// Per-tick workspace of a RobotModel (Simbody state + cached kinematics). Create with
/// RobotModel::createData(); use only with the model that created it.
class ModelData {
 public:
  ModelData(ModelData&&) noexcept;
  ModelData& operator=(ModelData&&) noexcept;
  ~ModelData();

 private:
  friend class RobotModel;
  using Impl = detail::ModelDataImpl;
  explicit ModelData(std::unique_ptr<Impl> impl);
  Impl& impl() { return *impl_; }
  const Impl& impl() const { return *impl_; }
  std::unique_ptr<Impl> impl_;
};

class RobotModel {
 public:
  /// Loads and validates the files (throws lexdyn::InputError naming file and element).
  static RobotModel fromFiles(const std::string& urdf_path, const std::string& data_path, const LoadOptions& options = {});
  explicit RobotModel(RobotDescription description);
  RobotModel(RobotModel&&) noexcept;
  RobotModel& operator=(RobotModel&&) noexcept;
  ~RobotModel();

  // ----- sizes and names ----------------------------------------------------------------
  const RobotDescription& description() const;
  const std::string& name() const;
  bool hasFreeFlyer() const;
  int nv() const;                                                     ///< size of u
  int numJoints() const;                                              ///< actuated joints
  int jointVelocityOffset() const { return hasFreeFlyer() ? 6 : 0; }  ///< u index of joint 0
  int numBodies() const;
  int numFrames() const;
  double totalMass() const;
  const Eigen::Vector3d& gravity() const;
  const std::vector<std::string>& jointNames() const;
  /// Throws InputError listing the known names when absent.
  int jointIndex(const std::string& name) const;
  FrameId frameId(const std::string& name) const;
  const std::string& frameName(FrameId f) const;
  int frameBody(FrameId f) const;
  const Eigen::Isometry3d& frameInBody(FrameId f) const;
  const Eigen::VectorXd& jointLowerLimits() const;
  const Eigen::VectorXd& jointUpperLimits() const;
  const Eigen::VectorXd& jointVelocityLimits() const;
  const Eigen::VectorXd& jointTorqueLimits() const;
  /// Named posture from the data file (throws InputError when absent).
  const Eigen::VectorXd& posture(const std::string& name) const;
  const KinematicTree& tree() const;
  /// Coupled mimic joints (docs/model.md, "Mimic joints") move with their masters, so the model's
  /// dofs (the columns of u) are fewer than its tree's: one dof per body's mobilizer, in body
  /// order (the free-flyer's first). tree(), dofAxes() and the analytic Hessians work in the tree
  /// dofs; every other query in the model's (G^T M G, G^T N, J G with u_tree = G u). Without
  /// coupled joints the two are the same, dof for dof.
  bool hasCoupledJoints() const;
  int numTreeDofs() const;
  int treeDofModel(int k) const;          ///< the model dof tree dof k moves with
  double treeDofMultiplier(int k) const;  ///< its factor (1 for a model dof)

  // ----- configuration helpers ------------------------------------------------------------
  Configuration neutralConfiguration() const;  ///< identity base at the origin, joints 0
  /// q_next = q "+" dt u, consistent with the paper's linear integration: joints and base
  /// position linearly; base rotation R_next = Rx(a) Ry(b) Rz(c) R with (a,b,c) = dt*omega_world
  /// (Euler angles re-zeroed at q). Allocation-free if `out.joints` has the right size.
  void integrate(const Configuration& q, const Eigen::Ref<const Eigen::VectorXd>& u, double dt, Configuration& out) const;
  /// The inverse of integrate with dt = 1: out such that integrate(q0, out, 1) == q1
  /// (requires the relative rotation's middle Euler angle away from +-90 deg).
  void difference(const Configuration& q0, const Configuration& q1, Eigen::Ref<Eigen::VectorXd> out) const;

  // ----- per tick -------------------------------------------------------------------------
  ModelData createData() const;
  /// Sets the state and computes kinematics (poses, velocities, velocity-product
  /// accelerations). Must be called before any query below.
  void update(ModelData& data, const Configuration& q, const Eigen::Ref<const Eigen::VectorXd>& u) const;

  /// Joint-space inertia matrix (nv x nv), composite-rigid-body algorithm (uses the data's
  /// workspace, hence the non-const data).
  void massMatrix(ModelData& data, Eigen::Ref<Eigen::MatrixXd> M) const;
  /// N(q, u) = Coriolis/centrifugal + gravity generalized forces (nv), Newton-Euler.
  void nonlinearEffects(ModelData& data, Eigen::Ref<Eigen::VectorXd> N) const;

  /// Pose of a frame in world.
  Eigen::Isometry3d framePlacement(const ModelData& data, FrameId f) const;
  /// [v_origin_world; omega_world] of a frame.
  Vector6d frameVelocity(const ModelData& data, FrameId f) const;
  /// 6 x nv, rows [linear velocity of the frame origin; angular velocity], world frame.
  void frameJacobian(const ModelData& data, FrameId f, Eigen::Ref<Eigen::MatrixXd> J) const;
  /// Jdot*u of frameJacobian: [classical acceleration of the origin; angular acceleration].
  Vector6d frameBias(const ModelData& data, FrameId f) const;
  /// 3 x nv Jacobian of a point given in the frame's coordinates.
  void pointJacobian(const ModelData& data, FrameId f, const Eigen::Vector3d& p_in_frame, Eigen::Ref<Eigen::MatrixXd> J) const;
  Eigen::Vector3d pointPosition(const ModelData& data, FrameId f, const Eigen::Vector3d& p_in_frame) const;
  Eigen::Vector3d pointVelocity(const ModelData& data, FrameId f, const Eigen::Vector3d& p_in_frame) const;
  Eigen::Vector3d pointBias(const ModelData& data, FrameId f, const Eigen::Vector3d& p_in_frame) const;

  Eigen::Vector3d centerOfMass(const ModelData& data) const;
  Eigen::Vector3d centerOfMassVelocity(const ModelData& data) const;
  /// 3 x nv, O(nv): subtree masses and centres of mass, not summed station Jacobians.
  void centerOfMassJacobian(const ModelData& data, Eigen::Ref<Eigen::MatrixXd> J) const;
  Eigen::Vector3d centerOfMassBias(const ModelData& data) const;

  /// Self-collision pair `pair` (index into description().collision_pairs): distance and, if
  /// J is non-empty (1 x nv; may be a row of a column-major matrix), its Jacobian
  /// n^T (J_a - J_b) at the witness points.
  CapsuleDistance capsuleDistance(const ModelData& data, int pair, Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> J) const;
  int numCollisionPairs() const;

  /// World axis and a point on the axis of every tree dof (3 x numTreeDofs() each), for analytic
  /// derivatives.
  void dofAxes(const ModelData& data, Eigen::Ref<Eigen::Matrix3Xd> axes, Eigen::Ref<Eigen::Matrix3Xd> points) const;
  /// World pose of a body frame.
  Eigen::Isometry3d bodyPlacement(const ModelData& data, int body) const;

  // ----- Simbody reference operators (allocate; for verification) -------------------------
  void massMatrixReference(const ModelData& data, Eigen::Ref<Eigen::MatrixXd> M) const;  ///< calcM
  /// calcResidualForceIgnoringConstraints: tau = M udot + N with gravity as applied body forces.
  void inverseDynamicsReference(const ModelData& data, const Eigen::Ref<const Eigen::VectorXd>& udot,
                                Eigen::Ref<Eigen::VectorXd> tau) const;
  /// Articulated-body forward dynamics with gravity: udot from generalized forces tau (nv).
  void forwardDynamicsReference(ModelData& data, const Eigen::Ref<const Eigen::VectorXd>& tau, Eigen::Ref<Eigen::VectorXd> udot) const;
  /// calcFrameJacobian, reordered to [linear; angular].
  void frameJacobianReference(const ModelData& data, FrameId f, Eigen::Ref<Eigen::MatrixXd> J) const;
  Eigen::Vector3d centerOfMassReference(const ModelData& data) const;  ///< Simbody's system CoM

 private:
  using Impl = detail::RobotModelImpl;
  std::unique_ptr<Impl> impl_;
};

/// Rx(a) Ry(b) Rz(c) for e = (a, b, c) (body-fixed X-Y-Z Euler angles, Simbody's sequence).
Eigen::Matrix3d rotationFromEulerXYZ(const Eigen::Vector3d& e);
/// Inverse of rotationFromEulerXYZ, b in [-pi/2, pi/2].
Eigen::Vector3d eulerXYZFromRotation(const Eigen::Matrix3d& R);

}  // namespace lexdyn::model
