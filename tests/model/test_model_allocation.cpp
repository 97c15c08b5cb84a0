// A controller tick's worth of model queries allocates nothing.
//
// Two guards: Eigen's own (EIGEN_RUNTIME_NO_MALLOC is a public definition of lexdyn; Eigen
// checks it with eigen_assert, so it is active in translation units built without NDEBUG such
// as the model's Simbody sources), and a count of every malloc, calloc, realloc, memalign and
// operator new call in the process (glibc's allocator is interposed below), which also sees
// allocations inside Simbody and the C++ runtime. The count is what the test asserts.
#include "model_test_utils.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
}

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
inline void countOne() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* malloc(size_t n) {
  countOne();
  return __libc_malloc(n);
}
void* calloc(size_t a, size_t b) {
  countOne();
  return __libc_calloc(a, b);
}
void* realloc(void* p, size_t n) {
  countOne();
  return __libc_realloc(p, n);
}
void* memalign(size_t a, size_t n) {
  countOne();
  return __libc_memalign(a, n);
}
void* aligned_alloc(size_t a, size_t n) {
  countOne();
  return __libc_memalign(a, n);
}
int posix_memalign(void** p, size_t a, size_t n) {
  countOne();
  *p = __libc_memalign(a, n);
  return *p ? 0 : 12;  // ENOMEM
}
}

void* operator new(std::size_t n) {
  countOne();
  if (void* p = __libc_malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  countOne();
  if (void* p = __libc_malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace lexdyn::model {
namespace {

struct Guard {
  Guard() {
    g_allocations = 0;
    Eigen::internal::set_is_malloc_allowed(false);
    g_counting = true;
  }
  ~Guard() {
    g_counting = false;
    Eigen::internal::set_is_malloc_allowed(true);
  }
};

TEST(ModelAllocation, CounterSeesAllocations) {
  // The counter works: a vector allocation inside the guard is seen.
  long seen = 0;
  {
    g_allocations = 0;
    g_counting = true;
    std::vector<double>* v = new std::vector<double>(100);
    g_counting = false;
    seen = g_allocations;
    delete v;
  }
  EXPECT_GE(seen, 2);
}

// Three ticks of the controller's model queries on `model`, counting allocations.
void expectTickQueriesAllocationFree(RobotModel& model, const std::vector<std::string>& frame_names) {
  ModelData data = model.createData();
  testing::RandomStates rs(21);
  const int n = model.nv(), nt = model.numTreeDofs();
  // Everything sized once at setup.
  Configuration q = rs.configuration(model), q_next = q;
  Eigen::VectorXd u = rs.velocity(model), N(n), du(n);
  Eigen::MatrixXd M(n, n), J6(6, n), J3(3, n), Jc(3, n);
  Eigen::RowVectorXd Jd = Eigen::RowVectorXd::Zero(n);  // (no collision pairs: stays zero)
  Eigen::Matrix3Xd axes(3, nt), points(3, nt);
  std::vector<FrameId> frames;
  for (const auto& f : frame_names) frames.push_back(model.frameId(f));
  double sink = 0.0;
  for (int tick = 0; tick < 3; ++tick) {
    Guard guard;
    model.update(data, q, u);
    model.massMatrix(data, M);
    model.nonlinearEffects(data, N);
    for (FrameId f : frames) {
      model.frameJacobian(data, f, J6);
      sink += model.frameBias(data, f).sum();
      sink += model.framePlacement(data, f).translation().sum();
      model.pointJacobian(data, f, Eigen::Vector3d(0.1, 0.0, 0.0), J3);
      sink += model.pointBias(data, f, Eigen::Vector3d(0.1, 0.0, 0.0)).sum();
    }
    model.centerOfMassJacobian(data, Jc);
    sink += model.centerOfMass(data).sum() + model.centerOfMassBias(data).sum();
    for (int p = 0; p < model.numCollisionPairs(); ++p) sink += model.capsuleDistance(data, p, Jd).distance;
    model.dofAxes(data, axes, points);
    model.integrate(q, u, 0.005, q_next);
    model.difference(q, q_next, du);
    q = q_next;
    EXPECT_EQ(g_allocations.load(), 0) << "tick " << tick;
  }
  EXPECT_TRUE(std::isfinite(sink + M.sum() + N.sum() + J6.sum() + Jc.sum() + Jd.sum() + du.sum()));
}

TEST(ModelAllocation, ControllerTickQueriesAreAllocationFree) {
  RobotModel model = testing::loadHumanoid();
  expectTickQueriesAllocationFree(model, {"RSOLE", "LSOLE", "RGRASP", "LGRASP", "CHEST_LINK1", "HEAD_LINK1"});
}

// With coupled mimic joints the queries reduce the tree's (G^T M G, J G) in workspaces.
TEST(ModelAllocation, CoupledMimicJointsAllocateNothingEither) {
  RobotModel model = testing::loadModel("tests/data/model", "coupled");
  ASSERT_TRUE(model.hasCoupledJoints());
  expectTickQueriesAllocationFree(model, {"fingertip", "nail_end", "tail_end", "torso"});
}

// Simbody's own operators allocate temporaries on every call (the reason the per-tick queries
// are computed from cached kinematics instead). The counter must see them: this also proves
// that allocations inside the Simbody shared libraries are counted.
TEST(ModelAllocation, SimbodyReferenceOperatorsAllocateAndAreSeen) {
  RobotModel model = testing::loadHumanoid();
  ModelData data = model.createData();
  testing::RandomStates rs(22);
  const int n = model.nv();
  model.update(data, rs.configuration(model), rs.velocity(model));
  Eigen::MatrixXd M(n, n), J6(6, n);
  Eigen::VectorXd udot = Eigen::VectorXd::Zero(n), tau(n);
  long calcM = 0, residual = 0, jacobian = 0;
  {
    g_allocations = 0;
    g_counting = true;
    model.massMatrixReference(data, M);
    calcM = g_allocations.exchange(0);
    model.inverseDynamicsReference(data, udot, tau);
    residual = g_allocations.exchange(0);
    model.frameJacobianReference(data, model.frameId("RSOLE"), J6);
    jacobian = g_allocations.exchange(0);
    g_counting = false;
  }
  std::printf("allocations per call: calcM %ld, calcResidualForceIgnoringConstraints %ld, calcFrameJacobian %ld\n", calcM, residual,
              jacobian);
  EXPECT_GT(calcM, 0);
  EXPECT_GT(residual, 0);
  EXPECT_GT(jacobian, 0);
}

}  // namespace
}  // namespace lexdyn::model
