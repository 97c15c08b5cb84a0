// Inequality tasks built on the velocity damper (joint_limits, self_collision, com_box):
//  - the damper formula: free outside d_i, -xi (d - d_s) / (d_i - d_s) inside, 0 at d_s,
//    positive (pushing back) below d_s; the acceleration form bounds u + dt udot the same way;
//  - joint limits: lower <= upper for every joint over positions sweeping through and beyond both
//    limits, the bounds within the velocity limit, signs near each limit;
//  - self-collision: J_d equals the model's capsule-distance Jacobian and the finite difference
//    of the distance; bounds only for pairs within d_i; the free rows of the others are zeros
//    unless TickContext::free_row_jacobians and the row was active in the previous solve
//    (TaskData::held), also after a pair leaves d_i or the flag or the held rows change, and
//    every row's witness points and normal are this tick's either way;
//  - CoM box: the damper engages d_i before each edge and only there; infinite sides are free.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/com_box.hpp"
#include "lexdyn/tasks/damper.hpp"
#include "lexdyn/tasks/joint_limits.hpp"
#include "lexdyn/tasks/self_collision.hpp"
#include "task_test_utils.hpp"

namespace lexdyn::tasks {
namespace {

using namespace testing;

TEST(Damper, FormulaAndSigns) {
  const double d_i = 0.1, d_s = 0.02, xi = 0.5;
  EXPECT_EQ(damperVelocityBound(0.1, d_i, d_s, xi), -kInf);  // at d_i: not yet
  EXPECT_EQ(damperVelocityBound(0.5, d_i, d_s, xi), -kInf);
  EXPECT_EQ(damperVelocityBound(kInf, d_i, d_s, xi), -kInf);
  EXPECT_NEAR(damperVelocityBound(0.06, d_i, d_s, xi), -0.25, 1e-15);  // halfway: -xi / 2
  EXPECT_NEAR(damperVelocityBound(std::nextafter(0.1, 0.0), d_i, d_s, xi), -0.5, 1e-12);
  EXPECT_EQ(damperVelocityBound(0.02, d_i, d_s, xi), 0.0);            // at d_s: no approach
  EXPECT_NEAR(damperVelocityBound(0.0, d_i, d_s, xi), 0.125, 1e-15);  // below: pushed back
  // Acceleration form: u + dt udot obeys the velocity bound.
  const double ddot = -0.3, bias = 0.7, dt = 0.005;
  const double a = damperAccelerationBound(0.06, d_i, d_s, xi, ddot, bias, dt);
  EXPECT_NEAR(ddot + dt * (a + bias), -0.25, 1e-12);
  EXPECT_EQ(damperAccelerationBound(0.2, d_i, d_s, xi, ddot, bias, dt), -kInf);
}

class JointLimits : public ::testing::TestWithParam<const char*> {};

TEST_P(JointLimits, ConsistentNearAndBeyondTheLimits) {
  TickFixture fx(GetParam());
  RandomStates rs(301);
  JointLimitsParams p;  // 0.1, 0.01, 0.5
  p.adaptive = false;   // the fixed-gain formula (the adaptive gain: AdaptiveDamper tests)
  JointLimitsTask task("limits", fx.model, p);
  auto d = task.createData(fx.layout);
  const int nj = fx.model.numJoints(), off = fx.model.jointVelocityOffset();
  std::vector<int> vars;
  task.boundVariables(fx.layout, vars);
  for (int j = 0; j < nj; ++j) EXPECT_EQ(vars[static_cast<size_t>(j)], off + j);
  const Eigen::VectorXd& lo = fx.model.jointLowerLimits();
  const Eigen::VectorXd& hi = fx.model.jointUpperLimits();
  const Eigen::VectorXd& vmax = fx.model.jointVelocityLimits();
  // Sweep every joint through [lo - 0.3 range, hi + 0.3 range].
  for (int step = 0; step <= 200; ++step) {
    const double s = -0.3 + 1.6 * step / 200.0;
    Configuration q = fx.q;
    for (int j = 0; j < nj; ++j) q.joints[j] = lo[j] + s * (hi[j] - lo[j]);
    fx.set(q, rs.velocity(fx.model, 2.0));
    for (Domain dom : {Domain::Velocity, Domain::Acceleration}) {
      fx.ctx.domain = dom;
      task.compute(fx.ctx, *d);
      for (int j = 0; j < nj; ++j) {
        double l = d->lower[j], u = d->upper[j];
        if (dom == Domain::Acceleration) {  // back to the bounds on qdot + dt qddot
          l = fx.u[off + j] + fx.ctx.dt * l;
          u = fx.u[off + j] + fx.ctx.dt * u;
        }
        ASSERT_LE(l, u + 1e-12) << "joint " << j << " at fraction " << s;
        EXPECT_GE(l, -vmax[j] - 1e-12);
        EXPECT_LE(u, vmax[j] + 1e-12);
        // Closed form of the velocity bounds.
        const double range = hi[j] - lo[j], di = 0.1 * range, ds = 0.01 * range;
        const double dl = q.joints[j] - lo[j], du = hi[j] - q.joints[j];
        const double el = dl < di ? std::min(std::max(-0.5 * (dl - ds) / (di - ds), -vmax[j]), vmax[j]) : -vmax[j];
        const double eu = du < di ? std::max(std::min(0.5 * (du - ds) / (di - ds), vmax[j]), -vmax[j]) : vmax[j];
        EXPECT_NEAR(l, el, 1e-9 * std::max(1.0, vmax[j]));
        EXPECT_NEAR(u, eu, 1e-9 * std::max(1.0, vmax[j]));
        EXPECT_EQ(d->engaged[static_cast<size_t>(j)], (dl < di || du < di) ? 1 : 0);
        EXPECT_DOUBLE_EQ(d->error[j], std::min(dl, du));
        // Signs: approaching the lower limit is bounded (lower <= 0 until d_s), leaving it is
        // free up to v_max; beyond the limit the lower bound pushes back (> 0).
        if (dom == Domain::Acceleration) continue;
        if (s > 0.0 && s < 0.01) {
          EXPECT_GT(l, 0.0);
        }
        if (s < 0.0) {
          EXPECT_GT(l, 0.0);
        }
        if (s > 0.011 && s < 0.09) {
          EXPECT_LT(l, 0.0);
          EXPECT_EQ(u, vmax[j]);
        }
        if (s > 1.0) {
          EXPECT_LT(u, 0.0);
        }
        if (s > 0.2 && s < 0.8) {
          EXPECT_EQ(l, -vmax[j]);
          EXPECT_EQ(u, vmax[j]);
        }
      }
    }
  }
  fx.ctx.domain = Domain::Velocity;
  // Without velocity limits, a joint far from its limits is free.
  p.velocity_limits = false;
  JointLimitsTask free_task("limits", fx.model, p);
  Configuration q = fx.q;
  for (int j = 0; j < nj; ++j) q.joints[j] = 0.5 * (lo[j] + hi[j]);
  fx.set(q, fx.u);
  free_task.compute(fx.ctx, *d);
  for (int j = 0; j < nj; ++j) {
    EXPECT_EQ(d->lower[j], -kInf);
    EXPECT_EQ(d->upper[j], kInf);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, JointLimits, ::testing::Values("hrp2kai_like", "arm_7dof", "planar_3r"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

TEST(JointLimitsParams, Validation) {
  const RobotModel model = testing::loadModel("planar_3r");
  auto where = [&](JointLimitsParams p) { return inputErrorWhere([&] { JointLimitsTask t("jl", model, p); }); };
  JointLimitsParams p;
  p.interaction_fraction = 0.6;
  EXPECT_EQ(where(p), "task \"jl\": interaction_fraction");
  p = {};
  p.safety_fraction = 0.1;
  EXPECT_EQ(where(p), "task \"jl\": safety_fraction");
  p = {};
  p.xi = 0.0;
  EXPECT_EQ(where(p), "task \"jl\": xi");
  p = {};
  EXPECT_EQ(where(p), "none");
}

TEST(SelfCollision, DamperOnCapsuleDistances) {
  TickFixture fx("hrp2kai_like");
  RandomStates rs(302);
  SelfCollisionParams scp;
  scp.adaptive = false;  // the fixed-gain formula (the adaptive gain: AdaptiveDamper tests)
  SelfCollisionTask task("collisions", fx.model, scp);
  EXPECT_EQ(task.rows(), fx.model.numCollisionPairs());
  EXPECT_DOUBLE_EQ(task.damper().interaction, 0.05);
  EXPECT_DOUBLE_EQ(task.damper().safety, 0.01);
  auto d = task.createData(fx.layout);
  const auto& sd = static_cast<const SelfCollisionTaskData&>(*d);
  const int nv = fx.model.nv();
  int inside = 0, outside = 0;
  int zeroRows = 0, heldFreeRows = 0;
  for (int trial = 0; trial < 40; ++trial) {
    fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
    // The held rows' Jacobians too (LexDynBFGS) two trials in three, every free row left out in
    // the third; a different half of the rows held at each trial.
    fx.ctx.free_row_jacobians = trial % 3 != 2;
    for (int r = 0; r < task.rows(); ++r) d->held[static_cast<size_t>(r)] = (r * 7 + trial) % 4 < 2 ? 1 : 0;
    for (Domain dom : {Domain::Velocity, Domain::Acceleration}) {
      fx.ctx.domain = dom;
      task.compute(fx.ctx, *d);
      for (int r = 0; r < task.rows(); ++r) {
        Eigen::RowVectorXd J(nv);
        const model::CapsuleDistance cd = fx.model.capsuleDistance(fx.data, task.modelPair(r), J);
        const double dist = cd.distance;
        // The witness points and the normal are this tick's, with or without the flag.
        EXPECT_TRUE(near(fx.model.pointPosition(fx.data, task.frameA(r), sd.point_a.col(r)), cd.point_a, 1e-12));
        EXPECT_TRUE(near(fx.model.pointPosition(fx.data, task.frameB(r), sd.point_b.col(r)), cd.point_b, 1e-12));
        EXPECT_TRUE(near(sd.normal.col(r), cd.normal, 0.0));
        // A free row (the pair at or beyond d_i) constrains nothing: its coefficients are zeros
        // unless the flag is set and the row was active in the previous solve.
        if (dist >= 0.05) {
          if (fx.ctx.free_row_jacobians && d->held[static_cast<size_t>(r)]) {
            ++heldFreeRows;
          } else {
            J.setZero();
            ++zeroRows;
          }
        }
        EXPECT_TRUE(near(d->J.row(r), J, 0.0));
        EXPECT_TRUE(near(d->A.row(r).head(nv), J, 0.0));
        EXPECT_EQ(d->A.row(r).tail(fx.layout.ng()).cwiseAbs().maxCoeff(), 0.0);
        EXPECT_EQ(d->error[r], dist);
        EXPECT_EQ(d->upper[r], kInf);
        if (dist >= 0.05) {
          EXPECT_EQ(d->lower[r], -kInf);
          EXPECT_EQ(d->engaged[static_cast<size_t>(r)], 0);
          if (dom == Domain::Velocity) ++outside;
        } else {
          EXPECT_EQ(d->engaged[static_cast<size_t>(r)], 1);
          const double vb = -0.5 * (dist - 0.01) / (0.05 - 0.01);
          const double expected = dom == Domain::Velocity ? vb : (vb - J.dot(fx.u)) / fx.ctx.dt;
          EXPECT_NEAR(d->lower[r], expected, 1e-9 * std::max(1.0, std::abs(expected)));
          if (dom == Domain::Velocity) ++inside;
        }
      }
    }
    fx.ctx.domain = Domain::Velocity;
    // J_d u against the finite difference of the distance (row 0..rows-1), every row's J.
    if (trial < 3) {
      fx.ctx.free_row_jacobians = true;
      std::fill(d->held.begin(), d->held.end(), 1);
      task.compute(fx.ctx, *d);
      const Eigen::MatrixXd dd = centralDifference(fx, fx.u, [&] {
        Eigen::VectorXd v(task.rows());
        Eigen::RowVectorXd none(0);
        for (int r = 0; r < task.rows(); ++r) v[r] = fx.model.capsuleDistance(fx.data, task.modelPair(r), none).distance;
        return Eigen::MatrixXd(v);
      });
      EXPECT_TRUE(near(d->J * fx.u, dd, 1e-6));
    }
  }
  // Both branches were exercised.
  EXPECT_GT(inside, 0);
  EXPECT_GT(outside, 0);
  EXPECT_GT(zeroRows, 0);
  EXPECT_GT(heldFreeRows, 0);
}

TEST(SelfCollision, PairSelectionAndValidation) {
  const RobotModel model = testing::loadModel("hrp2kai_like");
  SelfCollisionParams p;
  p.pairs = {{"WAIST_C", "RARM_LINK3_C"}, {"LARM_LINK5_C", "CHEST_LINK1_C"}};
  p.interaction_distance = 0.08;
  SelfCollisionTask task("elbows", model, p);
  ASSERT_EQ(task.rows(), 2);
  EXPECT_EQ(task.modelPair(0), 0);   // [RARM_LINK3_C, WAIST_C], either order
  EXPECT_EQ(task.modelPair(1), 15);  // [LARM_LINK5_C, CHEST_LINK1_C]
  EXPECT_DOUBLE_EQ(task.damper().interaction, 0.08);
  auto where = [&](const SelfCollisionParams& q) { return inputErrorWhere([&] { SelfCollisionTask t("sc", model, q); }); };
  SelfCollisionParams q;
  q.pairs = {{"WAIST_C", "RARM_LINK3_C"}, {"NOPE", "WAIST_C"}};
  EXPECT_EQ(where(q), "task \"sc\": pairs[1]");
  q.pairs = {{"WAIST_C", "CHEST_LINK0_C"}};  // both capsules exist, not a pair
  EXPECT_EQ(where(q), "task \"sc\": pairs[0]");
  q.pairs = {{"WAIST_C", "RARM_LINK3_C"}, {"RARM_LINK3_C", "WAIST_C"}};
  EXPECT_EQ(where(q), "task \"sc\": pairs[1]");
  q.pairs.clear();
  q.safety_distance = 0.06;  // >= interaction 0.05
  EXPECT_EQ(where(q), "task \"sc\": safety");
  q.safety_distance.reset();
  q.xi = -1;
  EXPECT_EQ(where(q), "task \"sc\": xi");
}

TEST(ComBox, DamperEngagesTwoCentimetresBeforeEachEdgeOnly) {
  TickFixture fx("hrp2kai_like");
  RandomStates rs(303);
  fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
  const Eigen::Vector3d c = fx.model.centerOfMassReference(fx.data);
  ComBoxParams p;
  p.damper.adaptive = false;  // the fixed-gain formula (the adaptive gain: AdaptiveDamper tests)
  const double xi = p.damper.xi;
  EXPECT_DOUBLE_EQ(p.damper.interaction, 0.02);
  EXPECT_DOUBLE_EQ(p.damper.safety, 0.0);
  // x: 1.5 cm from the lower edge; y: 1 cm from the upper edge; z: unbounded.
  p.lower = Eigen::Vector3d(c.x() - 0.015, c.y() - 0.5, -kInf);
  p.upper = Eigen::Vector3d(c.x() + 0.5, c.y() + 0.01, kInf);
  ComBoxTask task("com_box", fx.model, p);
  auto d = task.createData(fx.layout);
  EXPECT_TRUE(d->target_set);
  task.compute(fx.ctx, *d);
  Eigen::MatrixXd Jc(3, fx.model.nv());
  fx.model.centerOfMassJacobian(fx.data, Jc);
  EXPECT_TRUE(near(d->J, Jc, 0.0));
  EXPECT_TRUE(near(d->A.leftCols(fx.model.nv()), Jc, 0.0));
  EXPECT_NEAR(d->lower[0], -xi * 0.015 / 0.02, 1e-12);
  EXPECT_EQ(d->upper[0], kInf);
  EXPECT_EQ(d->lower[1], -kInf);
  EXPECT_NEAR(d->upper[1], xi * 0.01 / 0.02, 1e-12);
  EXPECT_EQ(d->lower[2], -kInf);
  EXPECT_EQ(d->upper[2], kInf);
  EXPECT_EQ(d->engaged, (std::vector<char>{1, 1, 0}));
  EXPECT_NEAR(d->error[0], 0.015, 1e-12);
  EXPECT_NEAR(d->error[1], 0.01, 1e-12);
  EXPECT_EQ(d->error[2], kInf);

  // Edges just beyond / within 2 cm on every side.
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      for (double gap : {0.0201, 0.0199, -0.01}) {
        Eigen::VectorXd box(6);
        box << Eigen::Vector3d::Constant(-kInf), Eigen::Vector3d::Constant(kInf);
        if (side == 0)
          box[axis] = c[axis] - gap;
        else
          box[3 + axis] = c[axis] + gap;
        if (gap < 0) {  // outside the box: the other side must stay above it
          if (side == 0)
            box[3 + axis] = kInf;
          else
            box[axis] = -kInf;
        }
        task.setTarget(*d, box);
        task.compute(fx.ctx, *d);
        for (int i = 0; i < 3; ++i) {
          const bool acts = i == axis && gap < 0.02;
          EXPECT_EQ(d->engaged[static_cast<size_t>(i)], acts ? 1 : 0) << axis << side << gap;
          if (!acts) {
            EXPECT_EQ(d->lower[i], -kInf);
            EXPECT_EQ(d->upper[i], kInf);
            continue;
          }
          if (side == 0) {
            EXPECT_NEAR(d->lower[i], -xi * gap / 0.02, 1e-9);
            EXPECT_EQ(d->upper[i], kInf);
            if (gap < 0) {
              EXPECT_GT(d->lower[i], 0.0);  // outside: pushed back in
            }
          } else {
            EXPECT_NEAR(d->upper[i], xi * gap / 0.02, 1e-9);
            EXPECT_EQ(d->lower[i], -kInf);
            if (gap < 0) {
              EXPECT_LT(d->upper[i], 0.0);
            }
          }
        }
      }
    }
  }

  // Acceleration domain: bounds on J udot such that J (u + dt udot) obeys the velocity bound,
  // with Jdot u from finite differences of the CoM Jacobian.
  Eigen::VectorXd box(6);
  box << c - Eigen::Vector3d(0.01, 0.3, 0.005), c + Eigen::Vector3d(0.3, 0.015, 0.3);
  task.setTarget(*d, box);
  task.compute(fx.ctx, *d);
  const Eigen::VectorXd vlo = d->lower, vhi = d->upper;
  fx.ctx.domain = Domain::Acceleration;
  task.compute(fx.ctx, *d);
  fx.ctx.domain = Domain::Velocity;
  const Eigen::VectorXd Jdot_u = centralDifference(fx, fx.u,
                                                   [&] {
                                                     Eigen::MatrixXd J(3, fx.model.nv());
                                                     fx.model.centerOfMassJacobian(fx.data, J);
                                                     return J;
                                                   }) *
                                 fx.u;
  const Eigen::VectorXd Ju = Jc * fx.u;
  for (int i = 0; i < 3; ++i) {
    if (std::isfinite(vlo[i])) {
      EXPECT_NEAR(Ju[i] + fx.ctx.dt * (d->lower[i] + Jdot_u[i]), vlo[i], 1e-8);
    } else
      EXPECT_EQ(d->lower[i], -kInf);
    if (std::isfinite(vhi[i])) {
      EXPECT_NEAR(Ju[i] + fx.ctx.dt * (d->upper[i] + Jdot_u[i]), vhi[i], 1e-8);
    } else
      EXPECT_EQ(d->upper[i], kInf);
  }
  EXPECT_TRUE(std::isfinite(vlo[0]) && std::isfinite(vhi[1]) && std::isfinite(vlo[2]));
}

TEST(ComBox, BoxValidation) {
  const RobotModel model = testing::loadModel("hrp2kai_like");
  const ContactLayout layout(model.nv(), {});
  ComBoxParams p;
  p.lower = Eigen::Vector3d(0.1, -0.1, -kInf);
  p.upper = Eigen::Vector3d(0.0, 0.1, kInf);
  try {
    ComBoxTask t("box", model, p);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "task \"box\": upper.x");
  }
  p.upper.x() = 0.2;
  p.damper.safety = 0.03;  // >= interaction 0.02
  try {
    ComBoxTask t("box", model, p);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "task \"box\": damper.safety");
  }
  p.damper.safety = 0.0;
  ComBoxTask task("box", model, p);
  auto d = task.createData(layout);
  Eigen::VectorXd box(6);
  box << kInf, 0, 0, kInf, 1, 1;  // lower.x = +inf
  try {
    task.setTarget(*d, box);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "task \"box\": lower.x");
  }
  box << 0, 0, std::nan(""), 1, 1, 1;
  EXPECT_THROW(task.setTarget(*d, box), InputError);
}

// The adaptive gain (damper.hpp): continuous at engagement, linear to the safety distance
// afterwards, released and re-armed outside the interaction distance.
TEST(AdaptiveDamper, ContinuousAtEngagementThenLinear) {
  const DamperParams p{0.02, 0.0, 0.1, true};
  DamperState st;
  // Outside: free, not engaged.
  EXPECT_EQ(damperVelocityBound(0.021, -0.3, p, st), -kInf);
  EXPECT_FALSE(st.engaged);
  // Engages at d = 0.0199 approaching at 0.3 m/s (> xi): the bound equals the approach speed.
  const double d0 = 0.0199;
  EXPECT_NEAR(damperVelocityBound(d0, -0.3, p, st), -0.3, 1e-15);
  EXPECT_TRUE(st.engaged);
  EXPECT_NEAR(st.xi, 0.3 * 0.02 / d0, 1e-15);
  // Then linear in d with the gain kept, whatever the current rate.
  EXPECT_NEAR(damperVelocityBound(0.01, -0.1, p, st), -st.xi * 0.01 / 0.02, 1e-15);
  EXPECT_NEAR(damperVelocityBound(0.0, 0.0, p, st), 0.0, 1e-15);
  // A slow approach keeps the nominal gain.
  DamperState slow;
  EXPECT_NEAR(damperVelocityBound(0.015, -0.01, p, slow), -0.1 * 0.015 / 0.02, 1e-15);
  // Released outside, re-armed with the new speed at the next engagement.
  EXPECT_EQ(damperVelocityBound(0.03, 0.2, p, st), -kInf);
  EXPECT_FALSE(st.engaged);
  EXPECT_NEAR(damperVelocityBound(0.019, -0.05, p, st), -0.1 * 0.019 / 0.02, 1e-15);
  // The fixed form jumps: at d0 it demands -0.1 m/s while the distance shrinks at 0.3 m/s.
  const DamperParams fixed{0.02, 0.0, 0.1, false};
  DamperState fs;
  EXPECT_NEAR(damperVelocityBound(d0, -0.3, fixed, fs), -0.1 * d0 / 0.02, 1e-15);
}

TEST(AdaptiveDamper, ComBoxIsContinuousWhenTheCentreOfMassEntersTheBand) {
  TickFixture fx("hrp2kai_like");
  RandomStates rs(304);
  fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
  const Eigen::Vector3d c = fx.model.centerOfMassReference(fx.data);
  ComBoxParams p;  // adaptive by default
  // The lower x edge 1.99 cm below the CoM; the task's reset() forgets the engagement.
  p.lower = Eigen::Vector3d(c.x() - 0.0199, -kInf, -kInf);
  ComBoxTask task("com_box", fx.model, p);
  auto d = task.createData(fx.layout);
  task.compute(fx.ctx, *d);
  const double vx = d->J.row(0).dot(fx.u);
  if (vx < -p.damper.xi) {
    EXPECT_NEAR(d->lower[0], vx, 1e-12);  // the bound starts at the current velocity
  } else {
    EXPECT_NEAR(d->lower[0], -p.damper.xi * 0.0199 / 0.02, 1e-12);
  }
  task.reset(*d);
  EXPECT_FALSE(static_cast<DamperTaskData&>(*d).dampers[0].engaged);
}

}  // namespace
}  // namespace lexdyn::tasks
