// After setup, the Hessian code allocates nothing: workspace update, the three accumulate
// functions, Higham's regularisation with changing occupied sets, the eigensolver on changing
// sizes, BFGS / SR1 updates, occupancy changes and factors, and the sign-change guard. Every
// heap allocation of the process is counted (tests/common/alloc_counter.hpp).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <vector>

#include "../common/alloc_counter.hpp"
#include "hessian_test_utils.hpp"
#include "lexdyn/hessian/bfgs.hpp"
#include "lexdyn/hessian/higham.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace lexdyn::hessian {
namespace {

using testing::Rng;

TEST(HessianAllocation, CounterSeesAllocations) {
  lexdyn::test::AllocationScope scope;
  Eigen::MatrixXd A(20, 20);
  std::vector<int>* v = new std::vector<int>(10);
  const std::size_t n = scope.finish();
  delete v;
  EXPECT_GE(n, 3u);
}

void expectAccumulateAllocationFree(const model::RobotModel& m, const std::string& posture) {
  model::ModelData data = m.createData();
  Rng rng(301);
  const model::Configuration q = testing::randomConfiguration(m, rng, posture, posture.empty() ? 0.0 : 0.3);
  m.update(data, q, rng.uniformVector(m.nv()));
  KinematicHessianWorkspace ws(m);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m.nv(), m.nv());
  Eigen::MatrixXd big = Eigen::MatrixXd::Zero(m.nv() + 5, m.nv() + 5);
  const Eigen::Vector3d w(0.3, -0.2, 0.5), p(0.01, 0.02, -0.03);
  lexdyn::test::AllocationScope scope;
  ws.update(m, data);
  for (model::FrameId f = 0; f < m.numFrames(); ++f) {
    accumulatePointHessian(m, data, ws, f, p, w, H);
    accumulateOrientationHessian(m, data, ws, f, w, H);
  }
  accumulateComHessian(m, ws, w, H);
  // Into a block of a larger matrix (a Ref with an outer stride).
  accumulateComHessian(m, ws, w, big.topLeftCorner(m.nv(), m.nv()));
  accumulatePointHessian(m, data, ws, 0, p, w, big.bottomRightCorner(m.nv(), m.nv()));
  const std::size_t count = scope.finish();
  EXPECT_EQ(count, 0u);
  EXPECT_GT(H.cwiseAbs().maxCoeff(), 0.0);
}

TEST(HessianAllocation, AccumulateFunctionsAllocateNothing) { expectAccumulateAllocationFree(testing::loadHumanoid(), "half_sitting"); }
// With coupled mimic joints the tree's Hessian is accumulated in the workspace, then reduced.
TEST(HessianAllocation, CoupledMimicJointsAllocateNothingEither) { expectAccumulateAllocationFree(testing::loadCoupled(), ""); }

TEST(HessianAllocation, RegularizeFactorAndEigenAllocateNothing) {
  const int n = 38;
  Rng rng(302);
  HighamRegularizer hr(n);
  SymmetricEigenSolver es(n);
  std::vector<std::vector<char>> masks;
  for (int k = 0; k < 6; ++k) {
    std::vector<char> mask(n, 0);
    for (int i = 0; i < n; ++i) mask[static_cast<size_t>(i)] = rng.uniform(0, 1) < 0.2 + 0.15 * k ? 1 : 0;
    masks.push_back(mask);
  }
  masks.push_back(std::vector<char>(n, 1));
  const Eigen::MatrixXd H = rng.symmetric(n);
  Eigen::MatrixXd R(n, n), X(n, n);
  std::vector<int> list;
  list.reserve(n);
  int rows = 0;
  lexdyn::test::AllocationScope scope;
  for (const auto& mask : masks) {
    rows += hr.regularizeAndFactor(H, mask, 1e-6, R);
    rows += hr.regularizeAndFactor(H, mask, 0.0, R, list);
    rows += hr.regularizedRows(H, mask, 1e-6, R, list);
  }
  for (int k : {38, 10, 25, 1}) {
    hr.nearestPsd(H.topLeftCorner(k, k), X.topLeftCorner(k, k));
    es.compute(H.topLeftCorner(k, k));
  }
  const std::size_t count = scope.finish();
  EXPECT_EQ(count, 0u);
  EXPECT_GT(rows, 0);
}

TEST(HessianAllocation, QuasiNewtonAndGuardAllocateNothing) {
  const int n = 38;
  Rng rng(303);
  for (QuasiNewtonUpdate kind : {QuasiNewtonUpdate::Bfgs, QuasiNewtonUpdate::Sr1}) {
    QuasiNewtonOptions o;
    o.update = kind;
    auto B = makeQuasiNewton(n, o);
    SignChangeGuard guard(n);
    std::vector<char> m1(n, 0), m2(n, 0);
    for (int i = 0; i < n; ++i) {
      m1[static_cast<size_t>(i)] = i < 20 ? 1 : 0;
      m2[static_cast<size_t>(i)] = i >= 10 ? 1 : 0;
    }
    const Eigen::VectorXd diag = Eigen::VectorXd::Constant(n, 1e-3);
    std::vector<Eigen::VectorXd> s, y, acc;
    for (int k = 0; k < 10; ++k) {
      s.push_back(rng.uniformVector(n));
      y.push_back(2.0 * s.back() + 0.1 * rng.uniformVector(n));
      acc.push_back(rng.uniformVector(n));
    }
    Eigen::MatrixXd R(n, n);
    std::vector<int> list;
    list.reserve(n);
    int rows = 0;
    lexdyn::test::AllocationScope scope;
    B->initialize(diag, m1);
    for (int k = 0; k < 10; ++k) {
      B->update(s[static_cast<size_t>(k)], y[static_cast<size_t>(k)]);
      B->setOccupied(k % 2 ? m1 : m2, 1e-8);
      guard.observe(acc[static_cast<size_t>(k)]);
      for (int dof : guard.triggered()) B->addDiagonal(dof, 1e-8);
      rows += B->factor(R);
      if (kind == QuasiNewtonUpdate::Bfgs) rows += choleskyOfOccupied(B->matrix(), B->occupied(), R, list);
    }
    B->setOccupied(m2, diag);
    B->reset();
    const std::size_t count = scope.finish();
    EXPECT_EQ(count, 0u) << (kind == QuasiNewtonUpdate::Bfgs ? "BFGS" : "SR1");
    EXPECT_GT(rows, 0);
  }
}

}  // namespace
}  // namespace lexdyn::hessian
