// Analytic Hessians of point positions, frame orientations and the centre of mass
// (lexdyn/hessian/kinematic_hessian.hpp) against two independent finite-difference references,
// on the humanoid (free-flyer included), the planar 3R arm, the 7-DoF arm and a free-flyer test
// model with a prismatic joint between revolute ones.
//
// Reference A, second differences of the task functions themselves, in the Hessians' chart
// q(delta) = integrate(q0, delta, 1) (hessian_test_utils.hpp):
//   H_ij ~ [f(h e_i + h e_j) - f(h e_i - h e_j) - f(-h e_i + h e_j) + f(-h e_i - h e_j)] / (4 h^2)
// with f = the point's world position, the CoM, or the rotation vector
// phi(delta) = log(R(q(delta)) R(q0)^T). h = 1e-4: truncation O(h^2 f'''') ~ 1e-8 and rounding
// ~ 4 eps |f| / (4 h^2) ~ 1e-7 for |f| ~ 2 m, so a tolerance of 1e-6 has a 10x margin while a
// wrong term (Hessian entries are O(0.1 - 1)) exceeds it by orders of magnitude.
//
// Reference B, central first differences (h = 1e-6) of the model's exact Jacobians (computed by
// lexdyn/model from motion subspaces, independently of the Hessian code). In the chart, the
// derivative of f is G(delta) = J(q(delta)) E(delta), E mapping chart rates to u (identity but
// for the free-flyer's Euler-rate block), so for positions and the CoM H_ij = d G_j / d delta_i.
// For the orientation, u's angular rows give the world angular velocity omega = J_l(phi) phi_dot
// (J_l the left Jacobian of SO(3), J_l(phi) = I + 1/2 [phi]x + O(|phi|^2)), hence
//   d phi / d delta = J_l(phi)^-1 J_w E  and at delta = 0 (phi = 0):
//   H_ij = d (J_w E)_j / d delta_i - 1/2 omega_i x omega_j,   omega_k = column k of J_w.
// (d J_w / dq alone is not symmetric and is not the Hessian of any function.) Error ~ h^2 + eps
// / h ~ 1e-10; tolerance 1e-8.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <vector>

#include "hessian_test_utils.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace lexdyn::hessian {
namespace {

using model::Configuration;
using model::FrameId;
using model::RobotModel;
using testing::Rng;

struct Probe {
  FrameId frame;
  Eigen::Vector3d point;  ///< in the frame
};

/// Per function component c (0..2): nv x nv Hessians of every probe's position and orientation
/// and of the CoM.
struct Hessians {
  std::vector<std::array<Eigen::MatrixXd, 3>> position, orientation;
  std::array<Eigen::MatrixXd, 3> com;
  void resize(size_t probes, int nv) {
    position.assign(probes, {});
    orientation.assign(probes, {});
    for (auto* set : {&position, &orientation}) {
      for (auto& arr : *set) {
        for (auto& M : arr) M.setZero(nv, nv);
      }
    }
    for (auto& M : com) M.setZero(nv, nv);
  }
};

struct Values {
  std::vector<Eigen::Vector3d> position, phi;
  Eigen::Vector3d com;
};

class Chart {
 public:
  Chart(const RobotModel& m, const Configuration& q0) : m_(m), data_(m.createData()), q0_(q0), q_(q0) {
    u_.setZero(m.nv());
    m_.update(data_, q0_, u_);
  }
  void set(const Eigen::VectorXd& delta) {
    m_.integrate(q0_, delta, 1.0, q_);
    m_.update(data_, q_, u_);
  }
  const model::ModelData& data() const { return data_; }
  void values(const std::vector<Probe>& probes, const std::vector<Eigen::Matrix3d>& R0, Values& v) const {
    v.position.resize(probes.size());
    v.phi.resize(probes.size());
    for (size_t k = 0; k < probes.size(); ++k) {
      v.position[k] = m_.pointPosition(data_, probes[k].frame, probes[k].point);
      const Eigen::Matrix3d R = m_.framePlacement(data_, probes[k].frame).linear();
      v.phi[k] = testing::rotationVector(R * R0[k].transpose());
    }
    v.com = m_.centerOfMass(data_);
  }

 private:
  const RobotModel& m_;
  model::ModelData data_;
  Configuration q0_, q_;
  Eigen::VectorXd u_;
};

std::vector<Eigen::Matrix3d> frameRotations(const RobotModel& m, const Configuration& q0, const std::vector<Probe>& probes) {
  model::ModelData d = m.createData();
  m.update(d, q0, Eigen::VectorXd::Zero(m.nv()));
  std::vector<Eigen::Matrix3d> R;
  for (const Probe& p : probes) R.push_back(m.framePlacement(d, p.frame).linear());
  return R;
}

/// Reference A: second differences of the functions in the chart.
Hessians secondDifferences(const RobotModel& m, const Configuration& q0, const std::vector<Probe>& probes, double h) {
  const int nv = m.nv();
  Hessians H;
  H.resize(probes.size(), nv);
  const std::vector<Eigen::Matrix3d> R0 = frameRotations(m, q0, probes);
  Chart chart(m, q0);
  Values v[4];
  const double si[4] = {1, 1, -1, -1}, sj[4] = {1, -1, 1, -1}, coef[4] = {1, -1, -1, 1};
  Eigen::VectorXd delta(nv);
  for (int i = 0; i < nv; ++i) {
    for (int j = i; j < nv; ++j) {
      for (int k = 0; k < 4; ++k) {
        delta.setZero();
        delta[i] += si[k] * h;
        delta[j] += sj[k] * h;
        chart.set(delta);
        chart.values(probes, R0, v[k]);
      }
      auto put = [&](std::array<Eigen::MatrixXd, 3>& arr, auto get) {
        Eigen::Vector3d s = Eigen::Vector3d::Zero();
        for (int k = 0; k < 4; ++k) s += coef[k] * get(v[k]);
        s /= 4.0 * h * h;
        for (int c = 0; c < 3; ++c) {
          arr[static_cast<size_t>(c)](i, j) = s[c];
          arr[static_cast<size_t>(c)](j, i) = s[c];
        }
      };
      for (size_t p = 0; p < probes.size(); ++p) {
        put(H.position[p], [p](const Values& x) { return x.position[p]; });
        put(H.orientation[p], [p](const Values& x) { return x.phi[p]; });
      }
      put(H.com, [](const Values& x) { return x.com; });
    }
  }
  return H;
}

/// Reference B: first differences of the model's Jacobians, mapped to the chart.
Hessians jacobianDifferences(const RobotModel& m, const Configuration& q0, const std::vector<Probe>& probes, double h) {
  const int nv = m.nv();
  Hessians H;
  H.resize(probes.size(), nv);
  Chart chart(m, q0);
  // G = J E at delta for every probe: [point position rows; angular rows], and the CoM.
  struct G {
    std::vector<Eigen::MatrixXd> point, angular;
    Eigen::MatrixXd com;
  };
  auto evaluate = [&](const Eigen::VectorXd& delta, G& g) {
    chart.set(delta);
    Eigen::MatrixXd E = Eigen::MatrixXd::Identity(nv, nv);
    if (m.hasFreeFlyer()) E.topLeftCorner<3, 3>() = testing::eulerRateMap(delta.head<3>());
    g.point.resize(probes.size());
    g.angular.resize(probes.size());
    Eigen::MatrixXd J3(3, nv), J6(6, nv);
    for (size_t p = 0; p < probes.size(); ++p) {
      m.pointJacobian(chart.data(), probes[p].frame, probes[p].point, J3);
      g.point[p] = J3 * E;
      m.frameJacobian(chart.data(), probes[p].frame, J6);
      g.angular[p] = J6.bottomRows<3>() * E;
    }
    m.centerOfMassJacobian(chart.data(), J3);
    g.com = J3 * E;
  };
  G g0, gp, gm;
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(nv);
  evaluate(delta, g0);
  for (int i = 0; i < nv; ++i) {
    delta.setZero();
    delta[i] = h;
    evaluate(delta, gp);
    delta[i] = -h;
    evaluate(delta, gm);
    for (int j = 0; j < nv; ++j) {
      for (size_t p = 0; p < probes.size(); ++p) {
        const Eigen::Vector3d dp = (gp.point[p].col(j) - gm.point[p].col(j)) / (2 * h);
        const Eigen::Vector3d dw = (gp.angular[p].col(j) - gm.angular[p].col(j)) / (2 * h) -
                                   0.5 * Eigen::Vector3d(g0.angular[p].col(i)).cross(Eigen::Vector3d(g0.angular[p].col(j)));
        for (int c = 0; c < 3; ++c) {
          H.position[p][static_cast<size_t>(c)](i, j) = dp[c];
          H.orientation[p][static_cast<size_t>(c)](i, j) = dw[c];
        }
      }
      const Eigen::Vector3d dc = (gp.com.col(j) - gm.com.col(j)) / (2 * h);
      for (int c = 0; c < 3; ++c) H.com[static_cast<size_t>(c)](i, j) = dc[c];
    }
  }
  return H;
}

Eigen::MatrixXd weighted(const std::array<Eigen::MatrixXd, 3>& arr, const Eigen::Vector3d& w) {
  return w[0] * arr[0] + w[1] * arr[1] + w[2] * arr[2];
}

double maxAbs(const Eigen::MatrixXd& A) { return A.cwiseAbs().maxCoeff(); }

/// Compares the analytic Hessians at q0 with a reference, for the unit weights (each component)
/// and for a random weight accumulated onto a random symmetric matrix.
void compare(const RobotModel& m, const Configuration& q0, const std::vector<Probe>& probes, const Hessians& ref, double tol, Rng& rng,
             const std::string& what, double& worst) {
  const int nv = m.nv();
  model::ModelData data = m.createData();
  m.update(data, q0, Eigen::VectorXd::Zero(nv));
  KinematicHessianWorkspace ws(m);
  ws.update(m, data);
  Eigen::MatrixXd H(nv, nv);
  std::vector<Eigen::Vector3d> weights = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
                                          rng.uniformVector(3)};
  for (size_t wi = 0; wi < weights.size(); ++wi) {
    const Eigen::Vector3d w = weights[wi];
    const Eigen::MatrixXd H0 = wi < 3 ? Eigen::MatrixXd::Zero(nv, nv) : rng.symmetric(nv);
    for (size_t p = 0; p < probes.size(); ++p) {
      const std::string where = what + " frame " + m.frameName(probes[p].frame) + " w=" + std::to_string(wi);
      H = H0;
      accumulatePointHessian(m, data, ws, probes[p].frame, probes[p].point, w, H);
      double e = maxAbs(H - H0 - weighted(ref.position[p], w));
      worst = std::max(worst, e);
      EXPECT_LE(e, tol) << where << " position";
      H = H0;
      accumulateOrientationHessian(m, data, ws, probes[p].frame, w, H);
      e = maxAbs(H - H0 - weighted(ref.orientation[p], w));
      worst = std::max(worst, e);
      EXPECT_LE(e, tol) << where << " orientation";
    }
    H = H0;
    accumulateComHessian(m, ws, w, H);
    const double e = maxAbs(H - H0 - weighted(ref.com, w));
    worst = std::max(worst, e);
    EXPECT_LE(e, tol) << what << " com w=" << wi;
  }
}

std::vector<Probe> allFrames(const RobotModel& m, Rng& rng) {
  std::vector<Probe> probes;
  for (FrameId f = 0; f < m.numFrames(); ++f) probes.push_back({f, rng.uniformVector(3, -0.1, 0.1)});
  return probes;
}

struct ModelCase {
  std::string name;
  RobotModel (*load)();
  std::string posture;
  double spread;
  int configurations;
};

void runCase(const ModelCase& mc, std::uint64_t seed) {
  const RobotModel m = mc.load();
  Rng rng(seed);
  double worstA = 0.0, worstB = 0.0, scale = 0.0;
  for (int c = 0; c < mc.configurations; ++c) {
    const Configuration q0 = testing::randomConfiguration(m, rng, mc.posture, mc.spread);
    const std::vector<Probe> probes = allFrames(m, rng);
    const Hessians A = secondDifferences(m, q0, probes, 1e-4);
    const Hessians B = jacobianDifferences(m, q0, probes, 1e-6);
    for (const auto& arr : A.position) scale = std::max(scale, maxAbs(arr[0]));
    const std::string what = mc.name + " configuration " + std::to_string(c);
    compare(m, q0, probes, A, 1e-6, rng, what + " (second differences)", worstA);
    compare(m, q0, probes, B, 1e-8, rng, what + " (Jacobian differences)", worstB);
  }
  // Recorded for the docs; the assertions are above.
  std::printf(
      "%s: max |analytic - reference|: second differences %.2e, Jacobian differences %.2e "
      "(largest Hessian entry %.2f)\n",
      mc.name.c_str(), worstA, worstB, scale);
  // The comparison must not be vacuous: the Hessians are far from zero.
  EXPECT_GT(scale, 0.1) << mc.name;
}

TEST(KinematicHessian, HumanoidNearHalfSittingWithRotatedFreeFlyer) {
  runCase({"hrp2kai_like", &testing::loadHumanoid, "half_sitting", 0.3, 3}, 41);
}
TEST(KinematicHessian, Planar3r) { runCase({"planar_3r", &testing::loadPlanar3r, "", 0.0, 5}, 42); }
TEST(KinematicHessian, Arm7dof) { runCase({"arm_7dof", &testing::loadArm7, "", 0.0, 5}, 43); }
TEST(KinematicHessian, FreeFlyerWithPrismaticBetweenRevolutes) { runCase({"branched_rpr", &testing::loadBranched, "", 0.0, 5}, 44); }
TEST(KinematicHessian, CoupledMimicJoints) { runCase({"coupled", &testing::loadCoupled, "", 0.0, 5}, 45); }

// The humanoid at a random configuration near half-sitting (seeded, zero velocity) with its
// Hessian workspace updated; the generator goes on from there.
struct HumanoidWorkspace {
  explicit HumanoidWorkspace(std::uint64_t seed) : rng(seed), data(m.createData()), ws(m) {
    m.update(data, testing::randomConfiguration(m, rng, "half_sitting", 0.3), Eigen::VectorXd::Zero(m.nv()));
    ws.update(m, data);
  }
  const RobotModel m = testing::loadHumanoid();
  Rng rng;
  model::ModelData data;
  KinematicHessianWorkspace ws;
};

TEST(KinematicHessian, ExactlySymmetricAndZeroOffTheChain) {
  HumanoidWorkspace state(45);
  auto& [m, rng, data, ws] = state;
  const int nv = m.nv();
  for (FrameId f = 0; f < m.numFrames(); ++f) {
    const Eigen::Vector3d w = rng.uniformVector(3);
    Eigen::MatrixXd Hp = Eigen::MatrixXd::Zero(nv, nv), Ho = Hp;
    accumulatePointHessian(m, data, ws, f, rng.uniformVector(3, -0.1, 0.1), w, Hp);
    accumulateOrientationHessian(m, data, ws, f, w, Ho);
    EXPECT_EQ((Hp - Hp.transpose()).cwiseAbs().maxCoeff(), 0.0) << m.frameName(f);
    EXPECT_EQ((Ho - Ho.transpose()).cwiseAbs().maxCoeff(), 0.0) << m.frameName(f);
    // Only dofs that move the frame appear.
    const int body = m.frameBody(f);
    for (int i = 0; i < nv; ++i) {
      if (m.tree().dofMovesBody(i, body)) continue;
      EXPECT_EQ(Hp.row(i).cwiseAbs().maxCoeff(), 0.0) << m.frameName(f) << " dof " << i;
      EXPECT_EQ(Ho.row(i).cwiseAbs().maxCoeff(), 0.0) << m.frameName(f) << " dof " << i;
    }
  }
  Eigen::MatrixXd Hc = Eigen::MatrixXd::Zero(nv, nv);
  accumulateComHessian(m, ws, rng.uniformVector(3), Hc);
  EXPECT_EQ((Hc - Hc.transpose()).cwiseAbs().maxCoeff(), 0.0);
  // Dofs of different limbs never share a body: e.g. the two legs' first joints.
  const int r0 = m.jointVelocityOffset() + m.jointIndex("RLEG_JOINT0");
  const int l0 = m.jointVelocityOffset() + m.jointIndex("LLEG_JOINT0");
  EXPECT_EQ(Hc(r0, l0), 0.0);
  EXPECT_NE(Hc(r0, r0), 0.0);
}

TEST(KinematicHessian, WorkspaceSubtreeCentresOfMass) {
  // The base dofs' subtree is the whole robot: its CoM is the model's.
  HumanoidWorkspace state(46);
  auto& [m, rng, data, ws] = state;
  for (int k = 0; k < 6; ++k) {
    EXPECT_LE((ws.subtreeCom().col(k) - m.centerOfMass(data)).norm(), 1e-12);
    EXPECT_DOUBLE_EQ(ws.subtreeMassFraction()[k], 1.0);
  }
  // The CoM Jacobian from the workspace's subtree quantities equals the model's.
  Eigen::MatrixXd Jc(3, m.nv());
  m.centerOfMassJacobian(data, Jc);
  for (int k = 0; k < m.nv(); ++k) {
    const Eigen::Vector3d a = ws.axes().col(k);
    const Eigen::Vector3d J = m.tree().dofs[static_cast<size_t>(k)].type == model::DofType::Revolute
                                  ? Eigen::Vector3d(a.cross(ws.subtreeCom().col(k) - ws.points().col(k)))
                                  : a;
    EXPECT_LE((ws.subtreeMassFraction()[k] * J - Jc.col(k)).norm(), 1e-12) << "dof " << k;
  }
}

}  // namespace
}  // namespace lexdyn::hessian
