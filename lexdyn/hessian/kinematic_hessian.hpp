// Analytic second derivatives of geometric task functions for LexDynAH (paper sec. VI-B).
//
// Coordinates. Every column i of the model's velocity u (docs/model.md) is the rate of one
// coordinate q_i at the current configuration: a joint angle / displacement, a base translation
// along a world axis, or a base rotation angle about a world axis (the base orientation written
// as Euler angles re-zeroed at this tick, R = Rx(t0) Ry(t1) Rz(t2) R_k). At the current
// configuration each coordinate moves its subtree by a rotation about (or a translation along)
// the world axis a_i through the point o_i given by RobotModel::dofAxes; the chain order
// ("inboard") is the one of model::KinematicTree (base translations inboard of base rotations,
// x rotation inboard of y inboard of z, then the joints).
//
// Second derivatives (symmetric, H_ij = H_ji; i inboard of or equal to j, both moving the point):
//  - position p of a point:   revolute i, revolute j:  a_i x (a_j x (p - o_j))
//                             revolute i, prismatic j: a_i x a_j
//                             prismatic i:             0
//  - orientation: the task function is the rotation vector phi(q) of R(q) R(q_k)^T (zero at
//    the current configuration, first derivative = the angular Jacobian). Revolute i strictly
//    inboard of revolute j: d2 phi / dq_i dq_j = 1/2 a_i x a_j; every other pair: 0.
//  - centre of mass: the mass-weighted position Hessians of all bodies, computed in O(nv^2)
//    from subtree masses and centres of mass.
// Each function accumulates H += sum_d w[d] * d^2 f_d / dq^2 for a weight vector w (the
// multipliers of eq. 21), in O(nv^2), without allocating. With coupled mimic joints the
// coordinates above are the tree's (one per mobilizer); the model's Hessian is G^T H_tree G with
// u_tree = G u (a tree coordinate is a linear function of the model's). Derivations, conventions and their
// verification: docs/controller.md, "Hessians".
#pragma once

#include <Eigen/Core>

#include <vector>

#include "lexdyn/model/robot_model.hpp"

namespace lexdyn::hessian {

/// Per-tick workspace (world axes and points of every dof, subtree centres of mass). Created
/// once per model (allocates); update() and the accumulate functions allocate nothing.
class KinematicHessianWorkspace {
 public:
  explicit KinematicHessianWorkspace(const model::RobotModel& model);
  /// Recomputes the dof axes/points and subtree CoMs for the data's current state (call after
  /// RobotModel::update, before the accumulate functions).
  void update(const model::RobotModel& model, const model::ModelData& data);

  /// The tree's dofs (model::RobotModel::numTreeDofs(): the model's, unless it has coupled joints).
  int nv() const { return static_cast<int>(axes_.cols()); }
  /// With coupled joints: a tree-size scratch the accumulate functions sum into before reducing
  /// to the model's dofs (G^T H G).
  Eigen::MatrixXd& treeScratch() const { return scratch_; }
  const Eigen::Matrix3Xd& axes() const { return axes_; }
  const Eigen::Matrix3Xd& points() const { return points_; }
  /// Centre of mass (world) of the subtree of the body moved by each dof's mobilizer (3 x nv).
  const Eigen::Matrix3Xd& subtreeCom() const { return subtreeCom_; }
  /// Mass of that subtree divided by the robot's total mass (nv).
  const Eigen::VectorXd& subtreeMassFraction() const { return subtreeMassFraction_; }
  /// Position of dof k in the ancestor list of its body (tree().bodies[b].ancestor_dofs): the
  /// dofs inboard of k (and k itself) are that list's entries 0..chainPosition(k).
  int chainPosition(int k) const { return chainPosition_[static_cast<size_t>(k)]; }

 private:
  Eigen::Matrix3Xd axes_, points_, subtreeCom_;
  Eigen::Matrix3Xd bodyMoment_;  ///< per body: mass-weighted sum of the subtree's body CoMs
  Eigen::VectorXd subtreeMassFraction_;
  std::vector<int> chainPosition_;
  mutable Eigen::MatrixXd scratch_;
};

/// Position of a point given in frame f's coordinates.
void accumulatePointHessian(const model::RobotModel& model, const model::ModelData& data, const KinematicHessianWorkspace& ws,
                            model::FrameId f, const Eigen::Vector3d& p_in_frame, const Eigen::Vector3d& w, Eigen::Ref<Eigen::MatrixXd> H);

/// Orientation of frame f (rotation-vector function, see above).
void accumulateOrientationHessian(const model::RobotModel& model, const model::ModelData& data, const KinematicHessianWorkspace& ws,
                                  model::FrameId f, const Eigen::Vector3d& w, Eigen::Ref<Eigen::MatrixXd> H);

/// Centre of mass of the whole robot.
void accumulateComHessian(const model::RobotModel& model, const KinematicHessianWorkspace& ws, const Eigen::Vector3d& w,
                          Eigen::Ref<Eigen::MatrixXd> H);

}  // namespace lexdyn::hessian
