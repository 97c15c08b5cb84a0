// Analytic second derivatives of point positions, frame orientations and the centre of mass
// (paper sec. VI-B; the formulas are derived in kinematic_hessian.hpp and docs/controller.md,
// "Hessians").
//
// Notation: chain = the dofs moving a body, from the ground outwards
// (KinematicTree::Body::ancestor_dofs); for two entries i (position a) and j (position b >= a) of
// one chain, i is inboard of or equal to j. Moving a revolute coordinate q_i rotates everything
// outboard of it (points, axes, axis points) about a_i, so the derivative of any vector v
// attached to the subtree is a_i x v; a prismatic coordinate translates it and leaves vectors
// (axes, differences of points) unchanged. Applied to the Jacobian column J_j of a point:
//   d J_j / d q_i = a_i x J_j   (revolute i inboard of or equal to j), 0 (prismatic i),
// which is the Hessian entry H_ij = H_ji. The weighted sum w . (a_i x J_j) is evaluated as a
// scalar triple product, so each pair costs one cross and one dot product.
#include "lexdyn/hessian/kinematic_hessian.hpp"

#include "lexdyn/common/error.hpp"

namespace lexdyn::hessian {

namespace {

inline void addSymmetric(Eigen::Ref<Eigen::MatrixXd>& H, int i, int j, double h) {
  H(i, j) += h;
  if (i != j) H(j, i) += h;
}

}  // namespace

void pointHessianOfTree(const model::RobotModel& model, const model::ModelData& data, const KinematicHessianWorkspace& ws, model::FrameId f,
                        const Eigen::Vector3d& p_in_frame, const Eigen::Vector3d& w, Eigen::Ref<Eigen::MatrixXd>& H);
void orientationHessianOfTree(const model::RobotModel& model, const KinematicHessianWorkspace& ws, model::FrameId f,
                              const Eigen::Vector3d& w, Eigen::Ref<Eigen::MatrixXd>& H);
void comHessianOfTree(const model::RobotModel& model, const KinematicHessianWorkspace& ws, const Eigen::Vector3d& w,
                      Eigen::Ref<Eigen::MatrixXd>& H);

namespace {

// H += G^T T G (the tree's Hessian T to the model's dofs).
void addReduced(const model::RobotModel& model, const Eigen::MatrixXd& T, Eigen::Ref<Eigen::MatrixXd>& H) {
  const int n = static_cast<int>(T.rows());
  for (int j = 0; j < n; ++j) {
    const int cj = model.treeDofModel(j);
    const double gj = model.treeDofMultiplier(j);
    for (int i = 0; i < n; ++i) {
      const double t = T(i, j);
      if (t != 0.0) H(model.treeDofModel(i), cj) += model.treeDofMultiplier(i) * gj * t;
    }
  }
}

// Runs accumulate(target) on H directly, or on the workspace's tree-size scratch then reduces it.
template <class F>
void accumulateVia(const model::RobotModel& model, const KinematicHessianWorkspace& ws, Eigen::Ref<Eigen::MatrixXd> H, F accumulate) {
  if (!model.hasCoupledJoints()) {
    accumulate(H);
    return;
  }
  Eigen::MatrixXd& T = ws.treeScratch();
  T.setZero();
  Eigen::Ref<Eigen::MatrixXd> target(T);
  accumulate(target);
  addReduced(model, T, H);
}

}  // namespace

KinematicHessianWorkspace::KinematicHessianWorkspace(const model::RobotModel& model) {
  const int nv = model.numTreeDofs();
  if (model.hasCoupledJoints()) scratch_.setZero(nv, nv);
  const model::KinematicTree& tree = model.tree();
  axes_.setZero(3, nv);
  points_.setZero(3, nv);
  subtreeCom_.setZero(3, nv);
  bodyMoment_.setZero(3, model.numBodies());
  subtreeMassFraction_.setZero(nv);
  chainPosition_.assign(static_cast<size_t>(nv), -1);
  const double total = model.totalMass();
  LEXDYN_ALWAYS_ASSERT(total > 0.0, "KinematicHessianWorkspace: the robot has no mass");
  for (int k = 0; k < nv; ++k) {
    const int b = tree.dofs[static_cast<size_t>(k)].body;
    const std::vector<int>& chain = tree.bodies[static_cast<size_t>(b)].ancestor_dofs;
    for (size_t p = 0; p < chain.size(); ++p) {
      if (chain[p] == k) chainPosition_[static_cast<size_t>(k)] = static_cast<int>(p);
    }
    LEXDYN_ALWAYS_ASSERT(chainPosition_[static_cast<size_t>(k)] >= 0,
                         "KinematicHessianWorkspace: a dof is missing from its body's ancestor list");
    subtreeMassFraction_[k] = tree.bodies[static_cast<size_t>(b)].subtree_mass / total;
  }
  // The chain order must be the inboard order of KinematicTree::Dof::parent.
  for (int k = 0; k < nv; ++k) {
    const int b = tree.dofs[static_cast<size_t>(k)].body;
    const std::vector<int>& chain = tree.bodies[static_cast<size_t>(b)].ancestor_dofs;
    const int p = chainPosition_[static_cast<size_t>(k)];
    const int expected_parent = p == 0 ? -1 : chain[static_cast<size_t>(p - 1)];
    LEXDYN_ALWAYS_ASSERT(tree.dofs[static_cast<size_t>(k)].parent == expected_parent,
                         "KinematicHessianWorkspace: ancestor_dofs is not in chain order");
  }
}

void KinematicHessianWorkspace::update(const model::RobotModel& model, const model::ModelData& data) {
  LEXDYN_ALWAYS_ASSERT(model.numTreeDofs() == nv(), "KinematicHessianWorkspace::update: another model");
  model.dofAxes(data, axes_, points_);
  // Subtree centres of mass: bodies are in tree order (parents first), so one backward sweep
  // accumulates the mass-weighted body CoMs into every ancestor.
  const model::KinematicTree& tree = model.tree();
  const int nb = model.numBodies();
  for (int b = 0; b < nb; ++b) {
    const model::KinematicTree::Body& B = tree.bodies[static_cast<size_t>(b)];
    const Eigen::Isometry3d X = model.bodyPlacement(data, b);
    bodyMoment_.col(b) = B.mass * (X * B.com);
  }
  for (int b = nb - 1; b > 0; --b) {
    bodyMoment_.col(tree.bodies[static_cast<size_t>(b)].parent) += bodyMoment_.col(b);
  }
  for (int k = 0; k < nv(); ++k) {
    const int b = tree.dofs[static_cast<size_t>(k)].body;
    const double ms = tree.bodies[static_cast<size_t>(b)].subtree_mass;
    if (ms > 0.0) {
      subtreeCom_.col(k) = bodyMoment_.col(b) / ms;
    } else {
      subtreeCom_.col(k).setZero();
    }
  }
}

void accumulatePointHessian(const model::RobotModel& model, const model::ModelData& data, const KinematicHessianWorkspace& ws,
                            model::FrameId f, const Eigen::Vector3d& p_in_frame, const Eigen::Vector3d& w, Eigen::Ref<Eigen::MatrixXd> H) {
  const int nv = model.nv();
  LEXDYN_ALWAYS_ASSERT(H.rows() == nv && H.cols() == nv, "accumulatePointHessian: H must be nv x nv");
  accumulateVia(model, ws, H, [&](Eigen::Ref<Eigen::MatrixXd>& Ht) { pointHessianOfTree(model, data, ws, f, p_in_frame, w, Ht); });
}

void pointHessianOfTree(const model::RobotModel& model, const model::ModelData& data, const KinematicHessianWorkspace& ws, model::FrameId f,
                        const Eigen::Vector3d& p_in_frame, const Eigen::Vector3d& w, Eigen::Ref<Eigen::MatrixXd>& H) {
  const model::KinematicTree& tree = model.tree();
  const std::vector<int>& chain = tree.bodies[static_cast<size_t>(model.frameBody(f))].ancestor_dofs;
  const Eigen::Vector3d p = model.pointPosition(data, f, p_in_frame);
  const int n = static_cast<int>(chain.size());
  for (int b = 0; b < n; ++b) {
    const int j = chain[static_cast<size_t>(b)];
    const Eigen::Vector3d a_j = ws.axes().col(j);
    // Jacobian column of the point for dof j.
    const Eigen::Vector3d J_j =
        tree.dofs[static_cast<size_t>(j)].type == model::DofType::Revolute ? Eigen::Vector3d(a_j.cross(p - ws.points().col(j))) : a_j;
    // H_ij = a_i x J_j for revolute i inboard of or equal to j.
    for (int a = 0; a <= b; ++a) {
      const int i = chain[static_cast<size_t>(a)];
      if (tree.dofs[static_cast<size_t>(i)].type != model::DofType::Revolute) continue;
      addSymmetric(H, i, j, w.dot(ws.axes().col(i).cross(J_j)));
    }
  }
}

void accumulateOrientationHessian(const model::RobotModel& model, const model::ModelData& data, const KinematicHessianWorkspace& ws,
                                  model::FrameId f, const Eigen::Vector3d& w, Eigen::Ref<Eigen::MatrixXd> H) {
  (void)data;  // the axes in the workspace are all the orientation Hessian needs
  const int nv = model.nv();
  LEXDYN_ALWAYS_ASSERT(H.rows() == nv && H.cols() == nv, "accumulateOrientationHessian: H must be nv x nv");
  accumulateVia(model, ws, H, [&](Eigen::Ref<Eigen::MatrixXd>& Ht) { orientationHessianOfTree(model, ws, f, w, Ht); });
}

void orientationHessianOfTree(const model::RobotModel& model, const KinematicHessianWorkspace& ws, model::FrameId f,
                              const Eigen::Vector3d& w, Eigen::Ref<Eigen::MatrixXd>& H) {
  const model::KinematicTree& tree = model.tree();
  const std::vector<int>& chain = tree.bodies[static_cast<size_t>(model.frameBody(f))].ancestor_dofs;
  const int n = static_cast<int>(chain.size());
  // phi(q) = log(R(q) R(q_k)^T) = log(prod_i exp(q_i [a_i]x)) (product in chain order, world
  // axes at q_k) = sum_i q_i a_i + 1/2 sum_{i strictly inboard of j} q_i q_j a_i x a_j + O(3)
  // (Baker-Campbell-Hausdorff): H_ij = 1/2 a_i x a_j, diagonal and prismatic entries 0.
  for (int b = 1; b < n; ++b) {
    const int j = chain[static_cast<size_t>(b)];
    if (tree.dofs[static_cast<size_t>(j)].type != model::DofType::Revolute) continue;
    const Eigen::Vector3d half_w_x_a_j = 0.5 * ws.axes().col(j).cross(w);  // 1/2 a_j x w
    for (int a = 0; a < b; ++a) {
      const int i = chain[static_cast<size_t>(a)];
      if (tree.dofs[static_cast<size_t>(i)].type != model::DofType::Revolute) continue;
      // 1/2 w . (a_i x a_j) = a_i . (1/2 a_j x w)
      addSymmetric(H, i, j, ws.axes().col(i).dot(half_w_x_a_j));
    }
  }
}

void accumulateComHessian(const model::RobotModel& model, const KinematicHessianWorkspace& ws, const Eigen::Vector3d& w,
                          Eigen::Ref<Eigen::MatrixXd> H) {
  const int nv_model = model.nv();
  LEXDYN_ALWAYS_ASSERT(H.rows() == nv_model && H.cols() == nv_model, "accumulateComHessian: H must be nv x nv");
  accumulateVia(model, ws, H, [&](Eigen::Ref<Eigen::MatrixXd>& Ht) { comHessianOfTree(model, ws, w, Ht); });
}

void comHessianOfTree(const model::RobotModel& model, const KinematicHessianWorkspace& ws, const Eigen::Vector3d& w,
                      Eigen::Ref<Eigen::MatrixXd>& H) {
  const int nv = ws.nv();
  const model::KinematicTree& tree = model.tree();
  // c = sum_b m_b c_b / m. Dof j moves its body's subtree rigidly, so the CoM Jacobian column is
  // J_j = (m_sub(j) / m) (a_j x (c_sub(j) - o_j)) (revolute) or (m_sub(j) / m) a_j (prismatic), a
  // vector attached to that subtree; every body of the subtree is moved by all dofs inboard of
  // j, hence H_ij = a_i x J_j for revolute i inboard of or equal to j (sum of the bodies' point
  // Hessians), and 0 for pairs on different branches.
  for (int j = 0; j < nv; ++j) {
    const model::KinematicTree::Dof& D = tree.dofs[static_cast<size_t>(j)];
    const Eigen::Vector3d a_j = ws.axes().col(j);
    const double mf = ws.subtreeMassFraction()[j];
    const Eigen::Vector3d J_j = D.type == model::DofType::Revolute
                                    ? Eigen::Vector3d(mf * a_j.cross(ws.subtreeCom().col(j) - ws.points().col(j)))
                                    : Eigen::Vector3d(mf * a_j);
    const std::vector<int>& chain = tree.bodies[static_cast<size_t>(D.body)].ancestor_dofs;
    const int pj = ws.chainPosition(j);
    for (int a = 0; a <= pj; ++a) {
      const int i = chain[static_cast<size_t>(a)];
      if (tree.dofs[static_cast<size_t>(i)].type != model::DofType::Revolute) continue;
      addSymmetric(H, i, j, w.dot(ws.axes().col(i).cross(J_j)));
    }
  }
}

}  // namespace lexdyn::hessian
