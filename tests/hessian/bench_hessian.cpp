// Timings of the Hessian code on the humanoid (docs/performance.md, "Hessians"). Not a test:
// figures compare on one machine only. Each operation is timed call by call (steady_clock)
// after a warm-up, in 3 repeats (argument 1 sets another number); the table gives the minimum of
// the repeats' medians, and the median, the 99th percentile and the maximum of all calls.
//
// The "paper-like hierarchy" is the geometric part of the paper's sec. IX hierarchy (exp. 1/2):
//   level 4  self-collision: 3 pairs, a point Hessian on each side (1 row each)
//   level 5  contacts: both soles, position + orientation
//   level 7  CoM box
//   level 8  both grasp points (position) and the chest orientation
//   level 9  stricter CoM box
// Each augmented level l needs its own hierarchical Hessian H_l = sum over the tasks of levels
// <= l (eq. 21), so the five levels make 15 + 14 + 11 + 10 + 6 = 56 accumulate calls.
#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "../common/alloc_counter.hpp"
#include "hessian_test_utils.hpp"
#include "lexdyn/hessian/bfgs.hpp"
#include "lexdyn/hessian/higham.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace {

using namespace lexdyn;
using hessian::testing::Rng;
using Clock = std::chrono::steady_clock;

int g_repeats = 3;

void report(const std::string& name, int reps, const std::function<void()>& f) {
  for (int i = 0; i < std::max(10, reps / 10); ++i) f();  // warm-up
  std::vector<double> all, one(static_cast<size_t>(reps));
  double minMedian = 0.0;
  for (int rep = 0; rep < g_repeats; ++rep) {
    for (int i = 0; i < reps; ++i) {
      const auto t0 = Clock::now();
      f();
      const auto t1 = Clock::now();
      one[static_cast<size_t>(i)] = std::chrono::duration<double, std::micro>(t1 - t0).count();
    }
    all.insert(all.end(), one.begin(), one.end());
    std::sort(one.begin(), one.end());
    const double median = one[one.size() / 2];
    minMedian = (rep == 0) ? median : std::min(minMedian, median);
  }
  std::sort(all.begin(), all.end());
  const double median = all[all.size() / 2];
  const double p99 = all[static_cast<size_t>(0.99 * static_cast<double>(all.size() - 1))];
  std::printf("| %-58s | %10.2f | %9.2f | %9.2f | %9.2f |\n", name.c_str(), minMedian, median, p99, all.back());
}

void header() {
  std::printf("| %-58s | %10s | %9s | %9s | %9s |\n", "operation", "min med us", "median us", "p99 us", "max us");
  const std::string c(11, '-');
  std::printf("|%s|%s|%s|%s|%s|\n", std::string(60, '-').c_str(), std::string(12, '-').c_str(), c.c_str(), c.c_str(), c.c_str());
}

struct Term {
  enum Kind { Point, Orientation, Com } kind;
  model::FrameId frame;
  Eigen::Vector3d point;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0)) {
    std::printf(
        "usage: bench_hessian [REPEATS]\n\nTimings of the kinematic Hessians, Higham's regularisation, the eigensolvers and\n"
        "the BFGS update on the humanoid (docs/performance.md, \"Hessians\"). Each line's timed calls run\n"
        "REPEATS times (default 3, at most 100): the minimum of the repeats' medians, the pooled median,\n"
        "p99 and maximum of the single calls.\n");
    return 0;
  }
  if (argc > 1) {
    char* end = nullptr;
    const long v = std::strtol(argv[1], &end, 10);
    g_repeats = (end && *end == '\0' && v >= 1 && v <= 100) ? static_cast<int>(v) : 0;
    if (g_repeats < 1) {
      std::fprintf(stderr, "bench_hessian: expected a number of repeats in [1, 100], found '%s'\n", argv[1]);
      return 2;
    }
  }
  const model::RobotModel m = hessian::testing::loadHumanoid();
  const int nv = m.nv();
  model::ModelData data = m.createData();
  Rng rng(401);
  const model::Configuration q = hessian::testing::randomConfiguration(m, rng, "half_sitting", 0.2);
  m.update(data, q, rng.uniformVector(nv));
  hessian::KinematicHessianWorkspace ws(m);
  ws.update(m, data);

  auto frame = [&](const char* name) { return m.frameId(name); };
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  // Tasks by level (the witness points are representative points on the capsules).
  const std::vector<std::vector<Term>> levels = {
      {{Term::Point, frame("RARM_LINK3"), Eigen::Vector3d(0, 0, -0.05)},
       {Term::Point, frame("CHEST_LINK1"), Eigen::Vector3d(0, -0.1, 0.12)},
       {Term::Point, frame("LARM_LINK3"), Eigen::Vector3d(0, 0, -0.05)},
       {Term::Point, frame("CHEST_LINK1"), Eigen::Vector3d(0, 0.1, 0.12)},
       {Term::Point, frame("RARM_LINK4"), Eigen::Vector3d(0, 0, -0.2)},
       {Term::Point, frame("WAIST"), Eigen::Vector3d(0, -0.05, 0.06)}},
      {{Term::Point, frame("RSOLE"), o},
       {Term::Orientation, frame("RSOLE"), o},
       {Term::Point, frame("LSOLE"), o},
       {Term::Orientation, frame("LSOLE"), o}},
      {{Term::Com, -1, o}},
      {{Term::Point, frame("RGRASP"), o}, {Term::Point, frame("LGRASP"), o}, {Term::Orientation, frame("CHEST_LINK1"), o}},
      {{Term::Com, -1, o}},
  };
  std::vector<Eigen::Vector3d> weights;
  for (int k = 0; k < 64; ++k) weights.push_back(rng.uniformVector(3));
  std::vector<Eigen::MatrixXd> H(levels.size(), Eigen::MatrixXd::Zero(nv, nv));
  auto accumulate = [&](const Term& t, const Eigen::Vector3d& w, Eigen::MatrixXd& Hl) {
    switch (t.kind) {
      case Term::Point:
        hessian::accumulatePointHessian(m, data, ws, t.frame, t.point, w, Hl);
        break;
      case Term::Orientation:
        hessian::accumulateOrientationHessian(m, data, ws, t.frame, w, Hl);
        break;
      case Term::Com:
        hessian::accumulateComHessian(m, ws, w, Hl);
        break;
    }
  };
  int calls = 0;
  auto allHessians = [&]() {
    ws.update(m, data);
    calls = 0;
    for (size_t l = 0; l < levels.size(); ++l) {
      H[l].setZero();
      for (size_t i = 0; i <= l; ++i) {
        for (const Term& t : levels[i]) accumulate(t, weights[static_cast<size_t>(calls++ % 64)], H[l]);
      }
    }
  };
  allHessians();
  // Occupied dofs of each level: every dof (the CoM moves with all of them) from level 7 on;
  // the chains of the collision pairs and the legs before.
  std::vector<std::vector<char>> occupied(levels.size(), std::vector<char>(static_cast<size_t>(nv), 0));
  for (size_t l = 0; l < levels.size(); ++l) {
    for (size_t i = 0; i <= l; ++i) {
      for (const Term& t : levels[i]) {
        for (int k = 0; k < nv; ++k) {
          const bool moves = t.kind == Term::Com || m.tree().dofMovesBody(k, m.frameBody(t.frame));
          if (moves) occupied[l][static_cast<size_t>(k)] = 1;
        }
      }
    }
  }
  hessian::HighamRegularizer higham(nv);
  Eigen::MatrixXd R(nv, nv);
  const double dt = 0.005, eps = 1e-3 * dt * dt;

  std::printf("%d repeats of each line's timed calls; min med: the smallest of the repeats' medians\n", g_repeats);
  std::printf("Hessians on %s (nv = %d), %d accumulate calls for the 5 augmented levels\n\n", m.name().c_str(), nv, calls);
  header();
  report("workspace update (axes, subtree CoMs)", 20000, [&] { ws.update(m, data); });
  Eigen::MatrixXd Hc = Eigen::MatrixXd::Zero(nv, nv);
  report("CoM Hessian (accumulateComHessian)", 20000, [&] { hessian::accumulateComHessian(m, ws, weights[0], Hc); });
  report("CoM Hessian incl. workspace update and H = 0", 20000, [&] {
    ws.update(m, data);
    Hc.setZero();
    hessian::accumulateComHessian(m, ws, weights[0], Hc);
  });
  report("hand point Hessian (RGRASP)", 20000, [&] { hessian::accumulatePointHessian(m, data, ws, frame("RGRASP"), o, weights[1], Hc); });
  report("sole orientation Hessian (RSOLE)", 20000,
         [&] { hessian::accumulateOrientationHessian(m, data, ws, frame("RSOLE"), weights[2], Hc); });
  report("all Hessians, 5 levels (56 calls, incl. update and H = 0)", 5000, allHessians);
  report("Higham + eps + Cholesky, level 9, 38 occupied dofs", 2000, [&] { higham.regularizeAndFactor(H[4], occupied[4], eps, R); });
  report("Higham + eps + Cholesky, level 4, " + std::to_string(std::count(occupied[0].begin(), occupied[0].end(), 1)) + " occupied dofs",
         2000, [&] { higham.regularizeAndFactor(H[0], occupied[0], eps, R); });
  std::vector<int> occList;
  occList.reserve(static_cast<size_t>(nv));
  report("Higham + eps as eigen-rows (LexDynAH), level 9, 38 occupied dofs", 2000,
         [&] { higham.regularizedRows(H[4], occupied[4], eps, R, occList); });
  report("all 5 levels: Hessians + Higham + Cholesky", 1000, [&] {
    allHessians();
    for (size_t l = 0; l < levels.size(); ++l) higham.regularizeAndFactor(H[l], occupied[l], eps, R);
  });
  report("all 5 levels: Hessians + Higham + eps as eigen-rows", 1000, [&] {
    allHessians();
    for (size_t l = 0; l < levels.size(); ++l) higham.regularizedRows(H[l], occupied[l], eps, R, occList);
  });
  {
    hessian::SymmetricEigenSolver es(nv);
    report("lexdyn SymmetricEigenSolver, 38 x 38", 2000, [&] { es.compute(H[4]); });
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ees(nv);
    report("(reference) Eigen SelfAdjointEigenSolver, 38 x 38", 2000, [&] { ees.compute(H[4]); });
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(nv, nv, Eigen::ComputeFullU | Eigen::ComputeFullV);
    report("(reference) Eigen JacobiSVD (full U, V), 38 x 38", 200, [&] { svd.compute(H[4], Eigen::ComputeFullU | Eigen::ComputeFullV); });
    lexdyn::test::AllocationScope scope;
    ees.compute(H[4]);
    const std::size_t same = scope.finish();
    lexdyn::test::AllocationScope scope2;
    ees.compute(H[0].topLeftCorner(20, 20));
    const std::size_t other = scope2.finish();
    lexdyn::test::AllocationScope scope3;
    es.compute(H[4]);
    es.compute(H[0].topLeftCorner(20, 20));
    const std::size_t ours = scope3.finish();
    std::printf(
        "\nheap allocations per compute(): Eigen SelfAdjointEigenSolver %zu (same size), %zu (other size); "
        "lexdyn SymmetricEigenSolver %zu\n",
        same, other, ours);
  }
  {
    auto B = hessian::makeBfgs(nv);
    B->initialize(Eigen::VectorXd::Constant(nv, 1e-3 * dt * dt), std::vector<char>(static_cast<size_t>(nv), 1));
    std::vector<Eigen::VectorXd> s, y;
    for (int k = 0; k < 64; ++k) {
      s.push_back(dt * rng.uniformVector(nv));
      y.push_back(2.0 * s.back());
    }
    int k = 0;
    std::printf("\n");
    header();
    report("BFGS update, 38 occupied dofs", 20000, [&] {
      B->update(s[static_cast<size_t>(k % 64)], y[static_cast<size_t>(k % 64)]);
      ++k;
    });
    report("BFGS Cholesky factor, 38 occupied dofs", 20000, [&] { B->factor(R); });
  }
  return 0;
}
