// The simulator against closed-form solutions (free pendulum, servo responses, grasp bushing),
// its sensors against the forces it applies, torque saturation, the static-equilibrium start,
// and failure handling.
#include "harness/sim/simulator.hpp"
#include "lexdyn/common/error.hpp"
#include "../common/closed_form.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include <cmath>

namespace lexdyn::sim {
namespace {

std::string src(const std::string& rel) { return std::string(LEXDYN_SOURCE_DIR) + "/" + rel; }

SimulatorSettings tightSettings(int nj, double period) {
  SimulatorSettings s;
  s.control_period_s = period;
  s.servo.kp = Eigen::VectorXd::Zero(nj);
  s.servo.kd = Eigen::VectorXd::Zero(nj);
  s.integrator.rtol = 1e-10;
  s.integrator.atol_position = 1e-12;
  s.integrator.atol_velocity = 1e-12;
  return s;
}

// One step of the simulator; a failure says its status, message and time.
::testing::AssertionResult stepped(Simulator& sim, const JointCommand& cmd) {
  const StepResult r = sim.step(cmd);
  if (r.ok) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "status " << toString(r.status) << " msg " << r.message << " t " << sim.time();
}

JointCommand hold(const Eigen::VectorXd& q) { return JointCommand{q, Eigen::VectorXd::Zero(q.size()), Eigen::VectorXd::Zero(q.size())}; }

using lexdyn::testing::agm;

TEST(Simulator, FreePendulumHalfPeriodMatchesClosedForm) {
  Simulator sim(src("tests/data/model/pendulum.urdf"), src("tests/data/model/pendulum.yaml"), tightSettings(1, 0.001));
  const double m = 2.5, d = 0.8, I = 0.03 + m * d * d, g = 9.81, th0 = 2.0;
  model::Configuration q = sim.model().neutralConfiguration();
  q.joints[0] = th0;
  sim.reset(q, Eigen::VectorXd::Zero(1));
  const double k = std::sin(th0 / 2);
  const double half_period = 2.0 * M_PI / (2.0 * agm(1.0, std::sqrt(1 - k * k))) * std::sqrt(I / (m * g * d));
  auto accel = [&](double th) { return -m * g * d * std::sin(th) / I; };
  double t_turn = -1.0;
  double th_prev = th0, om_prev = 0.0, t_prev = 0.0;
  for (int i = 0; i < 5000 && t_turn < 0; ++i) {
    ASSERT_TRUE(sim.step(hold(Eigen::VectorXd::Zero(1))).ok);
    const double th = sim.sensors().q[0], om = sim.sensors().qdot[0], t = sim.time();
    if (i > 10 && om_prev < 0.0 && om >= 0.0) {
      // Turning point from the cubic Hermite interpolant of omega (slopes = accelerations).
      const double h = t - t_prev, a0 = accel(th_prev), a1 = accel(th);
      double s = om_prev / (om_prev - om);
      for (int it = 0; it < 20; ++it) {
        const double s2 = s * s, s3 = s2 * s;
        const double v = (2 * s3 - 3 * s2 + 1) * om_prev + (s3 - 2 * s2 + s) * h * a0 + (-2 * s3 + 3 * s2) * om + (s3 - s2) * h * a1;
        const double dv = (6 * s2 - 6 * s) * om_prev + (3 * s2 - 4 * s + 1) * h * a0 + (-6 * s2 + 6 * s) * om + (3 * s2 - 2 * s) * h * a1;
        s -= v / dv;
      }
      t_turn = t_prev + s * h;
    }
    th_prev = th;
    om_prev = om;
    t_prev = t;
  }
  ASSERT_GT(t_turn, 0.0);
  EXPECT_NEAR(t_turn, half_period, 1e-6 * half_period);
}

TEST(Simulator, FreeFallOfASpinningBodyMatchesClosedForm) {
  // The free-flyer path of the simulator (Euler-angle coordinates, qdot = N(q) u, Simbody's
  // forward dynamics, CVODE) against the exact solution for a body with a spherical inertia:
  // the CoM follows a parabola and the body turns at a constant angular velocity in the world.
  Simulator sim(src("tests/data/model/free_body.urdf"), src("tests/data/model/free_body.yaml"), tightSettings(0, 0.005));
  const auto& model = sim.model();
  const Eigen::Vector3d c_local = model.description().links[0].com;
  model::Configuration q = model.neutralConfiguration();
  const Eigen::Matrix3d R0 = model::rotationFromEulerXYZ(Eigen::Vector3d(0.2, -0.3, 0.5));
  q.base_rotation = R0;
  q.base_position = Eigen::Vector3d(0.1, 0.2, 3.0);
  const Eigen::Vector3d w(0.7, -1.1, 0.4), vc0(0.5, -0.2, 1.0);
  const Eigen::Vector3d c0 = q.base_position + R0 * c_local;
  Eigen::VectorXd u(6);
  u << w, vc0 - w.cross(R0 * c_local);  // velocity of the base origin
  sim.reset(q, u);
  const JointCommand none{Eigen::VectorXd(0), Eigen::VectorXd(0), Eigen::VectorXd(0)};
  const Eigen::Vector3d g = model.gravity();
  for (int k = 1; k <= 200; ++k) {
    const StepResult r = sim.step(none);
    ASSERT_TRUE(r.ok) << r.message;
    const double t = sim.time();
    const model::Configuration& x = sim.configuration();
    const Eigen::Vector3d c = x.base_position + x.base_rotation * c_local;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(w.norm() * t, w.normalized()).toRotationMatrix() * R0;
    ASSERT_LT((c - (c0 + vc0 * t + 0.5 * g * t * t)).norm(), 1e-8) << "t = " << t;
    ASSERT_LT((x.base_rotation - R).norm(), 1e-8) << "t = " << t;
    ASSERT_LT((sim.velocity().head<3>() - w).norm(), 1e-8) << "t = " << t;
  }
}

TEST(Simulator, ASlidingBallEndsRollingAtFiveSeventhsOfItsSpeed) {
  // A ball foot (a contact surface with a radius): the ground touches the sphere at its lowest
  // point, so a solid ball thrown sliding (v0, no spin) is braked by friction until it rolls,
  // then rolls on: angular momentum about the contact point gives v = 5/7 v0, omega r = v. It is
  // thrown along y: rolling about x keeps the base's Euler angles clear of their singularity
  // (pitch 90 deg).
  SimulatorSettings s = tightSettings(0, 0.005);
  s.integrator.rtol = 1e-8;
  s.integrator.atol_position = 1e-10;
  s.integrator.atol_velocity = 1e-10;
  Simulator sim(src("tests/data/model/ball.urdf"), src("tests/data/model/ball.yaml"), s);
  ASSERT_EQ(sim.model().description().contact_surfaces.size(), 1u);
  EXPECT_DOUBLE_EQ(sim.model().description().contact_surfaces[0].radius, 0.1);
  model::Configuration q = sim.model().neutralConfiguration();
  const double r = 0.1, v0 = 1.0;
  q.base_position = Eigen::Vector3d(0.0, 0.0, r);  // resting on the ground
  Eigen::VectorXd u = Eigen::VectorXd::Zero(6);
  u[4] = v0;
  sim.reset(q, u);
  const JointCommand none{Eigen::VectorXd(0), Eigen::VectorXd(0), Eigen::VectorXd(0)};
  for (int k = 0; k < 200; ++k) ASSERT_TRUE(stepped(sim, none));  // 1 s: rolling after 2 v0 / (7 mu g) = 0.06 s
  const Eigen::VectorXd& w = sim.velocity();
  EXPECT_NEAR(w[4], 5.0 / 7.0 * v0, 2e-4) << w.transpose();
  EXPECT_NEAR(-w[0] * r, w[4], 1e-5) << w.transpose();  // -omega_x r = v_y: no slip
  EXPECT_NEAR(sim.configuration().base_position.z(), r, 2e-3);
  // The recorded contact point is the sphere's lowest point, below the centre.
  ASSERT_EQ(sim.contactPoints().size(), 1u);
  const Eigen::Vector3d c = sim.configuration().base_position;
  EXPECT_NEAR(sim.contactPoints()[0].position.y(), c.y(), 1e-9);
  EXPECT_NEAR(sim.contactPoints()[0].position.z(), c.z() - r, 1e-12);
}

class PointMass : public ::testing::Test {
 protected:
  Simulator make(double kp, double kd, SetpointProfile profile, std::vector<GraspSettings> grasps = {}) {
    SimulatorSettings s = tightSettings(1, 0.005);
    s.servo.kp[0] = kp;
    s.servo.kd[0] = kd;
    s.servo.profile = profile;
    s.grasps = std::move(grasps);
    return Simulator(src("models/point_mass/point_mass.urdf"), src("models/point_mass/point_mass.yaml"), s);
  }
  // From rest at 0: `ticks` steps holding the set-point q_ref, then check(t) after each.
  template <class Check>
  void holdFromRest(Simulator& sim, double q_ref, int ticks, Check check) {
    sim.reset(sim.model().neutralConfiguration(), Eigen::VectorXd::Zero(1));
    const JointCommand cmd = hold(Eigen::VectorXd::Constant(1, q_ref));
    for (int k = 1; k <= ticks; ++k) {
      ASSERT_TRUE(stepped(sim, cmd));
      check(sim.time());
    }
  }
};

TEST_F(PointMass, StepResponseOfTheServoIsCriticallyDamped) {
  // m = 1, kp = 100, kd = 20: x(t) = x_ref (1 - (1 + 10 t) exp(-10 t)).
  Simulator sim = make(100.0, 20.0, SetpointProfile::Step);
  holdFromRest(sim, 0.1, 200,
               [&](double t) { EXPECT_NEAR(sim.sensors().q[0], 0.1 * (1.0 - (1.0 + 10.0 * t) * std::exp(-10.0 * t)), 1e-8) << t; });
}

TEST_F(PointMass, HermiteAndLinearSetPointsFollowARampExactlyAStepDoesNot) {
  // Command q = v t_{k+1}, qdot = v. With a set-point exact within the tick, the tracking error
  // e = v t - x obeys e'' = -kp e - kd e' with e(0) = 0, e'(0) = v: e = v t exp(-10 t).
  const double v = 0.2;
  for (SetpointProfile p : {SetpointProfile::Hermite, SetpointProfile::Linear, SetpointProfile::Step}) {
    Simulator sim = make(100.0, 20.0, p);
    // At rest, with the ramp's command at time 0: (0, v).
    JointCommand start = hold(Eigen::VectorXd::Zero(1));
    start.qdot[0] = v;
    sim.reset(sim.model().neutralConfiguration(), Eigen::VectorXd::Zero(1), &start);
    double worst = 0.0;
    for (int k = 1; k <= 200; ++k) {
      JointCommand cmd = hold(Eigen::VectorXd::Constant(1, v * 0.005 * k));
      cmd.qdot[0] = v;
      ASSERT_TRUE(stepped(sim, cmd));
      const double t = sim.time();
      worst = std::max(worst, std::abs(sim.sensors().q[0] - (v * t - v * t * std::exp(-10.0 * t))));
    }
    if (p == SetpointProfile::Step) {
      EXPECT_GT(worst, 1e-4);  // the step leads the ramp by up to one tick
    } else {
      EXPECT_LT(worst, 1e-8);
    }
  }
}

TEST_F(PointMass, TorqueIsSaturatedAtTheEffortLimitAndRecorded) {
  // Effort limit 100 N: with kp = 1e4 towards 1 m the force saturates, x = 50 t^2.
  Simulator sim = make(1e4, 0.0, SetpointProfile::Step);
  holdFromRest(sim, 1.0, 20, [&](double t) {
    EXPECT_NEAR(sim.sensors().q[0], 50.0 * t * t, 1e-9);
    EXPECT_EQ(sim.sensors().tau[0], 100.0);
  });
}

TEST_F(PointMass, GraspBushingIsADampedSpringThatSwitchesOff) {
  // m x'' = -K x - D x' with K = 400, D = 4: w0 = 20, zeta = 0.1, released after 0.5 s.
  GraspSettings g;
  g.name = "pole";
  g.frame = "mass";
  g.stiffness_N_per_m = 400.0;
  g.damping_Ns_per_m = 4.0;
  g.initially_active = true;
  Simulator sim = make(0.0, 0.0, SetpointProfile::Hermite, {g});
  const double v0 = 0.3;
  sim.reset(sim.model().neutralConfiguration(), Eigen::VectorXd::Constant(1, v0));
  ASSERT_TRUE(sim.graspActive(0));
  const double w0 = 20.0, z = 0.1, wd = w0 * std::sqrt(1 - z * z);
  auto x = [&](double t) { return v0 / wd * std::exp(-z * w0 * t) * std::sin(wd * t); };
  auto xd = [&](double t) { return v0 * std::exp(-z * w0 * t) * (std::cos(wd * t) - z * w0 / wd * std::sin(wd * t)); };
  const JointCommand cmd = hold(Eigen::VectorXd::Zero(1));
  for (int k = 1; k <= 100; ++k) {
    ASSERT_TRUE(stepped(sim, cmd));
    EXPECT_NEAR(sim.sensors().q[0], x(sim.time()), 1e-8);
    EXPECT_NEAR(sim.graspWrenchWorld(0).force.x(), -400.0 * x(sim.time()) - 4.0 * xd(sim.time()), 1e-6);
  }
  sim.setGraspActive(0, false);
  const double x1 = x(0.5), v1 = xd(0.5);
  for (int k = 1; k <= 20; ++k) {
    ASSERT_TRUE(stepped(sim, cmd));
    EXPECT_NEAR(sim.sensors().q[0], x1 + v1 * 0.005 * k, 1e-8);
    EXPECT_EQ(sim.graspWrenchWorld(0).force.norm(), 0.0);
  }
}

class Humanoid : public ::testing::Test {
 protected:
  static SimulatorSettings settings() {
    SimulatorSettings s;
    s.servo.kp = Eigen::VectorXd::Constant(32, 2000.0);
    s.servo.kd = Eigen::VectorXd::Constant(32, 40.0);
    for (int j = 0; j < 14; ++j) {  // legs and chest
      s.servo.kp[j] = 20000.0;
      s.servo.kd[j] = 400.0;
    }
    GraspSettings g;
    g.name = "left";
    g.frame = "LGRASP";
    s.grasps.push_back(g);
    return s;
  }
  Simulator sim{src("models/hrp2kai_like/hrp2kai_like.urdf"), src("models/hrp2kai_like/hrp2kai_like.yaml"), settings()};
  Eigen::VectorXd hs = sim.model().posture("half_sitting");
  void SetUp() override { sim.reset(sim.placeOnGround(hs), Eigen::VectorXd::Zero(38)); }
};

TEST_F(Humanoid, FootSensorsReportTheContactWrench) {
  const JointCommand cmd = hold(hs);
  const auto& model = sim.model();
  const double weight = model.totalMass() * 9.81;
  for (int k = 0; k < 300; ++k) ASSERT_TRUE(stepped(sim, cmd));
  // Sensors 0 and 1 are on the feet. Rotate their forces to world and compare with the
  // contact points' forces and with the weight (the robot is at rest after 1.5 s).
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int s = 0; s < 2; ++s) {
    const auto& fs = model.description().force_sensors[static_cast<size_t>(s)];
    const Eigen::Isometry3d X = model.framePlacement(sim.data(), fs.frame);
    const Wrench& w = sim.sensors().wrenches[static_cast<size_t>(s)];
    const Eigen::Vector3d f_world = X.linear() * w.force;
    const Eigen::Vector3d t_world = X.linear() * w.torque;
    // The same wrench from the contact points of the foot under this sensor.
    Eigen::Vector3d f = Eigen::Vector3d::Zero(), t = Eigen::Vector3d::Zero();
    for (const ContactPoint& cp : sim.contactPoints()) {
      if (cp.surface != s) continue;
      f += cp.force;
      t += (cp.position - X.translation()).cross(cp.force);
    }
    EXPECT_LT((f_world - f).norm(), 1e-9);
    EXPECT_LT((t_world - t).norm(), 1e-9);
    // The centre of pressure lies inside the sole.
    const Eigen::Isometry3d sole = model.framePlacement(sim.data(), model.frameId(s == 0 ? "RSOLE" : "LSOLE"));
    const Eigen::Vector3d cop_arm = t_world.cross(f_world) / f_world.squaredNorm();
    const Eigen::Vector3d cop = X.translation() + cop_arm;
    EXPECT_LT(std::abs((cop - sole.translation()).x()), 0.108);
    EXPECT_LT(std::abs((cop - sole.translation()).y()), 0.070);
    total += f_world;
  }
  EXPECT_NEAR(total.z(), weight, 0.01 * weight);
  // The hand sensors read zero: no grasp.
  EXPECT_EQ(sim.sensors().wrenches[2].force.norm(), 0.0);
  EXPECT_EQ(sim.sensors().wrenches[3].force.norm(), 0.0);
  // Applied torques never exceed the limits.
  EXPECT_TRUE((sim.sensors().tau.array().abs() <= model.jointTorqueLimits().array()).all());
}

TEST_F(Humanoid, HandSensorReportsTheGraspWrench) {
  const auto& model = sim.model();
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(sim.step(hold(hs)).ok);
  sim.setGraspActive(0, true);
  // Pull the left arm forward against the grasp.
  Eigen::VectorXd target = hs;
  target[model.jointIndex("LARM_JOINT0")] -= 0.2;
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(sim.step(hold(target)).ok);
  const Wrench gw = sim.graspWrenchWorld(0);
  EXPECT_GT(gw.force.norm(), 5.0);  // the bushing resists the pull
  const auto& fs = model.description().force_sensors[3];
  ASSERT_EQ(fs.name, "LeftHandForceSensor");
  const Eigen::Isometry3d Xs = model.framePlacement(sim.data(), fs.frame);
  const Eigen::Isometry3d Xg = model.framePlacement(sim.data(), model.frameId("LGRASP"));
  const Wrench& w = sim.sensors().wrenches[3];
  EXPECT_LT((Xs.linear() * w.force - gw.force).norm(), 1e-9);
  const Eigen::Vector3d t_expected = gw.torque + (Xg.translation() - Xs.translation()).cross(gw.force);
  EXPECT_LT((Xs.linear() * w.torque - t_expected).norm(), 1e-9);
  sim.setGraspActive(0, false);
  ASSERT_TRUE(sim.step(hold(target)).ok);
  EXPECT_EQ(sim.sensors().wrenches[3].force.norm(), 0.0);
}

// The applied forces' Jacobian (IntegratorJacobian::AppliedForces) against central difference
// quotients of the right-hand side, on the humanoid standing on its soles with the left hand
// grasped and every speed perturbed (so that the feet slip a little and the friction's
// derivative is away from its value at rest). Per block, the Frobenius norm of the difference
// relative to the difference quotients' block:
//   d qdot / d u = N(q): exact (linear in u);
//   d udot / d u: leaves out the Coriolis terms' derivative only;
//   d udot / d q: leaves out gravity's, M(q)'s and the point Jacobians' derivatives.
// Leaving out the contact damping, the contact stiffness or the servo stiffness, or flipping the
// grasp stiffness's sign, moves the relative error of its block to 0.3-0.9 (checked by editing
// jacobian()).
TEST_F(Humanoid, AppliedForcesJacobianMatchesDifferenceQuotients) {
  for (int k = 0; k < 40; ++k) ASSERT_TRUE(sim.step(hold(hs)).ok);
  sim.setGraspActive(0, true);
  for (int k = 0; k < 10; ++k) ASSERT_TRUE(sim.step(hold(hs)).ok);
  const int n = sim.stateSize(), nq = n / 2;
  std::vector<double> y = sim.integratedState();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> speed(-0.02, 0.02);
  for (int i = nq; i < n; ++i) y[static_cast<size_t>(i)] += speed(rng);
  const double t = sim.time();
  Eigen::MatrixXd J;
  sim.appliedForcesJacobian(t, y, J);
  Eigen::MatrixXd D(n, n);
  std::vector<double> yp, ym, fp, fm;
  for (int j = 0; j < n; ++j) {
    const double h = 1e-7;
    yp = ym = y;
    yp[static_cast<size_t>(j)] += h;
    ym[static_cast<size_t>(j)] -= h;
    sim.rightHandSide(t, yp, fp);
    sim.rightHandSide(t, ym, fm);
    for (int i = 0; i < n; ++i) D(i, j) = (fp[static_cast<size_t>(i)] - fm[static_cast<size_t>(i)]) / (2 * h);
  }
  auto relative = [&](int r, int c, int rows, int cols) {
    return (J.block(r, c, rows, cols) - D.block(r, c, rows, cols)).norm() / D.block(r, c, rows, cols).norm();
  };
  const double rates = relative(0, nq, nq, nq), damping = relative(nq, nq, nq, nq), stiffness = relative(nq, 0, nq, nq);
  // Seen: 5.4e-12, 2.6e-6, 9.2e-4; the left-out d qdot / d q is 0.5 % of N.
  EXPECT_LT(rates, 1e-9);
  EXPECT_LT(damping, 1e-4);
  EXPECT_LT(stiffness, 1e-2);
  EXPECT_EQ(J.topLeftCorner(nq, nq).norm(), 0.0);
  EXPECT_LT(D.topLeftCorner(nq, nq).norm(), 1e-2 * D.topRightCorner(nq, nq).norm());
  std::printf("relative errors: N %.3g, d udot/du %.3g, d udot/dq %.3g\n", rates, damping, stiffness);
}

// The first 0.1 s from an initial state: largest WAIST displacement and largest relative error
// of the summed vertical contact force against m g, over the ticks.
struct StartTransient {
  double waist_drift_m = 0.0;
  double force_error_rel = 0.0;
};

StartTransient firstTenthOfASecond(Simulator& sim, const Eigen::VectorXd& posture) {
  const auto& model = sim.model();
  const double weight = model.totalMass() * model.gravity().norm();
  const model::FrameId waist = model.frameId("WAIST");
  const Eigen::Vector3d p0 = model.framePlacement(sim.data(), waist).translation();
  StartTransient tr;
  for (int k = 0; k < 20; ++k) {
    const StepResult r = sim.step(hold(posture));
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) break;
    double fz = 0.0;
    for (const ContactPoint& cp : sim.contactPoints()) fz += cp.force.z();
    tr.force_error_rel = std::max(tr.force_error_rel, std::abs(fz - weight) / weight);
    tr.waist_drift_m = std::max(tr.waist_drift_m, (model.framePlacement(sim.data(), waist).translation() - p0).norm());
  }
  return tr;
}

TEST_F(Humanoid, StaticEquilibriumStartIsAtRestFromTheFirstTick) {
  const auto& model = sim.model();
  const double weight = model.totalMass() * model.gravity().norm();
  const RestingState r = sim.restingState(hs, Settle::StaticEquilibrium);
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_GE(r.iterations, 1);
  EXPECT_LE(r.net_force_N, 1e-9 * weight);
  EXPECT_LE(r.joint_residual_Nm, 1e-9 * weight);
  // The base keeps its horizontal position and heading; the joints sit below the posture by the
  // servo's static deflection (load / kp: small, but not zero).
  EXPECT_EQ(r.q.base_position.x(), 0.0);
  EXPECT_EQ(r.q.base_position.y(), 0.0);
  EXPECT_NEAR(std::atan2(r.q.base_rotation(1, 0), r.q.base_rotation(0, 0)), 0.0, 1e-15);
  const double deflection = (r.q.joints - hs).cwiseAbs().maxCoeff();
  EXPECT_GT(deflection, 1e-4);
  EXPECT_LT(deflection, 0.02);

  const JointCommand command = hold(hs);
  sim.reset(r.q, Eigen::VectorXd::Zero(38), &command);
  // At t = 0, from the contact points themselves (not the solver's residual): the vertical
  // forces sum to m g, no horizontal force, no tilting moment about the CoM.
  Eigen::Vector3d F = Eigen::Vector3d::Zero(), M = Eigen::Vector3d::Zero();
  const Eigen::Vector3d com = model.centerOfMass(sim.data());
  for (const ContactPoint& cp : sim.contactPoints()) {
    F += cp.force;
    M += (cp.position - com).cross(cp.force);
  }
  EXPECT_NEAR(F.z(), weight, 1e-9 * weight);
  EXPECT_LT(F.head<2>().norm(), 1e-9 * weight);
  EXPECT_LT(M.head<2>().norm(), 1e-9 * weight * 1.0);  // N m
  // Every servo already carries its joint's load: torque = kp (posture - q) != 0.
  EXPECT_GT(sim.sensors().tau.cwiseAbs().maxCoeff(), 10.0);
  // The first 0.1 s: nothing moves beyond integrator noise (the unsettled starts of the next
  // test sink 0.3 mm and lose 9 % of the contact force in the same time).
  const StartTransient tr = firstTenthOfASecond(sim, hs);
  EXPECT_LT(tr.waist_drift_m, 2e-6);    // measured 0.3 um (atol_position 1e-6)
  EXPECT_LT(tr.force_error_rel, 1e-4);  // measured 1.4e-5
}

TEST_F(Humanoid, UnsettledStartsSinkWhileTheServosTakeUpTheLoad) {
  const double weight = sim.model().totalMass() * sim.model().gravity().norm();
  // BaseOnly balances the robot as a rigid body with its joints exactly at the posture.
  const RestingState base = sim.restingState(hs, Settle::BaseOnly);
  ASSERT_TRUE(base.converged) << base.message;
  EXPECT_EQ(base.q.joints, hs);
  EXPECT_LE(base.net_force_N, 1e-9 * weight);
  EXPECT_LE(base.net_moment_Nm, 1e-9 * weight);
  EXPECT_GT(base.joint_residual_Nm, 10.0);  // the servos start unloaded
  // None: lowest point at the even-share penetration, level base: the moments do not balance.
  const RestingState none = sim.restingState(hs, Settle::None);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_GT(none.net_moment_Nm, 0.1);
  for (const RestingState* r : {&base, &none}) {
    sim.reset(r->q, Eigen::VectorXd::Zero(38));
    double fz = 0.0;
    for (const ContactPoint& cp : sim.contactPoints()) fz += cp.force.z();
    EXPECT_NEAR(fz, weight, 1e-6 * weight) << toString(r->settle);
    const StartTransient tr = firstTenthOfASecond(sim, hs);
    EXPECT_GT(tr.waist_drift_m, 1e-4) << toString(r->settle);
    EXPECT_GT(tr.force_error_rel, 0.05) << toString(r->settle);
  }
}

TEST_F(Humanoid, StaticEquilibriumKeepsTheGivenHeadingAndPosition) {
  const RestingState a = sim.restingState(hs, Settle::StaticEquilibrium);
  const RestingState b = sim.restingState(hs, Settle::StaticEquilibrium, 0.7, Eigen::Vector2d(0.3, -0.2));
  ASSERT_TRUE(a.converged && b.converged) << a.message << b.message;
  EXPECT_EQ(b.q.base_position.x(), 0.3);
  EXPECT_EQ(b.q.base_position.y(), -0.2);
  EXPECT_NEAR(std::atan2(b.q.base_rotation(1, 0), b.q.base_rotation(0, 0)), 0.7, 1e-12);
  // On a flat ground the physics does not depend on the heading: the same joints, height, tilt.
  EXPECT_LT((a.q.joints - b.q.joints).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(a.q.base_position.z(), b.q.base_position.z(), 1e-10);
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_LT((Rz * a.q.base_rotation - b.q.base_rotation).norm(), 1e-9);
}

TEST_F(Humanoid, NoStaticEquilibriumIsReportedNotReturnedAsAStart) {
  // Right foot lifted: the robot would stand on its left foot with the CoM beside it.
  Eigen::VectorXd one_leg = hs;
  one_leg[sim.model().jointIndex("RLEG_JOINT2")] = -1.2;
  one_leg[sim.model().jointIndex("RLEG_JOINT3")] = 1.8;
  const RestingState r = sim.restingState(one_leg, Settle::StaticEquilibrium);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.message.find("no stable static equilibrium"), std::string::npos) << r.message;
  // The message says where the weight goes: the loaded contact points and the CoM's margin.
  EXPECT_NE(r.message.find("loaded contact points:"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("support polygon of the loaded points"), std::string::npos) << r.message;
  EXPECT_TRUE(r.q.joints.allFinite());
}

TEST(SimulatorEquilibrium, ServoHoldsAPendulumAgainstGravity) {
  // Fixed base: only the joint is solved. kp (theta_ref - theta) = m g d sin(theta), the
  // root found here by bisection.
  SimulatorSettings s = tightSettings(1, 0.005);
  s.servo.kp[0] = 50.0;
  s.servo.kd[0] = 5.0;
  Simulator sim(src("tests/data/model/pendulum.urdf"), src("tests/data/model/pendulum.yaml"), s);
  const double mgd = 2.5 * 9.81 * 0.8, theta_ref = 0.5;
  double lo = 0.0, hi = theta_ref;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (50.0 * (theta_ref - mid) - mgd * std::sin(mid) > 0.0 ? lo : hi) = mid;
  }
  const RestingState r = sim.restingState(Eigen::VectorXd::Constant(1, theta_ref), Settle::StaticEquilibrium);
  ASSERT_TRUE(r.converged) << r.message;
  // Converged means a torque imbalance below 1e-9 m g (N m): the angle is off by at most that
  // over the stiffness kp + m g d cos(theta).
  const double theta = 0.5 * (lo + hi);
  EXPECT_LE(r.joint_residual_Nm, 1e-9 * 2.5 * 9.81);
  EXPECT_NEAR(r.q.joints[0], theta, 1e-9 * 2.5 * 9.81 / (50.0 + mgd * std::cos(theta)));
  // And it stays there.
  const JointCommand command = hold(Eigen::VectorXd::Constant(1, theta_ref));
  sim.reset(r.q, Eigen::VectorXd::Zero(1), &command);
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(sim.step(command).ok);
  EXPECT_NEAR(sim.sensors().q[0], r.q.joints[0], 1e-9);
  // Upside down (theta_ref = pi) the servo balances nothing and the pendulum is at rest, but
  // that equilibrium is stable only when kp > m g d (19.6 N m/rad): a start must be stable.
  for (double kp : {10.0, 50.0}) {
    SimulatorSettings si = s;
    si.servo.kp[0] = kp;
    Simulator inverted(src("tests/data/model/pendulum.urdf"), src("tests/data/model/pendulum.yaml"), si);
    const RestingState up = inverted.restingState(Eigen::VectorXd::Constant(1, M_PI), Settle::StaticEquilibrium);
    EXPECT_LE(up.joint_residual_Nm, 1e-9 * 2.5 * 9.81);
    EXPECT_NEAR(up.q.joints[0], M_PI, 1e-12);
    EXPECT_EQ(up.converged, kp > mgd) << up.message;
    if (kp < mgd) {
      EXPECT_NE(up.message.find("unstable"), std::string::npos) << up.message;
      // The unstable mode is named by its largest components (here the only joint).
      EXPECT_NE(up.message.find("the unstable mode is joint swing"), std::string::npos) << up.message;
    }
  }
  // Requests that cannot be met are input errors.
  EXPECT_THROW(sim.restingState(Eigen::VectorXd::Constant(1, theta_ref), Settle::BaseOnly), InputError);
  EXPECT_THROW(sim.restingState(Eigen::VectorXd::Zero(2), Settle::StaticEquilibrium), InputError);
}

TEST(SimulatorFailure, IntegratorFailureStopsWithAClearStatus) {
  SimulatorSettings s;
  s.servo.kp = Eigen::VectorXd::Constant(32, 20000.0);
  s.servo.kd = Eigen::VectorXd::Constant(32, 400.0);
  s.integrator.max_steps_per_tick = 2;  // far too few for the first tick
  Simulator sim(src("models/hrp2kai_like/hrp2kai_like.urdf"), src("models/hrp2kai_like/hrp2kai_like.yaml"), s);
  const Eigen::VectorXd hs = sim.model().posture("half_sitting");
  sim.reset(sim.placeOnGround(hs), Eigen::VectorXd::Zero(38));
  const StepResult r = sim.step(hold(hs));
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.status, CvodeStatus::TooMuchWork);
  EXPECT_NE(r.message.find("too_much_work"), std::string::npos) << r.message;
  EXPECT_LT(sim.time(), 0.005);
  EXPECT_EQ(sim.tick(), 0);
  const StepResult again = sim.step(hold(hs));
  EXPECT_FALSE(again.ok);
  EXPECT_EQ(again.message, r.message);
}

TEST(SimulatorFailure, BadSettingsAreInputErrors) {
  SimulatorSettings s;
  s.servo.kp = Eigen::VectorXd::Constant(3, 1.0);  // wrong size
  s.servo.kd = Eigen::VectorXd::Constant(3, 1.0);
  EXPECT_THROW(Simulator(src("models/hrp2kai_like/hrp2kai_like.urdf"), src("models/hrp2kai_like/hrp2kai_like.yaml"), s), InputError);
}

}  // namespace
}  // namespace lexdyn::sim
