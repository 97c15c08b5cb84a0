// RobotModel: Simbody matter subsystem built from a RobotDescription, and the per-tick queries.
//
// Simbody computes the kinematics (body poses, velocities, velocity-product accelerations) in
// update(). The per-tick composite queries (M, N, Jacobians, CoM Jacobian, biases) are computed
// here from those cached quantities in world-frame spatial notation (motion subspace S_k of
// every dof, expressed at the world origin as [angular; linear]), because Simbody's own
// operators allocate temporaries on every call; the "Reference" functions call Simbody's
// operators and the tests compare the two (tests/model/test_model_dynamics.cpp).
#include "lexdyn/model/detail/model_impl.hpp"

#include "lexdyn/common/error.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lexdyn::model {

namespace {

// X = 0 by memset (+0.0 is all zero bits): Eigen's setZero() on a Ref with a run-time outer
// stride goes entry by entry (about 13 instructions an entry for a 3 x nv Jacobian). The same
// +0 entries.
void zeroFill(Eigen::Ref<Eigen::MatrixXd> X) {
  if (X.size() == 0) return;
  if (X.outerStride() == X.rows()) {
    std::memset(X.data(), 0, sizeof(double) * static_cast<size_t>(X.size()));
    return;
  }
  for (Eigen::Index c = 0; c < X.cols(); ++c) std::memset(X.col(c).data(), 0, sizeof(double) * static_cast<size_t>(X.rows()));
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

SimTK::Rotation toSimTKRotation(const Eigen::Matrix3d& R) {
  SimTK::Mat33 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = R(i, j);
  return SimTK::Rotation(m, true);
}

SimTK::Transform toSimTKTransform(const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
  return SimTK::Transform(toSimTKRotation(R), toSimTK(p));
}

// A rotation whose column `col` (0: x, 2: z) is the unit vector a.
Eigen::Matrix3d alignAxis(const Eigen::Vector3d& a, int col) {
  const Eigen::Vector3d n = a.normalized();
  // Any vector not parallel to n.
  const Eigen::Vector3d helper = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d b1 = n.cross(helper).normalized();
  const Eigen::Vector3d b2 = n.cross(b1);
  Eigen::Matrix3d R;
  if (col == 2) {
    R.col(0) = b1;
    R.col(1) = b2;
    R.col(2) = n;
  } else {
    R.col(0) = n;
    R.col(1) = b1;
    R.col(2) = b2;
  }
  return R;
}

SimTK::MassProperties massProperties(const LinkDescription& L) {
  if (L.mass == 0.0) return SimTK::MassProperties(0.0, SimTK::Vec3(0), SimTK::Inertia(0.0));
  const Eigen::Vector3d& c = L.com;
  const Eigen::Matrix3d I_O = L.inertia + L.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  const SimTK::Inertia inertia(SimTK::Vec3(I_O(0, 0), I_O(1, 1), I_O(2, 2)), SimTK::Vec3(I_O(0, 1), I_O(0, 2), I_O(1, 2)));
  return SimTK::MassProperties(L.mass, toSimTK(c), inertia);
}

}  // namespace

// =============================================================================================
// Euler angles
// =============================================================================================
Eigen::Matrix3d rotationFromEulerXYZ(const Eigen::Vector3d& e) {
  const double ca = std::cos(e[0]), sa = std::sin(e[0]);
  const double cb = std::cos(e[1]), sb = std::sin(e[1]);
  const double cc = std::cos(e[2]), sc = std::sin(e[2]);
  Eigen::Matrix3d R;
  R << cb * cc, -cb * sc, sb,                                    //
      ca * sc + sa * sb * cc, ca * cc - sa * sb * sc, -sa * cb,  //
      sa * sc - ca * sb * cc, sa * cc + ca * sb * sc, ca * cb;
  return R;
}

Eigen::Vector3d eulerXYZFromRotation(const Eigen::Matrix3d& R) {
  const double cb = std::sqrt(R(1, 2) * R(1, 2) + R(2, 2) * R(2, 2));
  const double b = std::atan2(R(0, 2), cb);
  if (cb < 1e-12) {
    // Gimbal lock (middle angle +-90 deg): only a combination of a and c is defined; take
    // a = 0, then R = Ry(b) Rz(c) and R(1, 0) = sin c, R(1, 1) = cos c.
    return Eigen::Vector3d(0.0, b, std::atan2(R(1, 0), R(1, 1)));
  }
  const double a = std::atan2(-R(1, 2), R(2, 2));
  const double c = std::atan2(-R(0, 1), R(0, 0));
  return Eigen::Vector3d(a, b, c);
}

bool KinematicTree::dofMovesBody(int dof, int body) const {
  const auto& a = bodies[static_cast<size_t>(body)].ancestor_dofs;
  return std::find(a.begin(), a.end(), dof) != a.end();
}

// =============================================================================================
// Construction
// =============================================================================================
detail::RobotModelImpl::RobotModelImpl(RobotDescription d) : desc(std::move(d)), matter(system) {
  free_flyer = desc.base == BaseType::FreeFlyer;
  nb = static_cast<int>(desc.links.size());
  nj = static_cast<int>(desc.joints.size());
  nv = nj + (free_flyer ? 6 : 0);
  const int off = free_flyer ? 6 : 0;
  total_mass = desc.totalMass();
  nt = nb - 1;
  ntv = nt + off;
  coupled = !desc.coupled_joints.empty();
  LEXDYN_ALWAYS_ASSERT(nt == nj + static_cast<int>(desc.coupled_joints.size()),
                       "description: one body per joint and coupled joint plus the root");

  // Tree joints in body order: body b moves on tree joint b - 1.
  tree_joints.resize(static_cast<size_t>(nt));
  for (int b = 1; b < nb; ++b) {
    const LinkDescription& L = desc.links[static_cast<size_t>(b)];
    TreeJoint& T = tree_joints[static_cast<size_t>(b - 1)];
    if (L.parent_joint >= 0) {
      const JointDescription& J = desc.joints[static_cast<size_t>(L.parent_joint)];
      T = {J.type, J.parent_link, J.origin, J.axis.normalized(), L.parent_joint, 1.0, 0.0};
    } else {
      const CoupledJointDescription& C = desc.coupled_joints[static_cast<size_t>(L.parent_coupled)];
      T = {C.type, C.parent_link, C.origin, C.axis.normalized(), C.master, C.multiplier, C.offset};
    }
    LEXDYN_ALWAYS_ASSERT(coupled || L.parent_joint == b - 1, "description: joint j moves body j + 1");
  }
  tree_dof_model.resize(static_cast<size_t>(ntv));
  tree_dof_multiplier.assign(static_cast<size_t>(ntv), 1.0);
  for (int k = 0; k < off; ++k) tree_dof_model[static_cast<size_t>(k)] = k;
  for (int t = 0; t < nt; ++t) {
    tree_dof_model[static_cast<size_t>(off + t)] = off + tree_joints[static_cast<size_t>(t)].model_joint;
    tree_dof_multiplier[static_cast<size_t>(off + t)] = tree_joints[static_cast<size_t>(t)].multiplier;
  }

  matter.setShowDefaultGeometry(false);
  mobod.resize(static_cast<size_t>(nb));
  for (int b = 0; b < nb; ++b) {
    const LinkDescription& L = desc.links[static_cast<size_t>(b)];
    SimTK::Body::Rigid body(massProperties(L));
    if (b == 0) {
      if (free_flyer) {
        SimTK::MobilizedBody::Free mb(matter.Ground(), SimTK::Transform(), body, SimTK::Transform());
        mobod[0] = mb.getMobilizedBodyIndex();
      } else {
        SimTK::MobilizedBody::Weld mb(matter.Ground(), SimTK::Transform(), body, SimTK::Transform());
        mobod[0] = mb.getMobilizedBodyIndex();
      }
      continue;
    }
    const TreeJoint& J = tree_joints[static_cast<size_t>(b - 1)];
    SimTK::MobilizedBody& parent = matter.updMobilizedBody(mobod[static_cast<size_t>(J.parent)]);
    const bool revolute = J.type == JointType::Revolute;
    // Pin rotates about the z axis of its F/M frames, Slider translates along x.
    const Eigen::Matrix3d R_align = alignAxis(J.axis, revolute ? 2 : 0);
    const SimTK::Transform X_PF = toSimTKTransform(J.origin.linear() * R_align, J.origin.translation());
    const SimTK::Transform X_BM = toSimTKTransform(R_align, Eigen::Vector3d::Zero());
    if (revolute) {
      SimTK::MobilizedBody::Pin mb(parent, X_PF, body, X_BM);
      mobod[static_cast<size_t>(b)] = mb.getMobilizedBodyIndex();
    } else {
      SimTK::MobilizedBody::Slider mb(parent, X_PF, body, X_BM);
      mobod[static_cast<size_t>(b)] = mb.getMobilizedBodyIndex();
    }
  }
  system.realizeTopology();
  default_state = system.getDefaultState();
  matter.setUseEulerAngles(default_state, true);
  system.realizeModel(default_state);
  simbody_nq = default_state.getNQ();
  simbody_nu = default_state.getNU();
  LEXDYN_ALWAYS_ASSERT(simbody_nu == ntv, "Simbody mobility count differs from the model's tree");

  // Index maps (Simbody numbers mobilities in mobilized-body order, which is our body order).
  joint_q_index.resize(static_cast<size_t>(nt));
  dof_u_index.resize(static_cast<size_t>(ntv));
  if (free_flyer) {
    const SimTK::MobilizedBody& base = matter.getMobilizedBody(mobod[0]);
    base_q_index = base.getFirstQIndex(default_state);
    const int u0 = base.getFirstUIndex(default_state);
    for (int k = 0; k < 6; ++k) dof_u_index[static_cast<size_t>(k)] = u0 + k;
  }
  for (int t = 0; t < nt; ++t) {
    const SimTK::MobilizedBody& mb = matter.getMobilizedBody(mobod[static_cast<size_t>(t + 1)]);
    joint_q_index[static_cast<size_t>(t)] = mb.getFirstQIndex(default_state);
    dof_u_index[static_cast<size_t>(off + t)] = mb.getFirstUIndex(default_state);
  }

  // Names and limits (model joints).
  lower.resize(nj);
  upper.resize(nj);
  velocity_limit.resize(nj);
  torque_limit.resize(nj);
  for (int j = 0; j < nj; ++j) {
    const JointDescription& J = desc.joints[static_cast<size_t>(j)];
    joint_names.push_back(J.name);
    lower[j] = J.lower;
    upper[j] = J.upper;
    velocity_limit[j] = J.velocity_limit;
    torque_limit[j] = J.effort_limit;
  }
  for (const TreeJoint& T : tree_joints) joint_axis_local.push_back(T.axis);

  // Kinematic tree (tree dofs).
  children.assign(static_cast<size_t>(nb), {});
  tree.bodies.resize(static_cast<size_t>(nb));
  tree.dofs.resize(static_cast<size_t>(ntv));
  for (int b = 0; b < nb; ++b) {
    const LinkDescription& L = desc.links[static_cast<size_t>(b)];
    KinematicTree::Body& B = tree.bodies[static_cast<size_t>(b)];
    B.name = L.name;
    B.mass = L.mass;
    B.com = L.com;
    B.inertia = L.inertia;
    if (b == 0) {
      B.parent = -1;
      if (free_flyer) {
        B.dofs = {0, 1, 2, 3, 4, 5};
        B.ancestor_dofs = {3, 4, 5, 0, 1, 2};
        const int parent_of[6] = {5, 0, 1, -1, 3, 4};
        for (int k = 0; k < 6; ++k) {
          KinematicTree::Dof& D = tree.dofs[static_cast<size_t>(k)];
          D.type = k < 3 ? DofType::Revolute : DofType::Prismatic;
          D.body = 0;
          D.parent = parent_of[k];
          D.joint = -1;
        }
      }
    } else {
      const TreeJoint& J = tree_joints[static_cast<size_t>(b - 1)];
      B.parent = J.parent;
      children[static_cast<size_t>(B.parent)].push_back(b);
      const int k = off + b - 1;
      B.dofs = {k};
      B.ancestor_dofs = tree.bodies[static_cast<size_t>(B.parent)].ancestor_dofs;
      KinematicTree::Dof& D = tree.dofs[static_cast<size_t>(k)];
      D.type = J.type == JointType::Revolute ? DofType::Revolute : DofType::Prismatic;
      D.body = b;
      D.parent = B.ancestor_dofs.empty() ? -1 : B.ancestor_dofs.back();
      D.joint = J.model_joint;
      B.ancestor_dofs.push_back(k);
    }
  }
  for (int b = nb - 1; b >= 0; --b) {
    KinematicTree::Body& B = tree.bodies[static_cast<size_t>(b)];
    B.subtree_mass += B.mass;
    if (B.parent >= 0) tree.bodies[static_cast<size_t>(B.parent)].subtree_mass += B.subtree_mass;
  }
}

RobotModel::RobotModel(RobotDescription description) : impl_(std::make_unique<Impl>(std::move(description))) {}
RobotModel RobotModel::fromFiles(const std::string& urdf_path, const std::string& data_path, const LoadOptions& options) {
  return RobotModel(loadRobotDescription(urdf_path, data_path, options));
}
RobotModel::RobotModel(RobotModel&&) noexcept = default;
RobotModel& RobotModel::operator=(RobotModel&&) noexcept = default;
RobotModel::~RobotModel() = default;

ModelData::ModelData(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ModelData::ModelData(ModelData&&) noexcept = default;
ModelData& ModelData::operator=(ModelData&&) noexcept = default;
ModelData::~ModelData() = default;

// =============================================================================================
// Sizes and names
// =============================================================================================
const RobotDescription& RobotModel::description() const { return impl_->desc; }
const std::string& RobotModel::name() const { return impl_->desc.name; }
bool RobotModel::hasFreeFlyer() const { return impl_->free_flyer; }
int RobotModel::nv() const { return impl_->nv; }
int RobotModel::numJoints() const { return impl_->nj; }
int RobotModel::numBodies() const { return impl_->nb; }
int RobotModel::numFrames() const { return static_cast<int>(impl_->desc.frames.size()); }
double RobotModel::totalMass() const { return impl_->total_mass; }
const Eigen::Vector3d& RobotModel::gravity() const { return impl_->desc.gravity; }
const std::vector<std::string>& RobotModel::jointNames() const { return impl_->joint_names; }
const Eigen::VectorXd& RobotModel::jointLowerLimits() const { return impl_->lower; }
const Eigen::VectorXd& RobotModel::jointUpperLimits() const { return impl_->upper; }
const Eigen::VectorXd& RobotModel::jointVelocityLimits() const { return impl_->velocity_limit; }
const Eigen::VectorXd& RobotModel::jointTorqueLimits() const { return impl_->torque_limit; }
const KinematicTree& RobotModel::tree() const { return impl_->tree; }
bool RobotModel::hasCoupledJoints() const { return impl_->coupled; }
int RobotModel::numTreeDofs() const { return impl_->ntv; }
int RobotModel::treeDofModel(int k) const { return impl_->tree_dof_model.at(static_cast<size_t>(k)); }
double RobotModel::treeDofMultiplier(int k) const { return impl_->tree_dof_multiplier.at(static_cast<size_t>(k)); }
int RobotModel::numCollisionPairs() const { return static_cast<int>(impl_->desc.collision_pairs.size()); }

int RobotModel::jointIndex(const std::string& n) const { return impl_->desc.jointIndex(n); }
FrameId RobotModel::frameId(const std::string& n) const { return impl_->desc.frameIndex(n); }

const std::string& RobotModel::frameName(FrameId f) const { return impl_->desc.frames.at(static_cast<size_t>(f)).name; }
int RobotModel::frameBody(FrameId f) const { return impl_->desc.frames.at(static_cast<size_t>(f)).link; }
const Eigen::Isometry3d& RobotModel::frameInBody(FrameId f) const { return impl_->desc.frames.at(static_cast<size_t>(f)).placement; }

const Eigen::VectorXd& RobotModel::posture(const std::string& n) const { return impl_->desc.posture(n); }

// =============================================================================================
// Configuration helpers
// =============================================================================================
Configuration RobotModel::neutralConfiguration() const {
  Configuration q;
  q.joints = Eigen::VectorXd::Zero(impl_->nj);
  return q;
}

void RobotModel::integrate(const Configuration& q, const Eigen::Ref<const Eigen::VectorXd>& u, double dt, Configuration& out) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(u.size() == m.nv && q.joints.size() == m.nj, "integrate: size mismatch");
  const int off = m.free_flyer ? 6 : 0;
  if (m.free_flyer) {
    const Eigen::Matrix3d dR = rotationFromEulerXYZ(dt * u.head<3>());
    const Eigen::Matrix3d R = dR * q.base_rotation;
    out.base_rotation = R;
    out.base_position = q.base_position + dt * u.segment<3>(3);
  } else {
    out.base_rotation = q.base_rotation;
    out.base_position = q.base_position;
  }
  out.joints = q.joints + dt * u.segment(off, m.nj);
}

void RobotModel::difference(const Configuration& q0, const Configuration& q1, Eigen::Ref<Eigen::VectorXd> out) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(out.size() == m.nv, "difference: size mismatch");
  const int off = m.free_flyer ? 6 : 0;
  if (m.free_flyer) {
    out.head<3>() = eulerXYZFromRotation(q1.base_rotation * q0.base_rotation.transpose());
    out.segment<3>(3) = q1.base_position - q0.base_position;
  }
  out.segment(off, m.nj) = q1.joints - q0.joints;
}

// =============================================================================================
// Per tick
// =============================================================================================
ModelData RobotModel::createData() const {
  const Impl& m = *impl_;
  auto d = std::make_unique<ModelData::Impl>();
  d->state = m.default_state;
  d->R.assign(static_cast<size_t>(m.nb), Eigen::Matrix3d::Identity());
  d->p.setZero(3, m.nb);
  d->com.setZero(3, m.nb);
  d->omega.setZero(3, m.nb);
  d->v.setZero(3, m.nb);
  d->alpha_bias.setZero(3, m.nb);
  d->a_bias.setZero(3, m.nb);
  d->subtree_com.setZero(3, m.nb);
  d->S.setZero(6, m.ntv);
  d->axis.setZero(3, m.ntv);
  d->point.setZero(3, m.ntv);
  d->composite.assign(static_cast<size_t>(m.nb), Matrix6d::Zero());
  d->wrench.setZero(6, m.nb);
  if (m.coupled) {
    d->q_tree.setZero(m.nt);
    d->u_tree.setZero(m.ntv);
    d->M_tree.setZero(m.ntv, m.ntv);
    d->N_tree.setZero(m.ntv);
    d->J_tree.setZero(6, m.ntv);
  }
  ModelData data(std::move(d));
  // One update so that the caches hold a valid state (Simbody's own caches are allocated when a
  // reference operator first realizes the state).
  const Configuration q0 = neutralConfiguration();
  update(data, q0, Eigen::VectorXd::Zero(m.nv));
  return data;
}

void RobotModel::update(ModelData& data, const Configuration& q, const Eigen::Ref<const Eigen::VectorXd>& u) const {
  const Impl& m = *impl_;
  ModelData::Impl& d = data.impl();
  LEXDYN_ALWAYS_ASSERT(q.joints.size() == m.nj, "update: configuration has the wrong number of joints");
  LEXDYN_ALWAYS_ASSERT(u.size() == m.nv, "update: velocity has the wrong size");
  // The Simbody state is for the reference operators only: q and u are kept, and written into it
  // when one of them asks (detail::realizedState), not here.
  d.q = q;  // same sizes: no allocation
  d.u = u;
  d.state_current = false;
  if (!m.coupled) {
    detail::computeKinematics(m, d, q, q.joints, u);
    return;
  }
  // The tree's coordinates: q_t = c q_master + o for a coupled joint, u_tree = G u.
  const int off = m.free_flyer ? 6 : 0;
  d.u_tree.head(off) = u.head(off);
  for (int t = 0; t < m.nt; ++t) {
    const detail::RobotModelImpl::TreeJoint& T = m.tree_joints[static_cast<size_t>(t)];
    d.q_tree[t] = T.multiplier * q.joints[T.model_joint] + T.offset;
    d.u_tree[off + t] = T.multiplier * u[off + T.model_joint];
  }
  detail::computeKinematics(m, d, q, d.q_tree, d.u_tree);
}

namespace detail {

const SimTK::State& realizedState(const RobotModelImpl& m, const ModelDataImpl& d) {
  if (!d.state_current) {
    SimTK::Vector& Q = d.state.updQ();
    if (m.free_flyer) {
      const Eigen::Vector3d e = eulerXYZFromRotation(d.q.base_rotation);
      for (int k = 0; k < 3; ++k) {
        Q[m.base_q_index + k] = e[k];
        Q[m.base_q_index + 3 + k] = d.q.base_position[k];
      }
    }
    const Eigen::VectorXd& qt = m.coupled ? d.q_tree : d.q.joints;
    const Eigen::VectorXd& ut = m.coupled ? d.u_tree : d.u;
    for (int t = 0; t < m.nt; ++t) Q[m.joint_q_index[static_cast<size_t>(t)]] = qt[t];
    SimTK::Vector& U = d.state.updU();
    for (int k = 0; k < m.ntv; ++k) U[m.dof_u_index[static_cast<size_t>(k)]] = ut[k];
    d.state_current = true;
  }
  m.system.realize(d.state, SimTK::Stage::Velocity);
  return d.state;
}

void computeKinematics(const RobotModelImpl& m, ModelDataImpl& d, const Configuration& q, const Eigen::Ref<const Eigen::VectorXd>& q_tree,
                       const Eigen::Ref<const Eigen::VectorXd>& u) {
  // Placements, velocities and velocity-product accelerations (Jdot u) of the bodies, root to
  // leaves (parents come before their children). The free-flyer's u are the base's angular
  // velocity and origin velocity in the world frame, so its Jdot u is zero; a joint sits at its
  // child's origin with its axis fixed in both bodies.
  if (m.free_flyer) {
    d.R[0] = q.base_rotation;
    d.p.col(0) = q.base_position;
    d.omega.col(0) = u.head<3>();
    d.v.col(0) = u.segment<3>(3);
  } else {
    d.R[0].setIdentity();
    d.p.col(0).setZero();
    d.omega.col(0).setZero();
    d.v.col(0).setZero();
  }
  d.alpha_bias.col(0).setZero();
  d.a_bias.col(0).setZero();
  const int off = m.free_flyer ? 6 : 0;
  for (int b = 1; b < m.nb; ++b) {
    const int j = b - 1;  // the body's tree joint
    const RobotModelImpl::TreeJoint& J = m.tree_joints[static_cast<size_t>(j)];
    const int P = J.parent;
    const Eigen::Matrix3d& RP = d.R[static_cast<size_t>(P)];
    const Eigen::Matrix3d RJ = RP * J.origin.linear();
    const Eigen::Vector3d& axis = m.joint_axis_local[static_cast<size_t>(j)];
    const double qj = q_tree[j];
    const double uj = u[off + j];
    const Eigen::Vector3d wP = d.omega.col(P);
    const Eigen::Vector3d a = RJ * axis;  // world axis (the same in the joint and child frames)
    Eigen::Matrix3d& R = d.R[static_cast<size_t>(b)];
    Eigen::Vector3d r = RP * J.origin.translation();
    if (J.type == JointType::Revolute) {
      R.noalias() = RJ * Eigen::AngleAxisd(qj, axis).toRotationMatrix();
      d.omega.col(b) = wP + a * uj;
      d.alpha_bias.col(b) = d.alpha_bias.col(P) + wP.cross(a * uj);
    } else {
      R = RJ;
      r += a * qj;
      d.omega.col(b) = wP;
      d.alpha_bias.col(b) = d.alpha_bias.col(P);
    }
    d.p.col(b) = d.p.col(P) + r;
    d.v.col(b) = d.v.col(P) + wP.cross(r);
    d.a_bias.col(b) = d.a_bias.col(P) + d.alpha_bias.col(P).cross(r) + wP.cross(wP.cross(r));
    if (J.type != JointType::Revolute) {
      d.v.col(b) += a * uj;
      d.a_bias.col(b) += 2.0 * wP.cross(a * uj);
    }
  }
  for (int b = 0; b < m.nb; ++b) {
    d.com.col(b) = d.p.col(b) + d.R[static_cast<size_t>(b)] * m.desc.links[static_cast<size_t>(b)].com;
  }

  // Motion subspaces at the world origin: revolute [a; o x a], prismatic [0; a].
  if (m.free_flyer) {
    const Eigen::Vector3d o = d.p.col(0);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = Eigen::Vector3d::Unit(k);
      d.axis.col(k) = a;
      d.point.col(k) = o;
      d.S.col(k).head<3>() = a;
      d.S.col(k).tail<3>() = o.cross(a);
      d.axis.col(3 + k) = a;
      d.point.col(3 + k) = o;
      d.S.col(3 + k).head<3>().setZero();
      d.S.col(3 + k).tail<3>() = a;
    }
  }
  for (int j = 0; j < m.nt; ++j) {
    const int b = j + 1;
    const int k = off + j;
    const Eigen::Vector3d a = d.R[static_cast<size_t>(b)] * m.joint_axis_local[static_cast<size_t>(j)];
    const Eigen::Vector3d o = d.p.col(b);
    d.axis.col(k) = a;
    d.point.col(k) = o;
    if (m.tree_joints[static_cast<size_t>(j)].type == JointType::Revolute) {
      d.S.col(k).head<3>() = a;
      d.S.col(k).tail<3>() = o.cross(a);
    } else {
      d.S.col(k).head<3>().setZero();
      d.S.col(k).tail<3>() = a;
    }
  }

  // Subtree centres of mass (children come after their parents in body order).
  for (int b = 0; b < m.nb; ++b) d.subtree_com.col(b) = m.tree.bodies[static_cast<size_t>(b)].mass * d.com.col(b);
  for (int b = m.nb - 1; b > 0; --b) {
    d.subtree_com.col(m.tree.bodies[static_cast<size_t>(b)].parent) += d.subtree_com.col(b);
  }
  for (int b = 0; b < m.nb; ++b) {
    const double ms = m.tree.bodies[static_cast<size_t>(b)].subtree_mass;
    if (ms > 0.0) d.subtree_com.col(b) /= ms;
  }
  d.updated = true;
}

}  // namespace detail

namespace {

// With coupled joints: the model's quantities from the tree's, u_tree = G u (G: one entry per
// tree dof, its multiplier in the column of its model dof).
void reduceMatrix(const detail::RobotModelImpl& m, const Eigen::MatrixXd& A, Eigen::Ref<Eigen::MatrixXd> out) {
  out.setZero();
  for (int j = 0; j < m.ntv; ++j) {
    const int cj = m.tree_dof_model[static_cast<size_t>(j)];
    const double gj = m.tree_dof_multiplier[static_cast<size_t>(j)];
    for (int i = 0; i < m.ntv; ++i) {
      out(m.tree_dof_model[static_cast<size_t>(i)], cj) += m.tree_dof_multiplier[static_cast<size_t>(i)] * gj * A(i, j);
    }
  }
}

void reduceVector(const detail::RobotModelImpl& m, const Eigen::VectorXd& a, Eigen::Ref<Eigen::VectorXd> out) {
  out.setZero();
  for (int i = 0; i < m.ntv; ++i) out[m.tree_dof_model[static_cast<size_t>(i)]] += m.tree_dof_multiplier[static_cast<size_t>(i)] * a[i];
}

void massMatrixOfTree(const detail::RobotModelImpl& m, detail::ModelDataImpl& d, Eigen::Ref<Eigen::MatrixXd> M);
void nonlinearEffectsOfTree(const detail::RobotModelImpl& m, detail::ModelDataImpl& d, Eigen::Ref<Eigen::VectorXd> N);

template <class Out>
void reduceColumns(const detail::RobotModelImpl& m, const Eigen::MatrixXd& A, int rows, Out& out) {
  out.setZero();
  for (int k = 0; k < m.ntv; ++k) {
    out.col(m.tree_dof_model[static_cast<size_t>(k)]) += m.tree_dof_multiplier[static_cast<size_t>(k)] * A.block(0, k, rows, 1);
  }
}

}  // namespace

void RobotModel::massMatrix(ModelData& data, Eigen::Ref<Eigen::MatrixXd> M) const {
  const Impl& m = *impl_;
  ModelData::Impl& d = data.impl();
  LEXDYN_ALWAYS_ASSERT(d.updated, "massMatrix: call update() first");
  LEXDYN_ALWAYS_ASSERT(M.rows() == m.nv && M.cols() == m.nv, "massMatrix: M must be nv x nv");
  if (m.coupled) {
    massMatrixOfTree(m, d, d.M_tree);
    reduceMatrix(m, d.M_tree, M);
    return;
  }
  massMatrixOfTree(m, d, M);
}

namespace {

void massMatrixOfTree(const detail::RobotModelImpl& m, detail::ModelDataImpl& d, Eigen::Ref<Eigen::MatrixXd> M) {
  // Spatial inertia of each body about the world origin, [angular; linear] ordering:
  //   I_O = [ Ic - m [c]x[c]x , m [c]x ; -m [c]x , m 1 ]
  for (int b = 0; b < m.nb; ++b) {
    const KinematicTree::Body& B = m.tree.bodies[static_cast<size_t>(b)];
    const Eigen::Matrix3d& R = d.R[static_cast<size_t>(b)];
    const Eigen::Matrix3d Ic = R * B.inertia * R.transpose();
    const Eigen::Matrix3d C = skew(d.com.col(b));
    Matrix6d& I = d.composite[static_cast<size_t>(b)];
    I.topLeftCorner<3, 3>() = Ic - B.mass * C * C;
    I.topRightCorner<3, 3>() = B.mass * C;
    I.bottomLeftCorner<3, 3>() = -B.mass * C;
    I.bottomRightCorner<3, 3>() = B.mass * Eigen::Matrix3d::Identity();
  }
  for (int b = m.nb - 1; b > 0; --b) {
    d.composite[static_cast<size_t>(m.tree.bodies[static_cast<size_t>(b)].parent)] += d.composite[static_cast<size_t>(b)];
  }
  zeroFill(M);
  for (int b = 0; b < m.nb; ++b) {
    const KinematicTree::Body& B = m.tree.bodies[static_cast<size_t>(b)];
    for (int i : B.dofs) {
      const Vector6d F = d.composite[static_cast<size_t>(b)] * d.S.col(i);
      for (int j : B.ancestor_dofs) {
        const double v = d.S.col(j).dot(F);
        M(i, j) = v;
        M(j, i) = v;
      }
    }
  }
}

}  // namespace

void RobotModel::nonlinearEffects(ModelData& data, Eigen::Ref<Eigen::VectorXd> N) const {
  const Impl& m = *impl_;
  ModelData::Impl& d = data.impl();
  LEXDYN_ALWAYS_ASSERT(d.updated, "nonlinearEffects: call update() first");
  LEXDYN_ALWAYS_ASSERT(N.size() == m.nv, "nonlinearEffects: N must have nv entries");
  if (m.coupled) {
    nonlinearEffectsOfTree(m, d, d.N_tree);
    reduceVector(m, d.N_tree, N);
    return;
  }
  nonlinearEffectsOfTree(m, d, N);
}

namespace {

void nonlinearEffectsOfTree(const detail::RobotModelImpl& m, detail::ModelDataImpl& d, Eigen::Ref<Eigen::VectorXd> N) {
  const Eigen::Vector3d& g = m.desc.gravity;
  // Newton-Euler wrench of each body at udot = 0, about the world origin:
  //   f = m (a_c - g),  n_O = Ic alpha + w x (Ic w) + c x f
  for (int b = 0; b < m.nb; ++b) {
    const KinematicTree::Body& B = m.tree.bodies[static_cast<size_t>(b)];
    const Eigen::Matrix3d& R = d.R[static_cast<size_t>(b)];
    const Eigen::Matrix3d Ic = R * B.inertia * R.transpose();
    const Eigen::Vector3d w = d.omega.col(b);
    const Eigen::Vector3d alpha = d.alpha_bias.col(b);
    const Eigen::Vector3d r = d.com.col(b) - d.p.col(b);
    const Eigen::Vector3d a_c = d.a_bias.col(b) + alpha.cross(r) + w.cross(w.cross(r));
    const Eigen::Vector3d f = B.mass * (a_c - g);
    const Eigen::Vector3d n = Ic * alpha + w.cross(Ic * w) + d.com.col(b).cross(f);
    d.wrench.col(b).head<3>() = n;
    d.wrench.col(b).tail<3>() = f;
  }
  for (int b = m.nb - 1; b > 0; --b) d.wrench.col(m.tree.bodies[static_cast<size_t>(b)].parent) += d.wrench.col(b);
  for (int k = 0; k < m.ntv; ++k) N[k] = d.S.col(k).dot(d.wrench.col(m.tree.dofs[static_cast<size_t>(k)].body));
}

}  // namespace

Eigen::Isometry3d RobotModel::bodyPlacement(const ModelData& data, int body) const {
  const ModelData::Impl& d = data.impl();
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = d.R[static_cast<size_t>(body)];
  X.translation() = d.p.col(body);
  return X;
}

Eigen::Isometry3d RobotModel::framePlacement(const ModelData& data, FrameId f) const {
  const FrameDescription& F = impl_->desc.frames[static_cast<size_t>(f)];
  return bodyPlacement(data, F.link) * F.placement;
}

Eigen::Vector3d RobotModel::pointPosition(const ModelData& data, FrameId f, const Eigen::Vector3d& p_in_frame) const {
  const FrameDescription& F = impl_->desc.frames[static_cast<size_t>(f)];
  const ModelData::Impl& d = data.impl();
  return d.p.col(F.link) + d.R[static_cast<size_t>(F.link)] * (F.placement * p_in_frame);
}

Eigen::Vector3d RobotModel::pointVelocity(const ModelData& data, FrameId f, const Eigen::Vector3d& p_in_frame) const {
  const FrameDescription& F = impl_->desc.frames[static_cast<size_t>(f)];
  const ModelData::Impl& d = data.impl();
  const Eigen::Vector3d r = d.R[static_cast<size_t>(F.link)] * (F.placement * p_in_frame);
  return d.v.col(F.link) + d.omega.col(F.link).cross(r);
}

Eigen::Vector3d RobotModel::pointBias(const ModelData& data, FrameId f, const Eigen::Vector3d& p_in_frame) const {
  const FrameDescription& F = impl_->desc.frames[static_cast<size_t>(f)];
  const ModelData::Impl& d = data.impl();
  const int b = F.link;
  const Eigen::Vector3d r = d.R[static_cast<size_t>(b)] * (F.placement * p_in_frame);
  const Eigen::Vector3d w = d.omega.col(b);
  return d.a_bias.col(b) + d.alpha_bias.col(b).cross(r) + w.cross(w.cross(r));
}

Vector6d RobotModel::frameVelocity(const ModelData& data, FrameId f) const {
  const FrameDescription& F = impl_->desc.frames[static_cast<size_t>(f)];
  Vector6d out;
  out.head<3>() = pointVelocity(data, f, Eigen::Vector3d::Zero());
  out.tail<3>() = data.impl().omega.col(F.link);
  return out;
}

void RobotModel::pointJacobian(const ModelData& data, FrameId f, const Eigen::Vector3d& p_in_frame, Eigen::Ref<Eigen::MatrixXd> J) const {
  const Impl& m = *impl_;
  const ModelData::Impl& d = data.impl();
  LEXDYN_ALWAYS_ASSERT(J.rows() == 3 && J.cols() == m.nv, "pointJacobian: J must be 3 x nv");
  const int b = m.desc.frames[static_cast<size_t>(f)].link;
  const Eigen::Vector3d p = pointPosition(data, f, p_in_frame);
  if (m.coupled) {
    d.J_tree.setZero();
    for (int k : m.tree.bodies[static_cast<size_t>(b)].ancestor_dofs) {
      d.J_tree.col(k).head<3>() = d.S.col(k).tail<3>() + d.S.col(k).head<3>().cross(p);
    }
    reduceColumns(m, d.J_tree, 3, J);
    return;
  }
  zeroFill(J);
  for (int k : m.tree.bodies[static_cast<size_t>(b)].ancestor_dofs) {
    J.col(k) = d.S.col(k).tail<3>() + d.S.col(k).head<3>().cross(p);
  }
}

void RobotModel::frameJacobian(const ModelData& data, FrameId f, Eigen::Ref<Eigen::MatrixXd> J) const {
  const Impl& m = *impl_;
  const ModelData::Impl& d = data.impl();
  LEXDYN_ALWAYS_ASSERT(J.rows() == 6 && J.cols() == m.nv, "frameJacobian: J must be 6 x nv");
  const int b = m.desc.frames[static_cast<size_t>(f)].link;
  const Eigen::Vector3d p = pointPosition(data, f, Eigen::Vector3d::Zero());
  if (m.coupled) {
    d.J_tree.setZero();
    for (int k : m.tree.bodies[static_cast<size_t>(b)].ancestor_dofs) {
      d.J_tree.col(k).head<3>() = d.S.col(k).tail<3>() + d.S.col(k).head<3>().cross(p);
      d.J_tree.col(k).tail<3>() = d.S.col(k).head<3>();
    }
    reduceColumns(m, d.J_tree, 6, J);
    return;
  }
  zeroFill(J);
  for (int k : m.tree.bodies[static_cast<size_t>(b)].ancestor_dofs) {
    J.col(k).head<3>() = d.S.col(k).tail<3>() + d.S.col(k).head<3>().cross(p);
    J.col(k).tail<3>() = d.S.col(k).head<3>();
  }
}

Vector6d RobotModel::frameBias(const ModelData& data, FrameId f) const {
  const int b = impl_->desc.frames[static_cast<size_t>(f)].link;
  Vector6d out;
  out.head<3>() = pointBias(data, f, Eigen::Vector3d::Zero());
  out.tail<3>() = data.impl().alpha_bias.col(b);
  return out;
}

Eigen::Vector3d RobotModel::centerOfMass(const ModelData& data) const { return data.impl().subtree_com.col(0); }

namespace {

// sum_b m_b x_b / M over the bodies, x_b = of_body(b, r_b) with r_b the body's CoM relative to
// its origin (world): the CoM's value of a rigid-body quantity given at the body origins.
template <class OfBody>
Eigen::Vector3d massWeightedMean(const detail::RobotModelImpl& m, const detail::ModelDataImpl& d, OfBody of_body) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int b = 0; b < m.nb; ++b) {
    const Eigen::Vector3d r = d.com.col(b) - d.p.col(b);
    sum += m.tree.bodies[static_cast<size_t>(b)].mass * of_body(b, r);
  }
  return sum / m.total_mass;
}

}  // namespace

Eigen::Vector3d RobotModel::centerOfMassVelocity(const ModelData& data) const {
  const ModelData::Impl& d = data.impl();
  return massWeightedMean(*impl_, d,
                          [&d](int b, const Eigen::Vector3d& r) -> Eigen::Vector3d { return d.v.col(b) + d.omega.col(b).cross(r); });
}

void RobotModel::centerOfMassJacobian(const ModelData& data, Eigen::Ref<Eigen::MatrixXd> J) const {
  const Impl& m = *impl_;
  const ModelData::Impl& d = data.impl();
  LEXDYN_ALWAYS_ASSERT(J.rows() == 3 && J.cols() == m.nv, "centerOfMassJacobian: J must be 3 x nv");
  // Column k moves the subtree of its body rigidly: the CoM moves by (m_sub / M) times the
  // velocity of the subtree's CoM.
  if (m.coupled) {
    d.J_tree.setZero();
    for (int k = 0; k < m.ntv; ++k) {
      const int b = m.tree.dofs[static_cast<size_t>(k)].body;
      const double w = m.tree.bodies[static_cast<size_t>(b)].subtree_mass / m.total_mass;
      d.J_tree.col(k).head<3>() = w * (d.S.col(k).tail<3>() + d.S.col(k).head<3>().cross(d.subtree_com.col(b)));
    }
    reduceColumns(m, d.J_tree, 3, J);
    return;
  }
  for (int k = 0; k < m.nv; ++k) {
    const int b = m.tree.dofs[static_cast<size_t>(k)].body;
    const double w = m.tree.bodies[static_cast<size_t>(b)].subtree_mass / m.total_mass;
    J.col(k) = w * (d.S.col(k).tail<3>() + d.S.col(k).head<3>().cross(d.subtree_com.col(b)));
  }
}

Eigen::Vector3d RobotModel::centerOfMassBias(const ModelData& data) const {
  const ModelData::Impl& d = data.impl();
  return massWeightedMean(*impl_, d, [&d](int b, const Eigen::Vector3d& r) -> Eigen::Vector3d {
    const Eigen::Vector3d w = d.omega.col(b);
    return d.a_bias.col(b) + d.alpha_bias.col(b).cross(r) + w.cross(w.cross(r));
  });
}

void RobotModel::dofAxes(const ModelData& data, Eigen::Ref<Eigen::Matrix3Xd> axes, Eigen::Ref<Eigen::Matrix3Xd> points) const {
  LEXDYN_ALWAYS_ASSERT(axes.cols() == impl_->ntv && points.cols() == impl_->ntv, "dofAxes: 3 x numTreeDofs() outputs");
  axes = data.impl().axis;
  points = data.impl().point;
}

// =============================================================================================
// Self-collision capsules
// =============================================================================================
namespace {

// Closest points of segments P0 + s d1 and Q0 + t d2 (s, t in [0, 1]).
void closestPointsSegments(const Eigen::Vector3d& P0, const Eigen::Vector3d& P1, const Eigen::Vector3d& Q0, const Eigen::Vector3d& Q1,
                           Eigen::Vector3d& cp, Eigen::Vector3d& cq) {
  const Eigen::Vector3d d1 = P1 - P0, d2 = Q1 - Q0, r = P0 - Q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double eps = 1e-14;
  double s = 0.0, t = 0.0;
  auto clamp01 = [](double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); };
  if (a <= eps && e <= eps) {
    s = t = 0.0;
  } else if (a <= eps) {
    s = 0.0;
    t = clamp01(f / e);
  } else {
    const double c = d1.dot(r);
    if (e <= eps) {
      t = 0.0;
      s = clamp01(-c / a);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      s = denom > eps * a * e ? clamp01((b * f - c * e) / denom) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = clamp01(-c / a);
      } else if (t > 1.0) {
        t = 1.0;
        s = clamp01((b - c) / a);
      }
    }
  }
  cp = P0 + s * d1;
  cq = Q0 + t * d2;
}

}  // namespace

CapsuleDistance RobotModel::capsuleDistance(const ModelData& data, int pair,
                                            Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> J) const {
  const Impl& m = *impl_;
  const ModelData::Impl& d = data.impl();
  LEXDYN_ALWAYS_ASSERT(pair >= 0 && pair < numCollisionPairs(), "capsuleDistance: pair index out of range");
  const CollisionPairDescription& P = m.desc.collision_pairs[static_cast<size_t>(pair)];
  const CapsuleDescription& A = m.desc.capsules[static_cast<size_t>(P.capsule_a)];
  const CapsuleDescription& B = m.desc.capsules[static_cast<size_t>(P.capsule_b)];
  auto world = [&](int body, const Eigen::Vector3d& x) { return Eigen::Vector3d(d.p.col(body) + d.R[static_cast<size_t>(body)] * x); };
  const Eigen::Vector3d a0 = world(A.link, A.p0), a1 = world(A.link, A.p1);
  const Eigen::Vector3d b0 = world(B.link, B.p0), b1 = world(B.link, B.p1);
  CapsuleDistance out;
  closestPointsSegments(a0, a1, b0, b1, out.point_a, out.point_b);
  const Eigen::Vector3d delta = out.point_a - out.point_b;
  const double dist = delta.norm();
  if (dist > 1e-12) {
    out.normal = delta / dist;
  } else {
    // Axes intersect: the direction between the segment midpoints, else world z.
    const Eigen::Vector3d mid = 0.5 * (a0 + a1) - 0.5 * (b0 + b1);
    out.normal = mid.norm() > 1e-12 ? Eigen::Vector3d(mid.normalized()) : Eigen::Vector3d::UnitZ();
  }
  out.distance = dist - A.radius - B.radius;
  if (J.size() > 0) {
    LEXDYN_ALWAYS_ASSERT(J.size() == m.nv, "capsuleDistance: J must be 1 x nv");
    J.setZero();
    for (int k : m.tree.bodies[static_cast<size_t>(A.link)].ancestor_dofs) {
      J[m.tree_dof_model[static_cast<size_t>(k)]] +=
          m.tree_dof_multiplier[static_cast<size_t>(k)] * out.normal.dot(d.S.col(k).tail<3>() + d.S.col(k).head<3>().cross(out.point_a));
    }
    for (int k : m.tree.bodies[static_cast<size_t>(B.link)].ancestor_dofs) {
      J[m.tree_dof_model[static_cast<size_t>(k)]] -=
          m.tree_dof_multiplier[static_cast<size_t>(k)] * out.normal.dot(d.S.col(k).tail<3>() + d.S.col(k).head<3>().cross(out.point_b));
    }
  }
  return out;
}

// =============================================================================================
// Simbody reference operators
// =============================================================================================
namespace {

void gravityBodyForces(const detail::RobotModelImpl& m, const detail::ModelDataImpl& d, SimTK::Vector_<SimTK::SpatialVec>& F) {
  F.resize(m.matter.getNumBodies());
  F.setToZero();
  for (int b = 0; b < m.nb; ++b) {
    const double mass = m.tree.bodies[static_cast<size_t>(b)].mass;
    const Eigen::Vector3d f = mass * m.desc.gravity;
    const Eigen::Vector3d r = d.com.col(b) - d.p.col(b);
    const Eigen::Vector3d t = r.cross(f);
    F[m.mobod[static_cast<size_t>(b)]] = SimTK::SpatialVec(toSimTK(t), toSimTK(f));
  }
}

}  // namespace

void RobotModel::massMatrixReference(const ModelData& data, Eigen::Ref<Eigen::MatrixXd> M) const {
  const Impl& m = *impl_;
  SimTK::Matrix Ms;
  m.matter.calcM(detail::realizedState(m, data.impl()), Ms);
  Eigen::MatrixXd Mt(m.ntv, m.ntv);
  for (int i = 0; i < m.ntv; ++i)
    for (int j = 0; j < m.ntv; ++j) Mt(i, j) = Ms(m.dof_u_index[static_cast<size_t>(i)], m.dof_u_index[static_cast<size_t>(j)]);
  reduceMatrix(m, Mt, M);
}

void RobotModel::inverseDynamicsReference(const ModelData& data, const Eigen::Ref<const Eigen::VectorXd>& udot,
                                          Eigen::Ref<Eigen::VectorXd> tau) const {
  const Impl& m = *impl_;
  const ModelData::Impl& d = data.impl();
  SimTK::Vector_<SimTK::SpatialVec> F;
  gravityBodyForces(m, d, F);
  // udot_tree = G udot (G is constant: no G-dot term).
  SimTK::Vector ud(m.simbody_nu), resid;
  for (int k = 0; k < m.ntv; ++k) {
    ud[m.dof_u_index[static_cast<size_t>(k)]] =
        m.tree_dof_multiplier[static_cast<size_t>(k)] * udot[m.tree_dof_model[static_cast<size_t>(k)]];
  }
  m.matter.calcResidualForceIgnoringConstraints(detail::realizedState(m, d), SimTK::Vector(), F, ud, resid);
  Eigen::VectorXd rt(m.ntv);
  for (int k = 0; k < m.ntv; ++k) rt[k] = resid[m.dof_u_index[static_cast<size_t>(k)]];
  reduceVector(m, rt, tau);
}

void RobotModel::forwardDynamicsReference(ModelData& data, const Eigen::Ref<const Eigen::VectorXd>& tau,
                                          Eigen::Ref<Eigen::VectorXd> udot) const {
  const Impl& m = *impl_;
  ModelData::Impl& d = data.impl();
  detail::realizedState(m, d);
  m.system.realize(d.state, SimTK::Stage::Dynamics);
  SimTK::Vector_<SimTK::SpatialVec> F;
  gravityBodyForces(m, d, F);
  if (m.coupled) {
    // (G^T M G) udot = tau - G^T N, with Simbody's M and N.
    Eigen::MatrixXd M(m.nv, m.nv);
    massMatrixReference(data, M);
    Eigen::VectorXd N(m.nv);
    inverseDynamicsReference(data, Eigen::VectorXd::Zero(m.nv), N);
    udot = M.ldlt().solve(tau - N);
    return;
  }
  SimTK::Vector f(m.simbody_nu), ud;
  for (int k = 0; k < m.nv; ++k) f[m.dof_u_index[static_cast<size_t>(k)]] = tau[k];
  SimTK::Vector_<SimTK::SpatialVec> A_GB;
  m.matter.calcAccelerationIgnoringConstraints(d.state, f, F, ud, A_GB);
  for (int k = 0; k < m.nv; ++k) udot[k] = ud[m.dof_u_index[static_cast<size_t>(k)]];
}

void RobotModel::frameJacobianReference(const ModelData& data, FrameId f, Eigen::Ref<Eigen::MatrixXd> J) const {
  const Impl& m = *impl_;
  const FrameDescription& F = m.desc.frames[static_cast<size_t>(f)];
  SimTK::Matrix Js;
  m.matter.calcFrameJacobian(detail::realizedState(m, data.impl()), m.mobod[static_cast<size_t>(F.link)],
                             toSimTK(F.placement.translation()), Js);
  Eigen::MatrixXd Jt(6, m.ntv);
  for (int k = 0; k < m.ntv; ++k) {
    const int c = m.dof_u_index[static_cast<size_t>(k)];
    for (int i = 0; i < 3; ++i) {
      Jt(i, k) = Js(3 + i, c);  // linear
      Jt(3 + i, k) = Js(i, c);  // angular
    }
  }
  reduceColumns(m, Jt, 6, J);
}

Eigen::Vector3d RobotModel::centerOfMassReference(const ModelData& data) const {
  return toEigen(impl_->matter.calcSystemMassCenterLocationInGround(detail::realizedState(*impl_, data.impl())));
}

}  // namespace lexdyn::model
