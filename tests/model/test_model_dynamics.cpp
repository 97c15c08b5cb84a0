// Model queries against independent references:
//  - M symmetric positive definite, equal to Simbody's calcM;
//  - M udot + N equals Simbody's inverse dynamics, and Simbody's articulated-body forward
//    dynamics inverts it;
//  - N's velocity part obeys the power identity u^T C = 1/2 u^T Mdot u, its gravity part equals
//    -J_com^T m g;
//  - every Jacobian (frame, point, CoM, capsule distance) and every Jdot*u bias against central
//    finite differences along q(h) = integrate(q, u, h) (frame, point and CoM Jacobians also
//    column by column along every unit velocity), and the frame Jacobian against Simbody's.
// Central differences with h = 1e-5 have an O(h^2) error: tolerances below are 1e-6 relative,
// much tighter than the h^(1/3) needed for one-sided differences.
#include "model_test_utils.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

namespace lexdyn::model {
namespace {

using testing::loadModel;
using testing::RandomStates;

struct ModelCase {
  const char* dir;
  const char* name;
};

const ModelCase kCases[] = {
    {"models/hrp2kai_like", "hrp2kai_like"}, {"models/arm_7dof", "arm_7dof"},   {"models/planar_3r", "planar_3r"},
    {"models/point_mass", "point_mass"},     {"tests/data/model", "free_body"}, {"tests/data/model", "merged"},
    {"tests/data/model", "coupled"},
};

constexpr double kH = 1e-5;

// Relative comparison with an absolute floor.
::testing::AssertionResult near(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double tol) {
  const double scale = std::max(1.0, std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()));
  const double err = (a - b).cwiseAbs().maxCoeff();
  if (err <= tol * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max error " << err << " > " << tol * scale << "\nA=\n" << a << "\nB=\n" << b;
}

class ModelDynamics : public ::testing::TestWithParam<ModelCase> {
 protected:
  void SetUp() override {
    model_ = std::make_unique<RobotModel>(loadModel(GetParam().dir, GetParam().name));
    data_ = std::make_unique<ModelData>(model_->createData());
  }
  RobotModel& model() { return *model_; }
  ModelData& data() { return *data_; }

  // Evaluates f at q(+h) and q(-h) along u and returns the central difference.
  template <class F>
  Eigen::MatrixXd centralDifference(const Configuration& q, const Eigen::VectorXd& u, F f) {
    Configuration qp = q, qm = q;
    model().integrate(q, u, kH, qp);
    model().integrate(q, u, -kH, qm);
    model().update(data(), qp, u);
    const Eigen::MatrixXd fp = f();
    model().update(data(), qm, u);
    const Eigen::MatrixXd fm = f();
    model().update(data(), q, u);
    return (fp - fm) / (2.0 * kH);
  }

  // `trials` random states (RandomStates(seed), velocities of scale `speed`): at each the model is
  // updated, then body(q, u).
  template <class Body>
  void forRandomStates(unsigned seed, int trials, double speed, Body body) {
    RandomStates rs(seed);
    for (int trial = 0; trial < trials; ++trial) {
      const Configuration q = rs.configuration(model());
      const Eigen::VectorXd u = rs.velocity(model(), speed);
      model().update(data(), q, u);
      body(q, u);
    }
  }

  // The rows x cols matrix that the model's query (data, args..., out) writes.
  template <class Query, class... Args>
  Eigen::MatrixXd matrixOf(int rows, int cols, Query query, const Args&... args) {
    Eigen::MatrixXd out(rows, cols);
    (model().*query)(data(), args..., out);
    return out;
  }

  std::unique_ptr<RobotModel> model_;
  std::unique_ptr<ModelData> data_;
};

TEST_P(ModelDynamics, MassMatrixIsSymmetricPositiveDefiniteAndMatchesSimbody) {
  RandomStates rs(11);
  const int n = model().nv();
  for (int trial = 0; trial < 5; ++trial) {
    const Configuration q = rs.configuration(model());
    model().update(data(), q, rs.velocity(model()));
    Eigen::MatrixXd M(n, n), Mref(n, n);
    model().massMatrix(data(), M);
    model().massMatrixReference(data(), Mref);
    EXPECT_TRUE(near(M, M.transpose(), 1e-14));
    EXPECT_TRUE(near(M, Mref, 1e-10));
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(M);
    EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(M).info(), Eigen::Success);
  }
}

TEST_P(ModelDynamics, EquationOfMotionMatchesSimbodyInverseAndForwardDynamics) {
  RandomStates rs(12);
  const int n = model().nv();
  for (int trial = 0; trial < 5; ++trial) {
    const Configuration q = rs.configuration(model());
    const Eigen::VectorXd u = rs.velocity(model(), 2.0);
    const Eigen::VectorXd udot = rs.velocity(model(), 5.0);
    model().update(data(), q, u);
    Eigen::MatrixXd M(n, n);
    Eigen::VectorXd N(n), tau_ref(n), udot_fd(n);
    model().massMatrix(data(), M);
    model().nonlinearEffects(data(), N);
    model().inverseDynamicsReference(data(), udot, tau_ref);
    const Eigen::VectorXd tau = M * udot + N;
    EXPECT_TRUE(near(tau, tau_ref, 1e-10));
    model().forwardDynamicsReference(data(), tau, udot_fd);
    EXPECT_TRUE(near(udot_fd, udot, 1e-8));
  }
}

TEST_P(ModelDynamics, VelocityTermsObeyThePowerIdentity) {
  // d/dt (1/2 u^T M u) = u^T (tau - N_gravity) for any udot; with M udot + C + G = tau this is
  // u^T C = 1/2 u^T Mdot u (skew-symmetry of Mdot - 2C along the motion).
  const int n = model().nv();
  forRandomStates(13, 4, 1.5, [&](const Configuration& q, const Eigen::VectorXd& u) {
    Eigen::VectorXd N(n), G(n);
    model().nonlinearEffects(data(), N);
    model().update(data(), q, Eigen::VectorXd::Zero(n));
    model().nonlinearEffects(data(), G);
    model().update(data(), q, u);
    const Eigen::MatrixXd Mdot = centralDifference(q, u, [&] { return matrixOf(n, n, &RobotModel::massMatrix); });
    const double lhs = u.dot(N - G);
    const double rhs = 0.5 * u.dot(Mdot * u);
    EXPECT_NEAR(lhs, rhs, 1e-6 * std::max(1.0, std::abs(rhs)));
  });
}

TEST_P(ModelDynamics, GravityTermIsMinusCoMJacobianTransposeTimesWeight) {
  RandomStates rs(14);
  const int n = model().nv();
  const Configuration q = rs.configuration(model());
  model().update(data(), q, Eigen::VectorXd::Zero(n));
  Eigen::VectorXd G(n);
  Eigen::MatrixXd Jc(3, n);
  model().nonlinearEffects(data(), G);
  model().centerOfMassJacobian(data(), Jc);
  const Eigen::VectorXd expected = -Jc.transpose() * (model().totalMass() * model().gravity());
  EXPECT_TRUE(near(G, expected, 1e-12));
}

TEST_P(ModelDynamics, FrameJacobiansAndBiasesMatchFiniteDifferencesAndSimbody) {
  const int n = model().nv();
  forRandomStates(15, 3, 1.5, [&](const Configuration& q, const Eigen::VectorXd& u) {
    for (FrameId f = 0; f < model().numFrames(); ++f) {
      SCOPED_TRACE(model().frameName(f));
      Eigen::MatrixXd J(6, n), Jref(6, n);
      model().frameJacobian(data(), f, J);
      model().frameJacobianReference(data(), f, Jref);
      EXPECT_TRUE(near(J, Jref, 1e-12));
      // J u against the finite difference of the placement.
      const Eigen::Isometry3d X0 = model().framePlacement(data(), f);
      const Eigen::MatrixXd dp = centralDifference(q, u, [&] { return Eigen::MatrixXd(model().framePlacement(data(), f).translation()); });
      Configuration qp = q, qm = q;
      model().integrate(q, u, kH, qp);
      model().integrate(q, u, -kH, qm);
      model().update(data(), qp, u);
      const Eigen::Matrix3d Rp = model().framePlacement(data(), f).linear();
      model().update(data(), qm, u);
      const Eigen::Matrix3d Rm = model().framePlacement(data(), f).linear();
      model().update(data(), q, u);
      const Eigen::AngleAxisd aa(Rp * Rm.transpose());
      const Eigen::Vector3d omega_fd = aa.angle() * aa.axis() / (2.0 * kH);
      const Eigen::VectorXd Ju = J * u;
      EXPECT_TRUE(near(Ju.head<3>(), dp, 1e-6));
      EXPECT_TRUE(near(Ju.tail<3>(), omega_fd, 1e-6));
      EXPECT_TRUE(near(model().frameVelocity(data(), f), Ju, 1e-12));
      (void)X0;
      // Jdot u against the finite difference of J along u.
      const Eigen::MatrixXd Jdot = centralDifference(q, u, [&] { return matrixOf(6, n, &RobotModel::frameJacobian, f); });
      EXPECT_TRUE(near(model().frameBias(data(), f), Jdot * u, 1e-6));
      // A point of the frame.
      const Eigen::Vector3d pt(0.05, -0.02, 0.1);
      Eigen::MatrixXd Jp(3, n);
      model().pointJacobian(data(), f, pt, Jp);
      const Eigen::MatrixXd dpt = centralDifference(q, u, [&] { return Eigen::MatrixXd(model().pointPosition(data(), f, pt)); });
      EXPECT_TRUE(near(Jp * u, dpt, 1e-6));
      EXPECT_TRUE(near(model().pointVelocity(data(), f, pt), Jp * u, 1e-12));
      const Eigen::MatrixXd Jpdot = centralDifference(q, u, [&] { return matrixOf(3, n, &RobotModel::pointJacobian, f, pt); });
      EXPECT_TRUE(near(model().pointBias(data(), f, pt), Jpdot * u, 1e-6));
    }
  });
}

TEST_P(ModelDynamics, FrameAndPointJacobiansMatchFiniteDifferencesColumnByColumn) {
  // Every column k of every frame and point Jacobian against the central difference of the
  // frame's placement (position; rotation vector of R(+h) R(-h)^T) along the unit velocity e_k,
  // so that no column escapes (the test above checks J u for one random u per state).
  RandomStates rs(17);
  const int n = model().nv();
  const int nf = model().numFrames();
  const Eigen::Vector3d pt(0.05, -0.02, 0.1);
  for (int trial = 0; trial < 2; ++trial) {
    const Configuration q = rs.configuration(model());
    const Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
    model().update(data(), q, u);
    std::vector<Eigen::MatrixXd> J(static_cast<size_t>(nf), Eigen::MatrixXd(6, n));
    std::vector<Eigen::MatrixXd> Jp(static_cast<size_t>(nf), Eigen::MatrixXd(3, n));
    for (FrameId f = 0; f < nf; ++f) {
      model().frameJacobian(data(), f, J[static_cast<size_t>(f)]);
      model().pointJacobian(data(), f, pt, Jp[static_cast<size_t>(f)]);
    }
    for (int k = 0; k < n; ++k) {
      const Eigen::VectorXd e = Eigen::VectorXd::Unit(n, k);
      Configuration qp = q, qm = q;
      model().integrate(q, e, kH, qp);
      model().integrate(q, e, -kH, qm);
      std::vector<Eigen::Isometry3d> Xp, Xm;
      std::vector<Eigen::Vector3d> pp, pm;
      model().update(data(), qp, u);
      for (FrameId f = 0; f < nf; ++f) {
        Xp.push_back(model().framePlacement(data(), f));
        pp.push_back(model().pointPosition(data(), f, pt));
      }
      model().update(data(), qm, u);
      for (FrameId f = 0; f < nf; ++f) {
        Xm.push_back(model().framePlacement(data(), f));
        pm.push_back(model().pointPosition(data(), f, pt));
      }
      for (FrameId f = 0; f < nf; ++f) {
        const size_t i = static_cast<size_t>(f);
        Eigen::Matrix<double, 6, 1> col;
        col.head<3>() = (Xp[i].translation() - Xm[i].translation()) / (2.0 * kH);
        const Eigen::AngleAxisd aa(Xp[i].linear() * Xm[i].linear().transpose());
        col.tail<3>() = aa.angle() * aa.axis() / (2.0 * kH);
        EXPECT_TRUE(near(J[i].col(k), col, 1e-6)) << model().frameName(f) << " column " << k;
        EXPECT_TRUE(near(Jp[i].col(k), (pp[i] - pm[i]) / (2.0 * kH), 1e-6)) << model().frameName(f) << " column " << k;
      }
    }
  }
}

TEST_P(ModelDynamics, CenterOfMassJacobianAndBiasMatchFiniteDifferences) {
  const int n = model().nv();
  forRandomStates(16, 4, 1.5, [&](const Configuration& q, const Eigen::VectorXd& u) {
    EXPECT_TRUE(near(model().centerOfMass(data()), model().centerOfMassReference(data()), 1e-12));
    Eigen::MatrixXd Jc(3, n);
    model().centerOfMassJacobian(data(), Jc);
    // Column by column: perturb along each unit velocity.
    for (int k = 0; k < n; ++k) {
      const Eigen::VectorXd e = Eigen::VectorXd::Unit(n, k);
      const Eigen::MatrixXd dc = centralDifference(q, e, [&] { return Eigen::MatrixXd(model().centerOfMass(data())); });
      EXPECT_TRUE(near(Jc.col(k), dc, 1e-6)) << "column " << k;
    }
    model().update(data(), q, u);
    EXPECT_TRUE(near(model().centerOfMassVelocity(data()), Jc * u, 1e-12));
    const Eigen::MatrixXd Jcdot = centralDifference(q, u, [&] { return matrixOf(3, n, &RobotModel::centerOfMassJacobian); });
    EXPECT_TRUE(near(model().centerOfMassBias(data()), Jcdot * u, 1e-6));
  });
}

// The tree's dofs are the model's, plus one per coupled mimic joint (moving with its master by a
// factor): each body's Jacobian is the sum of its moving dofs' screws, each in its model column.
TEST_P(ModelDynamics, DofAxesAndTreeRelationAgreeWithJacobians) {
  RandomStates rs(17);
  const int n = model().nv(), nt = model().numTreeDofs();
  EXPECT_EQ(nt > n, model().hasCoupledJoints());
  const Configuration q = rs.configuration(model());
  model().update(data(), q, rs.velocity(model()));
  const KinematicTree& tree = model().tree();
  Eigen::Matrix3Xd axes(3, nt), points(3, nt);
  model().dofAxes(data(), axes, points);
  for (int b = 0; b < model().numBodies(); ++b) {
    // The body frame is the frame of the same name.
    const FrameId f = model().frameId(tree.bodies[static_cast<size_t>(b)].name);
    Eigen::MatrixXd J(6, n);
    model().frameJacobian(data(), f, J);
    const Eigen::Vector3d p = model().framePlacement(data(), f).translation();
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(6, n);
    for (int k = 0; k < nt; ++k) {
      if (!tree.dofMovesBody(k, b)) continue;
      Eigen::VectorXd screw(6);
      if (tree.dofs[static_cast<size_t>(k)].type == DofType::Revolute) {
        screw << axes.col(k).cross(p - points.col(k)), axes.col(k);
      } else {
        screw << axes.col(k), Eigen::Vector3d::Zero();
      }
      expected.col(model().treeDofModel(k)) += model().treeDofMultiplier(k) * screw;
    }
    EXPECT_TRUE(near(J, expected, 1e-12)) << "body " << b;
  }
  // Parent links follow the ancestor lists.
  for (int b = 0; b < model().numBodies(); ++b) {
    const auto& anc = tree.bodies[static_cast<size_t>(b)].ancestor_dofs;
    for (size_t i = 1; i < anc.size(); ++i) EXPECT_EQ(tree.dofs[static_cast<size_t>(anc[i])].parent, anc[i - 1]);
    if (!anc.empty()) {
      EXPECT_EQ(tree.dofs[static_cast<size_t>(anc[0])].parent, -1);
    }
  }
}

TEST_P(ModelDynamics, IntegrateAndDifferenceAreInverse) {
  RandomStates rs(18);
  const Configuration q0 = rs.configuration(model());
  const Eigen::VectorXd u = rs.velocity(model(), 0.3);
  Configuration q1 = q0;
  model().integrate(q0, u, 1.0, q1);
  Eigen::VectorXd back(model().nv());
  model().difference(q0, q1, back);
  EXPECT_TRUE(near(back, u, 1e-12));
  // Rotations stay orthonormal.
  EXPECT_TRUE(near(q1.base_rotation * q1.base_rotation.transpose(), Eigen::Matrix3d::Identity(), 1e-14));
}

INSTANTIATE_TEST_SUITE_P(Models, ModelDynamics, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<ModelCase>& info) { return std::string(info.param.name); });

// Locked and coupled mimic joints are the same mechanism while the masters stand still: at the
// masters' posture value (0 here; no posture) the locked model's mass matrix and bias forces
// equal the coupled model's outside the masters' rows and columns, and every frame is in the same
// place.
TEST(MimicJoints, LockedIsCoupledWithTheMasterHeld) {
  const RobotModel coupled = loadModel("tests/data/model", "coupled");
  const RobotModel locked = RobotModel::fromFiles(testing::sourcePath("tests/data/model/coupled.urdf"),
                                                  testing::sourcePath("tests/data/model/coupled_locked.yaml"));
  ASSERT_TRUE(coupled.hasCoupledJoints());
  ASSERT_FALSE(locked.hasCoupledJoints());
  EXPECT_NEAR(coupled.totalMass(), locked.totalMass(), 1e-12);
  const int grip = coupled.jointIndex("grip"), shoulder = coupled.jointIndex("shoulder");
  // Both have the same joints (the masters stay model joints; 'nail_joint', below a finger, too).
  ASSERT_EQ(locked.numJoints(), coupled.numJoints());
  const int dof_grip = coupled.jointVelocityOffset() + grip, dof_shoulder = coupled.jointVelocityOffset() + shoulder;
  ModelData dc = coupled.createData(), dl = locked.createData();
  RandomStates rs(31);
  for (int trial = 0; trial < 5; ++trial) {
    Configuration qc = rs.configuration(coupled);
    qc.joints[grip] = 0.0;
    qc.joints[shoulder] = 0.0;  // the tail's master, at its locked value
    Eigen::VectorXd uc = rs.velocity(coupled);
    uc[coupled.jointVelocityOffset() + grip] = 0.0;
    uc[coupled.jointVelocityOffset() + shoulder] = 0.0;
    Configuration ql = locked.neutralConfiguration();
    ql.base_rotation = qc.base_rotation;
    ql.base_position = qc.base_position;
    Eigen::VectorXd ul(locked.nv());
    std::vector<int> map(static_cast<size_t>(locked.nv()));  // locked dof -> coupled dof
    for (int k = 0; k < locked.jointVelocityOffset(); ++k) map[static_cast<size_t>(k)] = k;
    for (int j = 0; j < locked.numJoints(); ++j) {
      const int cj = coupled.jointIndex(locked.jointNames()[static_cast<size_t>(j)]);
      ql.joints[j] = qc.joints[cj];
      map[static_cast<size_t>(locked.jointVelocityOffset() + j)] = coupled.jointVelocityOffset() + cj;
    }
    for (int k = 0; k < locked.nv(); ++k) ul[k] = uc[map[static_cast<size_t>(k)]];
    coupled.update(dc, qc, uc);
    locked.update(dl, ql, ul);
    Eigen::MatrixXd Mc(coupled.nv(), coupled.nv()), Ml(locked.nv(), locked.nv());
    Eigen::VectorXd Nc(coupled.nv()), Nl(locked.nv());
    coupled.massMatrix(dc, Mc);
    locked.massMatrix(dl, Ml);
    coupled.nonlinearEffects(dc, Nc);
    locked.nonlinearEffects(dl, Nl);
    Eigen::MatrixXd Mcl(locked.nv(), locked.nv());
    Eigen::VectorXd Ncl(locked.nv());
    auto master = [&](int k) { return map[static_cast<size_t>(k)] == dof_grip || map[static_cast<size_t>(k)] == dof_shoulder; };
    for (int i = 0; i < locked.nv(); ++i) {
      Ncl[i] = Nc[map[static_cast<size_t>(i)]];
      for (int j = 0; j < locked.nv(); ++j) Mcl(i, j) = Mc(map[static_cast<size_t>(i)], map[static_cast<size_t>(j)]);
    }
    // The masters' rows and columns differ (they move the fingers and the tail, or not).
    for (int i = 0; i < locked.nv(); ++i) {
      if (!master(i)) continue;
      Ncl[i] = Nl[i];
      Mcl.row(i) = Ml.row(i);
      Mcl.col(i) = Ml.col(i);
    }
    EXPECT_GT((Mc(dof_grip, dof_grip) - Ml(dof_grip, dof_grip)), 1e-6);  // the fingers' inertia
    EXPECT_TRUE(near(Mcl, Ml, 1e-12)) << "trial " << trial;
    EXPECT_TRUE(near(Ncl, Nl, 1e-12)) << "trial " << trial;
    for (const char* f : {"fingertip", "nail_end", "tail_end"}) {
      const Eigen::Isometry3d Xc = coupled.framePlacement(dc, coupled.frameId(f)), Xl = locked.framePlacement(dl, locked.frameId(f));
      EXPECT_TRUE(near(Xc.matrix(), Xl.matrix(), 1e-12)) << f;
    }
    EXPECT_TRUE(near(coupled.centerOfMass(dc), locked.centerOfMass(dl), 1e-12));
  }
}

TEST(EulerAngles, RoundTripIncludingGimbalLock) {
  RandomStates rs(20);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d e(rs.uniform(-3.1, 3.1), rs.uniform(-1.5, 1.5), rs.uniform(-3.1, 3.1));
    const Eigen::Matrix3d R = rotationFromEulerXYZ(e);
    EXPECT_TRUE(eulerXYZFromRotation(R).isApprox(e, 1e-12)) << e.transpose();
    // Rx(a) Ry(b) Rz(c) written with Eigen's angle-axis products.
    const Eigen::Matrix3d R2 = (Eigen::AngleAxisd(e[0], Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(e[1], Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(e[2], Eigen::Vector3d::UnitZ()))
                                   .toRotationMatrix();
    EXPECT_TRUE(R.isApprox(R2, 1e-14));
  }
  for (double b : {M_PI / 2, -M_PI / 2}) {
    const Eigen::Matrix3d R = rotationFromEulerXYZ(Eigen::Vector3d(0.4, b, -1.1));
    EXPECT_TRUE(rotationFromEulerXYZ(eulerXYZFromRotation(R)).isApprox(R, 1e-12));
  }
}

TEST(CapsuleDistance, JacobianMatchesFiniteDifferences) {
  RobotModel model = testing::loadHumanoid();
  ModelData data = model.createData();
  RandomStates rs(19);
  const int n = model.nv();
  int checked = 0;
  for (int trial = 0; trial < 6; ++trial) {
    Configuration q = rs.configuration(model);
    const Eigen::VectorXd u = rs.velocity(model);
    model.update(data, q, u);
    for (int p = 0; p < model.numCollisionPairs(); ++p) {
      Eigen::RowVectorXd J(n);
      const CapsuleDistance cd = model.capsuleDistance(data, p, J);
      Configuration qp = q, qm = q;
      model.integrate(q, u, kH, qp);
      model.integrate(q, u, -kH, qm);
      Eigen::RowVectorXd none(0);
      model.update(data, qp, u);
      const double dp = model.capsuleDistance(data, p, none).distance;
      model.update(data, qm, u);
      const double dm = model.capsuleDistance(data, p, none).distance;
      model.update(data, q, u);
      EXPECT_NEAR(J.dot(u), (dp - dm) / (2 * kH), 1e-6) << "pair " << p;
      Eigen::MatrixXd rows(3, n);  // the same Jacobian written into a row of a matrix
      model.capsuleDistance(data, p, rows.row(1));
      EXPECT_EQ((rows.row(1) - J).norm(), 0.0);
      // The witness points are on the capsule axes and realise the distance.
      const auto& pair = model.description().collision_pairs[static_cast<size_t>(p)];
      const double ra = model.description().capsules[static_cast<size_t>(pair.capsule_a)].radius;
      const double rb = model.description().capsules[static_cast<size_t>(pair.capsule_b)].radius;
      EXPECT_NEAR((cd.point_a - cd.point_b).norm() - ra - rb, cd.distance, 1e-12);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 6 * 16);
}

TEST(CapsuleDistance, SegmentGeometryInTheZeroPose) {
  // Pair 0 is RARM_LINK3_C vs WAIST_C. With the base at the origin and all joints at zero, the
  // elbow segment is vertical at x = 0, y = -0.25, z from 0.35 + 0.20 - 0.30 = 0.25 down to
  // 0.15; the waist segment lies along y in [-0.05, 0.05] at x = 0, z = 0.06. The closest
  // points are (0, -0.25, 0.15) and (0, -0.05, 0.06).
  RobotModel model = testing::loadHumanoid();
  ModelData data = model.createData();
  model.update(data, model.neutralConfiguration(), Eigen::VectorXd::Zero(model.nv()));
  const auto& d = model.description();
  const auto& pair = d.collision_pairs[0];
  ASSERT_EQ(d.capsules[static_cast<size_t>(pair.capsule_a)].name, "RARM_LINK3_C");
  ASSERT_EQ(d.capsules[static_cast<size_t>(pair.capsule_b)].name, "WAIST_C");
  Eigen::RowVectorXd none(0);
  const CapsuleDistance cd = model.capsuleDistance(data, 0, none);
  EXPECT_NEAR(cd.distance, Eigen::Vector2d(0.20, 0.09).norm() - 0.045 - 0.10, 1e-12);
  EXPECT_TRUE(cd.point_a.isApprox(Eigen::Vector3d(0, -0.25, 0.15), 1e-12));
  EXPECT_TRUE(cd.point_b.isApprox(Eigen::Vector3d(0, -0.05, 0.06), 1e-12));
}

}  // namespace
}  // namespace lexdyn::model
