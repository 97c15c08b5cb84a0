// compute() and accumulateHessian() of every task type allocate nothing (after createData), in
// both domains where supported, including the first compute of a holding task, a contact being
// broken and made again, targets set by setTarget, and reset().
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "../common/alloc_counter.hpp"
#include "lexdyn/tasks/com.hpp"
#include "lexdyn/tasks/com_box.hpp"
#include "lexdyn/tasks/contact.hpp"
#include "lexdyn/tasks/contact_force_bounds.hpp"
#include "lexdyn/tasks/equation_of_motion.hpp"
#include "lexdyn/tasks/joint_limits.hpp"
#include "lexdyn/tasks/joint_position.hpp"
#include "lexdyn/tasks/orientation.hpp"
#include "lexdyn/tasks/position.hpp"
#include "lexdyn/tasks/posture.hpp"
#include "lexdyn/tasks/self_collision.hpp"
#include "lexdyn/tasks/torque_limits.hpp"
#include "lexdyn/tasks/trust_region.hpp"
#include "lexdyn/tasks/velocity_min.hpp"
#include "lexdyn/tasks/wrench_min.hpp"
#include "task_test_utils.hpp"

namespace lexdyn::tasks {
namespace {

using namespace testing;

TEST(TaskAllocation, CounterSeesAllocations) {
  TickFixture fx("planar_3r");
  lexdyn::test::AllocationScope scope;
  PostureTask task("posture", fx.model);
  auto d = task.createData(fx.layout);
  EXPECT_GE(scope.finish(), 3u);
}

// One task of each type on the humanoid (contact three times): 17 tasks.
std::vector<std::unique_ptr<TaskModel>> everyTaskType(TickFixture& fx) {
  std::vector<std::unique_ptr<TaskModel>> tasks;
  tasks.push_back(std::make_unique<ContactForceBoundsTask>("gamma", fx.layout));
  tasks.push_back(std::make_unique<JointLimitsTask>("limits", fx.model));
  tasks.push_back(std::make_unique<EquationOfMotionTask>("eom", fx.model));
  tasks.push_back(std::make_unique<TorqueLimitsTask>("torque", fx.model));
  tasks.push_back(std::make_unique<TrustRegionTask>("trust", fx.model));
  tasks.push_back(std::make_unique<SelfCollisionTask>("collisions", fx.model));
  ContactTaskParams rf, lf, lh;
  rf.contact = "RIGHT_FOOT";
  lf.contact = "LEFT_FOOT";
  lh.contact = "LEFT_HAND";
  tasks.push_back(std::make_unique<ContactTask>("rf", fx.model, fx.layout, rf));
  tasks.push_back(std::make_unique<ContactTask>("lf", fx.model, fx.layout, lf));
  tasks.push_back(std::make_unique<ContactTask>("lh", fx.model, fx.layout, lh));
  PositionParams pp;
  pp.frame = "RGRASP";
  tasks.push_back(std::make_unique<PositionTask>("rh", fx.model, pp));
  OrientationParams op;
  op.frame = "CHEST_LINK1";
  tasks.push_back(std::make_unique<OrientationTask>("chest", fx.model, op));
  tasks.push_back(std::make_unique<ComTask>("com", fx.model));
  ComBoxParams bp;
  bp.lower = Eigen::Vector3d(-0.03, -0.1, -std::numeric_limits<double>::infinity());
  bp.upper = Eigen::Vector3d(0.03, 0.1, std::numeric_limits<double>::infinity());
  tasks.push_back(std::make_unique<ComBoxTask>("box", fx.model, bp));
  JointPositionParams jp;
  jp.joints = {"HEAD_JOINT0"};
  tasks.push_back(std::make_unique<JointPositionTask>("head", fx.model, jp));
  PostureParams sp;
  sp.posture = "half_sitting";
  tasks.push_back(std::make_unique<PostureTask>("posture", fx.model, sp));
  tasks.push_back(std::make_unique<VelocityMinTask>("qdot0", fx.model));
  tasks.push_back(std::make_unique<WrenchMinTask>("gamma0", fx.layout));
  return tasks;
}

TEST(TaskAllocation, ComputeAndHessiansAllocateNothing) {
  TickFixture fx("hrp2kai_like");
  RandomStates rs(501);
  const std::vector<std::unique_ptr<TaskModel>> tasks = everyTaskType(fx);
  ASSERT_EQ(tasks.size(), 17u);  // 15 types, contact three times

  std::vector<std::unique_ptr<TaskData>> data;
  for (const auto& t : tasks) data.push_back(t->createData(fx.layout));
  const int nv = fx.model.nv();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(nv, nv);
  std::vector<Eigen::VectorXd> weights;
  for (const auto& t : tasks) weights.push_back(Eigen::VectorXd::Constant(t->rows(), 0.5));
  const Eigen::Vector3d new_target(0.4, -0.5, 1.3);
  Eigen::VectorXd box(6);
  box << -0.2, 0.0, -1.0, 0.2, 0.1, 3.0;

  fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
  std::size_t count = 0;
  for (int tick = 0; tick < 4; ++tick) {
    fx.active = {1, 1, static_cast<char>(tick % 2)};  // the hand contact is made and broken
    for (Domain dom : {Domain::Velocity, Domain::Acceleration}) {
      fx.ctx.domain = dom;
      lexdyn::test::AllocationScope scope;
      for (size_t k = 0; k < tasks.size(); ++k) {
        if (!tasks[k]->supports(dom)) continue;
        tasks[k]->compute(fx.ctx, *data[k]);
        if (tasks[k]->geometric()) tasks[k]->accumulateHessian(fx.ctx, *data[k], weights[k], H);
      }
      tasks[9]->setTarget(*data[9], new_target);
      tasks[12]->setTarget(*data[12], box);
      if (tick == 2) {
        for (size_t k = 0; k < tasks.size(); ++k) tasks[k]->reset(*data[k]);  // hold / capture again
      }
      count += scope.finish();
    }
  }
  EXPECT_EQ(count, 0u);
  EXPECT_TRUE(H.allFinite());
  EXPECT_GT(H.cwiseAbs().maxCoeff(), 0.0);
}

// TaskModel::constantMatrix(): the controller copies such a task's A into the problem once, so
// compute() and reset() must never change it. Exactly the tasks whose rows are variables
// themselves (trust region, minimum velocity, minimum wrench, contact force bounds) claim it.
TEST(TaskAllocation, ConstantMatricesStayAsCreated) {
  TickFixture fx("hrp2kai_like");
  RandomStates rs(502);
  const std::vector<std::unique_ptr<TaskModel>> tasks = everyTaskType(fx);
  std::vector<std::unique_ptr<TaskData>> data;
  std::vector<Eigen::MatrixXd> created;
  std::vector<std::string> constant;
  for (const auto& t : tasks) {
    data.push_back(t->createData(fx.layout));
    created.push_back(data.back()->A);
    if (t->constantMatrix()) constant.push_back(t->name());
  }
  EXPECT_EQ(constant, (std::vector<std::string>{"gamma", "trust", "qdot0", "gamma0"}));
  for (int tick = 0; tick < 6; ++tick) {
    fx.set(rs.configuration(fx.model), rs.velocity(fx.model, 1.0));
    fx.active = {1, static_cast<char>(tick % 2), 1};
    for (Domain dom : {Domain::Velocity, Domain::Acceleration}) {
      fx.ctx.domain = dom;
      for (size_t k = 0; k < tasks.size(); ++k)
        if (tasks[k]->supports(dom)) tasks[k]->compute(fx.ctx, *data[k]);
    }
    if (tick == 3)
      for (size_t k = 0; k < tasks.size(); ++k) tasks[k]->reset(*data[k]);
  }
  for (size_t k = 0; k < tasks.size(); ++k) {
    if (!tasks[k]->constantMatrix()) continue;
    const Eigen::MatrixXd& A = data[k]->A;
    ASSERT_EQ(A.size(), created[k].size()) << tasks[k]->name();
    EXPECT_EQ(std::memcmp(A.data(), created[k].data(), sizeof(double) * static_cast<size_t>(A.size())), 0) << tasks[k]->name();
    EXPECT_GT(A.cwiseAbs().sum(), 0.0) << tasks[k]->name();
  }
}

}  // namespace
}  // namespace lexdyn::tasks
