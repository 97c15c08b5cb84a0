// Timings of the model's per-tick queries on the humanoid (docs/performance.md, "Model
// queries"). Not a test: figures compare on one machine only.
#include "model_test_utils.hpp"

#include <benchmark/benchmark.h>

namespace {

using namespace lexdyn::model;

struct Fixture {
  RobotModel model = testing::loadHumanoid();
  ModelData data = model.createData();
  Configuration q;
  Eigen::VectorXd u;
  Fixture() {
    testing::RandomStates rs(5);
    q = rs.configuration(model);
    u = rs.velocity(model);
    model.update(data, q, u);
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

void BM_Update(benchmark::State& st) {
  Fixture& f = fixture();
  for (auto _ : st) f.model.update(f.data, f.q, f.u);
}
// Benchmarks query(f, out), writing into `out`.
template <class Out, class Query>
void benchQuery(benchmark::State& st, Out out, Query query) {
  Fixture& f = fixture();
  for (auto _ : st) {
    query(f, out);
    benchmark::DoNotOptimize(out.data());
  }
}
void BM_MassMatrix(benchmark::State& st) {
  benchQuery(st, Eigen::MatrixXd(38, 38), [](Fixture& f, Eigen::MatrixXd& M) { f.model.massMatrix(f.data, M); });
}
void BM_MassMatrixSimbodyCalcM(benchmark::State& st) {
  benchQuery(st, Eigen::MatrixXd(38, 38), [](Fixture& f, Eigen::MatrixXd& M) { f.model.massMatrixReference(f.data, M); });
}
void BM_NonlinearEffects(benchmark::State& st) {
  benchQuery(st, Eigen::VectorXd(38), [](Fixture& f, Eigen::VectorXd& N) { f.model.nonlinearEffects(f.data, N); });
}
void BM_FrameJacobian(benchmark::State& st) {
  const FrameId id = fixture().model.frameId("LGRASP");
  benchQuery(st, Eigen::MatrixXd(6, 38), [id](Fixture& f, Eigen::MatrixXd& J) { f.model.frameJacobian(f.data, id, J); });
}
void BM_FrameJacobianSimbody(benchmark::State& st) {
  const FrameId id = fixture().model.frameId("LGRASP");
  benchQuery(st, Eigen::MatrixXd(6, 38), [id](Fixture& f, Eigen::MatrixXd& J) { f.model.frameJacobianReference(f.data, id, J); });
}
void BM_CenterOfMassJacobian(benchmark::State& st) {
  benchQuery(st, Eigen::MatrixXd(3, 38), [](Fixture& f, Eigen::MatrixXd& J) { f.model.centerOfMassJacobian(f.data, J); });
}
void BM_CapsuleDistances16(benchmark::State& st) {
  Fixture& f = fixture();
  Eigen::RowVectorXd J(38);
  for (auto _ : st) {
    for (int p = 0; p < f.model.numCollisionPairs(); ++p) benchmark::DoNotOptimize(f.model.capsuleDistance(f.data, p, J));
  }
}
// What a controller tick needs: state update, M, N, 4 frame Jacobians and biases (feet, hands),
// CoM Jacobian and bias, 16 capsule distances with Jacobians.
void BM_ControllerBundle(benchmark::State& st) {
  Fixture& f = fixture();
  Eigen::MatrixXd M(38, 38), J(6, 38), Jc(3, 38);
  Eigen::VectorXd N(38);
  Eigen::RowVectorXd Jd(38);
  const FrameId frames[] = {f.model.frameId("RSOLE"), f.model.frameId("LSOLE"), f.model.frameId("RGRASP"), f.model.frameId("LGRASP")};
  for (auto _ : st) {
    f.model.update(f.data, f.q, f.u);
    f.model.massMatrix(f.data, M);
    f.model.nonlinearEffects(f.data, N);
    for (FrameId id : frames) {
      f.model.frameJacobian(f.data, id, J);
      benchmark::DoNotOptimize(f.model.frameBias(f.data, id));
    }
    f.model.centerOfMassJacobian(f.data, Jc);
    benchmark::DoNotOptimize(f.model.centerOfMassBias(f.data));
    for (int p = 0; p < f.model.numCollisionPairs(); ++p) benchmark::DoNotOptimize(f.model.capsuleDistance(f.data, p, Jd));
    benchmark::DoNotOptimize(M.data());
  }
}

BENCHMARK(BM_Update);
BENCHMARK(BM_MassMatrix);
BENCHMARK(BM_MassMatrixSimbodyCalcM);
BENCHMARK(BM_NonlinearEffects);
BENCHMARK(BM_FrameJacobian);
BENCHMARK(BM_FrameJacobianSimbody);
BENCHMARK(BM_CenterOfMassJacobian);
BENCHMARK(BM_CapsuleDistances16);
BENCHMARK(BM_ControllerBundle);

}  // namespace

BENCHMARK_MAIN();
