// The model's dynamics against closed-form solutions: a point mass on a rail, a free-falling
// spinning body (parabola + constant rotation), and a large-amplitude compound pendulum whose
// half period is 2 K(k) sqrt(I / (m g d)) with K from the arithmetic-geometric mean.
#include "model_test_utils.hpp"
#include "../common/closed_form.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <cmath>

namespace lexdyn::model {
namespace {

using testing::loadModel;

// Forward dynamics of the model: udot = M^-1 (tau - N).
Eigen::VectorXd accel(const RobotModel& model, ModelData& data, const Configuration& q, const Eigen::VectorXd& u,
                      const Eigen::VectorXd& tau) {
  const int n = model.nv();
  model.update(data, q, u);
  Eigen::MatrixXd M(n, n);
  Eigen::VectorXd N(n);
  model.massMatrix(data, M);
  model.nonlinearEffects(data, N);
  return M.llt().solve(tau - N);
}

TEST(ClosedForm, PointMassOnARail) {
  RobotModel model = loadModel("models/point_mass", "point_mass");
  ModelData data = model.createData();
  ASSERT_EQ(model.nv(), 1);
  Configuration q = model.neutralConfiguration();
  q.joints[0] = 0.3;
  model.update(data, q, Eigen::VectorXd::Constant(1, 2.0));
  Eigen::MatrixXd M(1, 1);
  Eigen::VectorXd N(1);
  model.massMatrix(data, M);
  model.nonlinearEffects(data, N);
  EXPECT_NEAR(M(0, 0), 1.0, 1e-15);  // m = 1 kg
  EXPECT_NEAR(N[0], 0.0, 1e-15);     // horizontal rail: no gravity component
  Eigen::MatrixXd J(3, 1);
  model.pointJacobian(data, model.frameId("mass"), Eigen::Vector3d::Zero(), J);
  EXPECT_TRUE(J.isApprox(Eigen::Vector3d::UnitX(), 1e-15));
}

// Exact closed form of the free-falling body with a spherical inertia: the CoM follows a
// parabola and the body rotates at a constant angular velocity.
TEST(ClosedForm, FreeFallOfASpinningBody) {
  RobotModel model = loadModel("tests/data/model", "free_body");
  ModelData data = model.createData();
  ASSERT_EQ(model.nv(), 6);
  const Eigen::Vector3d c_local = model.tree().bodies[0].com;
  Configuration q = model.neutralConfiguration();
  q.base_rotation = rotationFromEulerXYZ(Eigen::Vector3d(0.2, -0.3, 0.5));
  q.base_position = Eigen::Vector3d(0.1, 0.2, 3.0);
  const Eigen::Vector3d w(0.7, -1.1, 2.0);
  const Eigen::Vector3d c0 = q.base_position + q.base_rotation * c_local;
  const Eigen::Vector3d vc0(0.5, -0.2, 1.0);
  Eigen::VectorXd u(6);
  u << w, vc0 - w.cross(q.base_rotation * c_local);  // velocity of the body origin

  // RK4 with the model's M and N, on (R, p, u), 1 s in steps of 1 ms. The rotation is advanced
  // with the exact exponential of each stage's angular velocity (not the Euler helper, which is
  // first-order only) so that the test measures the dynamics, not the integrator.
  const double dt = 1e-3;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(6);
  auto advance = [&](const Configuration& x, const Eigen::VectorXd& v, double h) {
    Configuration y = x;
    const Eigen::Vector3d wv = v.head<3>();
    if (wv.norm() > 0) y.base_rotation = Eigen::AngleAxisd(h * wv.norm(), wv.normalized()).toRotationMatrix() * x.base_rotation;
    y.base_position = x.base_position + h * v.segment<3>(3);
    return y;
  };
  for (int k = 0; k < 1000; ++k) {
    // Classical RK4 on the Lie group with frozen-stage velocities (exact for constant w).
    const Eigen::VectorXd k1 = accel(model, data, q, u, zero);
    const Eigen::VectorXd u2 = u + 0.5 * dt * k1;
    const Configuration q2 = advance(q, u, 0.5 * dt);
    const Eigen::VectorXd k2 = accel(model, data, q2, u2, zero);
    const Eigen::VectorXd u3 = u + 0.5 * dt * k2;
    const Configuration q3 = advance(q, u2, 0.5 * dt);
    const Eigen::VectorXd k3 = accel(model, data, q3, u3, zero);
    const Eigen::VectorXd u4 = u + dt * k3;
    const Configuration q4 = advance(q, u3, dt);
    const Eigen::VectorXd k4 = accel(model, data, q4, u4, zero);
    const Eigen::VectorXd ubar = (u + 2 * u2 + 2 * u3 + u4) / 6.0;
    q = advance(q, ubar, dt);
    u += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  const double t = 1.0;
  const Eigen::Vector3d g = model.gravity();
  const Eigen::Vector3d c_exact = c0 + vc0 * t + 0.5 * g * t * t;
  const Eigen::Matrix3d R_exact =
      Eigen::AngleAxisd(w.norm() * t, w.normalized()).toRotationMatrix() * rotationFromEulerXYZ(Eigen::Vector3d(0.2, -0.3, 0.5));
  model.update(data, q, u);
  EXPECT_LT((model.centerOfMass(data) - c_exact).norm(), 1e-9);
  EXPECT_LT((q.base_rotation - R_exact).norm(), 1e-9);
  EXPECT_LT((u.head<3>() - w).norm(), 1e-9);  // the angular velocity stays constant
  EXPECT_LT((model.centerOfMassVelocity(data) - (vc0 + g * t)).norm(), 1e-9);
}

using lexdyn::testing::agm;

TEST(ClosedForm, CompoundPendulumMassMatrixGravityAndPeriod) {
  RobotModel model = loadModel("tests/data/model", "pendulum");
  ModelData data = model.createData();
  ASSERT_EQ(model.nv(), 1);
  const double m = 2.5, d = 0.8, Iyy = 0.03, g = 9.81;
  const double I = Iyy + m * d * d;  // about the pivot
  // M and N at a few angles: N = dV/dtheta = m g d sin(theta) with V = -m g d cos(theta).
  for (double th : {-2.0, -0.4, 0.0, 0.9, 2.8}) {
    Configuration q = model.neutralConfiguration();
    q.joints[0] = th;
    model.update(data, q, Eigen::VectorXd::Constant(1, 1.3));
    Eigen::MatrixXd M(1, 1);
    Eigen::VectorXd N(1);
    model.massMatrix(data, M);
    model.nonlinearEffects(data, N);
    EXPECT_NEAR(M(0, 0), I, 1e-14);
    EXPECT_NEAR(N[0], m * g * d * std::sin(th), 1e-12);
  }
  // Large-amplitude half period: released at rest from theta0, theta reaches -theta0 after
  // T/2 = 2 K(k) sqrt(I / (m g d)), k = sin(theta0 / 2), K(k) = pi / (2 agm(1, sqrt(1 - k^2))).
  const double th0 = 2.0;
  const double k = std::sin(th0 / 2);
  const double K = M_PI / (2.0 * agm(1.0, std::sqrt(1.0 - k * k)));
  const double half_period = 2.0 * K * std::sqrt(I / (m * g * d));
  // RK4 with dt = 1e-4 until the velocity changes sign, then locate the turning point by
  // cubic Hermite interpolation of the velocity.
  double th = th0, om = 0.0, t = 0.0;
  const double dt = 1e-4;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(1);
  auto f = [&](double a, double b) {
    Configuration q = model.neutralConfiguration();
    q.joints[0] = a;
    return accel(model, data, q, Eigen::VectorXd::Constant(1, b), zero)[0];
  };
  double t_turn = -1.0;
  for (int step = 0; step < 200000; ++step) {
    const double k1t = om, k1o = f(th, om);
    const double k2t = om + 0.5 * dt * k1o, k2o = f(th + 0.5 * dt * k1t, om + 0.5 * dt * k1o);
    const double k3t = om + 0.5 * dt * k2o, k3o = f(th + 0.5 * dt * k2t, om + 0.5 * dt * k2o);
    const double k4t = om + dt * k3o, k4o = f(th + dt * k3t, om + dt * k3o);
    const double th_n = th + dt / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
    const double om_n = om + dt / 6 * (k1o + 2 * k2o + 2 * k3o + k4o);
    if (step > 10 && om < 0.0 && om_n >= 0.0) {
      // Velocity zero crossing: Newton on the Hermite interpolant of omega (slopes f).
      const double a0 = f(th, om), a1 = f(th_n, om_n);
      double s = om / (om - om_n);
      for (int it = 0; it < 20; ++it) {
        const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
        const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
        const double val = h00 * om + h10 * dt * a0 + h01 * om_n + h11 * dt * a1;
        const double d00 = 6 * s * s - 6 * s, d10 = 3 * s * s - 4 * s + 1, d01 = -6 * s * s + 6 * s, d11 = 3 * s * s - 2 * s;
        const double der = d00 * om + d10 * dt * a0 + d01 * om_n + d11 * dt * a1;
        s -= val / der;
      }
      t_turn = t + s * dt;
      break;
    }
    th = th_n;
    om = om_n;
    t += dt;
  }
  ASSERT_GT(t_turn, 0.0);
  EXPECT_NEAR(t_turn, half_period, 1e-7 * half_period);
  EXPECT_NEAR(th, -th0, 1e-3);  // energy is conserved: it swings to the opposite angle
}

}  // namespace
}  // namespace lexdyn::model
