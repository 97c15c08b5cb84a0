// Setup allocates; solving a problem of unchanged size allocates nothing.
#include <gtest/gtest.h>

#include <vector>

#include "../common/alloc_counter.hpp"
#include "lexdyn/solver/solver.hpp"
#include "reference.hpp"

namespace lexdyn::solver {
namespace {

TEST(SolverAllocation, CounterSeesAllocations) {
  // The counter itself must be able to fail.
  lexdyn::test::AllocationScope scope;
  std::vector<double>* v = new std::vector<double>(100);
  Eigen::VectorXd e(50);
  const std::size_t n = scope.finish();
  delete v;
  EXPECT_GE(n, 3u);
}

TEST(SolverAllocation, SolvesOfUnchangedSizeAllocateNothing) {
  test::GenOptions g;
  g.n = 20;
  g.levels = 8;
  g.maxRows = 12;
  g.pRankDeficient = 0.4;
  g.pConflict = 0.3;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Problem p = test::randomProblem(seed, g);
    test::appendMinNorm(p);  // a large last level: projected by default
    Options o;
    if (seed % 2 == 0) o.last_level_projection = Options::LastLevel::Never;
    Solver s;
    s.setup(p, o);
    s.solve(p);  // warm-up (nothing is lazily allocated, but make the point explicit)
    Problem q = test::randomProblem(seed + 1000, g);
    lexdyn::test::AllocationScope scope;
    const Result& r1 = s.solve(p);
    const Result& r2 = s.solve(p, s.result().active, s.result().x);
    // New data of the same sizes, written in place.
    for (int l = 0; l < p.levelCount(); ++l) {
      Level& lv = p.level(l);
      if (lv.kind == LevelKind::General) lv.A *= 1.25;
      lv.lower *= 0.5;
      lv.upper *= 0.5;
    }
    const Result& r3 = s.solve(p, s.result().active, s.result().x);
    const std::size_t count = scope.finish();
    EXPECT_EQ(count, 0u) << "seed " << seed;
    EXPECT_EQ(r1.status, Status::Solved);
    EXPECT_EQ(r2.status, Status::Solved);
    EXPECT_EQ(r3.status, Status::Solved);
  }
}

}  // namespace
}  // namespace lexdyn::solver
