// PD task types (position, orientation, com, joint_position, posture, contact) against
// independent references:
//  - J equals the model's Jacobian and J u the central finite difference of the task function
//    along the motion;
//  - the error equals the closed form (target - value; for orientations exp(e) R = R_d);
//  - the rows read J x = J u - dt (eddot_ctrl + Jdot u) (eq. 61) in the velocity domain and
//    J x = -eddot_ctrl - Jdot u in the acceleration domain, with edot and Jdot u taken from finite
//    differences (not from the model's bias functions) and eddot_ctrl = -kp e - kv edot (eq. 55);
//  - targets, holding, default gains and parameter validation.
#include <gtest/gtest.h>

#include <cmath>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/com.hpp"
#include "lexdyn/tasks/com_box.hpp"
#include "lexdyn/tasks/contact.hpp"
#include "lexdyn/tasks/joint_position.hpp"
#include "lexdyn/tasks/orientation.hpp"
#include "lexdyn/tasks/position.hpp"
#include "lexdyn/tasks/posture.hpp"
#include "task_test_utils.hpp"

namespace lexdyn::tasks {
namespace {

using namespace testing;

// Checks the PD rows of d against the task function values f(q) (a rows-vector function, with
// re-centring done by the caller) through finite differences: edot = -df/dt, Jdot u = dJ/dt u.
// jac() is the reference Jacobian (j_tol: 0 when it is the model's, more for finite differences).
template <class F, class JF>
void expectPdRows(TickFixture& fx, const TaskModel& task, const Pd& pd, F f, JF jac, const Eigen::VectorXd& e, double j_tol = 0.0) {
  const int nv = fx.model.nv();
  const Eigen::VectorXd u = fx.u;
  const Eigen::VectorXd fdot = centralDifference(fx, u, f);
  const Eigen::MatrixXd Jdot = centralDifference(fx, u, jac);
  const Eigen::VectorXd Jdot_u = Jdot * u;
  const Eigen::VectorXd edot = -fdot;
  const Eigen::VectorXd eddot_ctrl = -pd.kp * e - pd.kv * edot;  // eq. 55
  for (Domain dom : {Domain::Velocity, Domain::Acceleration}) {
    SCOPED_TRACE(dom == Domain::Velocity ? "velocity" : "acceleration");
    fx.ctx.domain = dom;
    auto d = task.createData(fx.layout);
    if (!d->target_set) FAIL() << "the test sets a target";
    task.compute(fx.ctx, *d);
    const Eigen::MatrixXd J = jac();
    EXPECT_TRUE(near(d->A.leftCols(nv), J, j_tol));
    EXPECT_EQ(d->A.rightCols(fx.layout.ng()).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_TRUE(near(d->J, J, j_tol));
    EXPECT_EQ(d->lower, d->upper);
    const Eigen::VectorXd expected = dom == Domain::Velocity ? Eigen::VectorXd(J * u - fx.ctx.dt * (eddot_ctrl + Jdot_u))  // eq. 61
                                                             : Eigen::VectorXd(-eddot_ctrl - Jdot_u);
    EXPECT_TRUE(near(d->lower, expected, 1e-6)) << "rows";
    EXPECT_TRUE(near(d->error, e, 1e-12));
  }
  fx.ctx.domain = Domain::Velocity;
}

class PdTasks : public ::testing::TestWithParam<const char*> {};

TEST_P(PdTasks, PositionRowsJacobianAndError) {
  TickFixture fx(GetParam());
  RandomStates rs(101);
  const std::string frame = fx.model.hasFreeFlyer() ? "LGRASP" : "tool";
  const Eigen::Vector3d point(0.03, -0.02, 0.05);
  for (int trial = 0; trial < 3; ++trial) {
    fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
    PositionParams p;
    p.frame = frame;
    p.point = point;
    p.target = Eigen::Vector3d(rs.uniform(-1, 1), rs.uniform(-1, 1), rs.uniform(0, 2));
    p.gains.kp = 2.5;
    PositionTask task("hand", fx.model, p);
    EXPECT_DOUBLE_EQ(task.gains().kv, 2.0 * std::sqrt(2.5));  // critical damping by default
    const model::FrameId f = fx.model.frameId(frame);
    // J u against the finite difference of the point's position (from the frame placement).
    auto pos = [&] { return Eigen::MatrixXd(fx.model.framePlacement(fx.data, f) * point); };
    auto jac = [&] {
      Eigen::MatrixXd J(3, fx.model.nv());
      fx.model.pointJacobian(fx.data, f, point, J);
      return J;
    };
    const Eigen::VectorXd e = *p.target - fx.model.framePlacement(fx.data, f) * point;
    auto d = task.createData(fx.layout);
    task.compute(fx.ctx, *d);
    EXPECT_TRUE(near(d->J * fx.u, centralDifference(fx, fx.u, pos), 1e-6));
    expectPdRows(fx, task, task.gains(), pos, jac, e);
  }
}

TEST_P(PdTasks, OrientationRowsJacobianAndLogError) {
  TickFixture fx(GetParam());
  RandomStates rs(102);
  const std::string frame = fx.model.hasFreeFlyer() ? "RGRASP" : "tool";
  for (int trial = 0; trial < 3; ++trial) {
    fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
    const model::FrameId f = fx.model.frameId(frame);
    const Eigen::Matrix3d R0 = fx.model.framePlacement(fx.data, f).linear();
    OrientationParams p;
    p.frame = frame;
    p.target = model::rotationFromEulerXYZ(Eigen::Vector3d(rs.uniform(-1, 1), rs.uniform(-1, 1), rs.uniform(-1, 1)));
    p.gains.kp = 4.0;
    p.gains.kv = 3.0;
    OrientationTask task("chest", fx.model, p);
    EXPECT_DOUBLE_EQ(task.gains().kv, 3.0);
    auto d = task.createData(fx.layout);
    task.compute(fx.ctx, *d);
    // Closed form: exp(e) R = R_d, |e| <= pi.
    const Eigen::Vector3d e = d->error;
    EXPECT_LE(e.norm(), M_PI);
    const Eigen::Matrix3d expE = Eigen::AngleAxisd(e.norm(), e.normalized()).toRotationMatrix();
    EXPECT_TRUE(near(expE * R0, *p.target, 1e-12));
    // The re-centred task function f(q) = log(R(q) R0^T) (orientation.hpp): J u = df/dt.
    auto f_rc = [&] { return Eigen::MatrixXd(logRotation(fx.model.framePlacement(fx.data, f).linear() * R0.transpose())); };
    auto jac = [&] {
      Eigen::MatrixXd J6(6, fx.model.nv());
      fx.model.frameJacobian(fx.data, f, J6);
      return Eigen::MatrixXd(J6.bottomRows(3));
    };
    EXPECT_TRUE(near(d->J * fx.u, centralDifference(fx, fx.u, f_rc), 1e-6));
    expectPdRows(fx, task, task.gains(), f_rc, jac, e);
  }
}

TEST_P(PdTasks, ComRowsJacobianAndError) {
  TickFixture fx(GetParam());
  RandomStates rs(103);
  for (int trial = 0; trial < 3; ++trial) {
    fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
    ComParams p;
    p.target = Eigen::Vector3d(0.1, -0.2, 0.7);
    p.gains.kp = 9.0;
    ComTask task("com", fx.model, p);
    EXPECT_DOUBLE_EQ(task.gains().kv, 6.0);
    auto com = [&] { return Eigen::MatrixXd(fx.model.centerOfMassReference(fx.data)); };  // Simbody's CoM
    auto jac = [&] {
      Eigen::MatrixXd J(3, fx.model.nv());
      fx.model.centerOfMassJacobian(fx.data, J);
      return J;
    };
    auto d = task.createData(fx.layout);
    task.compute(fx.ctx, *d);
    EXPECT_TRUE(near(d->J * fx.u, centralDifference(fx, fx.u, com), 1e-6));
    const Eigen::VectorXd e = *p.target - fx.model.centerOfMassReference(fx.data);
    EXPECT_TRUE(near(d->error, e, 1e-12));
    expectPdRows(fx, task, task.gains(), com, jac, e);
  }
}

TEST_P(PdTasks, JointPositionAndPostureRows) {
  TickFixture fx(GetParam());
  RandomStates rs(104);
  const int nv = fx.model.nv(), nj = fx.model.numJoints();
  fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
  const std::vector<std::string> names =
      fx.model.hasFreeFlyer() ? std::vector<std::string>{"HEAD_JOINT0", "RARM_JOINT2"} : std::vector<std::string>{"j2"};
  JointPositionParams jp;
  jp.joints = names;
  jp.target = Eigen::VectorXd::Constant(static_cast<int>(names.size()), 0.3);
  jp.gains.kp = 16.0;
  JointPositionTask head("head", fx.model, jp);
  EXPECT_DOUBLE_EQ(head.gains().kv, 8.0);
  // f = the selected joint angles, read from the configuration.
  auto f = [&] {
    Eigen::VectorXd v(static_cast<int>(names.size()));
    for (size_t k = 0; k < names.size(); ++k) v[static_cast<int>(k)] = fx.q.joints[fx.model.jointIndex(names[k])];
    return Eigen::MatrixXd(v);
  };
  auto jac = [&] {
    // J u = d f / dt: the columns from finite differences along unit velocities.
    Eigen::MatrixXd J(static_cast<int>(names.size()), nv);
    for (int k = 0; k < nv; ++k) J.col(k) = centralDifference(fx, Eigen::VectorXd::Unit(nv, k), f, 1e-3);
    return J;
  };
  const Eigen::MatrixXd J = jac();
  Eigen::VectorXd e = jp.target - f();
  expectPdRows(
      fx, head, head.gains(), f, [&] { return J; }, e, 1e-9);

  PostureParams pp;
  pp.posture = fx.model.description().postures.back().first;  // half_sitting, ready, bent
  pp.gains.kp = 1.0;
  PostureTask posture("posture", fx.model, pp);
  auto d = posture.createData(fx.layout);
  EXPECT_TRUE(d->target_set);
  EXPECT_EQ(d->target, fx.model.posture(pp.posture));
  auto fj = [&] { return Eigen::MatrixXd(fx.q.joints); };
  Eigen::MatrixXd Jp = Eigen::MatrixXd::Zero(nj, nv);
  for (int k = 0; k < nv; ++k) Jp.col(k) = centralDifference(fx, Eigen::VectorXd::Unit(nv, k), fj, 1e-3);
  e = fx.model.posture(pp.posture) - fx.q.joints;
  expectPdRows(
      fx, posture, posture.gains(), fj, [&] { return Jp; }, e, 1e-9);
}

TEST_P(PdTasks, TasksWithoutTargetHoldTheFirstValue) {
  TickFixture fx(GetParam());
  RandomStates rs(105);
  fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 0.5));
  const std::string frame = fx.model.hasFreeFlyer() ? "LGRASP" : "tool";
  PositionParams pp;
  pp.frame = frame;
  OrientationParams op;
  op.frame = frame;
  PositionTask pos("p", fx.model, pp);
  OrientationTask ori("o", fx.model, op);
  ComTask com("c", fx.model);
  JointPositionParams jp;
  jp.joints = {fx.model.jointNames()[0]};
  JointPositionTask joint("j", fx.model, jp);
  PostureTask posture("q", fx.model);
  const TaskModel* tasks[] = {&pos, &ori, &com, &joint, &posture};
  std::vector<std::unique_ptr<TaskData>> data;
  for (const TaskModel* t : tasks) {
    data.push_back(t->createData(fx.layout));
    EXPECT_FALSE(data.back()->target_set) << t->name();
    t->compute(fx.ctx, *data.back());
    EXPECT_TRUE(data.back()->target_set) << t->name();
    EXPECT_LT(data.back()->error.cwiseAbs().maxCoeff(), 1e-15) << t->name();
  }
  const Eigen::Isometry3d X = fx.model.framePlacement(fx.data, fx.model.frameId(frame));
  EXPECT_TRUE(near(data[0]->target, X.translation(), 0.0));
  EXPECT_TRUE(near(rotationFromTarget(data[1]->target), X.linear(), 0.0));
  EXPECT_TRUE(near(data[2]->target, fx.model.centerOfMass(fx.data), 0.0));
  // At another state the held targets stay, and the errors are target - value.
  fx.set(rs.configuration(fx.model), fx.u);
  for (size_t k = 0; k < data.size(); ++k) {
    const Eigen::VectorXd held = data[k]->target;
    tasks[k]->compute(fx.ctx, *data[k]);
    EXPECT_EQ(data[k]->target, held) << tasks[k]->name();
    EXPECT_GT(data[k]->error.norm(), 1e-3) << tasks[k]->name();
  }
  EXPECT_TRUE(near(data[4]->error, data[4]->target - fx.q.joints, 1e-15));
  // setTarget replaces a held target.
  pos.setTarget(*data[0], Eigen::Vector3d(1, 2, 3));
  pos.compute(fx.ctx, *data[0]);
  EXPECT_TRUE(
      near(data[0]->error, Eigen::Vector3d(1, 2, 3) - fx.model.framePlacement(fx.data, fx.model.frameId(frame)).translation(), 1e-15));
}

TEST_P(PdTasks, ContactHoldsThePoseCapturedWhenTheContactIsMade) {
  TickFixture fx(GetParam());
  RandomStates rs(106);
  const int c = fx.model.hasFreeFlyer() ? fx.layout.find("RIGHT_FOOT") : fx.layout.find("TOOL");
  ASSERT_GE(c, 0);
  const model::FrameId f = fx.layout.contact(c).frame;
  ContactTaskParams p;
  p.contact = fx.layout.contact(c).name;
  ContactTask task("foot", fx.model, fx.layout, p);
  EXPECT_DOUBLE_EQ(task.gains().kp, 100.0);
  EXPECT_DOUBLE_EQ(task.gains().kv, 20.0);
  auto d = task.createData(fx.layout);
  auto& cd = static_cast<ContactTaskData&>(*d);

  // Made at a state at rest: the rows read J u(k+1) = 0 (the frame stays still).
  fx.set(rs.configuration(fx.model), Eigen::VectorXd::Zero(fx.model.nv()));
  const Eigen::Isometry3d X0 = fx.model.framePlacement(fx.data, f);
  task.compute(fx.ctx, *d);
  EXPECT_TRUE(cd.holding);
  EXPECT_TRUE(near(cd.position, X0.translation(), 0.0));
  EXPECT_TRUE(near(cd.rotation, X0.linear(), 0.0));
  Eigen::MatrixXd J6(6, fx.model.nv());
  fx.model.frameJacobian(fx.data, f, J6);
  EXPECT_TRUE(near(d->J, J6, 0.0));
  EXPECT_TRUE(near(d->A.leftCols(fx.model.nv()), J6, 0.0));
  EXPECT_EQ(d->error.head<3>().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(d->error.tail<3>().cwiseAbs().maxCoeff(), 1e-15);  // log of R R^T, rounding only
  EXPECT_LT(d->lower.cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(d->lower, d->upper);

  // Later, moved and moving: the pose held is the captured one; rows are the PD of eq. 61 on
  // [p; re-centred rotation vector] towards it.
  fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
  const Eigen::Isometry3d X1 = fx.model.framePlacement(fx.data, f);
  const Eigen::Matrix3d R1 = X1.linear();
  auto pose = [&] {
    const Eigen::Isometry3d X = fx.model.framePlacement(fx.data, f);
    Eigen::VectorXd v(6);
    v << X.translation(), logRotation(X.linear() * R1.transpose());
    return Eigen::MatrixXd(v);
  };
  auto jac = [&] {
    Eigen::MatrixXd J(6, fx.model.nv());
    fx.model.frameJacobian(fx.data, f, J);
    return J;
  };
  Eigen::VectorXd e(6);
  e << X0.translation() - X1.translation(), logRotation(X0.linear() * R1.transpose());
  task.compute(fx.ctx, *d);
  EXPECT_TRUE(near(cd.position, X0.translation(), 0.0));
  EXPECT_TRUE(near(d->error, e, 1e-12));
  {
    // expectPdRows creates fresh data, which captures at its first compute: emulate with a
    // layout where the pose was captured at X0 by checking the rows directly here.
    const Eigen::VectorXd u = fx.u;
    const Eigen::VectorXd edot = -Eigen::VectorXd(centralDifference(fx, u, pose));
    const Eigen::VectorXd Jdot_u = centralDifference(fx, u, jac) * u;
    const Pd& pd = task.gains();
    const Eigen::VectorXd eddot = -pd.kp * e - pd.kv * edot;
    EXPECT_TRUE(near(d->lower, jac() * u - fx.ctx.dt * (eddot + Jdot_u), 1e-6));
    fx.ctx.domain = Domain::Acceleration;
    task.compute(fx.ctx, *d);
    EXPECT_TRUE(near(d->lower, -eddot - Jdot_u, 1e-6));
    fx.ctx.domain = Domain::Velocity;
  }

  // Broken: void rows; made again: a new pose is captured.
  fx.active[static_cast<size_t>(c)] = 0;
  task.compute(fx.ctx, *d);
  EXPECT_FALSE(cd.holding);
  EXPECT_EQ(d->A.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(d->lower.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(d->upper.cwiseAbs().maxCoeff(), 0.0);
  for (char g : d->engaged) EXPECT_EQ(g, 0);
  fx.active[static_cast<size_t>(c)] = 1;
  task.compute(fx.ctx, *d);
  EXPECT_TRUE(cd.holding);
  EXPECT_TRUE(near(cd.position, X1.translation(), 0.0));
  EXPECT_LT(d->error.cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_THROW(task.setTarget(*d, Eigen::VectorXd::Zero(6)), InputError);
}

TEST_P(PdTasks, APointContactHoldsItsPointOnlyAndPushesAlongTheGroundsNormal) {
  // A contact of one point (a ball foot): 3 rows on the point's position, the frame free to turn
  // about it; its friction pyramid is about the world's +z whatever the frame's attitude.
  TickFixture fx(GetParam());
  RandomStates rs(108);
  const int c0 = fx.model.hasFreeFlyer() ? fx.layout.find("RIGHT_FOOT") : fx.layout.find("TOOL");
  ContactSpec spec = fx.layout.contact(c0);
  spec.name = "BALL";
  spec.fixed = false;
  spec.point = true;
  spec.points = {Eigen::Vector3d(0.03, -0.02, -0.01)};
  const ContactLayout layout(fx.model.nv(), {spec});
  std::vector<char> active = {1};
  fx.ctx.contacts = &layout;
  fx.ctx.contact_active = &active;
  ContactTaskParams p;
  p.contact = "BALL";
  const ContactTask task("ball", fx.model, layout, p);
  EXPECT_EQ(task.rows(), 3);
  auto d = task.createData(layout);
  auto& cd = static_cast<ContactTaskData&>(*d);
  const model::FrameId f = spec.frame;
  fx.set(rs.configuration(fx.model), Eigen::VectorXd::Zero(fx.model.nv()));
  const Eigen::Vector3d p0 = fx.model.pointPosition(fx.data, f, spec.points[0]);
  task.compute(fx.ctx, *d);
  EXPECT_TRUE(cd.holding);
  EXPECT_TRUE(near(cd.position, p0, 1e-15));
  Eigen::MatrixXd J3(3, fx.model.nv());
  fx.model.pointJacobian(fx.data, f, spec.points[0], J3);
  EXPECT_EQ(d->J.rows(), 3);
  EXPECT_TRUE(near(d->J, J3, 0.0));
  EXPECT_LT(d->lower.cwiseAbs().maxCoeff(), 1e-15);  // at rest, where it was made
  // Moved and moving: the PD of eq. 61 on the point's position towards the captured one.
  fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
  auto position = [&] { return Eigen::MatrixXd(fx.model.pointPosition(fx.data, f, spec.points[0])); };
  auto jac = [&] {
    Eigen::MatrixXd J(3, fx.model.nv());
    fx.model.pointJacobian(fx.data, f, spec.points[0], J);
    return J;
  };
  const Eigen::Vector3d e = p0 - fx.model.pointPosition(fx.data, f, spec.points[0]);
  task.compute(fx.ctx, *d);
  EXPECT_TRUE(near(d->error, e, 1e-12));
  const Eigen::VectorXd u = fx.u;
  const Eigen::VectorXd edot = -Eigen::VectorXd(centralDifference(fx, u, position));
  const Eigen::VectorXd Jdot_u = centralDifference(fx, u, jac) * u;
  const Eigen::VectorXd eddot = -task.gains().kp * e - task.gains().kv * edot;
  EXPECT_TRUE(near(d->lower, jac() * u - fx.ctx.dt * (eddot + Jdot_u), 1e-6));
  fx.ctx.domain = Domain::Acceleration;
  task.compute(fx.ctx, *d);
  EXPECT_TRUE(near(d->lower, -eddot - Jdot_u, 1e-6));
  fx.ctx.domain = Domain::Velocity;
  // The generators: about world +z for the point contact on a turned frame; about the frame's
  // normal for the same contact of 6 rows.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
  Eigen::Matrix<double, 3, 4> D, Dz, Df;
  ContactLayout::generators(spec, R, D);
  ContactLayout::generators(Eigen::Matrix3d::Identity(), Eigen::Vector3d::UnitZ(), spec.friction, Dz);
  EXPECT_TRUE(near(D, Dz, 0.0));
  spec.point = false;
  ContactLayout::generators(spec, R, D);
  ContactLayout::generators(R, spec.normal_in_frame, spec.friction, Df);
  EXPECT_TRUE(near(D, Df, 0.0));
  EXPECT_FALSE(near(D, Dz, 1e-3));
  fx.ctx.contacts = &fx.layout;
  fx.ctx.contact_active = &fx.active;
}

TEST_P(PdTasks, ResetRestoresTheInitialTargetOrHoldsAgain) {
  TickFixture fx(GetParam());
  RandomStates rs(107);
  fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 0.5));
  const std::string frame = fx.model.hasFreeFlyer() ? "LGRASP" : "tool";
  PositionParams with, without;
  with.frame = without.frame = frame;
  with.target = Eigen::Vector3d(0.1, 0.2, 0.3);
  PositionTask a("a", fx.model, with), b("b", fx.model, without);
  auto da = a.createData(fx.layout), db = b.createData(fx.layout);
  a.compute(fx.ctx, *da);
  b.compute(fx.ctx, *db);
  const Eigen::VectorXd held = db->target;
  a.setTarget(*da, Eigen::Vector3d(1, 1, 1));
  b.setTarget(*db, Eigen::Vector3d(1, 1, 1));
  a.reset(*da);
  b.reset(*db);
  EXPECT_TRUE(da->target_set);
  EXPECT_EQ(da->target, *with.target);
  EXPECT_FALSE(db->target_set);
  fx.set(rs.configuration(fx.model), fx.u);  // elsewhere: b now holds the new position
  b.compute(fx.ctx, *db);
  EXPECT_TRUE(near(db->target, fx.model.pointPosition(fx.data, fx.model.frameId(frame), Eigen::Vector3d::Zero()), 0.0));
  EXPECT_GT((db->target - held).norm(), 1e-3);

  ComBoxParams bp;
  bp.lower = Eigen::Vector3d(-1, -1, -1);
  bp.upper = Eigen::Vector3d(1, 1, 1);
  ComBoxTask box("box", fx.model, bp);
  auto dbox = box.createData(fx.layout);
  Eigen::VectorXd other(6);
  other << -2, -2, -2, 2, 2, 2;
  box.setTarget(*dbox, other);
  box.reset(*dbox);
  EXPECT_EQ(dbox->target.head<3>(), bp.lower);
  EXPECT_EQ(dbox->target.tail<3>(), bp.upper);

  // A contact forgets its pose on reset and captures the current one at the next compute.
  ContactTaskParams cp;
  cp.contact = fx.layout.contact(0).name;
  ContactTask contact("c", fx.model, fx.layout, cp);
  auto dc = contact.createData(fx.layout);
  auto& cd = static_cast<ContactTaskData&>(*dc);
  contact.compute(fx.ctx, *dc);
  const Eigen::Vector3d p0 = cd.position;
  fx.set(rs.configuration(fx.model), fx.u);
  contact.compute(fx.ctx, *dc);
  EXPECT_EQ(cd.position, p0);
  contact.reset(*dc);
  EXPECT_FALSE(cd.holding);
  contact.compute(fx.ctx, *dc);
  EXPECT_TRUE(near(cd.position, fx.model.framePlacement(fx.data, contact.frame()).translation(), 0.0));
  EXPECT_GT((cd.position - p0).norm(), 1e-3);
}

INSTANTIATE_TEST_SUITE_P(Models, PdTasks, ::testing::Values("hrp2kai_like", "arm_7dof", "planar_3r"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

// ----- parameters and targets ---------------------------------------------------------------

// Expects an InputError whose `where` names the task and the field.
template <class F>
void expectInputError(F f, const std::string& where_contains) {
  try {
    f();
    ADD_FAILURE() << "no InputError for " << where_contains;
  } catch (const InputError& e) {
    EXPECT_NE(e.where().find(where_contains), std::string::npos) << "where = " << e.where() << "; " << e.what();
  }
}

TEST(PdTaskParams, InvalidParametersNameTheTaskAndTheField) {
  const RobotModel model = testing::loadModel("hrp2kai_like");
  const ContactLayout layout(model.nv(), testContacts(model));
  PositionParams p;
  p.frame = "NO_SUCH_FRAME";
  expectInputError([&] { PositionTask("rh", model, p); }, "task \"rh\": frame");
  p.frame = "RGRASP";
  p.gains.kp = -1.0;
  expectInputError([&] { PositionTask("rh", model, p); }, "task \"rh\": kp");
  p.gains.kp = 1.0;
  p.gains.kv = std::nan("");
  expectInputError([&] { PositionTask("rh", model, p); }, "task \"rh\": kv");
  p.gains.kv.reset();
  p.point = Eigen::Vector3d(0, std::numeric_limits<double>::infinity(), 0);
  expectInputError([&] { PositionTask("rh", model, p); }, "task \"rh\": point[1]");
  p.point.setZero();
  p.target = Eigen::Vector3d(0, 0, std::nan(""));
  expectInputError([&] { PositionTask("rh", model, p); }, "task \"rh\": target[2]");

  OrientationParams o;
  o.frame = "CHEST_LINK1";
  o.target = Eigen::Matrix3d::Identity() * 1.01;
  expectInputError([&] { OrientationTask("chest", model, o); }, "task \"chest\": target");
  o.target = -Eigen::Matrix3d::Identity();  // orthonormal, det -1
  expectInputError([&] { OrientationTask("chest", model, o); }, "task \"chest\": target");
  o.target.reset();
  OrientationTask chest("chest", model, o);
  auto d = chest.createData(layout);
  Eigen::VectorXd t = rotationToTarget(Eigen::Matrix3d::Identity());
  t[1] = 0.1;
  expectInputError([&] { chest.setTarget(*d, t); }, "task \"chest\": target");
  EXPECT_FALSE(d->target_set);
  expectInputError([&] { chest.setTarget(*d, Eigen::VectorXd::Zero(3)); }, "task \"chest\"");
  chest.setTarget(*d, rotationToTarget(model::rotationFromEulerXYZ(Eigen::Vector3d(0.1, 0.2, 0.3))));
  EXPECT_TRUE(d->target_set);

  JointPositionParams j;
  expectInputError([&] { JointPositionTask("head", model, j); }, "task \"head\": joints");
  j.joints = {"HEAD_JOINT0", "HEAD_JOINT9"};
  expectInputError([&] { JointPositionTask("head", model, j); }, "task \"head\": joints[1]");
  j.joints = {"HEAD_JOINT0", "HEAD_JOINT0"};
  expectInputError([&] { JointPositionTask("head", model, j); }, "task \"head\": joints[1]");
  j.joints = {"HEAD_JOINT0"};
  j.target = Eigen::VectorXd::Zero(2);
  expectInputError([&] { JointPositionTask("head", model, j); }, "task \"head\": target");

  PostureParams pp;
  pp.posture = "no_such_posture";
  expectInputError([&] { PostureTask("posture", model, pp); }, "task \"posture\": posture");
  pp.target = Eigen::VectorXd::Zero(model.numJoints());
  pp.posture = "half_sitting";
  expectInputError([&] { PostureTask("posture", model, pp); }, "task \"posture\": posture");
  pp.posture.clear();
  pp.target = Eigen::VectorXd::Zero(3);
  expectInputError([&] { PostureTask("posture", model, pp); }, "task \"posture\": target");

  ContactTaskParams cp;
  cp.contact = "NO_CONTACT";
  expectInputError([&] { ContactTask("feet", model, layout, cp); }, "task \"feet\": contact");
  ComParams cm;
  cm.gains.kp = std::numeric_limits<double>::infinity();
  expectInputError([&] { ComTask("com", model, cm); }, "task \"com\": kp");
}

}  // namespace
}  // namespace lexdyn::tasks
