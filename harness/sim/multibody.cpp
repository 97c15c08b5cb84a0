// The simulator's Simbody system, built from a RobotDescription by this file alone (see
// multibody.hpp). Nothing here calls lexdyn::model's Simbody code; the cross-check
// tests/sim/test_model_vs_simulator.cpp compares the two constructions.
//
// The construction is written to give the same Simbody system as the controller's model does
// for the same description, down to the last bit (the same mobilizers in the same order, the
// same mobilizer frames, the same mass-property arithmetic), so that the simulation is
// unchanged by the separation (docs/simulator.md, "The simulator's multibody system").
#include "harness/sim/multibody.hpp"

#include "lexdyn/common/error.hpp"

#include <Simbody.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <cstring>

namespace lexdyn::sim {

namespace {

SimTK::Vec3 vec3(const Eigen::Vector3d& v) { return SimTK::Vec3(v.x(), v.y(), v.z()); }

SimTK::Transform transform(const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
  SimTK::Mat33 m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = R(r, c);
  }
  // R is orthonormal to rounding already: taken as it is, not re-orthogonalized.
  return SimTK::Transform(SimTK::Rotation(m, true), vec3(p));
}

// Simbody's body mass properties: mass, centre of mass in the body frame, and the inertia about
// the body frame's origin, from the link's inertia about its centre of mass by the parallel-axis
// theorem, I_O = I_C + m (|c|^2 1 - c c^T). A massless link (a fixed-base root) has none.
SimTK::MassProperties linkMassProperties(const model::LinkDescription& link) {
  if (link.mass == 0.0) return SimTK::MassProperties(0.0, SimTK::Vec3(0), SimTK::Inertia(0.0));
  const Eigen::Vector3d& c = link.com;
  const Eigen::Matrix3d shift = c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose();
  const Eigen::Matrix3d I = link.inertia + link.mass * shift;
  return SimTK::MassProperties(link.mass, vec3(c),
                               SimTK::Inertia(SimTK::Vec3(I(0, 0), I(1, 1), I(2, 2)), SimTK::Vec3(I(0, 1), I(0, 2), I(1, 2))));
}

// Mobilizer frame of a one-dof joint: Simbody's Pin turns about the z axis of its F and M frames
// and its Slider moves along their x axis, so the joint's unit axis becomes that column
// (`along`: 2 for z, 0 for x) of an orthonormal frame completed by two perpendiculars.
Eigen::Matrix3d mobilizerFrame(const Eigen::Vector3d& axis, int along) {
  const Eigen::Vector3d a = axis.normalized();
  const Eigen::Vector3d other = std::abs(a.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d first = a.cross(other).normalized();
  const Eigen::Vector3d second = a.cross(first);
  Eigen::Matrix3d F;
  if (along == 2) {
    F << first, second, a;
  } else {
    F << a, first, second;
  }
  return F;
}

}  // namespace

// =============================================================================================
// The system
// =============================================================================================
struct Multibody::Impl {
  explicit Impl(model::RobotDescription d);

  model::RobotDescription desc;
  bool free_flyer = true;
  int nb = 0, nj = 0, nq = 0, nv = 0;
  double total_mass = 0.0;
  std::vector<double> subtree_mass;  // per body, the body and its descendants
  std::vector<std::string> joint_names;
  Eigen::VectorXd torque_limit;

  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter;
  SimTK::State default_state;                       // Euler angles on, realized to Model
  std::vector<SimTK::MobilizedBodyIndex> mobod;     // per body
  std::vector<const SimTK::MobilizedBody*> mobody;  // per body, looked up once
  // Simbody's numbering: q[k] of ours is Simbody's q[q_index[k]], u[k] is u[u_index[k]].
  std::vector<int> q_index, u_index;
  // Coupled mimic joints (RobotDescription::coupled_joints): a mobilizer of their own whose q and
  // u follow a model joint's, q_c = c q_master + o; the simulated system is the reduced one.
  struct Coupled {
    int q_index = 0, u_index = 0;  // Simbody's
    int master = 0;                // model joint
    double multiplier = 1.0, offset = 0.0;
  };
  std::vector<Coupled> coupled;

  void writeCoordinates(SimTK::State& state, const double* q, const double* u) const;
  // The accelerations of the reduced system from the unconstrained ones (s.udot): the coupled
  // joints' coordinates follow their masters, P udot = 0 with P_c = e_c - c e_master, so
  // udot = udot_free - M^-1 P^T (P M^-1 P^T)^-1 P udot_free (M^-1 by Simbody's O(n) operator).
  void constrainCoupled(MultibodyState::Impl& s) const;
  void copyBodies(const SimTK::State& state, const SimTK::SpatialVec* V, BodyKinematics& K) const;

  // J (6 x nv, rows [linear; angular], our u order) of the point r_body of a body, through
  // Simbody's calcFrameJacobian into Js (6 x nu, rows [angular; linear]).
  void frameJacobianOf(const SimTK::State& state, int body, const Eigen::Vector3d& r_body, SimTK::Matrix& Js,
                       Eigen::Ref<Eigen::MatrixXd> J) const {
    matter.calcFrameJacobian(state, mobod[static_cast<size_t>(body)], vec3(r_body), Js);
    for (int k = 0; k < nv; ++k) {
      const int c = u_index[static_cast<size_t>(k)];
      for (int i = 0; i < 3; ++i) {
        J(i, k) = Js(3 + i, c);
        J(3 + i, k) = Js(i, c);
      }
    }
    // A coupled joint's column goes to its master's, times its multiplier (J G).
    const int off = free_flyer ? 6 : 0;
    for (const Coupled& C : coupled) {
      for (int i = 0; i < 3; ++i) {
        J(i, off + C.master) += C.multiplier * Js(3 + i, C.u_index);
        J(3 + i, off + C.master) += C.multiplier * Js(i, C.u_index);
      }
    }
  }
  // Simbody's u (all mobilities) from ours: u_simbody = G u.
  void expandSpeeds(const double* u, SimTK::Vector& U) const {
    U.resize(nv + static_cast<int>(coupled.size()));
    for (int k = 0; k < nv; ++k) U[u_index[static_cast<size_t>(k)]] = u[k];
    const int off = free_flyer ? 6 : 0;
    for (const Coupled& C : coupled) U[C.u_index] = C.multiplier * u[off + C.master];
  }
  // Ours from a quantity in Simbody's mobilities (a generalized force): G^T f.
  void reduceForces(const SimTK::Vector& F, double* f) const {
    for (int k = 0; k < nv; ++k) f[k] = F[u_index[static_cast<size_t>(k)]];
    const int off = free_flyer ? 6 : 0;
    for (const Coupled& C : coupled) f[off + C.master] += C.multiplier * F[C.u_index];
  }
  // G^T M G from Simbody's M (all mobilities).
  void reduceMatrix(const SimTK::Matrix& Ms, Eigen::Ref<Eigen::MatrixXd> M) const {
    const int nu = nv + static_cast<int>(coupled.size());
    std::vector<int> model_of(static_cast<size_t>(nu), -1);
    std::vector<double> g(static_cast<size_t>(nu), 1.0);
    for (int k = 0; k < nv; ++k) model_of[static_cast<size_t>(u_index[static_cast<size_t>(k)])] = k;
    const int off = free_flyer ? 6 : 0;
    for (const Coupled& C : coupled) {
      model_of[static_cast<size_t>(C.u_index)] = off + C.master;
      g[static_cast<size_t>(C.u_index)] = C.multiplier;
    }
    M.setZero();
    for (int i = 0; i < nu; ++i) {
      for (int j = 0; j < nu; ++j) {
        M(model_of[static_cast<size_t>(i)], model_of[static_cast<size_t>(j)]) +=
            g[static_cast<size_t>(i)] * g[static_cast<size_t>(j)] * Ms(i, j);
      }
    }
  }
};

Multibody::Impl::Impl(model::RobotDescription d) : desc(std::move(d)), matter(system) {
  free_flyer = desc.base == model::BaseType::FreeFlyer;
  nb = static_cast<int>(desc.links.size());
  nj = static_cast<int>(desc.joints.size());
  const int base_dofs = free_flyer ? 6 : 0;
  nq = base_dofs + nj;
  nv = base_dofs + nj;
  total_mass = desc.totalMass();
  LEXDYN_ALWAYS_ASSERT(nb == nj + 1 + static_cast<int>(desc.coupled_joints.size()),
                       "robot description: one body per joint and coupled joint plus the root");

  // Bodies in description order (parents before children): the root on a Free (free-flyer) or
  // Weld (fixed base) mobilizer to Ground, every other link on its joint's Pin or Slider.
  matter.setShowDefaultGeometry(false);
  mobod.resize(static_cast<size_t>(nb));
  const SimTK::Body::Rigid root(linkMassProperties(desc.links[0]));
  if (free_flyer) {
    mobod[0] = SimTK::MobilizedBody::Free(matter.Ground(), SimTK::Transform(), root, SimTK::Transform()).getMobilizedBodyIndex();
  } else {
    mobod[0] = SimTK::MobilizedBody::Weld(matter.Ground(), SimTK::Transform(), root, SimTK::Transform()).getMobilizedBodyIndex();
  }
  // Every other body on its joint's (or coupled joint's) Pin or Slider, in body order (parents
  // before children).
  for (int b = 1; b < nb; ++b) {
    const model::LinkDescription& L = desc.links[static_cast<size_t>(b)];
    const bool is_joint = L.parent_joint >= 0;
    const model::JointType type =
        is_joint ? desc.joints[static_cast<size_t>(L.parent_joint)].type : desc.coupled_joints[static_cast<size_t>(L.parent_coupled)].type;
    const Eigen::Vector3d axis =
        is_joint ? desc.joints[static_cast<size_t>(L.parent_joint)].axis : desc.coupled_joints[static_cast<size_t>(L.parent_coupled)].axis;
    const Eigen::Isometry3d& origin = desc.jointOrigin(b);
    const int parent_body = desc.parentBody(b);
    LEXDYN_ALWAYS_ASSERT(parent_body >= 0 && parent_body < b, "robot description: a body's parent comes before it");
    const SimTK::Body::Rigid body(linkMassProperties(L));
    SimTK::MobilizedBody& parent = matter.updMobilizedBody(mobod[static_cast<size_t>(parent_body)]);
    // F on the parent: the joint origin, axis along the mobilizer's; M on the child: the child
    // link frame (which coincides with the joint frame at q = 0), axis along the mobilizer's.
    const bool revolute = type == model::JointType::Revolute;
    const Eigen::Matrix3d R_axis = mobilizerFrame(axis, revolute ? 2 : 0);
    const SimTK::Transform X_PF = transform(origin.linear() * R_axis, origin.translation());
    const SimTK::Transform X_BM = transform(R_axis, Eigen::Vector3d::Zero());
    SimTK::MobilizedBodyIndex index;
    if (revolute) {
      index = SimTK::MobilizedBody::Pin(parent, X_PF, body, X_BM).getMobilizedBodyIndex();
    } else {
      index = SimTK::MobilizedBody::Slider(parent, X_PF, body, X_BM).getMobilizedBodyIndex();
    }
    mobod[static_cast<size_t>(b)] = index;
  }
  system.realizeTopology();
  for (const SimTK::MobilizedBodyIndex i : mobod) mobody.push_back(&matter.getMobilizedBody(i));
  default_state = system.getDefaultState();
  matter.setUseEulerAngles(default_state, true);  // Free: q = body-fixed X-Y-Z angles, then position
  system.realizeModel(default_state);
  // (Simbody may keep room for a quaternion's fourth q; only the u count must match.)
  LEXDYN_ALWAYS_ASSERT(default_state.getNQ() >= nq && default_state.getNU() == nv + static_cast<int>(desc.coupled_joints.size()),
                       "Simbody's coordinate counts differ from the simulator's");

  // Index maps, asked from Simbody rather than assumed.
  q_index.resize(static_cast<size_t>(nq));
  u_index.resize(static_cast<size_t>(nv));
  if (free_flyer) {
    const SimTK::MobilizedBody& base = matter.getMobilizedBody(mobod[0]);
    for (int k = 0; k < 6; ++k) {
      q_index[static_cast<size_t>(k)] = base.getFirstQIndex(default_state) + k;
      u_index[static_cast<size_t>(k)] = base.getFirstUIndex(default_state) + k;
    }
  }
  for (int j = 0; j < nj; ++j) {
    const SimTK::MobilizedBody& mb = matter.getMobilizedBody(mobod[static_cast<size_t>(desc.joints[static_cast<size_t>(j)].child_link)]);
    q_index[static_cast<size_t>(base_dofs + j)] = mb.getFirstQIndex(default_state);
    u_index[static_cast<size_t>(base_dofs + j)] = mb.getFirstUIndex(default_state);
  }
  for (const model::CoupledJointDescription& C : desc.coupled_joints) {
    const SimTK::MobilizedBody& mb = matter.getMobilizedBody(mobod[static_cast<size_t>(C.child_link)]);
    coupled.push_back({mb.getFirstQIndex(default_state), mb.getFirstUIndex(default_state), C.master, C.multiplier, C.offset});
    // At q = 0 (the default state) a coupled joint is at its offset: writeCoordinates writes only
    // what differs from the state's q, so the default must already hold it.
    default_state.updQ()[coupled.back().q_index] = C.offset;
  }

  // Subtree masses, accumulated from the leaves to the root (children come after parents).
  subtree_mass.assign(static_cast<size_t>(nb), 0.0);
  for (int b = nb - 1; b >= 0; --b) {
    subtree_mass[static_cast<size_t>(b)] += desc.links[static_cast<size_t>(b)].mass;
    if (b > 0) subtree_mass[static_cast<size_t>(desc.parentBody(b))] += subtree_mass[static_cast<size_t>(b)];
  }
  torque_limit.resize(nj);
  for (int j = 0; j < nj; ++j) {
    joint_names.push_back(desc.joints[static_cast<size_t>(j)].name);
    torque_limit[j] = desc.joints[static_cast<size_t>(j)].effort_limit;
  }
}

struct MultibodyState::Impl {
  SimTK::State state;
  BodyKinematics bodies;
  Eigen::Matrix3Xd weighted_com;  // workspace of centerOfMass
  // Applied forces (Simbody's numbering) and the forward-dynamics outputs.
  SimTK::Vector mobility_forces, udot;
  SimTK::Vector_<SimTK::SpatialVec> body_forces, body_accelerations;
  SimTK::Vector_<SimTK::SpatialVec> body_velocities;  // J u of setKinematicState
  // Workspaces of the Jacobian queries.
  SimTK::Matrix jacobian, matrix;
  SimTK::Vector speeds, rates;
  // Workspaces of the coupled mimic joints' projection (constrainCoupled), sized once.
  Eigen::MatrixXd coupled_w, coupled_a;  // M^-1 P^T (nu x nc), P M^-1 P^T (nc x nc)
  Eigen::VectorXd coupled_b, coupled_ud, coupled_lambda;
  Eigen::LDLT<Eigen::MatrixXd> coupled_ldlt;
  SimTK::Vector coupled_p, coupled_mp;
};

Multibody::Multibody(model::RobotDescription description) : impl_(std::make_unique<Impl>(std::move(description))) {}
Multibody::Multibody(Multibody&&) noexcept = default;
Multibody& Multibody::operator=(Multibody&&) noexcept = default;
Multibody::~Multibody() = default;

MultibodyState::MultibodyState(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
MultibodyState::MultibodyState(MultibodyState&&) noexcept = default;
MultibodyState& MultibodyState::operator=(MultibodyState&&) noexcept = default;
MultibodyState::~MultibodyState() = default;
const BodyKinematics& MultibodyState::bodies() const { return impl_->bodies; }

// =============================================================================================
// The robot
// =============================================================================================
const model::RobotDescription& Multibody::description() const { return impl_->desc; }
const std::string& Multibody::name() const { return impl_->desc.name; }
bool Multibody::hasFreeFlyer() const { return impl_->free_flyer; }
int Multibody::numBodies() const { return impl_->nb; }
int Multibody::numJoints() const { return impl_->nj; }
int Multibody::nq() const { return impl_->nq; }
int Multibody::nv() const { return impl_->nv; }
double Multibody::totalMass() const { return impl_->total_mass; }
const Eigen::Vector3d& Multibody::gravity() const { return impl_->desc.gravity; }
const std::vector<std::string>& Multibody::jointNames() const { return impl_->joint_names; }
const Eigen::VectorXd& Multibody::jointTorqueLimits() const { return impl_->torque_limit; }
int Multibody::jointIndex(const std::string& n) const { return impl_->desc.jointIndex(n); }
model::FrameId Multibody::frameId(const std::string& n) const { return impl_->desc.frameIndex(n); }
const Eigen::VectorXd& Multibody::posture(const std::string& n) const { return impl_->desc.posture(n); }

model::Configuration Multibody::neutralConfiguration() const {
  model::Configuration c;
  c.joints = Eigen::VectorXd::Zero(impl_->nj);
  return c;
}

void Multibody::coordinates(const model::Configuration& c, double* q) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(c.joints.size() == m.nj, "coordinates: configuration has the wrong number of joints");
  int i = 0;
  if (m.free_flyer) {
    const Eigen::Vector3d e = model::eulerXYZFromRotation(c.base_rotation);
    for (int k = 0; k < 3; ++k) q[i++] = e[k];
    for (int k = 0; k < 3; ++k) q[i++] = c.base_position[k];
  }
  for (int j = 0; j < m.nj; ++j) q[i++] = c.joints[j];
}

void Multibody::configuration(const double* q, model::Configuration& c) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(c.joints.size() == m.nj, "configuration: c.joints has the wrong size");
  int i = 0;
  if (m.free_flyer) {
    c.base_rotation = model::rotationFromEulerXYZ(Eigen::Vector3d(q[0], q[1], q[2]));
    c.base_position = Eigen::Vector3d(q[3], q[4], q[5]);
    i = 6;
  }
  for (int j = 0; j < m.nj; ++j) c.joints[j] = q[i + j];
}

// =============================================================================================
// Per state
// =============================================================================================
MultibodyState Multibody::createState() const {
  const Impl& m = *impl_;
  auto s = std::make_unique<MultibodyState::Impl>();
  s->state = m.default_state;
  s->bodies.R.assign(static_cast<size_t>(m.nb), Eigen::Matrix3d::Identity());
  s->bodies.p.setZero(3, m.nb);
  s->bodies.com.setZero(3, m.nb);
  s->bodies.omega.setZero(3, m.nb);
  s->bodies.v.setZero(3, m.nb);
  s->weighted_com.setZero(3, m.nb);
  const int nu = m.nv + static_cast<int>(m.coupled.size());
  s->mobility_forces.resize(nu);
  s->udot.resize(nu);
  s->body_forces.resize(m.matter.getNumBodies());
  s->body_accelerations.resize(m.matter.getNumBodies());
  s->body_velocities.resize(m.matter.getNumBodies());
  if (!m.coupled.empty()) {
    const int nc = static_cast<int>(m.coupled.size());
    s->coupled_w.resize(nu, nc);
    s->coupled_a.resize(nc, nc);
    s->coupled_b.resize(nc);
    s->coupled_ud.resize(nu);
    s->coupled_lambda.resize(nc);
    s->coupled_ldlt = Eigen::LDLT<Eigen::MatrixXd>(nc);
    s->coupled_p.resize(nu);
    s->coupled_mp.resize(nu);
  }
  MultibodyState out(std::move(s));
  // One realization at the neutral state, so that Simbody's lazily allocated caches exist.
  const std::vector<double> zero(static_cast<size_t>(m.nq + m.nv), 0.0);
  setState(out, zero.data(), zero.data() + m.nq);
  return out;
}

// Writes q and u into the Simbody state, each only when it differs (bit for bit) from the
// state's: writing them invalidates Simbody's Position (Velocity) stage and everything computed
// from it, such as the articulated-body inertias, which depend on q only. The
// difference-quotient Jacobian changes u alone in half of its evaluations.
void Multibody::Impl::writeCoordinates(SimTK::State& state, const double* q, const double* u) const {
  // Through the vectors' contiguous storage: Simbody's element access is out of line.
  auto same = [](const SimTK::Vector& V, const std::vector<int>& index, const double* x, int n) {
    const double* v = V.getContiguousScalarData();
    for (int k = 0; k < n; ++k) {
      if (std::memcmp(&v[index[static_cast<size_t>(k)]], &x[k], sizeof(double)) != 0) return false;
    }
    return true;
  };
  const int off = free_flyer ? 6 : 0;
  if (!same(state.getQ(), q_index, q, nq)) {
    double* Q = state.updQ().updContiguousScalarData();
    for (int k = 0; k < nq; ++k) Q[q_index[static_cast<size_t>(k)]] = q[k];
    for (const Coupled& C : coupled) Q[C.q_index] = C.multiplier * q[off + C.master] + C.offset;
  }
  if (!same(state.getU(), u_index, u, nv)) {
    double* U = state.updU().updContiguousScalarData();
    for (int k = 0; k < nv; ++k) U[u_index[static_cast<size_t>(k)]] = u[k];
    for (const Coupled& C : coupled) U[C.u_index] = C.multiplier * u[off + C.master];
  }
}

// The body kinematics from a state realized through Position at least; the spatial velocities
// [omega; v of the origin] (Ground) from `V` (indexed by mobilized body), or from the state's
// Velocity stage when V is null.
void Multibody::Impl::copyBodies(const SimTK::State& state, const SimTK::SpatialVec* V, BodyKinematics& K) const {
  for (int b = 0; b < nb; ++b) {
    const SimTK::MobilizedBody& mb = *mobody[static_cast<size_t>(b)];
    const SimTK::Transform& X = mb.getBodyTransform(state);
    const SimTK::SpatialVec& Vb = V ? V[mobod[static_cast<size_t>(b)]] : mb.getBodyVelocity(state);
    Eigen::Matrix3d& R = K.R[static_cast<size_t>(b)];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R(r, c) = X.R().asMat33()(r, c);
      K.p(r, b) = X.p()[r];
      K.omega(r, b) = Vb[0][r];
      K.v(r, b) = Vb[1][r];
    }
    K.com.col(b) = K.p.col(b) + R * desc.links[static_cast<size_t>(b)].com;
  }
}

void Multibody::setState(MultibodyState& st, const double* q, const double* u) const {
  const Impl& m = *impl_;
  MultibodyState::Impl& s = *st.impl_;
  m.writeCoordinates(s.state, q, u);
  m.system.realize(s.state, SimTK::Stage::Velocity);
  m.copyBodies(s.state, nullptr, s.bodies);
}

void Multibody::setKinematicState(MultibodyState& st, const double* q, const double* u) const {
  const Impl& m = *impl_;
  MultibodyState::Impl& s = *st.impl_;
  m.writeCoordinates(s.state, q, u);
  m.system.realize(s.state, SimTK::Stage::Position);
  // J u gives each body's spatial velocity with the same operations, in the same order, as the
  // Velocity stage's (checked bit for bit by test_model_vs_simulator with the Simbody it is
  // built with).
  m.matter.multiplyBySystemJacobian(s.state, s.state.getU(), s.body_velocities);
  m.copyBodies(s.state, &s.body_velocities[0], s.bodies);
}

void Multibody::coordinateRates(const MultibodyState& st, double* qdot) const {
  const Impl& m = *impl_;
  // qdot is a Velocity-stage result: a state set by setKinematicState has none (Simbody checks
  // this in its debug builds only).
  LEXDYN_ALWAYS_ASSERT(st.impl_->state.getSystemStage() >= SimTK::Stage::Velocity,
                       "coordinateRates: the state is not realized through Velocity (set it with setState)");
  const SimTK::Vector& QD = st.impl_->state.getQDot();
  for (int k = 0; k < m.nq; ++k) qdot[k] = QD[m.q_index[static_cast<size_t>(k)]];
}

Eigen::Isometry3d Multibody::bodyPlacement(const MultibodyState& st, int body) const {
  const BodyKinematics& K = st.impl_->bodies;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = K.R[static_cast<size_t>(body)];
  X.translation() = K.p.col(body);
  return X;
}

Eigen::Isometry3d Multibody::framePlacement(const MultibodyState& st, model::FrameId f) const {
  const model::FrameDescription& F = impl_->desc.frames.at(static_cast<size_t>(f));
  return bodyPlacement(st, F.link) * F.placement;
}

Eigen::Vector3d Multibody::centerOfMass(const MultibodyState& st) const {
  const Impl& m = *impl_;
  Eigen::Matrix3Xd& W = st.impl_->weighted_com;
  for (int b = 0; b < m.nb; ++b) W.col(b) = m.desc.links[static_cast<size_t>(b)].mass * st.impl_->bodies.com.col(b);
  for (int b = m.nb - 1; b > 0; --b) W.col(m.desc.parentBody(b)) += W.col(b);
  return W.col(0) / m.subtree_mass[0];
}

// =============================================================================================
// Forces and dynamics
// =============================================================================================
void Multibody::clearForces(MultibodyState& st) const {
  st.impl_->body_forces.setToZero();
  st.impl_->mobility_forces.setToZero();
}

void Multibody::addBodyForce(MultibodyState& st, int body, const Eigen::Vector3d& torque_about_origin, const Eigen::Vector3d& force) const {
  SimTK::SpatialVec& F = st.impl_->body_forces[impl_->mobod[static_cast<size_t>(body)]];
  F[0] += vec3(torque_about_origin);
  F[1] += vec3(force);
}

void Multibody::setJointForce(MultibodyState& st, int joint, double tau) const {
  const Impl& m = *impl_;
  st.impl_->mobility_forces[m.u_index[static_cast<size_t>((m.free_flyer ? 6 : 0) + joint)]] = tau;
}

void Multibody::accelerations(MultibodyState& st, double* udot) const {
  const Impl& m = *impl_;
  MultibodyState::Impl& s = *st.impl_;
  m.system.realize(s.state, SimTK::Stage::Dynamics);
  m.matter.calcAccelerationIgnoringConstraints(s.state, s.mobility_forces, s.body_forces, s.udot, s.body_accelerations);
  if (!m.coupled.empty()) m.constrainCoupled(s);
  const double* ud = s.udot.getContiguousScalarData();
  for (int k = 0; k < m.nv; ++k) udot[k] = ud[m.u_index[static_cast<size_t>(k)]];
}

// udot of the free tree, projected onto the coupling P udot = 0 (row c of P: u_c - multiplier
// u_master) with the mass metric: udot - M^-1 P^T (P M^-1 P^T)^-1 P udot, the motion under the
// couplings' ideal constraint forces. M^-1 P^T takes one O(n) multiplyByMInv per coupled joint
// (which allocates inside Simbody); the workspaces here are sized once.
void Multibody::Impl::constrainCoupled(MultibodyState::Impl& s) const {
  const int nc = static_cast<int>(coupled.size());
  const int nu = nv + nc;
  const int off = free_flyer ? 6 : 0;
  Eigen::MatrixXd& W = s.coupled_w;
  for (int c = 0; c < nc; ++c) {
    const Coupled& C = coupled[static_cast<size_t>(c)];
    s.coupled_p = 0.0;
    s.coupled_p[C.u_index] = 1.0;
    s.coupled_p[u_index[static_cast<size_t>(off + C.master)]] = -C.multiplier;
    matter.multiplyByMInv(s.state, s.coupled_p, s.coupled_mp);
    for (int i = 0; i < nu; ++i) W(i, c) = s.coupled_mp[i];
  }
  auto applyP = [&](const auto& v, int c) {
    const Coupled& C = coupled[static_cast<size_t>(c)];
    return v[C.u_index] - C.multiplier * v[u_index[static_cast<size_t>(off + C.master)]];
  };
  Eigen::VectorXd& ud = s.coupled_ud;
  for (int i = 0; i < nu; ++i) ud[i] = s.udot[i];
  for (int c = 0; c < nc; ++c) {
    s.coupled_b[c] = applyP(ud, c);
    for (int k = 0; k < nc; ++k) s.coupled_a(c, k) = applyP(W.col(k), c);
  }
  s.coupled_ldlt.compute(s.coupled_a);
  s.coupled_lambda = s.coupled_ldlt.solve(s.coupled_b);
  ud.noalias() -= W * s.coupled_lambda;
  for (int i = 0; i < nu; ++i) s.udot[i] = ud[i];
}

void Multibody::netForce(MultibodyState& st, double* f) const {
  const Impl& m = *impl_;
  MultibodyState::Impl& s = *st.impl_;
  const int nu = m.nv + static_cast<int>(m.coupled.size());
  SimTK::Vector residual(nu, 0.0);
  const SimTK::Vector zero_udot(nu, 0.0);
  // residual = M udot + C(q, u) - applied forces; ours is G^T of it.
  m.matter.calcResidualForceIgnoringConstraints(s.state, s.mobility_forces, s.body_forces, zero_udot, residual);
  m.reduceForces(residual, f);
  for (int k = 0; k < m.nv; ++k) f[k] = -f[k];
}

// =============================================================================================
// For the integrator's Jacobian
// =============================================================================================
void Multibody::pointJacobian(MultibodyState& st, int body, const Eigen::Vector3d& r_body, Eigen::Ref<Eigen::MatrixXd> J) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(J.rows() == 6 && J.cols() == m.nv, "pointJacobian: J must be 6 x nv");
  m.frameJacobianOf(st.impl_->state, body, r_body, st.impl_->jacobian, J);
}

void Multibody::inverseMassMatrix(MultibodyState& st, Eigen::Ref<Eigen::MatrixXd> Minv) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(Minv.rows() == m.nv && Minv.cols() == m.nv, "inverseMassMatrix: Minv must be nv x nv");
  SimTK::Matrix& Ms = st.impl_->matrix;
  if (!m.coupled.empty()) {
    // The reduced system's: (G^T M G)^-1.
    m.matter.calcM(st.impl_->state, Ms);
    Eigen::MatrixXd M(m.nv, m.nv);
    m.reduceMatrix(Ms, M);
    Minv = M.ldlt().solve(Eigen::MatrixXd::Identity(m.nv, m.nv));
    return;
  }
  m.matter.calcMInv(st.impl_->state, Ms);
  for (int j = 0; j < m.nv; ++j) {
    const int c = m.u_index[static_cast<size_t>(j)];
    for (int i = 0; i < m.nv; ++i) Minv(i, j) = Ms(m.u_index[static_cast<size_t>(i)], c);
  }
}

void Multibody::rateMatrix(MultibodyState& st, Eigen::Ref<Eigen::MatrixXd> N) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(N.rows() == m.nq && N.cols() == m.nv, "rateMatrix: N must be nq x nv");
  MultibodyState::Impl& s = *st.impl_;
  const int nu = m.nv + static_cast<int>(m.coupled.size());
  s.speeds.resize(nu);
  s.speeds = 0.0;
  std::vector<double> unit(static_cast<size_t>(m.nv), 0.0);
  for (int j = 0; j < m.nv; ++j) {
    unit[static_cast<size_t>(j)] = 1.0;
    m.expandSpeeds(unit.data(), s.speeds);  // column j of G
    unit[static_cast<size_t>(j)] = 0.0;
    m.matter.multiplyByN(s.state, false, s.speeds, s.rates);
    for (int i = 0; i < m.nq; ++i) N(i, j) = s.rates[m.q_index[static_cast<size_t>(i)]];
  }
}

// =============================================================================================
// Simbody's operators
// =============================================================================================
void Multibody::massMatrix(const MultibodyState& st, Eigen::Ref<Eigen::MatrixXd> M) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(M.rows() == m.nv && M.cols() == m.nv, "massMatrix: M must be nv x nv");
  SimTK::Matrix Ms;
  m.matter.calcM(st.impl_->state, Ms);
  m.reduceMatrix(Ms, M);
}

void Multibody::biasForces(const MultibodyState& st, Eigen::Ref<Eigen::VectorXd> N) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(N.size() == m.nv, "biasForces: N must have nv entries");
  const SimTK::State& state = st.impl_->state;
  SimTK::Vector_<SimTK::SpatialVec> gravity(m.matter.getNumBodies(), SimTK::SpatialVec(SimTK::Vec3(0), SimTK::Vec3(0)));
  for (int b = 0; b < m.nb; ++b) {
    const model::LinkDescription& L = m.desc.links[static_cast<size_t>(b)];
    const SimTK::MobilizedBody& mb = *m.mobody[static_cast<size_t>(b)];
    // m g at the centre of mass: Simbody's station of the CoM, re-expressed in Ground.
    const SimTK::Vec3 r = mb.expressVectorInGroundFrame(state, vec3(L.com));
    const SimTK::Vec3 f = L.mass * vec3(m.desc.gravity);
    gravity[m.mobod[static_cast<size_t>(b)]] = SimTK::SpatialVec(r % f, f);
  }
  const int nu = m.nv + static_cast<int>(m.coupled.size());
  const SimTK::Vector no_mobility_forces(nu, 0.0), zero_udot(nu, 0.0);
  SimTK::Vector residual;
  m.matter.calcResidualForceIgnoringConstraints(state, no_mobility_forces, gravity, zero_udot, residual);
  std::vector<double> f(static_cast<size_t>(m.nv));
  m.reduceForces(residual, f.data());
  for (int k = 0; k < m.nv; ++k) N[k] = f[static_cast<size_t>(k)];
}

void Multibody::frameJacobian(const MultibodyState& st, model::FrameId f, Eigen::Ref<Eigen::MatrixXd> J) const {
  const Impl& m = *impl_;
  LEXDYN_ALWAYS_ASSERT(J.rows() == 6 && J.cols() == m.nv, "frameJacobian: J must be 6 x nv");
  const model::FrameDescription& F = m.desc.frames.at(static_cast<size_t>(f));
  SimTK::Matrix Js;
  m.frameJacobianOf(st.impl_->state, F.link, F.placement.translation(), Js, J);
}

Eigen::Vector3d Multibody::systemCenterOfMass(const MultibodyState& st) const {
  const SimTK::Vec3 c = impl_->matter.calcSystemMassCenterLocationInGround(st.impl_->state);
  return Eigen::Vector3d(c[0], c[1], c[2]);
}

}  // namespace lexdyn::sim
