// The controller on the humanoid with an exp. 1-like hierarchy, the loop closed on the
// controller's own model (the next state is the command): every method runs, keeps the feet
// and the dynamics, moves the hands, and a tick allocates nothing.
#include <gtest/gtest.h>

#include "../common/alloc_counter.hpp"
#include "humanoid_config.hpp"

namespace lexdyn::control {
namespace {

struct Outcome {
  double hand_error_start = 0.0, hand_error_end = 0.0;
  double max_foot_error = 0.0;
  double max_force_error = 0.0;  // |sum of vertical contact forces - m g| / m g
  bool ok = true;
};

Outcome runHumanoid(const std::string& method, int ticks) {
  const model::RobotModel m = test::loadHumanoid();
  Controller c(m, test::exp1Config(m, method));
  RobotState s = test::halfSitting(m);
  c.reset(s);
  const int rh = c.taskIndex("right_hand"), lh = c.taskIndex("left_hand");
  const int rf = c.taskIndex("right_foot"), lf = c.taskIndex("left_foot");
  const double mg = m.totalMass() * 9.81;
  Outcome o;
  for (int k = 0; k < ticks; ++k) {
    const Command& cmd = c.tick(s);
    if (!cmd.ok()) {
      o.ok = false;
      break;
    }
    const TickRecord& r = c.record();
    if (k == 0) o.hand_error_start = r.task_error_norm(rh) + r.task_error_norm(lh);
    o.hand_error_end = r.task_error_norm(rh) + r.task_error_norm(lh);
    o.max_foot_error = std::max({o.max_foot_error, r.task_error_norm(rf), r.task_error_norm(lf)});
    const double fz = r.contact_wrench(2, 0) + r.contact_wrench(2, 1);
    if (k > 0) o.max_force_error = std::max(o.max_force_error, std::abs(fz - mg) / mg);
    s.q = cmd.q;
    s.u = cmd.u;
    s.time += 0.005;
  }
  return o;
}

TEST(ControllerHumanoid, EveryMethodReachesTowardsTheHandTargets) {
  for (const std::string method : {"bfgs", "ah", "gn", "wls"}) {
    const Outcome o = runHumanoid(method, 600);  // 3 s
    ASSERT_TRUE(o.ok) << method;
    EXPECT_LT(o.hand_error_end, 0.75 * o.hand_error_start) << method;
    EXPECT_LT(o.max_foot_error, 1e-4) << method;  // feet held (m / rad)
    // The vertical contact force stays near the weight while the arms move (measured: < 10 %
    // for the velocity-domain methods, 14 % for WLS). A damper engaging with a fixed gain made
    // one-tick jolts of 45-100 % here (docs/controller.md, adaptive damper gain).
    EXPECT_LT(o.max_force_error, 0.2) << method;
  }
}

// TaskModel::velocityOnly(): the rows of such tasks are zero past the nv velocity columns at
// every tick (the controller copies and the solver multiplies only those), and the problem's
// levels made of such rows (and of the reserved rows) declare it, the others do not.
TEST(ControllerHumanoid, VelocityOnlyRowsHoldAndTheirLevelsDeclareThem) {
  const model::RobotModel m = test::loadHumanoid();
  for (const std::string method : {"bfgs", "ah", "gn", "wls"}) {
    Controller c(m, test::exp1Config(m, method, 1.0));
    RobotState s = test::halfSitting(m);
    c.reset(s);
    const int nv = m.nv(), nx = c.problem().variables();
    ASSERT_GT(nx, nv);
    int declared = 0, undeclared = 0;
    for (int l = 0; l < c.problem().levelCount(); ++l) {
      const solver::Level& lv = c.problem().level(l);
      if (lv.kind != solver::LevelKind::General) continue;
      EXPECT_TRUE(lv.columns == nv || lv.columns == -1) << method << " level " << lv.name;
      (lv.columns == nv ? declared : undeclared)++;
    }
    // LexDyn: trust, collisions, contacts, CoM, hands and minimum velocity. WLS's two levels both
    // read the contact forces (the hard level's dynamics, the objective's minimum wrench).
    EXPECT_GE(declared, method == "wls" ? 0 : 6) << method;
    EXPECT_GE(undeclared, 1) << method;  // the equation of motion reads the contact forces
    int checked = 0;
    for (int k = 0; k < 300; ++k) {
      if (k == 150) c.setTaskTarget(c.taskIndex("right_hand"), Eigen::Vector3d(0.4, -2.0, 2.0));  // out of reach
      const Command& cmd = c.tick(s);
      ASSERT_TRUE(cmd.ok()) << method;
      for (int i = 0; i < static_cast<int>(c.config().tasks.size()); ++i) {
        if (!c.config().tasks[static_cast<size_t>(i)]->velocityOnly()) continue;
        const Eigen::MatrixXd& A = c.taskData(i).A;
        ASSERT_TRUE((A.rightCols(nx - nv).array() == 0.0).all()) << method << " task " << c.config().tasks[static_cast<size_t>(i)]->name();
        ++checked;
      }
      for (int l = 0; l < c.problem().levelCount(); ++l) {
        const solver::Level& lv = c.problem().level(l);
        if (lv.columns == nv) {
          ASSERT_TRUE((lv.A.rightCols(nx - nv).array() == 0.0).all()) << method << " level " << lv.name;
        }
      }
      s.q = cmd.q;
      s.u = cmd.u;
      s.time += 0.005;
    }
    EXPECT_GE(checked, 300 * 5) << method;
  }
}

// TickContext::free_row_jacobians: a self-collision pair beyond its interaction distance gives a
// free row. LexDynBFGS reads the previous tick's Jacobians with the previous solve's multipliers
// (its secant), which are zero on the rows that solve left inactive; it and GN (the default)
// get a free row's J when the row was active in the previous solve (TaskData::held, which must
// be that solve's active set, outside which every multiplier is zero), zeros otherwise. For
// LexDynAH and WLS, which opt out, every free row's J and A are zeros. The hands are driven
// behind the waist, so that pairs engage and are held, then the state jumps back to the start:
// rows held at the last solve are free.
TEST(ControllerHumanoid, FreeCollisionRowsHaveJacobiansWhereTheMethodReadsThem) {
  const model::RobotModel m = test::loadHumanoid();
  for (const std::string method : {"bfgs", "ah", "gn", "wls"}) {
    Controller c(m, test::exp1Config(m, method, 10.0));
    RobotState s = test::halfSitting(m);
    c.reset(s);
    const int sc = c.taskIndex("collisions");
    const int rh = c.taskIndex("right_hand"), lh = c.taskIndex("left_hand");
    const auto& task = dynamic_cast<const tasks::SelfCollisionTask&>(c.task(sc));
    const bool reads = method == "bfgs" || method == "gn";
    int freeRows = 0, heldRows = 0, heldFreeRows = 0;
    for (int k = 0; k < 400; ++k) {
      if (k == 0) {
        c.setTaskTarget(rh, Eigen::Vector3d(-0.1, -0.1, 0.8));
        c.setTaskTarget(lh, Eigen::Vector3d(-0.1, 0.1, 0.8));
      } else if (k == 200) {
        c.setTaskTarget(rh, Eigen::Vector3d(0.4, -0.5, 1.3));
        c.setTaskTarget(lh, Eigen::Vector3d(0.4, 0.5, 1.3));
        // The state jumps back to the start (as a measured state may): the pairs held at the
        // last solve are now beyond their interaction distance, free while held.
        const double t = s.time;
        s = test::halfSitting(m);
        s.time = t;
      }
      const std::vector<char> held = c.taskData(sc).held;  // the previous solve's
      const Command& cmd = c.tick(s);
      ASSERT_TRUE(cmd.ok()) << method << " tick " << k;
      const tasks::TaskData& d = c.taskData(sc);
      for (int r = 0; r < task.rows(); ++r) {
        heldRows += held[static_cast<size_t>(r)];
        if (d.lower(r) != -solver::kInf) continue;
        ++freeRows;
        Eigen::RowVectorXd J(m.nv());
        m.capsuleDistance(c.modelData(), task.modelPair(r), J);
        const bool wanted = reads && held[static_cast<size_t>(r)];
        heldFreeRows += held[static_cast<size_t>(r)];
        if (!wanted) J.setZero();
        ASSERT_TRUE(d.J.row(r) == J) << method << " row " << r;
        ASSERT_TRUE(d.A.row(r).head(m.nv()) == J) << method << " row " << r;
        if (wanted) {
          ASSERT_GT(J.cwiseAbs().maxCoeff(), 0.0) << "row " << r;
        }
      }
      // TaskData::held is this solve's active set on the task's rows, and a row not held has
      // no multiplier in any level's column (what lets the secant leave its J out).
      const solver::Problem& pb = c.problem();
      const solver::Result& res = c.solverResult();
      int level = -1, off = 0;
      int row0 = 0;  // the task's first row in its level
      for (int l = 0, o = 0; l < pb.levelCount(); o += pb.level(l).rows(), ++l) {
        const solver::Level& L = pb.level(l);
        for (int f = 0; f + task.rows() <= L.rows(); ++f) {
          if (L.lower.segment(f, task.rows()) == d.lower && L.A.middleRows(f, task.rows()) == d.A) {
            level = l;
            off = o + f;
            row0 = f;
          }
        }
      }
      ASSERT_GE(level, 0) << method;
      for (int r = 0; r < task.rows(); ++r) {
        const bool active = res.active.level[static_cast<size_t>(level)][static_cast<size_t>(row0 + r)] != solver::RowState::Inactive;
        ASSERT_EQ(d.held[static_cast<size_t>(r)], active ? 1 : 0) << method << " row " << r;
        if (!active) {
          ASSERT_EQ(res.lambda.row(off + r).cwiseAbs().maxCoeff(), 0.0) << method << " row " << r;
        }
      }
      s.q = cmd.q;
      s.u = cmd.u;
      s.time += 0.005;
    }
    EXPECT_GE(freeRows, 400 * 4) << method;
    EXPECT_GT(heldRows, 0) << method;  // pairs engaged and held
    if (reads) {
      EXPECT_GT(heldFreeRows, 0) << method;  // and free at the next tick (the jump at tick 200)
    }
  }
}

TEST(ControllerHumanoid, TickAllocatesNothing) {
  const model::RobotModel m = test::loadHumanoid();
  for (const std::string method : {"bfgs", "ah", "gn", "wls"}) {
    Controller c(m, test::exp1Config(m, method, 1.0));
    RobotState s = test::halfSitting(m);
    c.reset(s);
    for (int k = 0; k < 200; ++k) {  // reach the augmented regime before measuring
      const Command& cmd = c.tick(s);
      ASSERT_TRUE(cmd.ok()) << method;
      s.q = cmd.q;
      s.u = cmd.u;
      s.time += 0.005;
    }
    c.setTaskTarget(c.taskIndex("right_hand"), Eigen::Vector3d(0.4, -2.0, 2.0));
    lexdyn::test::AllocationScope scope;
    for (int k = 0; k < 100; ++k) {
      const Command& cmd = c.tick(s);
      s.q = cmd.q;
      s.u = cmd.u;
      s.time += 0.005;
    }
    c.setContactActive(c.contactIndex("LEFT_FOOT"), true);
    EXPECT_EQ(scope.finish(), 0u) << method;
  }
}

}  // namespace
}  // namespace lexdyn::control
