// Second derivatives of the geometric task types (accumulateHessian) against finite differences
// of their task Jacobians (TaskData::J), on the humanoid and the small arms.
//
// The exact task function. A Newton step moves the configuration by q(s) = integrate(q_k, s, 1)
// (RobotModel::integrate: joints and base position linearly, base rotation
// R = Rx(s0) Ry(s1) Rz(s2) R_k: the Euler angles re-zeroed at this tick), so the Hessian is that
// of g(s) = f(q(s)) at s = 0. Its gradient is dg/ds(s) = J(q(s)) E(s), where J = TaskData::J is
// the Jacobian with respect to the velocity u and E(s) maps s-rates to u: the identity, except for
// the base rotation block [x, Rx(s0) y, Rx(s0) Ry(s1) z] (omega of the Euler chain). For the
// orientation rows the task function is the re-centred rotation vector phi(s) = log(R(s) R_k^T)
// (orientation.hpp), whose gradient is J_l^{-1}(phi) J_ang E(s) (J_l: left Jacobian of SO(3)).
// So H^d_ij = d/ds_i [dg_d/ds_j], by central differences along s = +-h e_i; the result must be
// symmetric (checked), which it would not be without E(s) on the free-flyer.
//
// self_collision's Hessian is an approximation (self_collision.hpp): it is checked against the
// finite differences of its defining function n^T (p_a - p_b) with the normal and the witness
// points held on their bodies, whose first derivative is checked to be TaskData::J.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>

#include "lexdyn/tasks/com.hpp"
#include "lexdyn/tasks/com_box.hpp"
#include "lexdyn/tasks/contact.hpp"
#include "lexdyn/tasks/orientation.hpp"
#include "lexdyn/tasks/position.hpp"
#include "lexdyn/tasks/self_collision.hpp"
#include "task_test_utils.hpp"

namespace lexdyn::tasks {
namespace {

using namespace testing;

/// E(s): u = E(s) sdot for q(s) = integrate(q_k, s, 1).
Eigen::MatrixXd chartMap(const RobotModel& model, const Eigen::VectorXd& s) {
  Eigen::MatrixXd E = Eigen::MatrixXd::Identity(model.nv(), model.nv());
  if (model.hasFreeFlyer()) {
    const Eigen::Matrix3d Rx = Eigen::AngleAxisd(s[0], Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Matrix3d Ry = Eigen::AngleAxisd(s[1], Eigen::Vector3d::UnitY()).toRotationMatrix();
    E.block<3, 1>(0, 0) = Eigen::Vector3d::UnitX();
    E.block<3, 1>(0, 1) = Rx * Eigen::Vector3d::UnitY();
    E.block<3, 1>(0, 2) = Rx * Ry * Eigen::Vector3d::UnitZ();
  }
  return E;
}

/// Inverse of the left Jacobian of SO(3) at the rotation vector phi.
Eigen::Matrix3d leftJacobianInverse(const Eigen::Vector3d& phi) {
  const double t = phi.norm();
  const Eigen::Matrix3d S = skew(phi);
  const double c = t < 1e-6 ? 1.0 / 12.0 : 1.0 / (t * t) - (1.0 + std::cos(t)) / (2.0 * t * std::sin(t));
  return Eigen::Matrix3d::Identity() - 0.5 * S + c * S * S;
}

/// Finite-difference Hessians H[d] (nv x nv) of the rows of a task. gradient(fx, s) returns
/// dg/ds at the fixture's current state q(s) (rows x nv).
template <class Gradient>
std::vector<Eigen::MatrixXd> fdHessians(TickFixture& fx, int rows, Gradient gradient, double h = kH) {
  const int nv = fx.model.nv();
  const Configuration q0 = fx.q;
  std::vector<Eigen::MatrixXd> H(static_cast<size_t>(rows), Eigen::MatrixXd::Zero(nv, nv));
  for (int i = 0; i < nv; ++i) {
    Eigen::MatrixXd G[2];
    for (int k = 0; k < 2; ++k) {
      const Eigen::VectorXd s = (k == 0 ? h : -h) * Eigen::VectorXd::Unit(nv, i);
      fx.model.integrate(q0, s, 1.0, fx.q);
      fx.update();
      G[k] = gradient(s);
    }
    const Eigen::MatrixXd D = (G[0] - G[1]) / (2.0 * h);
    for (int d = 0; d < rows; ++d) H[static_cast<size_t>(d)].row(i) = D.row(d);
  }
  fx.q = q0;
  fx.update();
  return H;
}

/// TaskData::J at the current state, composed into the gradient of the exact task function.
/// orientation_row: first row of a 3-row orientation block (-1: none), of frame `f`.
std::vector<Eigen::MatrixXd> taskHessiansFd(TickFixture& fx, const TaskModel& task, TaskData& d, int orientation_row, model::FrameId f) {
  const Eigen::Matrix3d R0 = f >= 0 ? Eigen::Matrix3d(fx.model.framePlacement(fx.data, f).linear()) : Eigen::Matrix3d::Identity();
  return fdHessians(fx, task.rows(), [&](const Eigen::VectorXd& s) {
    task.compute(fx.ctx, d);
    Eigen::MatrixXd G = d.J * chartMap(fx.model, s);
    if (orientation_row >= 0) {
      const Eigen::Vector3d phi = logRotation(fx.model.framePlacement(fx.data, f).linear() * R0.transpose());
      G.middleRows(orientation_row, 3) = leftJacobianInverse(phi) * G.middleRows(orientation_row, 3);
    }
    return G;
  });
}

::testing::AssertionResult symmetric(const Eigen::MatrixXd& H, double tol) { return near(H, H.transpose(), tol); }

// accumulateHessian against the FD Hessians: per row (unit weights, onto a non-zero H), and with
// a random weight vector; chainDofs against the sparsity of J and H.
// nontrivial: the Hessian must have entries above 1e-3 (false for orientations of a planar arm,
// whose parallel axes give a_i x a_j = 0).
void checkTask(TickFixture& fx, const TaskModel& task, TaskData& d, const std::vector<Eigen::MatrixXd>& Hfd, RandomStates& rs,
               bool nontrivial = true) {
  const int nv = fx.model.nv(), m = task.rows();
  ASSERT_TRUE(task.geometric());
  task.compute(fx.ctx, d);
  Eigen::MatrixXd H0 = Eigen::MatrixXd::Zero(nv, nv);
  for (int i = 0; i < nv; ++i)
    for (int j = 0; j <= i; ++j) H0(i, j) = H0(j, i) = rs.uniform(-1, 1);
  Eigen::VectorXd w(m);
  Eigen::MatrixXd Hw = Eigen::MatrixXd::Zero(nv, nv);
  double largest = 0.0;
  for (int r = 0; r < m; ++r) {
    SCOPED_TRACE("row " + std::to_string(r));
    EXPECT_TRUE(symmetric(Hfd[static_cast<size_t>(r)], 1e-6)) << "the finite-difference Hessian must be symmetric";
    Eigen::MatrixXd H = H0;
    task.accumulateHessian(fx.ctx, d, Eigen::VectorXd::Unit(m, r), H);
    EXPECT_TRUE(near(H - H0, Hfd[static_cast<size_t>(r)], 1e-6));
    w[r] = rs.uniform(-2, 2);
    Hw += w[r] * Hfd[static_cast<size_t>(r)];
    largest = std::max(largest, Hfd[static_cast<size_t>(r)].cwiseAbs().maxCoeff());
  }
  if (nontrivial) {
    EXPECT_GT(largest, 1e-3) << "a non-trivial Hessian";
  }
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(nv, nv);
  task.accumulateHessian(fx.ctx, d, w, H);
  EXPECT_TRUE(near(H, Hw, 1e-6));
  // chainDofs: J and H vanish outside the chain.
  std::vector<char> mask(static_cast<size_t>(nv), 0);
  task.chainDofs(fx.model, mask);
  int chain = 0;
  for (int k = 0; k < nv; ++k) {
    if (mask[static_cast<size_t>(k)]) {
      ++chain;
      continue;
    }
    EXPECT_EQ(d.J.col(k).cwiseAbs().maxCoeff(), 0.0) << "dof " << k << " outside the chain";
    EXPECT_EQ(H.col(k).cwiseAbs().maxCoeff(), 0.0) << "dof " << k << " outside the chain";
  }
  EXPECT_GT(chain, 0);
}

class TaskHessians : public ::testing::TestWithParam<const char*> {};

TEST_P(TaskHessians, PositionOrientationComAndContactMatchFiniteDifferences) {
  TickFixture fx(GetParam());
  RandomStates rs(401);
  const bool humanoid = fx.model.hasFreeFlyer();
  PositionParams pp;
  pp.frame = humanoid ? "LGRASP" : "tool";
  pp.point = Eigen::Vector3d(0.04, -0.03, 0.02);
  pp.target = Eigen::Vector3d(0.4, 0.5, 1.3);
  OrientationParams op;
  op.frame = humanoid ? "RGRASP" : "tool";
  op.target = Eigen::Matrix3d::Identity();
  OrientationParams op2;
  op2.frame = humanoid ? "CHEST_LINK1" : "link2";
  op2.target = Eigen::Matrix3d::Identity();
  ComParams cp;
  cp.target = Eigen::Vector3d::Zero();
  ComBoxParams bp;
  ContactTaskParams kp;
  kp.contact = humanoid ? "RIGHT_FOOT" : "TOOL";
  const PositionTask position("position", fx.model, pp);
  const OrientationTask orientation("orientation", fx.model, op);
  const OrientationTask orientation2("orientation2", fx.model, op2);
  const ComTask com("com", fx.model, cp);
  const ComBoxTask com_box("com_box", fx.model, bp);
  const ContactTask contact("contact", fx.model, fx.layout, kp);
  // A point contact (3 rows: a point of the contact's frame) in a layout of its own.
  ContactSpec ball = fx.layout.contact(fx.layout.find(kp.contact));
  ball.name = "BALL";
  ball.fixed = false;
  ball.point = true;
  ball.points = {Eigen::Vector3d(0.03, -0.02, -0.01)};
  const ContactLayout ball_layout(fx.model.nv(), {ball});
  std::vector<char> ball_active = {1};
  ContactTaskParams bkp;
  bkp.contact = "BALL";
  const ContactTask point_contact("point_contact", fx.model, ball_layout, bkp);
  for (int trial = 0; trial < 2; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
    {
      SCOPED_TRACE("position");
      auto d = position.createData(fx.layout);
      const auto H = taskHessiansFd(fx, position, *d, -1, -1);
      checkTask(fx, position, *d, H, rs);
    }
    for (const OrientationTask* t : {&orientation, &orientation2}) {
      SCOPED_TRACE(t->name());
      auto d = t->createData(fx.layout);
      const auto H = taskHessiansFd(fx, *t, *d, 0, t->frame());
      checkTask(fx, *t, *d, H, rs, GetParam() != std::string("planar_3r"));
    }
    for (const TaskModel* t : {static_cast<const TaskModel*>(&com), static_cast<const TaskModel*>(&com_box)}) {
      SCOPED_TRACE(t->name());
      auto d = t->createData(fx.layout);
      const auto H = taskHessiansFd(fx, *t, *d, -1, -1);
      checkTask(fx, *t, *d, H, rs);
    }
    {
      SCOPED_TRACE("contact");
      auto d = contact.createData(fx.layout);
      contact.compute(fx.ctx, *d);  // make the contact here (the held pose does not enter J)
      const auto H = taskHessiansFd(fx, contact, *d, 3, contact.frame());
      checkTask(fx, contact, *d, H, rs);
      // An inactive contact adds nothing.
      fx.active[static_cast<size_t>(contact.contactIndex())] = 0;
      contact.compute(fx.ctx, *d);
      Eigen::MatrixXd Hc = Eigen::MatrixXd::Zero(fx.model.nv(), fx.model.nv());
      contact.accumulateHessian(fx.ctx, *d, Eigen::VectorXd::Ones(6), Hc);
      EXPECT_EQ(Hc.cwiseAbs().maxCoeff(), 0.0);
      fx.active[static_cast<size_t>(contact.contactIndex())] = 1;
    }
    {
      SCOPED_TRACE("point contact");
      fx.ctx.contacts = &ball_layout;
      fx.ctx.contact_active = &ball_active;
      auto d = point_contact.createData(ball_layout);
      point_contact.compute(fx.ctx, *d);
      ASSERT_EQ(point_contact.rows(), 3);
      const auto H = taskHessiansFd(fx, point_contact, *d, -1, -1);
      checkTask(fx, point_contact, *d, H, rs);
      fx.ctx.contacts = &fx.layout;
      fx.ctx.contact_active = &fx.active;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, TaskHessians, ::testing::Values("hrp2kai_like", "arm_7dof", "planar_3r"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

TEST(SelfCollisionHessian, WitnessPointApproximationMatchesItsDefinition) {
  TickFixture fx("hrp2kai_like");
  RandomStates rs(402);
  const SelfCollisionTask task("collisions", fx.model);
  auto dptr = task.createData(fx.layout);
  auto& d = static_cast<SelfCollisionTaskData&>(*dptr);
  std::fill(d.held.begin(), d.held.end(), 1);  // every row's J, free rows' too (free_row_jacobians)
  const int nv = fx.model.nv();
  for (int trial = 0; trial < 2; ++trial) {
    fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
    task.compute(fx.ctx, d);
    const Eigen::Matrix3Xd pa = d.point_a, pb = d.point_b, n = d.normal;
    // The witness points are where the model says, and the held-point function's gradient at
    // s = 0 is TaskData::J.
    auto heldGradient = [&](const Eigen::VectorXd& s) {
      Eigen::MatrixXd G(task.rows(), nv), Ja(3, nv), Jb(3, nv);
      for (int r = 0; r < task.rows(); ++r) {
        fx.model.pointJacobian(fx.data, task.frameA(r), pa.col(r), Ja);
        fx.model.pointJacobian(fx.data, task.frameB(r), pb.col(r), Jb);
        G.row(r) = n.col(r).transpose() * (Ja - Jb);
      }
      return Eigen::MatrixXd(G * chartMap(fx.model, s));
    };
    EXPECT_TRUE(near(heldGradient(Eigen::VectorXd::Zero(nv)), d.J, 1e-12));
    for (int r = 0; r < task.rows(); ++r) {
      Eigen::RowVectorXd none(0);
      const model::CapsuleDistance cd = fx.model.capsuleDistance(fx.data, task.modelPair(r), none);
      EXPECT_TRUE(near(fx.model.pointPosition(fx.data, task.frameA(r), pa.col(r)), cd.point_a, 1e-12));
      EXPECT_TRUE(near(fx.model.pointPosition(fx.data, task.frameB(r), pb.col(r)), cd.point_b, 1e-12));
    }
    const auto H = fdHessians(fx, task.rows(), heldGradient);
    task.compute(fx.ctx, d);
    checkTask(fx, task, d, H, rs);
  }
}

}  // namespace
}  // namespace lexdyn::tasks
