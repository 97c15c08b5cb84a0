// Dynamics task types (equation_of_motion, torque_limits) and the generator-variable tasks
// (contact_force_bounds, wrench_min), plus trust_region and velocity_min, against independent
// references:
//  - friction pyramid generators: unit vectors at atan(mu) from the normal, on 4 edges;
//  - for seeded random joint torques tau and generators gamma, Simbody's articulated-body forward
//    dynamics (an independent solver) gives udot; x built from (udot, gamma) satisfies the
//    equation-of-motion rows exactly (velocity form with u(k+1) = u + dt udot), and the torque
//    limit rows reproduce tau; Jc^T gamma is assembled independently from point Jacobians;
//  - bounds of generators per contact kind and activity; sizes and constant rows.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/contact_force_bounds.hpp"
#include "lexdyn/tasks/equation_of_motion.hpp"
#include "lexdyn/tasks/torque_limits.hpp"
#include "lexdyn/tasks/trust_region.hpp"
#include "lexdyn/tasks/velocity_min.hpp"
#include "lexdyn/tasks/wrench_min.hpp"
#include "task_test_utils.hpp"

namespace lexdyn::tasks {
namespace {

using namespace testing;

TEST(Generators, UnitEdgesOfTheFrictionPyramid) {
  RandomStates rs(201);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d R = model::rotationFromEulerXYZ(Eigen::Vector3d(rs.uniform(-3, 3), rs.uniform(-1.5, 1.5), rs.uniform(-3, 3)));
    const Eigen::Vector3d n_in_frame = Eigen::Vector3d(rs.uniform(-1, 1), rs.uniform(-1, 1), rs.uniform(-1, 1)).normalized();
    const double mu = rs.uniform(0.1, 1.5);
    Eigen::Matrix<double, 3, 4> D;
    ContactLayout::generators(R, n_in_frame, mu, D);
    const Eigen::Vector3d n = R * n_in_frame;
    for (int g = 0; g < 4; ++g) {
      EXPECT_NEAR(D.col(g).norm(), 1.0, 1e-14);
      EXPECT_NEAR(std::acos(std::clamp(D.col(g).dot(n), -1.0, 1.0)), std::atan(mu), 1e-9) << "generator " << g;
    }
    // Opposite pairs: tangential parts opposite, and the two pairs orthogonal (4 edges of a
    // square pyramid).
    const Eigen::Vector3d t1 = D.col(0) - D.col(1), t2 = D.col(2) - D.col(3);
    EXPECT_NEAR(t1.dot(n), 0.0, 1e-14);
    EXPECT_NEAR(t2.dot(n), 0.0, 1e-14);
    EXPECT_NEAR(t1.dot(t2), 0.0, 1e-14);
    EXPECT_NEAR(t1.norm(), 2.0 * std::sin(std::atan(mu)), 1e-12);
  }
}

// Jc^T gamma assembled independently: sum over points of J_p^T (D_p gamma_p).
Eigen::VectorXd contactForce(TickFixture& fx, const Eigen::VectorXd& gamma) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(fx.model.nv());
  for (int c = 0; c < fx.layout.count(); ++c) {
    if (!fx.active[static_cast<size_t>(c)]) continue;
    const ContactSpec& s = fx.layout.contact(c);
    Eigen::Matrix<double, 3, 4> D;
    ContactLayout::generators(fx.model.framePlacement(fx.data, s.frame).linear(), s.normal_in_frame, s.friction, D);
    for (size_t p = 0; p < s.points.size(); ++p) {
      Eigen::MatrixXd Jp(3, fx.model.nv());
      fx.model.pointJacobian(fx.data, s.frame, s.points[p], Jp);
      const Eigen::Vector3d force = D * gamma.segment<4>(fx.layout.offset(c) + 4 * static_cast<int>(p));
      f += Jp.transpose() * force;
    }
  }
  return f;
}

class DynamicsTasks : public ::testing::TestWithParam<const char*> {};

TEST_P(DynamicsTasks, EquationOfMotionAndTorqueRowsMatchForwardDynamics) {
  TickFixture fx(GetParam());
  RandomStates rs(202);
  const int nv = fx.model.nv(), nj = fx.model.numJoints(), ng = fx.layout.ng(), off = fx.model.jointVelocityOffset();
  EquationOfMotionTask eom("eom", fx.model);
  TorqueLimitsTask torque("torque", fx.model);
  EXPECT_EQ(eom.rows(), fx.model.hasFreeFlyer() ? 6 : 0);
  EXPECT_TRUE(eom.separateLevel());
  EXPECT_FALSE(torque.separateLevel());
  EXPECT_EQ(torque.rows(), nj);
  auto de = eom.createData(fx.layout);
  auto dt_ = torque.createData(fx.layout);
  for (int trial = 0; trial < 6; ++trial) {
    fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
    // Contact activity varies; the hand grasp (last contact) active in odd trials.
    for (size_t c = 0; c < fx.active.size(); ++c) fx.active[c] = (c + 1 == fx.active.size()) ? (trial % 2) : (trial % 3 != 2);
    Eigen::VectorXd gamma(ng), tau(nj);
    for (int k = 0; k < ng; ++k) gamma[k] = rs.uniform(0.0, 80.0);
    for (int j = 0; j < nj; ++j) tau[j] = rs.uniform(-1.2, 1.2) * fx.model.jointTorqueLimits()[j];
    // Generalized forces S^T tau + Jc^T gamma, and Simbody's forward dynamics with gravity.
    Eigen::VectorXd generalized = contactForce(fx, gamma);
    generalized.segment(off, nj) += tau;
    Eigen::VectorXd udot(nv);
    fx.model.forwardDynamicsReference(fx.data, generalized, udot);
    fx.update();  // the reference may realize further; restore the cached kinematics

    const double dt = fx.ctx.dt;
    for (Domain dom : {Domain::Velocity, Domain::Acceleration}) {
      SCOPED_TRACE(dom == Domain::Velocity ? "velocity" : "acceleration");
      fx.ctx.domain = dom;
      eom.compute(fx.ctx, *de);
      torque.compute(fx.ctx, *dt_);
      Eigen::VectorXd x(nv + ng);
      if (dom == Domain::Velocity) {
        x << fx.u + dt * udot, dt * gamma;  // x = [u(k+1); dt gamma]
      } else {
        x << udot, gamma;
      }
      // Equation of motion: satisfied to rounding.
      EXPECT_EQ(de->lower, de->upper);
      if (eom.rows() > 0) {
        const Eigen::VectorXd r = de->A * x - de->lower;
        const double scale = dom == Domain::Velocity ? dt : 1.0;
        EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-8 * scale * std::max(1.0, generalized.cwiseAbs().maxCoeff())) << r.transpose();
      }
      // Torque rows: the row value minus the bounds' centre is (dt) tau.
      const Eigen::VectorXd Ax = dt_->A * x;
      const Eigen::VectorXd centre = 0.5 * (dt_->lower + dt_->upper);
      const Eigen::VectorXd half = 0.5 * (dt_->upper - dt_->lower);
      const double s = dom == Domain::Velocity ? dt : 1.0;
      EXPECT_TRUE(near((Ax - centre) / s, tau, 1e-7));
      EXPECT_TRUE(near(half / s, fx.model.jointTorqueLimits(), 1e-12));
      for (int j = 0; j < nj; ++j) {
        const bool within = std::abs(tau[j]) <= fx.model.jointTorqueLimits()[j];
        EXPECT_EQ(within, Ax[j] >= dt_->lower[j] && Ax[j] <= dt_->upper[j]) << "joint " << j;
      }
      // Changing an active contact's generators changes the rows; an inactive one's does not.
      for (int c = 0; c < fx.layout.count(); ++c) {
        Eigen::VectorXd x2 = x;
        x2[nv + fx.layout.offset(c)] += 1.0;
        const double change = (dt_->A * x2 - Ax).norm() + (eom.rows() ? (de->A * x2 - de->A * x).norm() : 0.0);
        if (fx.active[static_cast<size_t>(c)]) {
          EXPECT_GT(change, 1e-6) << "contact " << c;
        } else {
          EXPECT_EQ(change, 0.0) << "contact " << c;
        }
      }
    }
    fx.ctx.domain = Domain::Velocity;
  }
  std::fill(fx.active.begin(), fx.active.end(), 1);
  TorqueLimitsParams half;
  half.scale = 0.5;
  TorqueLimitsTask t2("torque", fx.model, half);
  auto d2 = t2.createData(fx.layout);
  t2.compute(fx.ctx, *d2);
  EXPECT_TRUE(near(0.5 * (d2->upper - d2->lower) / fx.ctx.dt, 0.5 * fx.model.jointTorqueLimits(), 1e-12));
}

INSTANTIATE_TEST_SUITE_P(Models, DynamicsTasks, ::testing::Values("hrp2kai_like", "arm_7dof", "planar_3r"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

TEST(ContactForceBounds, FrictionFixedAndInactiveContacts) {
  TickFixture fx("hrp2kai_like");
  const int nv = fx.model.nv(), ng = fx.layout.ng();
  ASSERT_EQ(fx.layout.count(), 3);
  ASSERT_EQ(ng, 4 * 4 + 4 * 4 + 4);
  ContactForceBoundsTask task("gamma", fx.layout);
  EXPECT_EQ(task.kind(), TaskKind::Bounds);
  auto d = task.createData(fx.layout);
  std::vector<int> vars;
  task.boundVariables(fx.layout, vars);
  ASSERT_EQ(static_cast<int>(vars.size()), ng);
  for (int k = 0; k < ng; ++k) {
    EXPECT_EQ(vars[static_cast<size_t>(k)], nv + k);
    EXPECT_EQ(d->A.row(k).sum(), 1.0);
    EXPECT_EQ(d->A(k, vars[static_cast<size_t>(k)]), 1.0);
  }
  fx.active = {1, 0, 1};  // right foot, left foot, hand grasp (fixed)
  for (Domain dom : {Domain::Velocity, Domain::Acceleration}) {
    fx.ctx.domain = dom;
    task.compute(fx.ctx, *d);
    for (int k = 0; k < 16; ++k) {
      EXPECT_EQ(d->lower[k], 0.0);
      EXPECT_EQ(d->upper[k], kInf);
    }
    for (int k = 16; k < 32; ++k) {
      EXPECT_EQ(d->lower[k], 0.0);
      EXPECT_EQ(d->upper[k], 0.0);
    }
    // Fixed contact: generators 0..2 free, generator 3 held at 0 (the redundant pyramid
    // direction; 0..2 span every force).
    for (int k = 32; k < 35; ++k) {
      EXPECT_EQ(d->lower[k], -kInf);
      EXPECT_EQ(d->upper[k], kInf);
      EXPECT_EQ(d->engaged[static_cast<size_t>(k)], 0);
    }
    EXPECT_EQ(d->lower[35], 0.0);
    EXPECT_EQ(d->upper[35], 0.0);
  }
  {
    Eigen::Matrix<double, 3, 4> D;
    ContactLayout::generators(Eigen::Matrix3d::Identity(), Eigen::Vector3d::UnitZ(), 0.7, D);
    Eigen::FullPivLU<Eigen::Matrix3d> lu(D.leftCols(3));
    EXPECT_EQ(lu.rank(), 3);
    EXPECT_LT((D * Eigen::Vector4d(1, 1, -1, -1)).norm(), 1e-15);  // the redundant combination
  }
  fx.active = {1, 1, 0};
  task.compute(fx.ctx, *d);
  for (int k = 16; k < 32; ++k) EXPECT_EQ(d->upper[k], kInf);
  for (int k = 32; k < 36; ++k) EXPECT_EQ(d->upper[k], 0.0);
  // A layout of other sizes is refused.
  const ContactLayout other(nv, {});
  EXPECT_THROW(task.createData(other), InputError);
}

TEST(ConstantRows, WrenchMinVelocityMinAndTrustRegion) {
  TickFixture fx("hrp2kai_like");
  const int nv = fx.model.nv(), ng = fx.layout.ng();
  WrenchMinTask wmin("gamma0", fx.layout);
  VelocityMinTask vmin("qdot0", fx.model);
  TrustRegionParams tp;
  tp.delta = 0.02;
  TrustRegionTask trust("trust", fx.model, tp);
  EXPECT_TRUE(wmin.supports(Domain::Acceleration));
  EXPECT_FALSE(vmin.supports(Domain::Acceleration));
  EXPECT_FALSE(trust.supports(Domain::Acceleration));
  auto dw = wmin.createData(fx.layout);
  auto dv = vmin.createData(fx.layout);
  auto dtr = trust.createData(fx.layout);
  wmin.compute(fx.ctx, *dw);
  vmin.compute(fx.ctx, *dv);
  trust.compute(fx.ctx, *dtr);
  // A x picks the generators / velocities: check with a random x.
  RandomStates rs(203);
  Eigen::VectorXd x(nv + ng);
  for (int k = 0; k < x.size(); ++k) x[k] = rs.uniform(-1, 1);
  EXPECT_TRUE(near(dw->A * x, x.tail(ng), 0.0));
  EXPECT_TRUE(near(dv->A * x, x.head(nv), 0.0));
  EXPECT_TRUE(near(dtr->A * x, x.head(nv), 0.0));
  EXPECT_EQ(dw->lower.cwiseAbs().maxCoeff() + dw->upper.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(dv->lower.cwiseAbs().maxCoeff() + dv->upper.cwiseAbs().maxCoeff(), 0.0);
  // ||dt u(k+1)||_inf <= Delta, free-flyer included.
  EXPECT_TRUE(near(dtr->upper, Eigen::VectorXd::Constant(nv, 0.02 / fx.ctx.dt), 1e-15));
  EXPECT_TRUE(near(dtr->lower, Eigen::VectorXd::Constant(nv, -0.02 / fx.ctx.dt), 1e-15));
  tp.delta = 0.0;
  EXPECT_EQ(inputErrorWhere([&] { TrustRegionTask bad("trust", fx.model, tp); }), "task \"trust\": delta");
  TorqueLimitsParams tl;
  tl.scale = 1.5;
  EXPECT_EQ(inputErrorWhere([&] { TorqueLimitsTask bad("tau", fx.model, tl); }), "task \"tau\": scale");
}

}  // namespace
}  // namespace lexdyn::tasks
