// Internal: the Simbody side of RobotModel / ModelData. Included only by lexdyn/model source
// files (which are compiled with -UNDEBUG, see docs/architecture.md); the simulator builds its
// own Simbody system (harness/sim/multibody.hpp). Not a public header: it includes Simbody.
#pragma once

#include "lexdyn/model/robot_model.hpp"

#include <Simbody.h>

#include <Eigen/Core>

#include <vector>

namespace lexdyn::model {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

inline Eigen::Vector3d toEigen(const SimTK::Vec3& v) { return Eigen::Vector3d(v[0], v[1], v[2]); }
inline SimTK::Vec3 toSimTK(const Eigen::Vector3d& v) { return SimTK::Vec3(v[0], v[1], v[2]); }
inline Eigen::Matrix3d toEigen(const SimTK::Rotation& R) {
  Eigen::Matrix3d M;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) M(i, j) = R.asMat33()(i, j);
  return M;
}

namespace detail {

struct RobotModelImpl {
  explicit RobotModelImpl(RobotDescription d);
  RobotModelImpl(const RobotModelImpl&) = delete;
  RobotModelImpl& operator=(const RobotModelImpl&) = delete;

  RobotDescription desc;
  bool free_flyer = true;
  int nb = 0;  // bodies (description links)
  int nj = 0;  // actuated joints
  int nv = 0;
  // The tree's joints: one per body after the root (body b moves on tree joint b - 1): the model
  // joints and the coupled mimic joints (RobotDescription::coupled_joints). Without coupled
  // joints the tree joints are the model joints, in the same order.
  struct TreeJoint {
    JointType type = JointType::Revolute;
    int parent = -1;  // parent body
    Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit, joint frame
    int model_joint = -1;                             // the model joint it is, or its master's for a coupled one
    double multiplier = 1.0, offset = 0.0;            // q = multiplier * q_model_joint + offset
  };
  std::vector<TreeJoint> tree_joints;
  int nt = 0;                       // tree joints
  int ntv = 0;                      // tree dofs: (6) + nt
  bool coupled = false;             // some tree joint is coupled: the model's quantities are reduced
  std::vector<int> tree_dof_model;  // per tree dof: the model dof it moves with
  std::vector<double> tree_dof_multiplier;
  double total_mass = 0.0;

  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter;
  std::vector<SimTK::MobilizedBodyIndex> mobod;  // per body
  SimTK::State default_state;                    // Euler angles on, realized to Model
  int simbody_nq = 0, simbody_nu = 0;
  int base_q_index = 0;            // first q of the free-flyer (3 angles then 3 positions)
  std::vector<int> joint_q_index;  // per tree joint
  std::vector<int> dof_u_index;    // Simbody u index of each tree dof

  KinematicTree tree;
  std::vector<std::string> joint_names;
  Eigen::VectorXd lower, upper, velocity_limit, torque_limit;
  std::vector<Eigen::Vector3d> joint_axis_local;  // per tree joint, in the child body frame, normalised
                                                  // (as Simbody's mobilizers take it)
  std::vector<std::vector<int>> children;         // per body
};

struct ModelDataImpl {
  // The Simbody state of q and u, written and realized on demand (realizedState) by the const
  // reference operators: they write it, so one ModelData is not for concurrent use.
  mutable SimTK::State state;
  Configuration q;  // of the last update
  Eigen::VectorXd u;
  mutable bool state_current = false;  // `state` holds q and u
  bool updated = false;
  // Per body (world frame).
  std::vector<Eigen::Matrix3d> R;  // R_world_body
  Eigen::Matrix3Xd p;              // body origin
  Eigen::Matrix3Xd com;            // body CoM
  Eigen::Matrix3Xd omega;          // angular velocity
  Eigen::Matrix3Xd v;              // velocity of the body origin
  Eigen::Matrix3Xd alpha_bias;     // Jdot*u angular part (Simbody's total Coriolis acceleration)
  Eigen::Matrix3Xd a_bias;         // Jdot*u linear part at the body origin
  Eigen::Matrix3Xd subtree_com;    // CoM of the subtree rooted at each body
  // Per dof: motion subspace at the world origin [angular; linear] and its axis / point.
  Eigen::Matrix<double, 6, Eigen::Dynamic> S;
  Eigen::Matrix3Xd axis;
  Eigen::Matrix3Xd point;
  // Workspaces.
  std::vector<Matrix6d> composite;                  // composite spatial inertia (world origin)
  Eigen::Matrix<double, 6, Eigen::Dynamic> wrench;  // subtree wrench (world origin)
  // With coupled joints: the tree's coordinates and speeds, and the tree-size results reduced
  // to the model's (G^T M G, G^T N, J G).
  Eigen::VectorXd q_tree, u_tree;
  Eigen::MatrixXd M_tree;
  Eigen::VectorXd N_tree;
  mutable Eigen::MatrixXd J_tree;  // 6 x tree dofs
};

/// Fills the kinematic caches of `d` for the base of q, the tree joints' coordinates q_tree and
/// the tree speeds u_tree (our own recursion; Simbody is not realized).
void computeKinematics(const RobotModelImpl& m, ModelDataImpl& d, const Configuration& q, const Eigen::Ref<const Eigen::VectorXd>& q_tree,
                       const Eigen::Ref<const Eigen::VectorXd>& u_tree);

/// d.state realized to Velocity (for the Simbody reference operators).
const SimTK::State& realizedState(const RobotModelImpl& m, const ModelDataImpl& d);

}  // namespace detail

}  // namespace lexdyn::model
