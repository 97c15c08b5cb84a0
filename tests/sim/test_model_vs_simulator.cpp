// The controller's robot model against the simulator's multibody system, built from the same
// robot description by separate code (docs/simulator.md, "The simulator's multibody system"):
// on seeded random states of every robot, the controller's own mass matrix (composite rigid
// bodies), bias forces (Newton-Euler), frame Jacobians and centre of mass against Simbody's
// calcM, calcResidualForceIgnoringConstraints, calcFrameJacobian and
// calcSystemMassCenterLocationInGround on the simulator's system, and the simulator's forward
// dynamics under gravity and joint forces against M udot + N = tau, to 1e-9 relative. A
// conversion bug on either side (an inertia shifted wrongly, a joint axis or frame mixed up, an
// index map off by one) shows here.
//
// The coordinate mapping, written out rather than assumed:
//  - simulator q_s = [e (body-fixed X-Y-Z Euler angles of the base); p (base origin); joints],
//    controller Configuration {R, p, joints} with R = Rx(e0) Ry(e1) Rz(e2), built here with
//    Eigen's AngleAxis (neither side's conversion code);
//  - simulator u_s and controller u_c are both [omega_world; v_base_origin_world; qdot_joints]
//    (Simbody's Free-mobilizer speeds), so u_c[map[k]] = u_s[k] with map the identity on the
//    base block and the joints matched by name;
//  - rows of both sides' Jacobians are [linear; angular] in world.
#include "harness/sim/multibody.hpp"
#include "lexdyn/model/robot_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <random>
#include <string>
#include <vector>

namespace lexdyn::sim {
namespace {

std::string src(const std::string& rel) { return std::string(LEXDYN_SOURCE_DIR) + "/" + rel; }

constexpr double kRelativeTolerance = 1e-9;

// Largest entry-wise difference relative to the largest entry of the reference. A reference
// that vanishes (below `floor`, e.g. the bias force of a mass on a horizontal slider) is
// compared absolutely: the difference relative to the floor.
double relativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& ref, double floor) {
  const double scale = std::max(ref.cwiseAbs().maxCoeff(), floor);
  return (a - ref).cwiseAbs().maxCoeff() / scale;
}

struct Worst {
  double mass_matrix = 0.0, bias = 0.0, jacobian = 0.0, com = 0.0, placement = 0.0, acceleration = 0.0;
};

Worst crossCheck(const std::string& dir, const std::string& name, unsigned seed, int states) {
  const std::string urdf = src(dir + "/" + name + ".urdf"), data = src(dir + "/" + name + ".yaml");
  const model::RobotModel ctrl = model::RobotModel::fromFiles(urdf, data);
  const Multibody simu(model::loadRobotDescription(urdf, data));
  const int nv = simu.nv(), nj = simu.numJoints(), base = simu.hasFreeFlyer() ? 6 : 0;
  EXPECT_EQ(ctrl.nv(), nv);
  EXPECT_EQ(ctrl.numJoints(), nj);
  EXPECT_EQ(ctrl.hasFreeFlyer(), simu.hasFreeFlyer());

  // u_c[map[k]] = u_s[k].
  std::vector<int> map(static_cast<size_t>(nv));
  for (int k = 0; k < base; ++k) map[static_cast<size_t>(k)] = k;
  for (int j = 0; j < nj; ++j) {
    map[static_cast<size_t>(base + j)] = ctrl.jointVelocityOffset() + ctrl.jointIndex(simu.jointNames()[static_cast<size_t>(j)]);
  }

  std::mt19937 rng(seed);
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  model::ModelData cd = ctrl.createData();
  MultibodyState sd = simu.createState();
  std::vector<double> q_s(static_cast<size_t>(simu.nq())), u_s(static_cast<size_t>(nv)), q_back(q_s.size());
  model::Configuration qc = ctrl.neutralConfiguration();
  Eigen::VectorXd u_c(nv), N_c(nv), N_s(nv);
  Eigen::MatrixXd M_c(nv, nv), M_s(nv, nv), J_c(6, nv), J_s(6, nv);
  Worst worst;
  for (int n = 0; n < states; ++n) {
    // A random simulator state (joints within their limits, pitch away from the Euler
    // singularity) and the same state in the controller's terms.
    int i = 0;
    if (base > 0) {
      const Eigen::Vector3d e(uniform(-M_PI, M_PI), uniform(-1.3, 1.3), uniform(-M_PI, M_PI));
      const Eigen::Vector3d p(uniform(-1.0, 1.0), uniform(-1.0, 1.0), uniform(0.2, 1.5));
      for (int k = 0; k < 3; ++k) q_s[static_cast<size_t>(i++)] = e[k];
      for (int k = 0; k < 3; ++k) q_s[static_cast<size_t>(i++)] = p[k];
      qc.base_rotation = (Eigen::AngleAxisd(e[0], Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(e[1], Eigen::Vector3d::UnitY()) *
                          Eigen::AngleAxisd(e[2], Eigen::Vector3d::UnitZ()))
                             .toRotationMatrix();
      qc.base_position = p;
    }
    for (int j = 0; j < nj; ++j) {
      const model::JointDescription& J = simu.description().joints[static_cast<size_t>(j)];
      const double lo = std::isfinite(J.lower) ? J.lower : -3.0, hi = std::isfinite(J.upper) ? J.upper : 3.0;
      q_s[static_cast<size_t>(i)] = uniform(lo, hi);
      qc.joints[ctrl.jointIndex(J.name)] = q_s[static_cast<size_t>(i++)];
    }
    for (int k = 0; k < nv; ++k) {
      u_s[static_cast<size_t>(k)] = uniform(-2.0, 2.0);
      u_c[map[static_cast<size_t>(k)]] = u_s[static_cast<size_t>(k)];
    }
    // The simulator's own conversion of a configuration gives the same coordinates back.
    simu.coordinates(qc, q_back.data());
    for (size_t k = 0; k < q_s.size(); ++k) EXPECT_NEAR(q_back[k], q_s[k], 1e-12) << name << " state " << n << " q " << k;

    ctrl.update(cd, qc, u_c);
    simu.setState(sd, q_s.data(), u_s.data());

    ctrl.massMatrix(cd, M_c);
    simu.massMatrix(sd, M_s);
    Eigen::MatrixXd M_cs(nv, nv);  // the controller's, in the simulator's order
    for (int r = 0; r < nv; ++r) {
      for (int c = 0; c < nv; ++c) M_cs(r, c) = M_c(map[static_cast<size_t>(r)], map[static_cast<size_t>(c)]);
    }
    worst.mass_matrix = std::max(worst.mass_matrix, relativeDifference(M_cs, M_s, 1e-12));

    ctrl.nonlinearEffects(cd, N_c);
    simu.biasForces(sd, N_s);
    Eigen::VectorXd N_cs(nv);
    for (int r = 0; r < nv; ++r) N_cs[r] = N_c[map[static_cast<size_t>(r)]];
    worst.bias = std::max(worst.bias, relativeDifference(N_cs, N_s, 1e-12));

    for (int f = 0; f < static_cast<int>(simu.description().frames.size()); ++f) {
      const std::string& frame = simu.description().frames[static_cast<size_t>(f)].name;
      const model::FrameId fc = ctrl.frameId(frame);
      ctrl.frameJacobian(cd, fc, J_c);
      simu.frameJacobian(sd, f, J_s);
      Eigen::MatrixXd J_cs(6, nv);
      for (int c = 0; c < nv; ++c) J_cs.col(c) = J_c.col(map[static_cast<size_t>(c)]);
      worst.jacobian = std::max(worst.jacobian, relativeDifference(J_cs, J_s, 1e-12));
      // Ground truth the harness records (frame placements) against the controller's.
      const Eigen::Isometry3d Xc = ctrl.framePlacement(cd, fc), Xs = simu.framePlacement(sd, f);
      const double scale = std::max(1.0, Xs.translation().norm());
      worst.placement = std::max(worst.placement, (Xc.translation() - Xs.translation()).cwiseAbs().maxCoeff() / scale);
      worst.placement = std::max(worst.placement, (Xc.linear() - Xs.linear()).cwiseAbs().maxCoeff());
    }

    // The simulator's forward dynamics (articulated bodies; with coupled mimic joints, projected
    // onto the couplings) under gravity and random joint forces against the controller's
    // M udot + N = tau. Gravity is an applied force in the simulator (the harness adds it).
    Eigen::VectorXd tau_s = Eigen::VectorXd::Zero(nv), tau_c(nv), udot_s(nv);
    simu.clearForces(sd);
    for (int b = 0; b < simu.numBodies(); ++b) {
      const Eigen::Vector3d f = simu.description().links[static_cast<size_t>(b)].mass * simu.gravity();
      const Eigen::Vector3d r = sd.bodies().com.col(b) - sd.bodies().p.col(b);
      simu.addBodyForce(sd, b, r.cross(f), f);
    }
    for (int j = 0; j < nj; ++j) {
      tau_s[base + j] = uniform(-5.0, 5.0);
      simu.setJointForce(sd, j, tau_s[base + j]);
    }
    simu.accelerations(sd, udot_s.data());
    for (int r = 0; r < nv; ++r) tau_c[map[static_cast<size_t>(r)]] = tau_s[r];
    const Eigen::VectorXd udot_c = M_c.ldlt().solve(tau_c - N_c);
    Eigen::VectorXd udot_cs(nv);
    for (int r = 0; r < nv; ++r) udot_cs[r] = udot_c[map[static_cast<size_t>(r)]];
    worst.acceleration = std::max(worst.acceleration, relativeDifference(udot_s, udot_cs, 1e-12));
    simu.clearForces(sd);

    const Eigen::Vector3d c_ref = simu.systemCenterOfMass(sd);
    const double c_scale = std::max(1.0, c_ref.norm());
    worst.com = std::max(worst.com, (ctrl.centerOfMass(cd) - c_ref).cwiseAbs().maxCoeff() / c_scale);
    // The simulator's own centre of mass (the trace's com.*) against Simbody's.
    worst.com = std::max(worst.com, (simu.centerOfMass(sd) - c_ref).cwiseAbs().maxCoeff() / c_scale);
  }
  std::printf("%-14s %3d states: M %.2e  N %.2e  J %.2e  CoM %.2e  frames %.2e  udot %.2e\n", name.c_str(), states, worst.mass_matrix,
              worst.bias, worst.jacobian, worst.com, worst.placement, worst.acceleration);
  EXPECT_LE(worst.mass_matrix, kRelativeTolerance) << name << ": mass matrix";
  EXPECT_LE(worst.bias, kRelativeTolerance) << name << ": bias forces";
  EXPECT_LE(worst.jacobian, kRelativeTolerance) << name << ": frame Jacobians";
  EXPECT_LE(worst.com, kRelativeTolerance) << name << ": centre of mass";
  EXPECT_LE(worst.placement, kRelativeTolerance) << name << ": frame placements";
  EXPECT_LE(worst.acceleration, kRelativeTolerance) << name << ": forward dynamics";
  return worst;
}

TEST(ModelVsSimulator, Humanoid) { crossCheck("models/hrp2kai_like", "hrp2kai_like", 12001, 100); }
TEST(ModelVsSimulator, PointMass) { crossCheck("models/point_mass", "point_mass", 12002, 100); }
TEST(ModelVsSimulator, Planar3R) { crossCheck("models/planar_3r", "planar_3r", 12003, 100); }
TEST(ModelVsSimulator, Arm7Dof) { crossCheck("models/arm_7dof", "arm_7dof", 12004, 100); }
TEST(ModelVsSimulator, Pendulum) { crossCheck("tests/data/model", "pendulum", 12005, 100); }
TEST(ModelVsSimulator, FreeBody) { crossCheck("tests/data/model", "free_body", 12006, 100); }
TEST(ModelVsSimulator, MergedFixedJoints) { crossCheck("tests/data/model", "merged", 12007, 100); }
// Coupled mimic joints: the controller reduces its tree (G^T M G, G^T N, J G); the simulator
// keeps a mobilizer per coupled joint and projects Simbody's accelerations onto the couplings.
TEST(ModelVsSimulator, CoupledMimicJoints) { crossCheck("tests/data/model", "coupled", 12008, 100); }

// A fresh simulator state at q = 0 has its coupled joints at their offsets (the state is written
// only where q changes: the default state must hold them).
TEST(ModelVsSimulator, CoupledJointsSitAtTheirOffsetsAtZero) {
  const std::string urdf = src("tests/data/model/coupled.urdf");
  std::string data_text;
  {
    std::ifstream in(src("tests/data/model/coupled.yaml"));
    std::stringstream ss;
    ss << in.rdbuf();
    data_text = ss.str();
  }
  for (const char* base : {"free_flyer", "fixed"}) {
    SCOPED_TRACE(base);
    std::string text = data_text;
    text.replace(text.find("base: free_flyer"), 16, std::string("base: ") + base);
    const std::string data = std::string(LEXDYN_BINARY_DIR) + "/coupled_" + base + ".yaml";
    std::ofstream(data) << text;
    // (the data file names no URDF: it is given beside it)
    const model::RobotModel ctrl = model::RobotModel::fromFiles(urdf, data);
    const Multibody simu(model::loadRobotDescription(urdf, data));
    MultibodyState sd = simu.createState();
    const std::vector<double> q(static_cast<size_t>(simu.nq()), 0.0), u(static_cast<size_t>(simu.nv()), 0.0);
    simu.setState(sd, q.data(), u.data());
    model::ModelData cd = ctrl.createData();
    ctrl.update(cd, ctrl.neutralConfiguration(), Eigen::VectorXd::Zero(ctrl.nv()));
    for (const char* f : {"fingertip", "nail_end", "tail_end"}) {
      const Eigen::Vector3d a = ctrl.framePlacement(cd, ctrl.frameId(f)).translation(),
                            b = simu.framePlacement(sd, simu.frameId(f)).translation();
      EXPECT_LT((a - b).norm(), 1e-12) << f << ": model " << a.transpose() << ", simulator " << b.transpose();
    }
  }
}

// setKinematicState realizes Simbody's state through Position only and takes the body
// velocities from the system Jacobian: its body kinematics must be setState's to the bit (the
// simulator's observations use it, and traces must not change).
void expectKinematicStateIsSetStates(const std::string& dir, const std::string& name, unsigned seed) {
  const Multibody simu(model::loadRobotDescription(src(dir + "/" + name + ".urdf"), src(dir + "/" + name + ".yaml")));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  MultibodyState full = simu.createState(), kinematic = simu.createState();
  std::vector<double> q(static_cast<size_t>(simu.nq())), u(static_cast<size_t>(simu.nv()));
  auto same = [](const double* a, const double* b, size_t n) { return std::memcmp(a, b, n * sizeof(double)) == 0; };
  for (int n = 0; n < 50; ++n) {
    for (double& x : q) x = uniform(rng);
    for (double& x : u) x = 3.0 * uniform(rng);
    simu.setState(full, q.data(), u.data());
    simu.setKinematicState(kinematic, q.data(), u.data());
    const BodyKinematics &a = full.bodies(), &b = kinematic.bodies();
    for (int k = 0; k < simu.numBodies(); ++k) {
      EXPECT_TRUE(same(a.R[static_cast<size_t>(k)].data(), b.R[static_cast<size_t>(k)].data(), 9)) << name << " body " << k;
    }
    const size_t m = 3 * static_cast<size_t>(simu.numBodies());
    EXPECT_TRUE(same(a.p.data(), b.p.data(), m)) << name << " state " << n;
    EXPECT_TRUE(same(a.com.data(), b.com.data(), m)) << name << " state " << n;
    EXPECT_TRUE(same(a.omega.data(), b.omega.data(), m)) << name << " state " << n;
    EXPECT_TRUE(same(a.v.data(), b.v.data(), m)) << name << " state " << n;
    ASSERT_GT(a.omega.cwiseAbs().maxCoeff() + a.v.cwiseAbs().maxCoeff(), 0.01);  // not all zero
  }
}

TEST(Multibody, KinematicStateHasSetStatesBodiesToTheBit) {
  expectKinematicStateIsSetStates("models/hrp2kai_like", "hrp2kai_like", 12101);
  expectKinematicStateIsSetStates("models/arm_7dof", "arm_7dof", 12102);
  expectKinematicStateIsSetStates("tests/data/model", "merged", 12103);
}

// The cross-check can fail: a simulator built from a description whose joint axis is flipped
// (the kind of conversion bug it guards against) disagrees with the controller's model.
TEST(ModelVsSimulator, SeesAFlippedJointAxis) {
  const std::string urdf = src("models/arm_7dof/arm_7dof.urdf"), data = src("models/arm_7dof/arm_7dof.yaml");
  const model::RobotModel ctrl = model::RobotModel::fromFiles(urdf, data);
  model::RobotDescription flipped = model::loadRobotDescription(urdf, data);
  flipped.joints[2].axis = -flipped.joints[2].axis;
  const Multibody simu(std::move(flipped));
  model::ModelData cd = ctrl.createData();
  MultibodyState sd = simu.createState();
  model::Configuration qc = ctrl.neutralConfiguration();
  for (int j = 0; j < qc.joints.size(); ++j) qc.joints[j] = 0.3 + 0.1 * j;
  const Eigen::VectorXd u = Eigen::VectorXd::Constant(ctrl.nv(), 0.5);
  ctrl.update(cd, qc, u);
  simu.setState(sd, qc.joints.data(), u.data());
  Eigen::MatrixXd J_c(6, ctrl.nv()), J_s(6, ctrl.nv());
  const model::FrameId f = ctrl.frameId(ctrl.description().frames.back().name);
  ctrl.frameJacobian(cd, f, J_c);
  simu.frameJacobian(sd, f, J_s);
  EXPECT_GT(relativeDifference(J_c, J_s, 1e-12), 1e-3);
}

}  // namespace
}  // namespace lexdyn::sim
