// Unit tests of the hierarchical least-squares solver against independent references.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <cstdint>
#include <cstring>
#include <string>

#include "lexdyn/common/error.hpp"
#include "lexdyn/solver/detail/hls_factorization.hpp"
#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/problem_io.hpp"
#include "lexdyn/solver/solver.hpp"
#include "reference.hpp"
#include "../common/expect_text.hpp"

namespace lexdyn::solver {
namespace {

using test::appendMinNorm;
using test::bruteForce;
using test::checkKkt;
using test::GenOptions;
using test::nullSpaceReference;
using test::randomProblem;

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd r(static_cast<Eigen::Index>(v.size()));
  int i = 0;
  for (double d : v) r(i++) = d;
  return r;
}

Eigen::MatrixXd mat(int rows, int cols, std::initializer_list<double> v) {
  Eigen::MatrixXd r(rows, cols);
  int i = 0;
  for (double d : v) {
    r(i / cols, i % cols) = d;
    ++i;
  }
  return r;
}

const Result& solveOnce(Solver& s, const Problem& p, const Options& o = Options{}) {
  s.setup(p, o);
  return s.solve(p);
}

bool sameBits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

// Every field a solve computes, bit for bit.
void expectSameResult(const Result& a, const Result& b, const std::string& what) {
  EXPECT_EQ(a.status, b.status) << what;
  EXPECT_TRUE(sameBits(a.x, b.x)) << what;
  EXPECT_TRUE(sameBits(a.violation_norm, b.violation_norm)) << what;
  ASSERT_EQ(a.violation.size(), b.violation.size()) << what;
  for (size_t l = 0; l < a.violation.size(); ++l) EXPECT_TRUE(sameBits(a.violation[l], b.violation[l])) << what << " level " << l;
  EXPECT_TRUE(sameBits(a.lambda, b.lambda)) << what;
  EXPECT_EQ(a.active.level, b.active.level) << what;
  EXPECT_EQ(a.rank, b.rank) << what;
  EXPECT_EQ(a.iterations, b.iterations) << what;
  EXPECT_EQ(a.factorizations, b.factorizations) << what;
}

// swapResult() hands the result over without a copy: it is the one the solve computed, and the
// next solve into the buffers given back (empty ones, an earlier result's, same-shape ones of
// any values) computes the same bits as a solver whose result was never taken, cold and warm,
// also after a solve that refuses its input.
TEST(Solver, ASwappedResultIsTheSolvesAndTheNextSolveFillsTheBuffersGivenBack) {
  test::GenOptions g;
  g.n = 15;
  g.levels = 6;
  g.maxRows = 8;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const Problem prob = test::randomProblem(seed, g);
    const Problem other = test::randomProblem(seed + 100, g);
    Solver a, b;
    a.setup(prob);
    b.setup(prob);
    const Result expected = a.solve(prob);
    ASSERT_GT(expected.lambda.size(), 0);
    Result taken;  // empty: the solver reshapes it at its next solve
    a.swapResult(taken);
    expectSameResult(taken, expected, "taken, seed " + std::to_string(seed));
    EXPECT_EQ(a.result().lambda.size(), 0);

    // Warm, into the empty buffers.
    const Result& again = a.solve(prob, expected.active, expected.x);
    const Result& reference = b.solve(prob, expected.active, expected.x);
    expectSameResult(again, reference, "warm into empty buffers, seed " + std::to_string(seed));

    // Cold, into an earlier result's buffers (another problem's, of other sizes).
    Result earlier;
    {
      Solver c;
      c.setup(other);
      c.solve(other);
      c.swapResult(earlier);
    }
    a.swapResult(earlier);
    expectSameResult(a.solve(prob), b.solve(prob), "cold into recycled buffers, seed " + std::to_string(seed));
    // Into buffers of the same shape, holding an earlier result of this problem (reused as they
    // are, not reshaped).
    Result same = expected;
    a.swapResult(same);
    expectSameResult(a.solve(prob, expected.active, expected.x), b.solve(prob, expected.active, expected.x),
                     "warm into same-shape buffers, seed " + std::to_string(seed));
    // Column l of the multipliers is zero past the rows of level l (the solver zeroes only
    // those rows when it filled the buffers itself); same-shape buffers holding anything else
    // are zeroed whole.
    for (int l = 0, end = 0; l < prob.levelCount(); ++l) {
      end += prob.level(l).rows();
      EXPECT_TRUE(expected.lambda.col(l).tail(expected.lambda.rows() - end).isZero(0.0)) << "level " << l;
    }
    Result junk = expected;
    junk.lambda.setConstant(7.0);
    a.swapResult(junk);
    expectSameResult(a.solve(prob), b.solve(prob), "cold into same-shape buffers of other values, seed " + std::to_string(seed));
    expectSameResult(a.solve(prob, expected.active, expected.x), b.solve(prob, expected.active, expected.x),
                     "warm after them, seed " + std::to_string(seed));

    // A refused input leaves no figure of an earlier solve, whatever buffers it computes into.
    Problem bad = prob;
    bad.level(bad.levelCount() - 1).upper(0) = std::numeric_limits<double>::quiet_NaN();
    Result stale = expected;
    a.swapResult(stale);
    const Result& refused = a.solve(bad);
    EXPECT_EQ(refused.status, Status::NonFiniteInput);
    EXPECT_EQ(refused.bad_level, bad.levelCount() - 1);
    EXPECT_EQ(refused.bad_row, 0);
    EXPECT_TRUE(refused.x.isZero(0.0));
    EXPECT_TRUE(refused.lambda.isZero(0.0));
    EXPECT_TRUE(refused.violation_norm.isZero(0.0));
    EXPECT_EQ(refused.active.activeCount(), 0);
    EXPECT_EQ(refused.iterations, 0);
    EXPECT_EQ(refused.factorizations, 0);
    EXPECT_EQ(refused.optimal_through, -1);
    EXPECT_EQ(a.solve(prob).status, Status::Solved);
    expectSameResult(a.result(), b.solve(prob), "after a refused input, seed " + std::to_string(seed));
  }
}

// Right after a release, the released constraint does not block a step that moves it by rounding
// only (docs/solver.md, "Anti-cycling"); every other constraint still does, however large the
// slacks elsewhere. Here level 1 (x2 = 1e8 against the bound x2 <= 1) leaves a slack of 1e8;
// warm-started from an active set that holds x0 >= 0 and x0 = 1e-6, the solver releases a row and
// the step towards x0 = 1e-6 must stop at the hard bound x0 <= 5e-7.
TEST(Solver, AfterAReleaseEveryOtherConstraintStillBlocksBesideALargeSlack) {
  for (const double big : {1e3, 1e6, 1e8}) {
    const double d = 1e-6;
    Problem p(3);
    p.addBoundsLevel("bounds", {0, 2}, Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(-kInf, -kInf), Eigen::Vector2d(d / 2, 1.0));
    p.addLevel("x2 = big", (Eigen::MatrixXd(1, 3) << 0, 0, 1).finished(), Eigen::VectorXd::Constant(1, big),
               Eigen::VectorXd::Constant(1, big));
    p.addLevel("x0 >= 0", (Eigen::MatrixXd(1, 3) << 1, 0, 0).finished(), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, kInf));
    p.addLevel("x0 = d", (Eigen::MatrixXd(1, 3) << 1, 0, 0).finished(), Eigen::VectorXd::Constant(1, d), Eigen::VectorXd::Constant(1, d));
    p.addLevel("x1 = 0", (Eigen::MatrixXd(1, 3) << 0, 1, 0).finished(), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1));
    ActiveSet warm;
    warm.level = {
        {RowState::Inactive, RowState::Upper}, {RowState::Equality}, {RowState::Lower}, {RowState::Equality}, {RowState::Equality}};
    for (const bool cold : {false, true}) {
      Solver s;
      s.setup(p);
      const Result& r = cold ? s.solve(p) : s.solve(p, warm, Eigen::Vector3d(0.0, 0.0, 1.0));
      ASSERT_EQ(r.status, Status::Solved) << big << (cold ? " cold" : " warm");
      EXPECT_EQ(r.violation_norm(0), 0.0) << big << (cold ? " cold" : " warm");
      EXPECT_DOUBLE_EQ(r.x(0), d / 2) << big << (cold ? " cold" : " warm");
      EXPECT_NEAR(r.violation_norm(1), big - 1.0, 1e-9 * big) << big;
      EXPECT_NEAR(r.violation_norm(3), d / 2, 1e-15) << big;
      EXPECT_EQ(test::checkKkt(p, r), "") << big << (cold ? " cold" : " warm");
    }
  }
}

TEST(Solver, SingleEqualityLevelIsLeastSquares) {
  Problem p(2);
  p.addLevel("ls", mat(3, 2, {1, 0, 0, 1, 1, 1}), vec({1, 1, 3}), vec({1, 1, 3}));
  Solver s;
  const Result& r = solveOnce(s, p);
  ASSERT_EQ(r.status, Status::Solved);
  // Normal equations: [2 1; 1 2] x = [4; 4] -> x = [4/3, 4/3].
  EXPECT_NEAR(r.x(0), 4.0 / 3.0, 1e-12);
  EXPECT_NEAR(r.x(1), 4.0 / 3.0, 1e-12);
  EXPECT_NEAR(r.violation_norm(0), std::sqrt(3.0) / 3.0, 1e-12);
  EXPECT_EQ(checkKkt(p, r), "");
}

// Result::factorizations counts the level stages factorised: deterministic, and a warm start
// that keeps the active set factorises once.
TEST(Solver, FactorizationsCountTheStagesFactorised) {
  GenOptions g;
  g.n = 8;
  g.levels = 4;
  g.maxRows = 4;
  g.inequalities = false;  // equalities only: one iteration, every level once
  g.boundsLevel = false;
  const Problem p = randomProblem(7, g);
  Solver s;
  s.setup(p);
  const Result& r = s.solve(p);
  ASSERT_EQ(r.status, Status::Solved);
  EXPECT_EQ(r.iterations, 1);
  // Each level once (the first may be eliminated, which counts as one stage), plus the
  // multipliers' solve when the working set changed: at least the levels, at most twice.
  EXPECT_GE(r.factorizations, p.levelCount());
  EXPECT_LE(r.factorizations, 2 * p.levelCount());
  const int cold = r.factorizations;
  Solver s2;
  s2.setup(p);
  EXPECT_EQ(s2.solve(p).factorizations, cold);  // deterministic
  g.inequalities = true;
  g.boundsLevel = true;
  const Problem q = randomProblem(11, g);
  Solver sq;
  sq.setup(q);
  const Result& rq = sq.solve(q);
  EXPECT_GE(rq.factorizations, rq.iterations);
}

TEST(Solver, LowerLevelCannotDegradeHigherLevel) {
  // Level 0: x0 + x1 = 1. Level 1: x0 = 5, x1 = 5 (conflicting with level 0 in sum).
  Problem p(2);
  p.addLevel("sum", mat(1, 2, {1, 1}), vec({1}), vec({1}));
  p.addLevel("targets", mat(2, 2, {1, 0, 0, 1}), vec({5, 5}), vec({5, 5}));
  Solver s;
  const Result& r = solveOnce(s, p);
  EXPECT_NEAR(r.violation_norm(0), 0.0, 1e-12);
  EXPECT_NEAR(r.x(0), 0.5, 1e-12);
  EXPECT_NEAR(r.x(1), 0.5, 1e-12);
  EXPECT_EQ(checkKkt(p, r), "");
}

TEST(Solver, InfeasibleInequalityLevelIsRelaxedNotAnError) {
  // x >= 2 and x <= 1 on the same level: the least violation is at x = 1.5.
  Problem p(1);
  p.addLevel("conflict", mat(2, 1, {1, 1}), vec({2, -kInf}), vec({kInf, 1}));
  p.addLevel("x=0", mat(1, 1, {1}), vec({0}), vec({0}));
  Solver s;
  const Result& r = solveOnce(s, p);
  ASSERT_EQ(r.status, Status::Solved);
  EXPECT_NEAR(r.x(0), 1.5, 1e-12);
  EXPECT_NEAR(r.violation_norm(0), std::sqrt(0.5), 1e-12);
  EXPECT_EQ(checkKkt(p, r), "");
}

TEST(Solver, BoundsLevelIsTrustRegion) {
  // A near-singular task under a box: x stays inside the box.
  Problem p(2);
  p.addBoundsLevel("box", {0, 1}, vec({1, 1}), vec({-1, -1}), vec({1, 1}));
  p.addLevel("near-singular", mat(2, 2, {1, 1, 1, 1 + 1e-8}), vec({1, 2}), vec({1, 2}));
  Solver s;
  const Result& r = solveOnce(s, p);
  ASSERT_EQ(r.status, Status::Solved);
  EXPECT_LE(r.x.lpNorm<Eigen::Infinity>(), 1.0 + 1e-12);
  EXPECT_EQ(checkKkt(p, r), "");
  EXPECT_NEAR(r.violation_norm(1), bruteForce(p)[1], 1e-7);
}

TEST(Solver, ZeroAndDuplicatedRows) {
  Problem p(3);
  p.addLevel("dups", mat(4, 3, {1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0}), vec({1, 3, 1, 2}), vec({1, 3, 1, 2}));
  appendMinNorm(p);
  Solver s;
  const Result& r = solveOnce(s, p);
  ASSERT_EQ(r.status, Status::Solved);
  EXPECT_NEAR(r.x(0), 2.0, 1e-12);  // average of the duplicated targets
  EXPECT_NEAR(r.x(1), 2.0, 1e-12);
  EXPECT_NEAR(r.x(2), 0.0, 1e-12);
  EXPECT_NEAR(r.violation_norm(0), std::sqrt(1 + 1 + 1), 1e-12);  // dups +-1, zero row 1
  EXPECT_EQ(r.rank[0], 2);
  EXPECT_EQ(checkKkt(p, r), "");
}

TEST(Solver, EqualityHierarchiesMatchNullSpaceRecursion) {
  GenOptions g;
  g.inequalities = false;
  g.boundsLevel = false;
  Options noElim;
  noElim.eliminate_first_level = false;
  int eliminated = 0;
  for (std::uint64_t seed = 1; seed <= 300; ++seed) {
    g.n = 3 + static_cast<int>(seed % 8);
    g.levels = 1 + static_cast<int>(seed % 5);
    g.maxRows = 1 + static_cast<int>(seed % 6);
    Problem p = randomProblem(seed, g);
    const bool unique = (seed % 2 == 0);
    if (unique) appendMinNorm(p);
    const auto ref = nullSpaceReference(p);
    ASSERT_EQ(ref.nullity == 0, unique || ref.nullity == 0);
    for (const Options& o : {Options{}, noElim}) {
      Solver s;
      const Result& r = solveOnce(s, p, o);
      ASSERT_EQ(r.status, Status::Solved) << "seed " << seed;
      for (int l = 0; l < p.levelCount(); ++l) {
        EXPECT_NEAR(r.violation_norm(l), ref.residualNorm[static_cast<size_t>(l)], 1e-8 * (1 + ref.residualNorm[static_cast<size_t>(l)]))
            << "seed " << seed << " level " << l;
      }
      // The optimum is unique: same x. Without elimination the solver returns the minimum-norm
      // optimum like the reference; with elimination it returns an optimum (docs/solver.md).
      if (ref.nullity == 0 || !o.eliminate_first_level) {
        EXPECT_LE((r.x - ref.x).norm(), 1e-8 * (1 + ref.x.norm())) << "seed " << seed;
      }
      EXPECT_EQ(checkKkt(p, r), "") << "seed " << seed;
      if (o.eliminate_first_level && r.rank[0] == p.level(0).rows() && ref.nullity >= 0) ++eliminated;
    }
  }
  EXPECT_GT(eliminated, 50);  // the elimination stage was exercised
}

TEST(Solver, TinyInequalityProblemsMatchBruteForce) {
  GenOptions g;
  g.n = 3;
  g.maxRows = 2;
  int checked = 0;
  for (std::uint64_t seed = 1; seed <= 160; ++seed) {
    g.levels = 2 + static_cast<int>(seed % 2);
    g.boundsLevel = (seed % 3 != 0);
    g.n = 2 + static_cast<int>(seed % 2);
    Problem p = randomProblem(seed, g);
    if (p.totalRows() > 8) continue;
    const auto bf = bruteForce(p);
    Solver s;
    const Result& r = solveOnce(s, p);
    ASSERT_EQ(r.status, Status::Solved) << "seed " << seed;
    for (int l = 0; l < p.levelCount(); ++l) {
      EXPECT_NEAR(r.violation_norm(l), bf[static_cast<size_t>(l)], 1e-7 * (1 + bf[static_cast<size_t>(l)]))
          << "seed " << seed << " level " << l;
    }
    EXPECT_EQ(checkKkt(p, r), "") << "seed " << seed;
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(Solver, KktCertificateOnRandomProblems) {
  GenOptions g;
  for (std::uint64_t seed = 1000; seed < 1400; ++seed) {
    g.n = 4 + static_cast<int>(seed % 10);
    g.levels = 2 + static_cast<int>(seed % 6);
    g.maxRows = 2 + static_cast<int>(seed % 7);
    const Problem p = randomProblem(seed, g);
    Solver s;
    const Result& r = solveOnce(s, p);
    ASSERT_EQ(r.status, Status::Solved) << "seed " << seed;
    EXPECT_EQ(checkKkt(p, r), "") << "seed " << seed;
  }
}

TEST(Solver, WarmStartGivesTheColdAnswer) {
  GenOptions g;
  for (std::uint64_t seed = 2000; seed < 2150; ++seed) {
    g.n = 5 + static_cast<int>(seed % 6);
    g.levels = 3 + static_cast<int>(seed % 4);
    Problem p = randomProblem(seed, g);
    appendMinNorm(p);
    Solver cold, warm;
    cold.setup(p);
    warm.setup(p);
    const Result& rc = cold.solve(p);
    // Warm start from the optimum itself, from an unrelated problem's active set, and from its own result.
    warm.solve(p, rc.active, rc.x);
    EXPECT_EQ(warm.result().iterations, 1) << "seed " << seed;
    Problem q = randomProblem(seed + 7777, g);
    appendMinNorm(q);
    // Same sizes are needed for an active set of q to apply to p; otherwise it is ignored.
    warm.solve(p, rc.active, Eigen::VectorXd::Zero(p.variables()));
    warm.solve(p, warm.result().active, warm.result().x);
    const Result& rw = warm.result();
    ASSERT_EQ(rw.status, Status::Solved) << "seed " << seed;
    for (int l = 0; l < p.levelCount(); ++l)
      EXPECT_NEAR(rw.violation_norm(l), rc.violation_norm(l), 1e-8 * (1 + rc.violation_norm(l))) << "seed " << seed;
    EXPECT_LE((rw.x - rc.x).norm(), 1e-7 * (1 + rc.x.norm())) << "seed " << seed;
  }
}

// Levels whose rows are never active (here: inequalities far from any solution) between the
// others: stages without rows, whose snapshots the restarts at the next level read. The answer
// is that of the problem without them, over the many restarts of cold solves with inequalities.
TEST(Solver, NeverActiveLevelsBetweenOthersChangeNothing) {
  GenOptions g;
  g.inequalities = true;
  g.maxRows = 4;
  int restarts = 0;
  for (std::uint64_t seed = 7000; seed < 7120; ++seed) {
    g.n = 5 + static_cast<int>(seed % 7);
    g.levels = 3 + static_cast<int>(seed % 3);
    Problem p = randomProblem(seed, g);
    appendMinNorm(p);
    // q: p with two never-active levels before each general level after the first.
    Problem q(p.variables());
    bool firstGeneral = true;
    for (int l = 0; l < p.levelCount(); ++l) {
      const Level& lv = p.level(l);
      if (lv.kind == LevelKind::Bounds) {
        q.addBoundsLevel(lv.name, lv.variable, lv.coefficient, lv.lower, lv.upper);
        continue;
      }
      if (!firstGeneral) {
        for (int e = 0; e < 2; ++e) {
          Eigen::MatrixXd A = Eigen::MatrixXd::Ones(2, p.variables());
          A(1, 0) = -1.0;
          q.addLevel("never" + std::to_string(e), A, Eigen::VectorXd::Constant(2, -1e9), Eigen::VectorXd::Constant(2, 1e9));
        }
      }
      firstGeneral = false;
      q.addLevel(lv.name, lv.A, lv.lower, lv.upper);
    }
    Solver sp, sq;
    const Result rp = solveOnce(sp, p);
    const Result& rq = solveOnce(sq, q);
    ASSERT_EQ(rp.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(rq.status, Status::Solved) << "seed " << seed;
    restarts += rq.iterations > 1 ? 1 : 0;
    EXPECT_LE((rq.x - rp.x).norm(), 1e-9 * (1 + rp.x.norm())) << "seed " << seed;
    EXPECT_EQ(checkKkt(q, rq), "") << "seed " << seed;
  }
  EXPECT_GE(restarts, 60);  // most solves change their active set at least once
}

// The premise of the projected level's shortcut (HlsFactorization::projectDeferredLevel): with
// Eigen's matrix-product kernel, Z^T A for columns of A with a single nonzero v at row i gives
// v Z(i, :) + 0 bit for bit, signed zeros included (Z with exact zeros, v of both signs).
TEST(Solver, ProductWithSingleNonzeroColumnsIsAScaledRow) {
  std::mt19937_64 rng(91);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int nr = 10 + static_cast<int>(rng() % 60), d = 1 + static_cast<int>(rng() % static_cast<std::uint64_t>(nr));
    const int m = 2 + static_cast<int>(rng() % 40);
    if (nr + d + m < EIGEN_GEMM_TO_COEFFBASED_THRESHOLD) continue;
    Eigen::MatrixXd Z(nr, d), A = Eigen::MatrixXd::Zero(nr, m);
    for (int j = 0; j < d; ++j)
      for (int i = 0; i < nr; ++i) Z(i, j) = (rng() % 4 == 0) ? 0.0 : u(rng);
    std::vector<int> at(static_cast<size_t>(m));
    for (int j = 0; j < m; ++j) {
      at[static_cast<size_t>(j)] = static_cast<int>(rng() % static_cast<std::uint64_t>(nr));
      A(at[static_cast<size_t>(j)], j) = (rng() % 2 ? 1.0 : -1.0) * (0.5 + u(rng) * u(rng));
    }
    Eigen::MatrixXd P(d, m);
    P.noalias() = Z.transpose() * A;
    for (int j = 0; j < m; ++j) {
      const int i = at[static_cast<size_t>(j)];
      const Eigen::VectorXd row = (A(i, j) * Z.row(i).transpose()).array() + 0.0;
      ASSERT_EQ(std::memcmp(row.data(), P.col(j).data(), sizeof(double) * static_cast<size_t>(d)), 0)
          << "trial " << trial << " column " << j;
    }
  }
}

// The premise of the projected level's unit columns (HlsFactorization::projectDeferredLevel):
// with Z's columns from t on unit vectors (column i at row c0 + i), Z^T A equals, bit for bit and
// signed zeros included, the product over Z's first `lead` columns followed by rows c0 + i of
// A + 0, for every case where unitColumnProductRows (the solver's own decision) gives a lead: t
// rounded up to a multiple of the widest micro-kernel's rows (gebp's mr), within that
// micro-kernel's part of the full product.
TEST(Solver, ProductOfLeadingColumnsKeepsTheFullProductsBits) {
  constexpr int mr = Eigen::internal::gebp_traits<double, double>::mr;
  std::mt19937_64 rng(92);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const int nr = 4 + static_cast<int>(rng() % 76);
    const int c0 = static_cast<int>(rng() % static_cast<std::uint64_t>(nr - 1));
    const int d = nr - c0, m = 1 + static_cast<int>(rng() % 41);
    const int t = static_cast<int>(rng() % static_cast<std::uint64_t>(d + 1));
    // The cases projectDeferredLevel takes (otherwise it multiplies in full).
    const int lead = HlsFactorization::unitColumnProductRows(nr, d, m, t);
    if (lead < 0) continue;
    EXPECT_EQ(lead % mr, 0);
    EXPECT_GE(lead, t);
    Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(nr, d), A(nr, m);
    for (int j = 0; j < d; ++j) {
      if (j < t) {
        for (int i = 0; i < nr; ++i) Z(i, j) = (rng() % 4 == 0) ? 0.0 : u(rng);
      } else {
        Z(c0 + j, j) = 1.0;
      }
    }
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < nr; ++i) {
        const std::uint64_t r = rng() % 8;
        A(i, j) = r == 0 ? 0.0 : r == 1 ? -0.0 : u(rng) * std::pow(10.0, static_cast<int>(rng() % 9) - 4);
      }
    Eigen::MatrixXd full(d, m), parts(d, m);
    full.noalias() = Z.transpose() * A;
    if (lead > 0) parts.topRows(lead).noalias() = Z.leftCols(lead).transpose() * A;
    parts.bottomRows(d - lead) = A.bottomRows(d - lead).array() + 0.0;
    for (int j = 0; j < m; ++j)
      ASSERT_EQ(std::memcmp(full.col(j).data(), parts.col(j).data(), sizeof(double) * static_cast<size_t>(d)), 0)
          << "trial " << trial << " nr " << nr << " c0 " << c0 << " t " << t << " m " << m << " column " << j;
    ++checked;
  }
  EXPECT_GE(checked, 200);
}

// The premise of HlsFactorization::blockReflectorUpdate: leaving out groups of exactly zero
// columns (signed zeros among them) keeps every bit of the full compact-WY update C - V T^T V^T C,
// for the columns left out and for the others. Fails when the groups are not the kernel's panels
// (nr columns counted from the first) or when a part falls to the matrix-vector or the
// coefficient-wise product.
TEST(Solver, BlockReflectorUpdateSkippingZeroColumnsKeepsTheBits) {
  constexpr int nr = Eigen::internal::gebp_traits<double, double>::nr;
  std::mt19937_64 rng(93);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int skipped = 0;
  for (int trial = 0; trial < 800; ++trial) {
    const int r = 2 + static_cast<int>(rng() % 23);
    const int d = r + static_cast<int>(rng() % 30), n = 1 + static_cast<int>(rng() % 70);
    Eigen::MatrixXd V = Eigen::MatrixXd::Zero(d, r), T = Eigen::MatrixXd::Zero(r, r), C(d, n);
    for (int j = 0; j < r; ++j) {
      V(j, j) = 1.0;
      for (int i = j + 1; i < d; ++i) V(i, j) = (rng() % 5 == 0) ? 0.0 : u(rng);
      for (int i = 0; i <= j; ++i) T(i, j) = u(rng);
    }
    for (int j = 0; j < n; ++j) {
      // Zero columns in runs that need not match the panels: some groups are whole, some not.
      const bool zero = (j / 3 + trial) % 3 == 0 || (j / nr + trial) % 4 == 1;
      for (int i = 0; i < d; ++i) {
        const std::uint64_t k = rng() % 6;
        C(i, j) = (zero || k == 0) ? ((rng() % 2) ? 0.0 : -0.0) : u(rng) * std::pow(10.0, static_cast<int>(k) - 3);
      }
    }
    Eigen::MatrixXd full = C, Y(r, n), Y2(r, n);
    Y.noalias() = V.transpose() * full;
    Y2.noalias() = T.transpose().triangularView<Eigen::Lower>() * Y;
    full.noalias() -= V * Y2;
    Eigen::MatrixXd parts = C, Yp(r, n), Y2p(r, n);
    const int kept = HlsFactorization::blockReflectorUpdate(V, T, parts, Yp, Y2p);
    if (kept < n) ++skipped;
    EXPECT_EQ((n - kept) % nr, 0);
    for (int j = 0; j < n; ++j)
      ASSERT_EQ(std::memcmp(full.col(j).data(), parts.col(j).data(), sizeof(double) * static_cast<size_t>(d)), 0)
          << "trial " << trial << " d " << d << " r " << r << " n " << n << " kept " << kept << " column " << j;
  }
  EXPECT_GE(skipped, 300);
}

// Level::columns: a level declared zero past its first c columns gives the same bits as the same
// problem without the declaration (the solver leaves those columns out of its products A x),
// cold and warm-started; a declaration contradicted by the matrix is an input error naming the
// entry, and a count outside -1 .. n or on a bounds level is refused.
TEST(Solver, DeclaredLeadingColumnsKeepEveryBit) {
  GenOptions g;
  int declared = 0, fixedSeen = 0;
  for (std::uint64_t seed = 300; seed < 420; ++seed) {
    g.n = 4 + static_cast<int>((seed * 7) % 150);  // beyond 128 columns too
    g.levels = 2 + static_cast<int>(seed % 4);
    g.maxRows = 2 + static_cast<int>(seed % 7);
    Problem plain = randomProblem(seed, g);
    std::mt19937_64 rng(seed);
    // Some general levels lose their trailing columns (signed zeros), then declare them.
    std::vector<int> cols(static_cast<size_t>(plain.levelCount()), -1);
    for (int l = 0; l < plain.levelCount(); ++l) {
      Level& lv = plain.level(l);
      if (lv.kind != LevelKind::General || rng() % 3 == 0) continue;
      const int c = 1 + static_cast<int>(rng() % static_cast<std::uint64_t>(g.n - 1));
      for (int j = c; j < g.n; ++j)
        for (int r = 0; r < lv.rows(); ++r) lv.A(r, j) = (rng() % 2) ? 0.0 : -0.0;
      cols[static_cast<size_t>(l)] = c;
      // Targets of -0 (a sum that starts at -0 stays sensitive to the sign of its zero terms).
      for (int r = 0; r < lv.rows(); ++r)
        if (rng() % 4 == 0) {
          lv.lower(r) = std::min(lv.lower(r), -0.0);
          lv.upper(r) = -0.0;
        }
    }
    // Negative bounds on the bounds level, so that fixed variables take negative values too.
    for (int l = 0; l < plain.levelCount(); ++l) {
      Level& lv = plain.level(l);
      if (lv.kind != LevelKind::Bounds) continue;
      for (int r = 0; r < lv.rows(); ++r) {
        if (rng() % 2 != 0 || !std::isfinite(lv.lower(r)) || !std::isfinite(lv.upper(r))) continue;
        const double w = lv.upper(r) - lv.lower(r);
        lv.upper(r) = -0.25 - 0.5 * std::abs(lv.upper(r));
        lv.lower(r) = lv.upper(r) - w;
      }
    }
    Problem withColumns = plain;
    for (int l = 0; l < plain.levelCount(); ++l)
      if (cols[static_cast<size_t>(l)] >= 0) {
        withColumns.setLevelColumns(l, cols[static_cast<size_t>(l)]);
        ++declared;
      }
    Solver a, b;
    const Result& ra = solveOnce(a, plain);
    const Result& rb = solveOnce(b, withColumns);
    const auto same = [](const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
      return u.size() == v.size() && std::memcmp(u.data(), v.data(), sizeof(double) * static_cast<size_t>(u.size())) == 0;
    };
    ASSERT_TRUE(same(ra.x, rb.x)) << "seed " << seed;
    ASSERT_TRUE(same(ra.violation_norm, rb.violation_norm)) << "seed " << seed;
    EXPECT_EQ(ra.iterations, rb.iterations) << "seed " << seed;
    ASSERT_EQ(ra.lambda.size(), rb.lambda.size()) << "seed " << seed;
    EXPECT_EQ(std::memcmp(ra.lambda.data(), rb.lambda.data(), sizeof(double) * static_cast<size_t>(ra.lambda.size())), 0)
        << "seed " << seed;
    fixedSeen += ra.active.level.empty() ? 0
                                         : static_cast<int>(std::count_if(ra.active.level[0].begin(), ra.active.level[0].end(),
                                                                          [](RowState st) { return st != RowState::Inactive; }));
    // Warm-started from the answer of a perturbed problem.
    Problem plain2 = plain, withColumns2 = withColumns;
    for (int l = 0; l < plain.levelCount(); ++l) {
      if (plain.level(l).kind != LevelKind::General) continue;
      plain2.level(l).lower.array() -= 0.125;
      withColumns2.level(l).lower.array() -= 0.125;
    }
    const Result& wa = a.solve(plain2, ra.active, ra.x);
    const Result& wb = b.solve(withColumns2, rb.active, rb.x);
    ASSERT_TRUE(same(wa.x, wb.x)) << "seed " << seed << " (warm)";
  }
  EXPECT_GE(declared, 100);
  EXPECT_GE(fixedSeen, 50);  // the fixed variables' terms in the targets and multipliers were exercised

  Problem p(3);
  p.addBoundsLevel("box", {0}, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Ones(1));
  p.addLevel("rows", mat(2, 3, {1, 2, 0, 3, 0, 0.5}), vec({0, 0}), vec({1, 1}));
  EXPECT_THROW(p.setLevelColumns(0, 1), InputError);
  EXPECT_THROW(p.setLevelColumns(1, 4), InputError);
  EXPECT_THROW(p.setLevelColumns(1, -2), InputError);
  p.setLevelColumns(1, 2);
  EXPECT_TRUE(
      lexdyn::testing::containsAll(lexdyn::testing::inputErrorOf([&] { p.validate("test"); }), {"A[1][2] is 0.5", "first 2 columns"}));
  p.level(1).A(1, 2) = -0.0;
  EXPECT_NO_THROW(p.validate("test"));
}

// Each multiplier column is zeroed over its own and earlier levels' rows only, so nothing may
// be written below them. A correction by an earlier level's column with an infinite factor (a
// hold of 1e-100 against a multiplier of 1e300) makes that solve's result non-finite; the next
// solve, of a harmless problem, must be solved with the bits of a fresh solver's.
TEST(Solver, AnInfiniteCorrectionDoesNotOutliveItsSolve) {
  auto build = [](double t1, double t2) {
    Problem p(2);
    p.addLevel("x1 >= 0", mat(1, 2, {0, 1}), vec({0}), vec({kInf}));
    p.addLevel("x1 = t1", mat(1, 2, {0, 1}), vec({t1}), vec({t1}));
    p.addLevel("x1 = t2", mat(1, 2, {0, 1}), vec({t2}), vec({t2}));
    p.addLevel("x0 = 0", mat(1, 2, {1, 0}), vec({0}), vec({0}));
    return p;
  };
  const Problem bad = build(-1e-100, 1e300), good = build(1.0, 2.0);
  Solver a, fresh;
  a.setup(bad);
  fresh.setup(good);
  const Result& r0 = a.solve(bad);
  EXPECT_EQ(r0.status, Status::NonFiniteResult);
  expectSameResult(a.solve(good), fresh.solve(good), "after the non-finite result");
  EXPECT_EQ(a.result().status, Status::Solved);
  EXPECT_TRUE(a.result().lambda.allFinite());
}

// A x is formed for the rows that can constrain only: runs of them, with fewer than four free
// rows (bounds -inf and +inf) between, each run of two rows at least; a free row's A x is 0, and
// its norm is not computed. Every bit of the result is that of the same problem whose free rows
// have bounds of -1e300 and 1e300 instead (rows that are multiplied and never block), and of
// the same problem with other coefficients in its free rows; the violations of the other rows
// are those of their A x, computed here independently; cold and warm; free rows alone, in runs,
// at a level's end (the controller's reserved rows), every other row, beyond 128 columns too.
TEST(Solver, FreeRowsLeftOutOfAxKeepEveryBit) {
  GenOptions g;
  int freeRows = 0, levelsWithFree = 0;
  for (std::uint64_t seed = 500; seed < 700; ++seed) {
    g.n = 2 + static_cast<int>((seed * 11) % 140);
    g.levels = 2 + static_cast<int>(seed % 5);
    g.maxRows = 2 + static_cast<int>(seed % 14);
    Problem p = randomProblem(seed, g);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<std::vector<char>> isFree(static_cast<size_t>(p.levelCount()));
    for (int l = 0; l < p.levelCount(); ++l) {
      Level& lv = p.level(l);
      isFree[static_cast<size_t>(l)].assign(static_cast<size_t>(lv.rows()), 0);
      if (lv.kind != LevelKind::General) continue;
      const int pattern = static_cast<int>(rng() % 4);
      bool any = false;
      for (int r = 0; r < lv.rows(); ++r) {
        const bool f = pattern == 1 ? rng() % 2 == 0 : pattern == 2 ? 2 * r >= lv.rows() : pattern == 3 ? r % 2 == 1 : false;
        if (!f) continue;
        lv.lower(r) = -kInf;
        lv.upper(r) = kInf;
        isFree[static_cast<size_t>(l)][static_cast<size_t>(r)] = 1;
        any = true;
        ++freeRows;
      }
      levelsWithFree += any ? 1 : 0;
    }
    Problem q = p, wide = p;
    for (int l = 0; l < q.levelCount(); ++l)
      for (int r = 0; r < q.level(l).rows(); ++r)
        if (isFree[static_cast<size_t>(l)][static_cast<size_t>(r)]) {
          for (int c = 0; c < g.n; ++c) q.level(l).A(r, c) = u(rng) * 1e3;
          wide.level(l).lower(r) = -1e300;
          wide.level(l).upper(r) = 1e300;
        }
    auto checkViolations = [&](const Problem& pb, const Result& res, const std::string& what) {
      for (int l = 0; l < pb.levelCount(); ++l) {
        const Level& lv = pb.level(l);
        if (lv.kind != LevelKind::General) continue;
        for (int r = 0; r < lv.rows(); ++r) {
          const double v = res.violation[static_cast<size_t>(l)](r);
          if (isFree[static_cast<size_t>(l)][static_cast<size_t>(r)]) {
            EXPECT_EQ(v, 0.0) << what << " level " << l << " row " << r;
            continue;
          }
          const double ax = lv.A.row(r).dot(res.x);
          const double expected = ax - std::min(std::max(ax, lv.lower(r)), lv.upper(r));
          const double scale = 1.0 + lv.A.row(r).cwiseAbs().sum() * res.x.lpNorm<Eigen::Infinity>();
          EXPECT_NEAR(v, expected, 1e-12 * scale) << what << " level " << l << " row " << r;
        }
      }
    };
    Solver a, b, w;
    const Result& ra = solveOnce(a, p);
    const Result& rb = solveOnce(b, q);
    const Result& rw = solveOnce(w, wide);
    expectSameResult(ra, rb, "cold, seed " + std::to_string(seed));
    expectSameResult(ra, rw, "cold, wide bounds, seed " + std::to_string(seed));
    checkViolations(p, ra, "cold, seed " + std::to_string(seed));
    // Warm, from the answer, with the constraining rows' bounds moved.
    Problem p2 = p, q2 = q, wide2 = wide;
    for (int l = 0; l < p.levelCount(); ++l) {
      if (p.level(l).kind != LevelKind::General) continue;
      p2.level(l).lower.array() -= 0.125;
      q2.level(l).lower.array() -= 0.125;
      wide2.level(l).lower.array() -= 0.125;
    }
    const ActiveSet act = ra.active;
    const Eigen::VectorXd x0 = ra.x;
    const Result& wa = a.solve(p2, act, x0);
    const Result& wb = b.solve(q2, act, x0);
    const Result& ww = w.solve(wide2, act, x0);
    expectSameResult(wa, wb, "warm, seed " + std::to_string(seed));
    expectSameResult(wa, ww, "warm, wide bounds, seed " + std::to_string(seed));
    checkViolations(p2, wa, "warm, seed " + std::to_string(seed));
  }
  EXPECT_GE(levelsWithFree, 150);
  EXPECT_GE(freeRows, 600);
}

// Free rows are left out of the row norms, whose finiteness stands for the rows'; their own
// coefficients are still checked: a NaN or an infinity anywhere in a free row, outside or inside
// a run of constraining rows, alone or in an all-free level, is NonFiniteInput naming its row.
TEST(Solver, NonFiniteCoefficientsOfFreeRowsAreRefused) {
  std::mt19937_64 rng(81);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int refused = 0;
  for (int pattern = 0; pattern < 3; ++pattern) {
    for (int bad = 0; bad < 12; ++bad) {
      for (const double value : {std::numeric_limits<double>::quiet_NaN(), kInf, -kInf}) {
        Problem p(5);
        Eigen::MatrixXd A0(2, 5), A1(12, 5);
        for (Eigen::Index k = 0; k < A0.size(); ++k) A0.data()[k] = u(rng);
        for (Eigen::Index k = 0; k < A1.size(); ++k) A1.data()[k] = u(rng);
        Eigen::VectorXd lo = Eigen::VectorXd::Constant(12, -1.0), up = Eigen::VectorXd::Constant(12, 1.0);
        for (int r = 0; r < 12; ++r) {
          // 0: rows 2.. free (a run of two, then free); 1: every row free; 2: rows 0 and 11 held
          // around free ones (the gap of ten lies outside any run).
          const bool f = pattern == 0 ? r >= 2 : pattern == 1 ? true : (r != 0 && r != 11);
          if (f) lo(r) = -kInf, up(r) = kInf;
        }
        p.addLevel("first", A0, vec({0, 0}), vec({0, 0}));
        p.addLevel("rows", A1, lo, up);
        Solver s;
        s.setup(p);  // finite; the solve's data carry the bad value
        Problem q = p;
        q.level(1).A(bad, static_cast<int>(rng() % 5)) = value;
        const Result& r = s.solve(q);
        ASSERT_EQ(r.status, Status::NonFiniteInput) << "pattern " << pattern << " row " << bad;
        EXPECT_EQ(r.bad_level, 1);
        EXPECT_EQ(r.bad_row, bad);
        ++refused;
      }
    }
  }
  EXPECT_EQ(refused, 3 * 12 * 3);
}

// The factorisation reads a level's adjacent active rows two or four at a time (one load per pair
// of rows and column) and other rows one at a time. Rows that never become active (bounds of
// -inf and +inf) put between a level's rows break those runs and change nothing else that the
// gathered rows decide: the answers, the counts of iterations and factorisations and the
// multipliers of the original rows must agree bit for bit, cold and warm, on controller-shaped
// problems (split coordinates, declared columns, unit rows, spanning stages). That checks each
// row's values and, where it decides anything, its classification (zero, one nonzero and where,
// several): a row taken for a unit row by the spanning stages, or a basic part taken for a single
// nonzero by the elimination, changes the answer's bits (a basic part of one nonzero classified as
// several only takes the product that adds exact zeros). The violations are not compared: the
// matrix-vector products of the steps round a row by its place among the level's rows.
TEST(Solver, AdjacentRowsReadTogetherGiveTheBitsOfScatteredRows) {
  int compared = 0, runsBroken = 0;
  for (std::uint64_t seed = 1; seed <= 300; ++seed) {
    Options o;
    const Problem p = test::controllerShapedProblem(seed, 40, 4, 8, o);
    std::mt19937_64 rng(seed * 7919);
    // The same problem with never-active rows between some of a level's rows (the first general
    // level, the equation of motion, stays all equalities so that it is still eliminated), and
    // where each original row now is in the stack of rows of the multipliers.
    Problem q(p.variables());
    std::vector<int> stackRow;
    int stack = 0;
    bool firstGeneral = true;
    for (int l = 0; l < p.levelCount(); ++l) {
      const Level& lv = p.level(l);
      if (lv.kind == LevelKind::Bounds) {
        q.addBoundsLevel(lv.name, lv.variable, lv.coefficient, lv.lower, lv.upper);
        for (int r = 0; r < lv.rows(); ++r) stackRow.push_back(stack++);
        continue;
      }
      std::vector<int> from;  // q's rows: the original row, or -1 - the row it copies
      for (int r = 0; r < lv.rows(); ++r) {
        from.push_back(r);
        if (!firstGeneral && rng() % 2 == 0) from.push_back(-1 - r);
      }
      firstGeneral = false;
      const int m = static_cast<int>(from.size());
      Eigen::MatrixXd A(m, p.variables());
      Eigen::VectorXd lo(m), up(m);
      for (int i = 0; i < m; ++i) {
        const int r = from[static_cast<size_t>(i)] >= 0 ? from[static_cast<size_t>(i)] : -1 - from[static_cast<size_t>(i)];
        A.row(i) = lv.A.row(r);
        lo(i) = from[static_cast<size_t>(i)] >= 0 ? lv.lower(r) : -std::numeric_limits<double>::infinity();
        up(i) = from[static_cast<size_t>(i)] >= 0 ? lv.upper(r) : std::numeric_limits<double>::infinity();
        if (from[static_cast<size_t>(i)] >= 0) stackRow.push_back(stack + i);
      }
      runsBroken += m - lv.rows();
      stack += m;
      q.addLevel(lv.name, A, lo, up);
      if (lv.columns >= 0) q.setLevelColumns(q.levelCount() - 1, lv.columns);
    }
    Solver a, b;
    const Result ra = solveOnce(a, p, o);
    const Result rb = solveOnce(b, q, o);
    const std::string what = "seed " + std::to_string(seed);
    ASSERT_EQ(ra.status, rb.status) << what;
    ASSERT_TRUE(sameBits(ra.x, rb.x)) << what;
    EXPECT_EQ(ra.iterations, rb.iterations) << what;
    EXPECT_EQ(ra.factorizations, rb.factorizations) << what;
    ASSERT_EQ(ra.lambda.cols(), rb.lambda.cols()) << what;
    for (int i = 0; i < static_cast<int>(stackRow.size()); ++i)
      ASSERT_TRUE(sameBits(ra.lambda.row(i), rb.lambda.row(stackRow[static_cast<size_t>(i)]))) << what << ", row " << i;
    // Warm, from the answer, with the targets moved.
    Problem p2 = p, q2 = q;
    for (int l = 0; l < p.levelCount(); ++l) {
      if (p.level(l).kind != LevelKind::General) continue;
      for (Problem* t : {&p2, &q2})
        for (int r = 0; r < t->level(l).rows(); ++r)
          if (std::isfinite(t->level(l).lower(r))) t->level(l).lower(r) -= 0.125;
    }
    const Result wa = a.solve(p2, ra.active, ra.x);
    ActiveSet activeB = rb.active;
    const Result wb = b.solve(q2, activeB, rb.x);
    ASSERT_TRUE(sameBits(wa.x, wb.x)) << what << " (warm)";
    EXPECT_EQ(wa.iterations, wb.iterations) << what << " (warm)";
    ++compared;
  }
  EXPECT_EQ(compared, 300);
  EXPECT_GE(runsBroken, 1000);
}

// Options::swap_reflectors on random hierarchies with levels of unit rows (inequalities,
// duplicates, conflicts, rank-deficient levels), cold and warm: the answer of the generic
// arithmetic to rounding, with a valid KKT certificate; on some problems the bits differ (the
// swaps were taken).
TEST(Solver, SwapReflectorsGiveTheGenericAnswer) {
  GenOptions g;
  g.pUnitLevel = 0.5;
  g.dyadic = true;
  int differ = 0, checked = 0;
  for (std::uint64_t seed = 3000; seed < 3400; ++seed) {
    g.n = 4 + static_cast<int>(seed % 11);
    g.levels = 2 + static_cast<int>(seed % 5);
    g.maxRows = 2 + static_cast<int>(seed % 6);
    Problem p = randomProblem(seed, g);
    appendMinNorm(p);
    Options on, off;
    on.eliminate_first_level = off.eliminate_first_level = seed % 2 == 0;
    off.swap_reflectors = false;
    Solver a, b;
    const Result ra = solveOnce(a, p, on);
    const Result rb = solveOnce(b, p, off);
    ASSERT_EQ(ra.status, rb.status) << "seed " << seed;
    if (ra.status != Status::Solved) continue;
    ++checked;
    EXPECT_LE((ra.x - rb.x).norm(), 1e-9 * (1 + rb.x.norm())) << "seed " << seed;
    EXPECT_LE((ra.violation_norm - rb.violation_norm).norm(), 1e-9 * (1 + rb.violation_norm.norm())) << "seed " << seed;
    EXPECT_EQ(checkKkt(p, ra), "") << "seed " << seed;
    if (!sameBits(ra.x, rb.x)) ++differ;
    Problem q = p;
    for (int l = 0; l < q.levelCount(); ++l) {
      q.level(l).lower.array() -= 0.001;
      q.level(l).upper.array() -= 0.001;
    }
    const Result wa = a.solve(q, ra.active, ra.x);
    const Result wb = b.solve(q, rb.active, rb.x);
    ASSERT_EQ(wa.status, wb.status) << "seed " << seed;
    EXPECT_LE((wa.x - wb.x).norm(), 1e-9 * (1 + wb.x.norm())) << "seed " << seed;
    EXPECT_EQ(checkKkt(q, wa), "") << "seed " << seed;
  }
  EXPECT_GE(checked, 350);
  EXPECT_GE(differ, 20);
}

// Options::lazy_snapshots: a solve of one iteration gives the bits of the solve with snapshots; a
// solve that restarts gives the same answer to rounding (its restarted stages factorised from
// the first level again), cold and warm, with a valid KKT certificate.
TEST(Solver, LazySnapshotsGiveTheSameAnswer) {
  GenOptions g;
  int single = 0, restarted = 0, moreStages = 0;
  for (std::uint64_t seed = 600; seed < 900; ++seed) {
    g.n = 4 + static_cast<int>(seed % 9);
    g.levels = 2 + static_cast<int>(seed % 5);
    g.maxRows = 2 + static_cast<int>(seed % 6);
    g.dyadic = true;
    Problem p = randomProblem(seed, g);
    appendMinNorm(p);
    Options eager, lazy;
    lazy.lazy_snapshots = true;
    Solver a, b;
    const Result ra = solveOnce(a, p, eager);
    const Result rb = solveOnce(b, p, lazy);
    ASSERT_EQ(rb.status, ra.status) << "seed " << seed;
    EXPECT_LE((rb.x - ra.x).norm(), 1e-9 * (1 + ra.x.norm())) << "seed " << seed;
    EXPECT_EQ(checkKkt(p, rb), "") << "seed " << seed;
    // Warm-started from the answer to a shifted problem: mostly one iteration.
    Problem q = p;
    for (int l = 0; l < q.levelCount(); ++l) {
      q.level(l).lower.array() -= 0.001;
      q.level(l).upper.array() -= 0.001;
    }
    const Result wa = a.solve(q, ra.active, ra.x);
    const Result wb = b.solve(q, rb.active, rb.x);
    EXPECT_LE((wb.x - wa.x).norm(), 1e-9 * (1 + wa.x.norm())) << "seed " << seed;
    EXPECT_EQ(checkKkt(q, wb), "") << "seed " << seed;
    for (const auto* pair : {&ra, &wa}) {
      const Result& x = *pair;
      const Result& y = pair == &ra ? rb : wb;
      if (x.iterations == 1 && y.iterations == 1) {
        EXPECT_EQ(std::memcmp(x.x.data(), y.x.data(), sizeof(double) * static_cast<size_t>(x.x.size())), 0) << "seed " << seed;
        EXPECT_EQ(y.factorizations, x.factorizations) << "seed " << seed;
        ++single;
      } else {
        ++restarted;
        // The first restart of a lazy solve factorises every level again: never fewer stages,
        // more when the eager solve restarted above the first level.
        if (x.iterations == y.iterations) {
          EXPECT_GE(y.factorizations, x.factorizations) << "seed " << seed;
          moreStages += y.factorizations > x.factorizations;
        }
      }
    }
  }
  EXPECT_GE(single, 50);
  EXPECT_GE(restarted, 100);
  EXPECT_GE(moreStages, 50);
}

// HlsFactorization::rowNorms over the leading columns that hold a level's nonzero entries gives
// the bits of the norms over every column, for any count of rows, columns and zero columns, and
// at any offset of the destination (Eigen vectorises the rows at aligned positions only). Fails
// when the leading block is cut at the declared count itself.
TEST(Solver, RowNormsOverDeclaredColumnsKeepEveryBit) {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int cut = 0;
  for (int n = 1; n <= 130; ++n) {
    for (int rows = 1; rows <= 9; rows += 2) {
      const int c = 1 + static_cast<int>(rng() % static_cast<std::uint64_t>(n));
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, n);
      for (int j = 0; j < c; ++j)
        for (int i = 0; i < rows; ++i) A(i, j) = (rng() % 5 == 0) ? 0.0 : u(rng) * std::ldexp(1.0, static_cast<int>(rng() % 40) - 20);
      for (int off = 0; off < 3; ++off) {
        Eigen::VectorXd full = Eigen::VectorXd::Zero(rows + 3), lead = full;
        HlsFactorization::rowNorms(A, -1, full.segment(off, rows));
        HlsFactorization::rowNorms(A, c, lead.segment(off, rows));
        ASSERT_EQ(std::memcmp(full.data(), lead.data(), sizeof(double) * static_cast<size_t>(full.size())), 0)
            << "n " << n << " rows " << rows << " columns " << c << " offset " << off;
      }
      cut += c < n;
    }
  }
  EXPECT_GE(cut, 500);
}

// HlsFactorization::computeRowNorms with runs of rows (the solver leaves free rows out) gives
// each row of a run the bits of the whole levels' computation: Eigen forms an aligned pair of
// rows together and an unaligned first or last row alone, so each run is widened to aligned
// ends. Any counts of rows and columns, declared columns, levels at odd and even offsets, runs
// of any length and gap. Fails without the widening.
TEST(Solver, RowNormsOfRunsKeepTheBits) {
  std::mt19937_64 rng(78);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  long rowsChecked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 130);
    const int levels = 1 + static_cast<int>(rng() % 4);
    std::vector<int> rows;
    std::vector<Eigen::MatrixXd> A;
    std::vector<int> cols;
    for (int k = 0; k < levels; ++k) {
      rows.push_back(1 + static_cast<int>(rng() % 60));
      const int c = rng() % 3 == 0 ? -1 : 1 + static_cast<int>(rng() % static_cast<std::uint64_t>(n));
      Eigen::MatrixXd a = Eigen::MatrixXd::Zero(rows.back(), n);
      for (int j = 0; j < (c < 0 ? n : c); ++j)
        for (int i = 0; i < rows.back(); ++i) a(i, j) = u(rng) * std::ldexp(1.0, static_cast<int>(rng() % 40) - 20);
      A.push_back(a);
      cols.push_back(c);
    }
    HlsFactorization whole, parts;
    whole.setup(n, rows);
    parts.setup(n, rows);
    std::vector<int> runs, runsOff;
    std::vector<std::vector<char>> want(static_cast<size_t>(levels));
    for (int k = 0; k < levels; ++k) {
      whole.setLevelMatrix(k, &A[static_cast<size_t>(k)], cols[static_cast<size_t>(k)]);
      parts.setLevelMatrix(k, &A[static_cast<size_t>(k)], cols[static_cast<size_t>(k)]);
      runsOff.push_back(static_cast<int>(runs.size()));
      const int m = rows[static_cast<size_t>(k)];
      want[static_cast<size_t>(k)].assign(static_cast<size_t>(m), 0);
      for (int r = 0; r < m;) {
        const int len = 1 + static_cast<int>(rng() % 6), gap = static_cast<int>(rng() % 5);
        const int e = std::min(m, r + len);
        if (rng() % 4 != 0) {
          runs.push_back(r);
          runs.push_back(e);
          for (int q = r; q < e; ++q) want[static_cast<size_t>(k)][static_cast<size_t>(q)] = 1;
        }
        r = e + gap;
      }
    }
    runsOff.push_back(static_cast<int>(runs.size()));
    whole.computeRowNorms();
    parts.computeRowNorms(&runs, &runsOff);
    for (int k = 0, off = 0; k < levels; off += rows[static_cast<size_t>(k)], ++k) {
      for (int r = 0; r < rows[static_cast<size_t>(k)]; ++r) {
        if (!want[static_cast<size_t>(k)][static_cast<size_t>(r)]) continue;
        ++rowsChecked;
        const double a = whole.rowNorms()(off + r), b = parts.rowNorms()(off + r);
        ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "trial " << trial << " level " << k << " row " << r;
      }
    }
  }
  EXPECT_GE(rowsChecked, 10000);
}

// The start of the split-coordinate and spanning-stage hierarchies: n variables in two halves,
// bounds on a few variables of both (their activation during a solve changes the free set: the
// elimination is then updated, keeping the reduced variables' order), then a first level of 1 to
// 3 equalities (by the seed) over all of them, whose first half pivots unless disfavoured.
// A level of m0 random equality rows over all the variables (entries and targets uniform in
// [-1, 1]), the entries of the first `split` variables scaled by `firstScale`: a first level that
// the elimination takes, as a controller's equation of motion.
void addScaledEqualities(Problem& p, std::mt19937_64& rng, int m0, int split, double firstScale, const std::string& name) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = p.variables();
  Eigen::MatrixXd E(m0, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < m0; ++i) E(i, j) = (j < split ? firstScale : 1.0) * u(rng);
  Eigen::VectorXd e(m0);
  for (int i = 0; i < m0; ++i) e(i) = u(rng);
  p.addLevel(name, E, e, e);
}

Problem twoHalvesStart(std::uint64_t seed, std::mt19937_64& rng, int n) {
  const int half = n / 2;
  Problem p(n);
  {
    std::vector<int> vars = {0, half - 1, half, n - 1};
    Eigen::VectorXd c = Eigen::VectorXd::Ones(4), lo = Eigen::VectorXd::Constant(4, -0.05), hi = Eigen::VectorXd::Constant(4, 0.05);
    p.addBoundsLevel("box", vars, c, lo, hi);
  }
  addScaledEqualities(p, rng, 1 + static_cast<int>(seed % 3), half, 10.0, "eq");
  return p;
}

// A level of `rows` random rows over the first half of the variables, the second half or all of
// them, each an equality or an inequality.
void addHalvesLevel(Problem& p, std::mt19937_64& rng, int rows, const std::string& name) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = p.variables(), half = n / 2;
  const int part = static_cast<int>(rng() % 3);  // 0: first half, 1: second half, 2: all
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, n);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < n; ++j)
      if (part == 2 || (part == 0) == (j < half)) A(i, j) = u(rng);
  Eigen::VectorXd lo(rows), hi(rows);
  for (int i = 0; i < rows; ++i) {
    lo(i) = u(rng);
    hi(i) = (rng() % 2) ? lo(i) : lo(i) + 0.5;  // equalities and inequalities
  }
  p.addLevel(name, A, lo, hi);
}

// The answer `r`, solved with options `o`, is `ref`'s to rounding: x and every level's violation;
// the multipliers and ranks when the active sets agree (returned: a row duplicated as an
// inequality can sit exactly at its bound at the optimum, held or not as rounding has it, both
// optimal); a KKT certificate; and the same x from a warm start at ref's active set.
bool expectSameAnswer(const Problem& p, const Result& ref, const Result& r, const Options& o, const std::string& what) {
  EXPECT_LE((r.x - ref.x).norm(), 1e-9 * (1 + ref.x.norm())) << what;
  for (int l = 0; l < p.levelCount(); ++l)
    EXPECT_NEAR(r.violation_norm(l), ref.violation_norm(l), 1e-9 * (1 + ref.violation_norm(l))) << what << " level " << l;
  const bool same = r.active.level == ref.active.level;
  if (same) {
    EXPECT_LE((r.lambda - ref.lambda).norm(), 1e-7 * (1 + ref.lambda.norm())) << what;
    EXPECT_EQ(r.rank, ref.rank) << what;
  }
  EXPECT_EQ(checkKkt(p, r), "") << what;
  Solver w;
  w.setup(p, o);
  w.solve(p, ref.active, ref.x);
  EXPECT_LE((w.result().x - ref.x).norm(), 1e-9 * (1 + ref.x.norm())) << what << " (warm)";
  return same;
}

// Options::spanning_stages: levels of single-variable rows (x_j = c over a set of variables, some
// scaled, some inequalities, some duplicated) that span what is left to them are solved by one
// QR; the answers, violations and multipliers are the standard factorisation's to rounding, with
// and without split coordinates, cold and warm, and the multipliers are a KKT certificate.
// Levels that do not span (fewer variables than the coordinates left) are factorised as before.
// Options::spanning_structured too: the stages whose rows include one row of its own per
// coordinate (a unit-row level over variables no earlier stage mixed, with the basic variables'
// rows dense in split coordinates) take the structured QR, with the same answers.
TEST(Solver, SpanningStagesGiveTheStandardAnswer) {
  int checked = 0, spanned = 0, notSpanned = 0, sameActive = 0, structuredTaken = 0;
  for (std::uint64_t seed = 9000; seed < 9160; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int n = 8 + static_cast<int>(seed % 9), half = n / 2;
    Problem p = twoHalvesStart(seed, rng, n);
    for (int l = 0; l < 1 + static_cast<int>(seed % 3); ++l)
      addHalvesLevel(p, rng, 1 + static_cast<int>(rng() % 3), "t" + std::to_string(l));
    // Single-variable rows: over the first half (all of it, or some of it), then over the second
    // half, each row scaled; a duplicated row now and then; targets zero or not; some inequalities.
    const auto unitLevel = [&](const std::string& name, int from, int to, bool some) {
      std::vector<int> vars;
      for (int j = from; j < to; ++j)
        if (!some || rng() % 3 != 0) vars.push_back(j);
      if (!vars.empty() && rng() % 4 == 0) vars.push_back(vars[rng() % vars.size()]);
      if (vars.empty()) vars.push_back(from);
      const int rows = static_cast<int>(vars.size());
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, n);
      Eigen::VectorXd lo(rows), hi(rows);
      for (int i = 0; i < rows; ++i) {
        const double w = 0.01 + std::abs(u(rng));
        A(i, vars[static_cast<size_t>(i)]) = (rng() % 2) ? w : -w;
        lo(i) = (rng() % 2) ? 0.0 : 0.1 * u(rng);
        hi(i) = (rng() % 5 == 0) ? lo(i) + 0.05 : lo(i);
      }
      p.addLevel(name, A, lo, hi);
    };
    unitLevel("velocity", 0, half, seed % 4 == 0);
    unitLevel("wrench", half, n, seed % 5 == 0);
    for (const bool split : {false, true}) {
      Options standard;
      if (split) standard.split_from_variable = half;
      Solver s0;
      const Result r0 = solveOnce(s0, p, standard);
      ASSERT_EQ(r0.status, Status::Solved) << "seed " << seed;
      EXPECT_EQ(r0.spanning_stages, 0);
      for (const bool structured : {false, true}) {
        Options spanning = standard;
        spanning.spanning_stages = true;
        spanning.spanning_structured = structured;
        const std::string what = "seed " + std::to_string(seed) + (split ? " split" : "") + (structured ? " structured" : "");
        Solver s1;
        const Result r1 = solveOnce(s1, p, spanning);
        ASSERT_EQ(r1.status, Status::Solved) << what;
        if (!structured) {
          (r1.spanning_stages > 0 ? spanned : notSpanned)++;
          EXPECT_EQ(r1.structured_stages, 0) << what;
        }
        if (r1.structured_stages > 0) ++structuredTaken;
        EXPECT_LE(r1.structured_stages, r1.spanning_stages) << what;
        if (expectSameAnswer(p, r0, r1, spanning, what)) ++sameActive;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 640);
  EXPECT_GE(sameActive, 600);
  EXPECT_GE(spanned, 200);        // the wrench level, and often the velocity level, span what is left
  EXPECT_GE(structuredTaken, 5);  // a unit-row level over coordinates that no earlier stage mixed
  EXPECT_GE(notSpanned, 1);       // e.g. a level over some of its half only
}

// Options::spanning_structured on controller-shaped hierarchies (velocities, then forces, split
// coordinates, the minimum-velocity and minimum-wrench levels): where a stage takes the
// structured QR (the wrench level's, over forces no earlier stage mixed), the answers, violations and multipliers are those of the
// column-pivoted spanning stage to rounding, cold and warm, with a KKT certificate.
TEST(Solver, StructuredSpanningStagesGiveTheSameAnswer) {
  int checked = 0, structured = 0, sameActive = 0;
  for (std::uint64_t seed = 1; seed <= 400; ++seed) {
    Options o;
    const Problem p = test::controllerShapedProblem(seed, 40, 4, 6, o);
    o.spanning_stages = true;
    o.spanning_structured = false;
    Options on = o;
    on.spanning_structured = true;
    Solver a, b;
    const Result ra = solveOnce(a, p, o);
    const Result rb = solveOnce(b, p, on);
    const std::string what = "seed " + std::to_string(seed);
    ASSERT_EQ(ra.status, Status::Solved) << what;
    ASSERT_EQ(rb.status, Status::Solved) << what;
    EXPECT_EQ(ra.structured_stages, 0) << what;
    if (rb.structured_stages > 0) ++structured;
    if (expectSameAnswer(p, ra, rb, on, what)) ++sameActive;
    ++checked;
  }
  EXPECT_EQ(checked, 400);
  EXPECT_GE(sameActive, 380);
  EXPECT_GE(structured, 40);  // small stages often have more dense rows than half their coordinates
}

// A structured stage with dense rows, against the closed form. 2 velocities and 6 forces; the
// first level's 2 equalities over all 8 are eliminated with 2 forces as basic variables (split
// coordinates from variable 2); the velocities are then fixed by their level; the minimum-wrench
// level's rows are, in the stage's 4 force coordinates, 4 rows of their own and the 2 basic
// forces' dense rows (d = 4, p = 2). Its answer is the minimum-norm force f = E_f^T (E_f
// E_f^T)^-1 (b - E_v v), and the pivoted spanning stage's to rounding.
TEST(Solver, AStructuredStageWithDenseRowsGivesTheMinimumNormForces) {
  Problem p(8);
  Eigen::MatrixXd E(2, 8);
  E << 2.0, 0.5, 1.0, 0.25, -0.5, 0.75, 1.0, 0.5,  //
      -1.0, 2.0, 0.5, 1.0, 0.25, -0.75, 0.5, 1.0;
  const Eigen::Vector2d b(1.0, -0.5), v(0.3, -0.2);
  p.addLevel("eom", E, b, b);
  Eigen::MatrixXd V = Eigen::MatrixXd::Zero(2, 8);
  V(0, 0) = V(1, 1) = 1.0;
  p.addLevel("velocity", V, v, v);
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(6, 8);
  W.rightCols(6).setIdentity();
  p.addLevel("wrench", W, Eigen::VectorXd::Zero(6), Eigen::VectorXd::Zero(6));
  Options pivoted;
  pivoted.split_from_variable = 2;
  pivoted.spanning_stages = true;
  Options structured = pivoted;
  structured.spanning_structured = true;
  Solver a, s;
  const Result ra = solveOnce(a, p, pivoted);
  const Result rs = solveOnce(s, p, structured);
  ASSERT_EQ(ra.status, Status::Solved);
  ASSERT_EQ(rs.status, Status::Solved);
  EXPECT_TRUE(rs.split_applied);
  EXPECT_EQ(ra.structured_stages, 0);
  EXPECT_EQ(rs.spanning_stages, 2);
  EXPECT_EQ(rs.structured_stages, 2);  // the velocities' stage (no dense row) and the wrench's
  const Eigen::MatrixXd Ef = E.rightCols(6);
  const Eigen::VectorXd f = Ef.transpose() * (Ef * Ef.transpose()).ldlt().solve(b - E.leftCols(2) * v);
  EXPECT_LE((rs.x.head(2) - v).norm(), 1e-14);
  EXPECT_LE((rs.x.tail(6) - f).norm(), 1e-13 * (1 + f.norm())) << rs.x.tail(6).transpose() << " | " << f.transpose();
  expectSameAnswer(p, ra, rs, structured, "dense rows");
}

// A level of 5 dense rows over 3 variables with singular values 1, 0.5 and sv, then a minimum
// norm (the two tests below).
Problem denseLevelWithSingularValue(double sv) {
  Eigen::MatrixXd M(5, 3), N(3, 3);
  M << 1.0, 0.5, -0.25, 0.75, -1.0, 0.5, -0.5, 0.25, 1.0, 0.25, 0.75, -0.5, 1.0, -0.25, 0.75;
  N << 0.5, 1.0, -0.75, -1.0, 0.25, 0.5, 0.75, -0.5, 1.0;
  const Eigen::MatrixXd U = Eigen::HouseholderQR<Eigen::MatrixXd>(M).householderQ() * Eigen::MatrixXd::Identity(5, 3);
  const Eigen::MatrixXd Vt = (Eigen::HouseholderQR<Eigen::MatrixXd>(N).householderQ() * Eigen::MatrixXd::Identity(3, 3)).transpose();
  const Eigen::VectorXd t = (Eigen::VectorXd(5) << 0.5, -0.25, 1.0, 0.75, -0.5).finished();
  Problem p(3);
  p.addLevel("dense", U * Eigen::Vector3d(1.0, 0.5, sv).asDiagonal() * Vt, t, t);
  p.addLevel("min", Eigen::MatrixXd::Identity(3, 3), Eigen::VectorXd::Zero(3), Eigen::VectorXd::Zero(3));
  return p;
}

// Spanning stages of any rows follow the rank tolerance with several coordinates too: a level of
// 5 dense rows over 3 variables with singular values 1, 0.5 and s, then a minimum norm. With s =
// 1e-12 the standard factorisation finds rank 2 (rank_tolerance 1e-9) and the spanning stage is
// declined by its pivot test, so both find rank 2 and the same answer; with s = 1e-3 both find
// rank 3, and the level is a spanning stage.
TEST(Solver, SpanningStagesOfAnyRowsDeclineANearlyDeficientLevel) {
  for (const double sv : {1e-12, 1e-3}) {
    const Problem p = denseLevelWithSingularValue(sv);
    Options standard;
    standard.eliminate_first_level = false;
    Options unitOnly = standard;
    unitOnly.spanning_stages = true;
    Options any = unitOnly;
    any.spanning_any_rows = true;
    Solver s0, s1, s2;
    const Result r0 = solveOnce(s0, p, standard);
    const Result r1 = solveOnce(s1, p, unitOnly);
    const Result r2 = solveOnce(s2, p, any);
    const std::string what = "s " + std::to_string(sv);
    ASSERT_EQ(r0.status, Status::Solved) << what;
    ASSERT_EQ(r2.status, Status::Solved) << what;
    const int rank = sv > 1e-6 ? 3 : 2;
    EXPECT_EQ(r0.rank[0], rank) << what;
    EXPECT_EQ(r2.rank[0], rank) << what;
    // The dense level is a spanning stage only with spanning_any_rows, and only at full rank (the
    // minimum norm's unit rows span what is left at rank 2 either way).
    EXPECT_EQ(r2.spanning_stages - r1.spanning_stages, rank == 3 ? 1 : 0) << what;
    expectSameAnswer(p, r0, r2, any, what);
  }
}

// A declined spanning level is not tried again within its solve only: the same solver, given new
// data on which the level spans (the level above at s = 1e-3 after s = 1e-12), takes the spanning
// stage again, cold and warm, with the bits of a fresh solver.
TEST(Solver, ADeclinedSpanningLevelIsTriedAgainOnNewData) {
  const Problem deficient = denseLevelWithSingularValue(1e-12), full = denseLevelWithSingularValue(1e-3);
  Options any;
  any.eliminate_first_level = false;
  any.spanning_stages = true;
  any.spanning_any_rows = true;
  Options unitOnly = any;
  unitOnly.spanning_any_rows = false;
  Solver fresh, reused, u1, u2;
  const Result rf = solveOnce(fresh, full, any);
  const int spanned = rf.spanning_stages;
  ASSERT_EQ(rf.rank[0], 3);
  EXPECT_EQ(spanned - solveOnce(u1, full, unitOnly).spanning_stages, 1) << "the dense level spans at rank 3";
  const Result rd = solveOnce(reused, deficient, any);
  ASSERT_EQ(rd.rank[0], 2);
  EXPECT_EQ(rd.spanning_stages, solveOnce(u2, deficient, unitOnly).spanning_stages) << "declined at rank 2";
  const auto same = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
  };
  const Result cold = reused.solve(full);
  EXPECT_EQ(cold.spanning_stages, spanned);
  EXPECT_TRUE(same(cold.x, rf.x));
  reused.solve(deficient);
  const Result warm = reused.solve(full, reused.result().active, reused.result().x);
  const Result warmFresh = fresh.solve(full, rd.active, rd.x);
  EXPECT_EQ(warm.spanning_stages, warmFresh.spanning_stages);
  EXPECT_EQ(warm.spanning_stages, spanned);
  EXPECT_TRUE(same(warm.x, warmFresh.x));
}

// Options::spanning_any_rows: a level whose rows read several variables (as the controller's
// level of Newton rows over the velocities: as many rows as the coordinates of its part or more)
// is taken as a spanning stage too when it spans what is left to it. The answers, violations and
// multipliers are the standard factorisation's to rounding, with and without split coordinates,
// cold and warm, and the multipliers are a KKT certificate; such levels add spanning stages to
// those of the unit-row levels alone.
TEST(Solver, SpanningStagesOfAnyRowsGiveTheStandardAnswer) {
  int checked = 0, sameActive = 0, moreSpanned = 0;
  for (std::uint64_t seed = 9500; seed < 9660; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int n = 8 + static_cast<int>(seed % 9), half = n / 2;
    Problem p = twoHalvesStart(seed, rng, n);
    addHalvesLevel(p, rng, 1 + static_cast<int>(rng() % 3), "task");
    // Dense rows over the first half, some entries zero: half of them or more, equalities and
    // now and then an inequality, now and then a duplicated row.
    {
      const int rows = half + static_cast<int>(rng() % 3);
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, n);
      Eigen::VectorXd lo(rows), hi(rows);
      for (int i = 0; i < rows; ++i) {
        for (int j = 0; j < half; ++j) A(i, j) = (rng() % 4 == 0) ? 0.0 : u(rng);
        lo(i) = 0.1 * u(rng);
        hi(i) = (rng() % 6 == 0) ? lo(i) + 0.05 : lo(i);
      }
      if (rng() % 4 == 0) {
        A.row(rows - 1) = A.row(0);
        lo(rows - 1) = lo(0);
        hi(rows - 1) = hi(0);
      }
      p.addLevel("newton", A, lo, hi);
    }
    for (const auto& [name, from, to] : {std::tuple<const char*, int, int>{"velocity", 0, half}, {"wrench", half, n}}) {
      const int rows = to - from;
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, n);
      for (int i = 0; i < rows; ++i) A(i, from + i) = 0.01 + std::abs(u(rng));
      p.addLevel(name, A, Eigen::VectorXd::Zero(rows), Eigen::VectorXd::Zero(rows));
    }
    for (const bool split : {false, true}) {
      Options standard;
      if (split) standard.split_from_variable = half;
      Options unitOnly = standard;
      unitOnly.spanning_stages = true;
      Options any = unitOnly;
      any.spanning_any_rows = true;
      Solver s0, s1, s2;
      const Result r0 = solveOnce(s0, p, standard);
      const Result r1 = solveOnce(s1, p, unitOnly);
      const Result r2 = solveOnce(s2, p, any);
      const std::string what = "seed " + std::to_string(seed) + (split ? " split" : "");
      ASSERT_EQ(r0.status, Status::Solved) << what;
      ASSERT_EQ(r1.status, Status::Solved) << what;
      ASSERT_EQ(r2.status, Status::Solved) << what;
      if (r2.spanning_stages > r1.spanning_stages) ++moreSpanned;
      if (expectSameAnswer(p, r0, r2, any, what)) ++sameActive;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 320);
  EXPECT_GE(sameActive, 300);
  EXPECT_GE(moreSpanned, 100);  // the dense level spans the first half's coordinates left to it
}

// Spanning stages decide the stage's rank as the standard factorisation does, rank_tolerance
// included: a unit-row level whose only direction is covered by a component below the tolerance
// (x0 = 0 after x0 + c x1 = 1: the direction left is mostly x1) is rank 0 both ways, and the
// spanning stage is declined (its pivot test failed after its QR was formed: the standard
// factorisation then has the level's columns as they were); above the tolerance both determine
// x0. Cold and warm, with and without the elimination of the first level.
TEST(Solver, SpanningStagesFollowTheRankTolerance) {
  struct Case {
    double c, rankTol;
    int rank;
  };
  for (const Case cs : {Case{1e-5, 1e-4, 0}, Case{0.9e-6, 1e-6, 0}, Case{1e-5, 1e-9, 1}, Case{1e-7, 1e-9, 1}}) {
    for (const bool eliminate : {false, true}) {
      for (const int duplicates : {1, 4, -1, -4}) {
        // -1, -4: rows (1, 1.5 c), which read both variables, with spanning_any_rows; their
        // component along the direction left (about (-c, 1)) is about 0.5 c, as small.
        const int rows = std::abs(duplicates);
        const bool dense = duplicates < 0;
        Problem p(2);
        p.addLevel("first", mat(1, 2, {1.0, cs.c}), vec({1.0}), vec({1.0}));
        Eigen::MatrixXd U = Eigen::MatrixXd::Zero(rows, 2);
        U.col(0).setOnes();
        if (dense) U.col(1).setConstant(1.5 * cs.c);
        p.addLevel("unit", U, Eigen::VectorXd::Zero(rows), Eigen::VectorXd::Zero(rows));
        Options standard;
        standard.rank_tolerance = cs.rankTol;
        standard.eliminate_first_level = eliminate;
        Options spanning = standard;
        spanning.spanning_stages = true;
        spanning.spanning_any_rows = dense;
        Solver a, b;
        const Result ra = solveOnce(a, p, standard);
        const Result rb = solveOnce(b, p, spanning);
        const std::string what = "c " + std::to_string(cs.c) + " rank_tolerance " + std::to_string(cs.rankTol) +
                                 (eliminate ? " eliminated" : "") + " rows " + std::to_string(rows) + (dense ? " dense" : "");
        ASSERT_EQ(ra.status, Status::Solved) << what;
        ASSERT_EQ(rb.status, Status::Solved) << what;
        EXPECT_EQ(ra.rank[1], cs.rank) << what;
        EXPECT_EQ(rb.rank[1], cs.rank) << what;
        EXPECT_LE((rb.x - ra.x).norm(), 1e-9 * (1 + ra.x.norm())) << what;
        if (cs.rank == 0) {
          EXPECT_EQ(rb.spanning_stages, 0) << what;
        }
        // A component of 5e-6 passes the spanning test at rank_tolerance 1e-9 (5e-8 does not).
        if (dense && cs.c == 1e-5 && cs.rankTol == 1e-9) {
          EXPECT_EQ(rb.spanning_stages, 1) << what;
        }
        // A tolerance above the certificate's own leaves a component of 1e-5 unresolved on purpose.
        if (cs.rankTol <= 1e-9) {
          EXPECT_EQ(checkKkt(p, rb), "") << what;
        }
        const Result wb = b.solve(p, rb.active, rb.x);
        EXPECT_LE((wb.x - ra.x).norm(), 1e-9 * (1 + ra.x.norm())) << what << " (warm)";
      }
    }
  }
}

// Split coordinates (Options::split_from_variable): a first level of equalities over all the
// variables, eliminated with its basic variables taken from the second half when they are well
// conditioned, later levels over the first half, the second half or both, and a last level over
// all. The answer, the level violations and the multipliers are those of the plain solver, cold
// and warm-started, over the many restarts of inequality levels and bound changes; a split index
// beyond the variables (no preferred pivot) and preferred pivots that need large multipliers
// fall back to the plain elimination.
TEST(Solver, SplitCoordinatesGiveThePlainAnswer) {
  int checked = 0, applied = 0;
  for (std::uint64_t seed = 8000; seed < 8120; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int n = 8 + static_cast<int>(seed % 9), half = n / 2;
    Problem p = twoHalvesStart(seed, rng, n);
    for (int l = 0; l < 3 + static_cast<int>(seed % 3); ++l)
      addHalvesLevel(p, rng, 1 + static_cast<int>(rng() % 4), "l" + std::to_string(l));
    appendMinNorm(p);
    Options split;
    split.split_from_variable = half;
    Options none;
    none.split_from_variable = n + 5;  // no preferred variable: the plain elimination
    Solver s0, s1, s2;
    const Result r0 = solveOnce(s0, p);
    const Result r1 = solveOnce(s1, p, split);
    const Result r2 = solveOnce(s2, p, none);
    ASSERT_EQ(r0.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(r1.status, Status::Solved) << "seed " << seed;
    EXPECT_FALSE(r0.split_applied);
    applied += r1.split_applied ? 1 : 0;
    EXPECT_FALSE(r2.split_applied) << "seed " << seed;
    EXPECT_LE((r1.x - r0.x).norm(), 1e-9 * (1 + r0.x.norm())) << "seed " << seed;
    for (int l = 0; l < p.levelCount(); ++l)
      EXPECT_NEAR(r1.violation_norm(l), r0.violation_norm(l), 1e-9 * (1 + r0.violation_norm(l))) << "seed " << seed;
    EXPECT_LE((r1.lambda - r0.lambda).norm(), 1e-7 * (1 + r0.lambda.norm())) << "seed " << seed;
    EXPECT_EQ(checkKkt(p, r1), "") << "seed " << seed;
    ASSERT_EQ(r2.status, Status::Solved) << "seed " << seed;
    EXPECT_LE((r2.x - r0.x).norm(), 1e-9 * (1 + r0.x.norm())) << "seed " << seed;
    // Warm-started from the plain answer's active set.
    Solver w;
    w.setup(p, split);
    w.solve(p, r0.active, r0.x);
    EXPECT_LE((w.result().x - r0.x).norm(), 1e-9 * (1 + r0.x.norm())) << "seed " << seed;
    ++checked;
  }
  EXPECT_EQ(checked, 120);
  EXPECT_GE(applied, 100);  // the preferred elimination was taken (the rest: a bound fixed a preferred pivot)
  // Preferred variables that would need large multipliers (threshold pivoting): the plain
  // elimination instead, with the same answer.
  {
    Problem q(4);
    q.addLevel("eq", mat(1, 4, {1, 1, 1e-5, 1e-5}), vec({1}), vec({1}));  // pivots pass, multipliers 1e5 do not
    q.addLevel("t", mat(2, 4, {1, 0, 0, 0, 0, 0, 1, 0}), vec({0.3, 0.2}), vec({0.3, 0.2}));
    appendMinNorm(q);
    Options o;
    o.split_from_variable = 2;
    Solver sa, sb;
    const Result ra = solveOnce(sa, q);
    const Result& rb = solveOnce(sb, q, o);
    EXPECT_FALSE(rb.split_applied);
    EXPECT_LE((rb.x - ra.x).norm(), 1e-12);
    o.split_from_variable = 1;  // variable 1 has a large coefficient: taken
    Solver sc;
    EXPECT_TRUE(solveOnce(sc, q, o).split_applied);
  }
  Options bad;
  bad.split_from_variable = -2;
  EXPECT_THROW(bad.validate(), InputError);
}

// Options::restart_after_bound_change on controller-shaped problems: a first level of equalities
// over all the variables, "forces" x_j >= f_min as a bounds level on the second half, task levels
// over the first half (mostly declared velocity-only, as the controller declares its geometric
// tasks), then minimum velocity and minimum wrench levels projected as the controller's (or a
// wrench level and a minimum norm), solved with split coordinates. The active-set search fixes
// many forces at their bound one at a time, basic ones included, and a warm start from a
// perturbed active set frees and fixes them again. With the option such changes restart after
// the stages they cannot alter: the answers, violations and multipliers are those of the option
// off to rounding, with the same active sets and iteration counts, cold and warm; the multipliers
// are a KKT certificate; and the work counted (Result::factorizations) is smaller where a restart
// was taken.
TEST(Solver, RestartsAfterABoundChangeGiveTheFullRestartsAnswer) {
  int checked = 0, fewer = 0, sameActive = 0, fixes = 0;
  for (std::uint64_t seed = 8300; seed < 8500; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int nv = 4 + static_cast<int>(seed % 7), nf = 6 + static_cast<int>(seed % 11), n = nv + nf;
    Problem p(n);
    {
      std::vector<int> vars;
      for (int j = nv; j < n; ++j) vars.push_back(j);
      const Eigen::VectorXd c = Eigen::VectorXd::Ones(nf), lo = Eigen::VectorXd::Constant(nf, 0.01);
      p.addBoundsLevel("force bounds", vars, c, lo, Eigen::VectorXd::Constant(nf, kInf));
    }
    addScaledEqualities(p, rng, 1 + static_cast<int>(seed % 3), nv, 2.0, "dynamics");
    for (int l = 0; l < 2 + static_cast<int>(seed % 3); ++l) {
      const int rows = 1 + static_cast<int>(rng() % 3);
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, n);
      A.leftCols(nv) = Eigen::MatrixXd::NullaryExpr(rows, nv, [&]() { return u(rng); });
      Eigen::VectorXd lo(rows), hi(rows);
      for (int i = 0; i < rows; ++i) {
        lo(i) = u(rng);
        hi(i) = (rng() % 2) ? lo(i) : lo(i) + 0.5;
      }
      p.addLevel("task " + std::to_string(l), A, lo, hi);
      if (seed % 3 != 0) p.setLevelColumns(p.levelCount() - 1, nv);  // velocity-only, declared as the controller does
    }
    // Now and then an inequality level over pairs of forces (as friction cones read forces),
    // before the projected levels: its restart snapshots hold rows at force coordinates.
    if (seed % 5 == 0) {
      const int rows = std::max(1, nf / 2);
      Eigen::MatrixXd F = Eigen::MatrixXd::Zero(rows, n);
      for (int i = 0; i < rows; ++i) {
        F(i, nv + (2 * i) % nf) = 1.0;
        F(i, nv + (2 * i + 1) % nf) = -0.5 - 0.5 * std::abs(u(rng));
      }
      p.addLevel("force pairs", F, Eigen::VectorXd::Constant(rows, -0.02), Eigen::VectorXd::Constant(rows, kInf));
    }
    // As the controller's last levels: minimum velocity (unit rows on the velocities) and minimum
    // wrench (unit rows on the forces), both projected (project_unit_suffix); or, a quarter of the
    // time, the wrench level and a minimum norm over everything.
    const bool controllerLike = seed % 4 != 0;
    test::appendRegularisationLevels(p, nv, controllerLike);
    Options on;
    on.split_from_variable = nv;
    on.lazy_snapshots = seed % 2 == 0;
    on.project_unit_suffix = controllerLike;
    on.spanning_stages = seed % 3 == 1;
    Options off = on;
    off.restart_after_bound_change = false;
    Solver s0, s1;
    const Result r0 = solveOnce(s0, p, off);
    const Result r1 = solveOnce(s1, p, on);
    ASSERT_EQ(r0.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(r1.status, Status::Solved) << "seed " << seed;
    for (const RowState st : r1.active.level[0]) fixes += st != RowState::Inactive ? 1 : 0;
    EXPECT_LE((r1.x - r0.x).norm(), 1e-9 * (1 + r0.x.norm())) << "seed " << seed;
    for (int l = 0; l < p.levelCount(); ++l)
      EXPECT_NEAR(r1.violation_norm(l), r0.violation_norm(l), 1e-9 * (1 + r0.violation_norm(l))) << "seed " << seed;
    if (r1.active.level == r0.active.level) {
      EXPECT_LE((r1.lambda - r0.lambda).norm(), 1e-7 * (1 + r0.lambda.norm())) << "seed " << seed;
      EXPECT_EQ(r1.iterations, r0.iterations) << "seed " << seed;
      ++sameActive;
    }
    EXPECT_EQ(checkKkt(p, r1), "") << "seed " << seed;
    EXPECT_LE(r1.factorizations, r0.factorizations) << "seed " << seed;
    fewer += r1.factorizations < r0.factorizations ? 1 : 0;
    // Warm-started from a perturbed answer's active set: releases and fixes again.
    ActiveSet warm = r0.active;
    for (size_t r = 0; r < warm.level[0].size(); r += 2) warm.level[0][r] = RowState::Inactive;
    Solver w0, w1;
    w0.setup(p, off);
    w1.setup(p, on);
    const Result& a = w0.solve(p, warm, r0.x);
    const Result& b = w1.solve(p, warm, r0.x);
    EXPECT_LE((b.x - a.x).norm(), 1e-9 * (1 + a.x.norm())) << "seed " << seed << " (warm)";
    EXPECT_EQ(checkKkt(p, b), "") << "seed " << seed << " (warm)";
    ++checked;
  }
  EXPECT_EQ(checked, 200);
  EXPECT_GE(sameActive, 195);
  EXPECT_GE(fixes, 1000);  // forces held at their bound in the answers
  EXPECT_GE(fewer, 180);   // the restart after the stages a fix leaves unchanged was taken
}

// A bound whose variable an earlier level's row also holds alone, at the same value (a force at
// its floor of 0 and a minimum-wrench target of 0, before a minimum-norm level): the bound's
// multiplier for the last level has the wrong sign where the factorisation gives it all, but the
// wrench row can carry it, so the bound is not released (releasing it would move nothing), and
// the reported multipliers pass it to that row: a valid certificate with the bound at zero.
TEST(Solver, ABoundThatAnEarlierRowHoldsAloneIsNotReleased) {
  Problem p(2);
  p.addBoundsLevel("floor", {1}, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, kInf));
  Eigen::MatrixXd E(1, 2);
  E << 1.0, 1.0;
  p.addLevel("dynamics", E, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(1));
  Eigen::MatrixXd W(1, 2);
  W << 0.0, 2.0;
  p.addLevel("wrench", W, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1));
  appendMinNorm(p);
  ActiveSet start;
  start.level = {{RowState::Lower}, {RowState::Equality}, {RowState::Equality}, {RowState::Equality, RowState::Equality}};
  Solver s;
  s.setup(p);
  const Result& r = s.solve(p, start, Eigen::Vector2d(1.0, 0.0));
  ASSERT_EQ(r.status, Status::Solved);
  EXPECT_EQ(r.x, Eigen::Vector2d(1.0, 0.0));
  EXPECT_EQ(r.active.level[0][0], RowState::Lower);  // held, not released
  EXPECT_EQ(r.deactivations, 0);
  EXPECT_EQ(r.iterations, 1);
  EXPECT_EQ(checkKkt(p, r), "");
  // The last level's multipliers: the bound's passed to the wrench row (a_w = 2).
  const int last = p.levelCount() - 1;
  EXPECT_EQ(r.lambda(0, last), 0.0);
  EXPECT_NE(r.lambda(2, last), 0.0);
}

// An inequality row that reads the variable alone holds a bound only when its multiplier keeps its
// correct sign after taking the bound's: x0 >= 0 as a bound and as an earlier row (held at the
// same value), then a target x0 = 1. Both push the same way, so neither can carry the other's
// wrong sign: the bound and the row are released and x0 reaches 1. Also with the row written as
// -x0 <= 0 (held at its upper bound).
TEST(Solver, AnInequalityRowHoldsABoundOnlyWithItsCorrectSign) {
  for (const double a : {1.0, -1.0}) {
    Problem p(1);
    p.addBoundsLevel("floor", {0}, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, kInf));
    p.addLevel("holder", Eigen::MatrixXd::Constant(1, 1, a), Eigen::VectorXd::Constant(1, a > 0 ? 0.0 : -kInf),
               Eigen::VectorXd::Constant(1, a > 0 ? kInf : 0.0));
    p.addLevel("target", Eigen::MatrixXd::Ones(1, 1), Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(1));
    ActiveSet start;
    start.level = {{RowState::Lower}, {a > 0 ? RowState::Lower : RowState::Upper}, {RowState::Equality}};
    Solver s;
    s.setup(p);
    const Result& r = s.solve(p, start, Eigen::VectorXd::Zero(1));
    ASSERT_EQ(r.status, Status::Solved) << "a = " << a;
    EXPECT_EQ(r.x(0), 1.0) << "a = " << a;
    EXPECT_EQ(checkKkt(p, r), "") << "a = " << a;
  }
}

// The holding row must be satisfied on its own scale: here x0 = 1e6 would hide, in the scale of
// the whole x, the residual 5e-5 of the row x1 = 5e-5 while x1 sits at its floor 0. That row's
// level can still be met by releasing the bound, so the bound is released: x1 = 5e-5, the
// lexicographic optimum.
TEST(Solver, ARowHoldsABoundOnlyWhenSatisfiedOnItsOwnScale) {
  for (const double big : {1.0, 1e6}) {
    Problem p(2);
    p.addBoundsLevel("floor", {1}, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, kInf));
    Eigen::MatrixXd B(1, 2), H(1, 2);
    B << 1.0, 0.0;
    H << 0.0, 1.0;
    p.addLevel("big", B, Eigen::VectorXd::Constant(1, big), Eigen::VectorXd::Constant(1, big));
    p.addLevel("holder", H, Eigen::VectorXd::Constant(1, 5e-5), Eigen::VectorXd::Constant(1, 5e-5));
    p.addLevel("target", H, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(1));
    ActiveSet start;
    start.level = {{RowState::Lower}, {RowState::Equality}, {RowState::Equality}, {RowState::Equality}};
    Solver s;
    s.setup(p);
    const Result& r = s.solve(p, start, Eigen::Vector2d(big, 0.0));
    ASSERT_EQ(r.status, Status::Solved) << "big = " << big;
    EXPECT_NEAR(r.x(1), 5e-5, 1e-18) << "big = " << big;
    EXPECT_EQ(r.violation_norm(2), 0.0) << "big = " << big;
    EXPECT_EQ(checkKkt(p, r), "") << "big = " << big;
  }
}

// The same situation in controller-shaped hierarchies (tests/support/reference.hpp,
// controllerShapedProblem) made a warm start cycle: released, the bound moved nothing, rounding
// made it block again, and the search ran to the hard cap of 1000 iterations. These seeds did
// (lexdyn-solver-sweep --controller-shaped found them); warm from the cold answer's active set
// with every second bound released, each is now solved in a few iterations, with the cold
// answer's violations and a valid certificate.
TEST(Solver, AWarmStartDoesNotCycleOnABoundThatAnEarlierRowHolds) {
  for (const std::uint64_t seed : {4596ULL, 6822ULL, 8073ULL, 9362ULL, 15628ULL, 16283ULL, 16513ULL, 17807ULL, 18547ULL}) {
    Options o;
    const Problem p = test::controllerShapedProblem(seed, 12, 7, 8, o);
    Solver cold, warm;
    const Result r = solveOnce(cold, p, o);
    ASSERT_EQ(r.status, Status::Solved) << "seed " << seed;
    ActiveSet start = r.active;
    for (size_t i = 0; i < start.level[0].size(); i += 2) start.level[0][i] = RowState::Inactive;
    warm.setup(p, o);
    const Result& w = warm.solve(p, start, r.x);
    EXPECT_EQ(w.status, Status::Solved) << "seed " << seed;
    EXPECT_LE(w.iterations, 20) << "seed " << seed;
    EXPECT_EQ(checkKkt(p, w), "") << "seed " << seed;
    for (int l = 0; l < p.levelCount(); ++l)
      EXPECT_NEAR(w.violation_norm(l), r.violation_norm(l), 1e-9 * (1 + r.violation_norm(l))) << "seed " << seed << " level " << l;
  }
}

// A restart after a fixed variable keeps rows without loading them again. A row that read the
// fixed variable and one other free variable is a unit row from then on, and a spanning stage
// takes it as a full factorisation does (tests/data/solver/restart_unit_row.json: 7 variables,
// split coordinates from 3, spanning stages, a projected unit suffix; its wrench row x3 + x6 = 0
// becomes a unit row when the search fixes x3). The same active set, iterations and bits of x as
// without the restarts, in fewer factorised stages.
TEST(Solver, ARestartAfterAFixKeepsAFullFactorisationsSpanningStages) {
  const ProblemFile file = readProblemFile(std::string(LEXDYN_SOURCE_DIR) + "/tests/data/solver/restart_unit_row.json");
  Problem p = file.problem;
  ASSERT_TRUE(p.detectBoundsLevel());
  ASSERT_TRUE(file.options.has_value());
  Options on = *file.options;
  on.restart_after_bound_change = true;
  Options off = on;
  off.restart_after_bound_change = false;
  Solver a, b;
  const Result ra = solveOnce(a, p, on);
  const Result rb = solveOnce(b, p, off);
  ASSERT_EQ(ra.status, Status::Solved);
  ASSERT_EQ(rb.status, Status::Solved);
  EXPECT_EQ(ra.active.level, rb.active.level);
  EXPECT_EQ(ra.iterations, rb.iterations);
  EXPECT_EQ(ra.spanning_stages, rb.spanning_stages);
  EXPECT_GT(ra.spanning_stages, 0);
  for (int i = 0; i < p.variables(); ++i) EXPECT_EQ(ra.x(i), rb.x(i)) << "x[" << i << "]";
  EXPECT_LT(ra.factorizations, rb.factorizations);
  EXPECT_EQ(checkKkt(p, ra), "");
}

TEST(Solver, ProjectedLastLevelGivesTheStandardAnswer) {
  // A large last level (minimum norm over all variables) after a few small ones: Auto projects
  // it onto the null space left by the earlier levels; the answer, the multipliers and the
  // residuals are those of the standard factorisation.
  GenOptions g;
  g.maxRows = 3;
  g.inequalities = true;
  int projected = 0;
  for (std::uint64_t seed = 5000; seed < 5100; ++seed) {
    g.n = 8 + static_cast<int>(seed % 9);
    g.levels = 2 + static_cast<int>(seed % 4);
    Problem p = randomProblem(seed, g);
    appendMinNorm(p);
    Options never;
    never.last_level_projection = Options::LastLevel::Never;
    Solver s1, s2;
    const Result r1 = solveOnce(s1, p, never);
    const Result& r2 = solveOnce(s2, p);
    ASSERT_EQ(r1.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(r2.status, Status::Solved) << "seed " << seed;
    EXPECT_FALSE(r1.last_level_projected);
    projected += r2.last_level_projected ? 1 : 0;
    EXPECT_LE((r2.x - r1.x).norm(), 1e-9 * (1 + r1.x.norm())) << "seed " << seed;
    for (int l = 0; l < p.levelCount(); ++l)
      EXPECT_NEAR(r2.violation_norm(l), r1.violation_norm(l), 1e-9 * (1 + r1.violation_norm(l))) << "seed " << seed;
    EXPECT_LE((r2.lambda - r1.lambda).norm(), 1e-7 * (1 + r1.lambda.norm())) << "seed " << seed;
    EXPECT_EQ(checkKkt(p, r2), "") << "seed " << seed;
  }
  EXPECT_GE(projected, 90);
  // A last level smaller than the null space left to it is not projected by Auto.
  Problem q(6);
  q.addLevel("a", mat(1, 6, {1, 1, 0, 0, 0, 0}), vec({1}), vec({1}));
  q.addLevel("b", mat(1, 6, {0, 0, 1, 0, 0, 0}), vec({2}), vec({2}));
  q.addLevel("c", mat(2, 6, {0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0}), vec({-1, -1}), vec({1, 1}));
  Solver s3;
  EXPECT_FALSE(solveOnce(s3, q).last_level_projected);
  Options always;
  always.last_level_projection = Options::LastLevel::Always;
  Solver s4;
  const Result& r4 = solveOnce(s4, q, always);
  EXPECT_TRUE(r4.last_level_projected);
  EXPECT_EQ(checkKkt(q, r4), "");
}

// Box centres c uniform in [-1, 1], targets 0.6 from them on a random side (outside a box of
// half-width 0.2), and the same with every other target at its centre: the unit levels of the
// projected-suffix tests.
struct BoxTargets {
  Eigen::VectorXd c, outside, half;
};
BoxTargets boxTargets(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  BoxTargets b{Eigen::VectorXd(n), Eigen::VectorXd(n), Eigen::VectorXd(n)};
  for (int j = 0; j < n; ++j) {
    b.c(j) = u(rng);
    b.outside(j) = b.c(j) + (u(rng) < 0.0 ? -0.6 : 0.6);
    b.half(j) = j % 2 == 0 ? b.c(j) : b.outside(j);
  }
  return b;
}

// Their last three levels: a dense one, the box (half-width 0.2 around c) and the targets t.
void addDenseBoxTarget(Problem& p, const Eigen::MatrixXd& D, const Eigen::VectorXd& d, const Eigen::VectorXd& c, const Eigen::VectorXd& t) {
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(p.variables(), p.variables());
  p.addLevel("dense", D, d, d);
  p.addLevel("box", I, c.array() - 0.2, c.array() + 0.2);
  p.addLevel("target", I, t, t);
}

TEST(Solver, ProjectedUnitSuffixGivesTheStandardAnswer) {
  // A box level (unit inequality rows l_j <= x_j <= u_j) and a target level (x_j = t_j, most
  // targets outside the box) after a few small random levels and a dense one: the shape of the
  // controller's minimum-velocity and minimum-wrench levels. Solved cold with lazy snapshots, the
  // box rows enter the active set one blocking step after another, the first restart decides the
  // projections anew and Options::project_unit_suffix projects both levels; later restarts begin
  // inside the projected suffix. Then warm, with half the targets moved inside the box. The
  // answer and the residuals are those of the standard factorisation (both projections off), and
  // the KKT certificate holds. (A wrong column offset of the projected rows and trailing updates
  // that still reach the projected level fail here; the second part below catches multipliers
  // read from a projected level's unformed rows, a wrong raw-row index, a wrong column offset in
  // the pivot swaps and a wrong projection of a zero row.)
  GenOptions g;
  g.maxRows = 3;
  g.inequalities = true;
  int suffix = 0, restarted = 0;
  for (std::uint64_t seed = 7000; seed < 7150; ++seed) {
    g.n = 8 + static_cast<int>(seed % 9);
    g.levels = 2 + static_cast<int>(seed % 4);
    const Problem base = randomProblem(seed, g);
    const int n = base.variables();
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const BoxTargets bt = boxTargets(n, rng);
    const Eigen::VectorXd &c = bt.c, &outside = bt.outside, &half = bt.half;
    // A dense level takes all but three dimensions, so that a few active box rows outnumber
    // what is left to them (the row-count test of the projection).
    Eigen::MatrixXd D(n - 3, n);
    for (int i = 0; i < n - 3; ++i)
      for (int j = 0; j < n; ++j) D(i, j) = u(rng);
    Eigen::VectorXd d(n - 3);
    for (int i = 0; i < n - 3; ++i) d(i) = u(rng);
    auto withTargets = [&](const Eigen::VectorXd& t) {
      Problem p = base;
      addDenseBoxTarget(p, D, d, c, t);
      return p;
    };
    const Problem p1 = withTargets(outside), p2 = withTargets(half);
    Options standard, on;
    standard.last_level_projection = Options::LastLevel::Never;
    on.project_unit_suffix = true;
    // Cold: box rows enter the active set one blocking step after another. With lazy snapshots
    // the first restart factorises from the first level again and decides the projections anew,
    // with the box rows active by then; the later restarts begin inside the projected suffix.
    on.lazy_snapshots = true;
    Solver s1, s2;
    const Result r1 = solveOnce(s1, p1, standard);
    const Result r2 = solveOnce(s2, p1, on);
    ASSERT_EQ(r1.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(r2.status, Status::Solved) << "seed " << seed;
    // Warm from the optimum with half the targets inside the box.
    Solver s3;
    s3.setup(p2, on);
    const Result r3 = s3.solve(p2, r2.active, r2.x);
    Solver s4;
    const Result r4 = solveOnce(s4, p2, standard);
    ASSERT_EQ(r3.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(r4.status, Status::Solved) << "seed " << seed;
    EXPECT_LE((r3.x - r4.x).norm(), 1e-9 * (1 + r4.x.norm())) << "warm, seed " << seed;
    EXPECT_EQ(checkKkt(p2, r3), "") << "warm, seed " << seed;
    suffix += r2.projected_levels == 2 ? 1 : 0;
    restarted += r2.projected_levels == 2 && r2.factorizations > 2 * p1.levelCount() ? 1 : 0;
    EXPECT_LE((r2.x - r1.x).norm(), 1e-9 * (1 + r1.x.norm())) << "seed " << seed;
    for (int l = 0; l < p1.levelCount(); ++l)
      EXPECT_NEAR(r2.violation_norm(l), r1.violation_norm(l), 1e-9 * (1 + r1.violation_norm(l))) << "seed " << seed;
    EXPECT_EQ(checkKkt(p1, r1), "") << "standard, seed " << seed;
    EXPECT_EQ(checkKkt(p1, r2), "") << "seed " << seed;
  }
  EXPECT_GE(suffix, 100);
  EXPECT_GE(restarted, 100);
  // lexdyn-solver-sweep's problems with unit levels (--unit-levels 0.5), the controller's other
  // options on: the KKT certificate holds, and each level's violation is the standard
  // factorisation's. Seeds 12648 and 13223 are among those whose multipliers came out wrong
  // while the multipliers of a later level read a projected level's unformed leading rows (an
  // earlier stage for them) instead of its raw rows.
  Options ctl, plain;
  ctl.spanning_stages = true;
  ctl.lazy_snapshots = true;
  ctl.project_unit_suffix = true;
  plain.last_level_projection = Options::LastLevel::Never;
  int sweepSuffix = 0;
  std::vector<std::uint64_t> seeds = {12648, 13223, 17053, 21805, 25734};
  for (std::uint64_t seed = 1; seed <= 3000; ++seed) seeds.push_back(seed);
  for (std::uint64_t seed : seeds) {
    GenOptions sg = test::sweepOptions(seed, 12, 7, 8);
    sg.pUnitLevel = 0.5;
    const Problem p = randomProblem(seed, sg);
    Solver sv, sp;
    const Result r = solveOnce(sv, p, ctl);
    const Result& rp = solveOnce(sp, p, plain);
    ASSERT_EQ(r.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(rp.status, Status::Solved) << "seed " << seed;
    sweepSuffix += r.projected_levels == 2 ? 1 : 0;
    EXPECT_EQ(checkKkt(p, r), "") << "seed " << seed;
    for (int l = 0; l < p.levelCount(); ++l)
      EXPECT_NEAR(r.violation_norm(l), rp.violation_norm(l), 1e-8 * (1 + rp.violation_norm(l))) << "seed " << seed;
  }
  EXPECT_GE(sweepSuffix, 300);
}

TEST(Solver, ProjectedUnitSuffixOnBasicVariablesGivesTheStandardAnswer) {
  // An equality first level that the elimination takes (its basic variables among every
  // variable's box and target rows), a dense level that leaves three dimensions, then the box
  // and the target levels over every variable. With the suffix projected, a box or target row on
  // a basic variable is a column of D^T in reduced coordinates plus its basic part, projected like
  // the last level's rows. Lower bounds on every third variable, tighter than its box, are
  // reached on the way: each fixes a variable, the elimination is brought to the new free
  // variables and the projections are decided again, by then with box rows active (in most cold
  // solves both levels are projected and a bound is held at the end). Cold, and warm with half
  // the targets inside the box, where the warm start's active box rows make both projections
  // pay: the answer and every level's violation are the standard factorisation's, and the KKT
  // certificate holds.
  int suffix = 0, boundHeld = 0;
  for (std::uint64_t seed = 7200; seed < 7320; ++seed) {
    const int n = 8 + static_cast<int>(seed % 9);
    const int m0 = 2 + static_cast<int>(seed % 3);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto random = [&](int rows, int cols) {
      Eigen::MatrixXd M(rows, cols);
      for (int i = 0; i < rows; ++i)
        for (int j = 0; j < cols; ++j) M(i, j) = u(rng);
      return M;
    };
    const Eigen::MatrixXd E = random(m0, n), D = random(n - m0 - 3, n);
    const Eigen::VectorXd e = random(m0, 1), d = random(n - m0 - 3, 1);
    const BoxTargets bt = boxTargets(n, rng);
    const Eigen::VectorXd &c = bt.c, &outside = bt.outside, &half = bt.half;
    const auto withTargets = [&](const Eigen::VectorXd& t) {
      Problem p(n);
      std::vector<int> vars;
      for (int j = 0; j < n; j += 3) vars.push_back(j);
      const int nb = static_cast<int>(vars.size());
      Eigen::VectorXd lo(nb), up = Eigen::VectorXd::Constant(nb, std::numeric_limits<double>::infinity());
      for (int q = 0; q < nb; ++q) lo(q) = c(vars[static_cast<size_t>(q)]) - 0.1;
      p.addBoundsLevel("bounds", vars, Eigen::VectorXd::Ones(nb), lo, up);
      p.addLevel("equation", E, e, e);
      addDenseBoxTarget(p, D, d, c, t);
      return p;
    };
    const Problem p1 = withTargets(outside), p2 = withTargets(half);
    Options standard, on;
    standard.eliminate_first_level = on.eliminate_first_level = true;
    standard.last_level_projection = Options::LastLevel::Never;
    on.project_unit_suffix = true;
    on.lazy_snapshots = false;
    Solver s1, s2, s3, s4;
    const Result r1 = solveOnce(s1, p1, standard);
    const Result r2 = solveOnce(s2, p1, on);
    ASSERT_EQ(r1.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(r2.status, Status::Solved) << "seed " << seed;
    EXPECT_LE((r2.x - r1.x).norm(), 1e-9 * (1 + r1.x.norm())) << "seed " << seed;
    for (int l = 0; l < p1.levelCount(); ++l)
      EXPECT_NEAR(r2.violation_norm(l), r1.violation_norm(l), 1e-9 * (1 + r1.violation_norm(l))) << "seed " << seed;
    EXPECT_EQ(checkKkt(p1, r2), "") << "seed " << seed;
    s3.setup(p2, on);
    const Result r3 = s3.solve(p2, r2.active, r2.x);
    const Result r4 = solveOnce(s4, p2, standard);
    ASSERT_EQ(r3.status, Status::Solved) << "seed " << seed;
    ASSERT_EQ(r4.status, Status::Solved) << "seed " << seed;
    EXPECT_LE((r3.x - r4.x).norm(), 1e-9 * (1 + r4.x.norm())) << "warm, seed " << seed;
    EXPECT_EQ(checkKkt(p2, r3), "") << "warm, seed " << seed;
    suffix += r3.projected_levels == 2 ? 1 : 0;  // (the warm start's box rows make projection pay)
    int held = 0;
    for (RowState st : r2.active.level[0]) held += st != RowState::Inactive ? 1 : 0;
    boundHeld += r2.projected_levels == 2 && held > 0 ? 1 : 0;
  }
  EXPECT_GE(suffix, 100);
  EXPECT_GE(boundHeld, 50);
}

TEST(Solver, ScalingPermutingAndAppendingKeepEarlierOptima) {
  GenOptions g;
  for (std::uint64_t seed = 3000; seed < 3100; ++seed) {
    g.n = 4 + static_cast<int>(seed % 6);
    g.levels = 3;
    const Problem p = randomProblem(seed, g);
    Solver s0;
    const Result r0 = solveOnce(s0, p);
    ASSERT_EQ(r0.status, Status::Solved);
    const int L = p.levelCount();
    const int gl = L - 2;  // a general level in the middle
    // Scale a level by -3: violations scale by 3, the rest is unchanged.
    {
      Problem q = p;
      Level& lv = q.level(gl);
      lv.A *= -3.0;
      Eigen::VectorXd lo = -3.0 * lv.upper, up = -3.0 * lv.lower;
      lv.lower = lo;
      lv.upper = up;
      Solver s;
      const Result& r = solveOnce(s, q);
      for (int l = 0; l < L; ++l) {
        const double f = (l == gl) ? 3.0 : 1.0;
        EXPECT_NEAR(r.violation_norm(l), f * r0.violation_norm(l), 1e-7 * (1 + r0.violation_norm(l))) << "seed " << seed;
      }
    }
    // Permute the rows of a level.
    {
      Problem q = p;
      Level& lv = q.level(gl);
      const int m = lv.rows();
      Eigen::MatrixXd A = lv.A;
      Eigen::VectorXd lo = lv.lower, up = lv.upper;
      for (int i = 0; i < m; ++i) {
        lv.A.row(i) = A.row(m - 1 - i);
        lv.lower(i) = lo(m - 1 - i);
        lv.upper(i) = up(m - 1 - i);
      }
      Solver s;
      const Result& r = solveOnce(s, q);
      for (int l = 0; l < L; ++l)
        EXPECT_NEAR(r.violation_norm(l), r0.violation_norm(l), 1e-7 * (1 + r0.violation_norm(l))) << "seed " << seed;
    }
    // Append a level.
    {
      Problem q = p;
      const Problem extra = randomProblem(seed + 99, g);
      const Level& e = extra.level(extra.levelCount() - 1);
      q.addLevel("appended", e.A, e.lower, e.upper);
      Solver s;
      const Result& r = solveOnce(s, q);
      for (int l = 0; l < L; ++l)
        EXPECT_NEAR(r.violation_norm(l), r0.violation_norm(l), 1e-7 * (1 + r0.violation_norm(l))) << "seed " << seed;
      EXPECT_EQ(checkKkt(q, r), "") << "seed " << seed;
    }
  }
}

TEST(Solver, MultipliersSatisfyStationarityWithBounds) {
  // A task pushing against a bound: the bound's multiplier carries the level's gradient.
  Problem p(2);
  p.addBoundsLevel("box", {0}, vec({1}), vec({-kInf}), vec({1}));
  p.addLevel("task", mat(1, 2, {1, 0}), vec({3}), vec({3}));
  Solver s;
  const Result& r = solveOnce(s, p);
  EXPECT_NEAR(r.x(0), 1.0, 1e-12);
  EXPECT_EQ(r.active.level[0][0], RowState::Upper);
  // lambda_{1,1} = residual = -2; lambda_{bound,1} = 2 (>= 0 at an upper bound).
  EXPECT_NEAR(r.lambda(1, 1), -2.0, 1e-12);
  EXPECT_NEAR(r.lambda(0, 1), 2.0, 1e-12);
  EXPECT_EQ(checkKkt(p, r), "");
}

TEST(Solver, PaperTerminationRulesStopEarly) {
  // Many bound activations are needed cold: a task pulling every variable beyond its bound.
  const int n = 40;
  Problem p(n);
  std::vector<int> vars(n);
  for (int i = 0; i < n; ++i) vars[static_cast<size_t>(i)] = i;
  p.addBoundsLevel("box", vars, Eigen::VectorXd::Ones(n), -Eigen::VectorXd::Ones(n), Eigen::VectorXd::Ones(n));
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n);
  for (int i = 0; i + 1 < n; ++i) A(i, i + 1) = 0.5;
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 2.0, 10.0);
  p.addLevel("far", A, t, t);
  Options o;
  o.stop_total_iterations = 5;
  Solver s;
  const Result& r = solveOnce(s, p, o);
  EXPECT_EQ(r.status, Status::StoppedEarly);
  EXPECT_EQ(r.reason, StopReason::TotalIterationLimit);
  EXPECT_EQ(r.iterations, 5);
  EXPECT_LE(r.x.lpNorm<Eigen::Infinity>(), 1.0 + 1e-12);  // the bounds level holds
  Options cap;
  cap.max_iterations = 3;
  const Result& r2 = solveOnce(s, p, cap);
  EXPECT_EQ(r2.status, Status::IterationLimit);
  EXPECT_LE(r2.x.lpNorm<Eigen::Infinity>(), 1.0 + 1e-12);
  const Result& r3 = solveOnce(s, p);
  EXPECT_EQ(r3.status, Status::Solved);
  EXPECT_EQ(checkKkt(p, r3), "");
  EXPECT_GT(r3.iterations, 5);
}

TEST(Solver, NonFiniteDataIsReportedNotSolved) {
  Problem p(2);
  p.addLevel("a", mat(1, 2, {1, 1}), vec({0}), vec({0}));
  Solver s;
  s.setup(p);
  p.level(0).A(0, 1) = std::nan("");
  const Result& r = s.solve(p);
  EXPECT_EQ(r.status, Status::NonFiniteInput);
  EXPECT_EQ(r.bad_level, 0);
  EXPECT_EQ(r.bad_row, 0);
}

TEST(Solver, SetupRejectsInvalidProblems) {
  Problem p(2);
  p.addLevel("bad", mat(1, 2, {1, 1}), vec({2}), vec({1}));
  Solver s;
  try {
    s.setup(p);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("levels[0]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("row[0]"), std::string::npos) << e.what();
  }
}

TEST(Solver, SameInputsGiveBitIdenticalResults) {
  GenOptions g;
  g.n = 12;
  g.levels = 6;
  const Problem p = randomProblem(4242, g);
  Solver a, b;
  const Result ra = solveOnce(a, p);
  const Result& rb = solveOnce(b, p);
  for (int i = 0; i < p.variables(); ++i) EXPECT_EQ(ra.x(i), rb.x(i));
  EXPECT_EQ(ra.iterations, rb.iterations);
}

TEST(SolverOptions, FieldsOutOfRangeAreRefusedNamingTheField) {
  Problem p(2);
  p.addLevel("a", mat(1, 2, {1, 1}), vec({1}), vec({1}));
  auto refused = [&](const Options& o) -> std::string {
    Solver s;
    try {
      s.setup(p, o);
    } catch (const InputError& e) {
      // setOptions refuses the same options with the same message.
      Solver t;
      t.setup(p);
      EXPECT_THROW(t.setOptions(o), InputError);
      return e.what();
    }
    return "<accepted>";
  };
  Options o;
  EXPECT_EQ(refused(o), "<accepted>");
  EXPECT_EQ(refused(Options::paper(0.005)), "<accepted>");
  o.rank_tolerance = 0.0;
  EXPECT_EQ(refused(o), "solver options: rank_tolerance: expected a number in (0, 0.01], found 0");
  o = Options{};
  o.zero_tolerance = std::nan("");
  EXPECT_EQ(refused(o), "solver options: zero_tolerance: expected a number in [0, 0.01], found nan");
  o = Options{};
  o.dual_tolerance = 0.5;
  EXPECT_EQ(refused(o), "solver options: dual_tolerance: expected a number in [0, 0.01], found 0.5");
  o = Options{};
  o.max_iterations = 0;
  EXPECT_EQ(refused(o), "solver options: max_iterations: expected an integer in [1, 1000000], found 0");
  o = Options{};
  o.cycle_tolerance_factor = 0.5;
  EXPECT_EQ(refused(o), "solver options: cycle_tolerance_factor: expected a finite number >= 1, found 0.5");
  o = Options{};
  o.stop_slack_norm = INFINITY;
  EXPECT_EQ(refused(o), "solver options: stop_slack_norm: expected a finite number (<= 0: the rule is off), found inf");
  o = Options{};
  o.stop_after_level = -2;
  EXPECT_EQ(refused(o), "solver options: stop_after_level: expected -1 (any level) or a level index >= 0, found -2");
  o = Options{};
  o.elimination_tolerance = 0.0;
  EXPECT_EQ(refused(o), "solver options: elimination_tolerance: expected a number in (0, 1], found 0");
}

TEST(SolverOptions, LevelIndicesAreChecked) {
  Problem p(2);
  p.addLevel("a", mat(1, 2, {1, 1}), vec({1}), vec({1}));
  EXPECT_EQ(p.level(0).name, "a");
  EXPECT_EQ(lexdyn::testing::exceptionMessage<std::out_of_range>([&] { (void)p.level(1); }), "Problem::level: index 1 out of range [0, 1)");
  EXPECT_THROW((void)p.level(-1), std::out_of_range);
}

// Solver::setStageTimes: a diagnostic. The solves are the same to the bit with it attached, and
// its counts are the solves' own: every factorised stage counted at its problem level (none at a
// bounds level), Result::factorizations adding at most one elimination or elimination update per
// pass; detached, nothing more is added.
// Targets of -0 on a level declared zero past its first column, a fixed variable past it (x1 = +-1,
// the entry +-0): the target's terms of that variable are left out only where that keeps the
// target's bits, so x (x0 = target / 2, a signed zero) is the undeclared level's to the bit.
TEST(Solver, DeclaredColumnsKeepTheSignOfAZeroTarget) {
  int cases = 0;
  for (const double fixed : {1.0, -1.0}) {
    for (const double entry : {0.0, -0.0}) {
      Problem plain(2);
      plain.addBoundsLevel("fix", {1}, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Constant(1, fixed), Eigen::VectorXd::Constant(1, fixed));
      plain.addLevel("t", mat(1, 2, {2.0, entry}), vec({-0.0}), vec({-0.0}));
      Problem declared = plain;
      declared.setLevelColumns(1, 1);
      for (const bool eliminate : {true, false}) {
        Options o;
        o.eliminate_first_level = eliminate;
        Solver a, b;
        const Result& ra = solveOnce(a, plain, o);
        const Result& rb = solveOnce(b, declared, o);
        ASSERT_EQ(ra.status, Status::Solved);
        EXPECT_EQ(std::memcmp(ra.x.data(), rb.x.data(), sizeof(double) * 2), 0)
            << "x1 " << fixed << ", entry " << entry << ", eliminate " << eliminate << ": x0 " << ra.x(0) << " / " << rb.x(0);
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 8);
}

TEST(Solver, StageTimesChangeNothingAndCountTheStages) {
  GenOptions g;
  long searched = 0;
  for (std::uint64_t seed = 700; seed < 780; ++seed) {
    g.n = 4 + static_cast<int>(seed % 20);
    g.levels = 2 + static_cast<int>(seed % 4);
    g.maxRows = 2 + static_cast<int>(seed % 6);
    const Problem prob = randomProblem(seed, g);
    Options o;
    o.restart_after_bound_change = (seed % 2) == 0;
    o.lazy_snapshots = (seed % 3) == 0;
    Solver a, b;
    StageTimes t;
    b.setStageTimes(&t);  // before setup: attached there
    const Result& ra = solveOnce(a, prob, o);
    const Result& rb = solveOnce(b, prob, o);
    ASSERT_EQ(std::memcmp(ra.x.data(), rb.x.data(), sizeof(double) * static_cast<size_t>(ra.x.size())), 0) << "seed " << seed;
    ASSERT_EQ(ra.iterations, rb.iterations) << "seed " << seed;
    ASSERT_EQ(ra.factorizations, rb.factorizations) << "seed " << seed;
    ASSERT_EQ(t.stage_count.size(), static_cast<size_t>(prob.levelCount()));
    ASSERT_EQ(t.stage_us.size(), static_cast<size_t>(prob.levelCount()));
    long stages = 0;
    for (size_t l = 0; l < t.stage_count.size(); ++l) {
      stages += t.stage_count[l];
      EXPECT_GE(t.stage_us[l], 0.0);
      if (prob.level(static_cast<int>(l)).kind == LevelKind::Bounds) {
        EXPECT_EQ(t.stage_count[l], 0) << "seed " << seed;
      }
    }
    EXPECT_GE(t.passes, 1) << "seed " << seed;
    EXPECT_LE(stages, rb.factorizations) << "seed " << seed;
    EXPECT_GE(stages, rb.factorizations - t.passes) << "seed " << seed;
    EXPECT_GE(t.preparation_us, 0.0);
    EXPECT_GE(t.layout_us, 0.0);
    searched += rb.iterations > 1 ? 1 : 0;
    b.setStageTimes(nullptr);
    const long passes = t.passes;
    b.solve(prob);
    EXPECT_EQ(t.passes, passes) << "seed " << seed;
  }
  EXPECT_GE(searched, 20);  // active-set searches, with restarts, not only single factorisations
}

}  // namespace
}  // namespace lexdyn::solver
