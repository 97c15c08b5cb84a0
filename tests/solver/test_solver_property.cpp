// Property-based tests of the solver (rapidcheck; the seed is fixed by RC_PARAMS in ctest).
#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include "lexdyn/solver/solver.hpp"
#include "reference.hpp"

namespace lexdyn::solver {
namespace {

using test::GenOptions;

GenOptions genOptions(int maxN, int maxLevels, int maxRows) {
  GenOptions g;
  g.n = *rc::gen::inRange(1, maxN + 1);
  g.levels = *rc::gen::inRange(1, maxLevels + 1);
  g.maxRows = *rc::gen::inRange(1, maxRows + 1);
  g.inequalities = *rc::gen::arbitrary<bool>();
  g.boundsLevel = *rc::gen::arbitrary<bool>();
  g.pRankDeficient = *rc::gen::element(0.0, 0.3, 0.8);
  g.pDuplicate = *rc::gen::element(0.0, 0.2, 0.5);
  g.pZeroRow = *rc::gen::element(0.0, 0.1);
  g.pConflict = *rc::gen::element(0.0, 0.2, 0.5);
  g.pEquality = *rc::gen::element(0.1, 0.4, 0.9);
  return g;
}

Options withLastLevel(Options::LastLevel mode, bool eliminate = true) {
  Options o;
  o.last_level_projection = mode;
  o.eliminate_first_level = eliminate;
  return o;
}

RC_GTEST_PROP(SolverProperty, RandomHierarchiesAreSolvedWithAKktCertificate, ()) {
  const GenOptions g = genOptions(12, 7, 8);
  const auto seed = *rc::gen::inRange<std::uint64_t>(0, std::uint64_t(1) << 62);
  const Problem p = test::randomProblem(seed, g);
  // The last level factorised like the others and projected: both exact, same optima.
  Eigen::VectorXd firstNorms;
  for (const Options& o : {withLastLevel(Options::LastLevel::Never), withLastLevel(Options::LastLevel::Always)}) {
    Solver s;
    s.setup(p, o);
    const Result& r = s.solve(p);
    RC_ASSERT(r.status == Status::Solved);
    const std::string kkt = test::checkKkt(p, r);
    RC_LOG() << kkt;
    RC_ASSERT(kkt.empty());
    // The bounds level is never violated.
    if (p.level(0).kind == LevelKind::Bounds) RC_ASSERT(r.violation_norm(0) <= 1e-9);
    if (firstNorms.size() == 0) {
      firstNorms = r.violation_norm;
      continue;
    }
    for (int l = 0; l < p.levelCount(); ++l) RC_ASSERT(std::abs(r.violation_norm(l) - firstNorms(l)) <= 1e-7 * (1 + firstNorms(l)));
  }
}

RC_GTEST_PROP(SolverProperty, TinyProblemsMatchBruteForce, ()) {
  GenOptions g = genOptions(3, 3, 2);
  g.inequalities = true;
  const auto seed = *rc::gen::inRange<std::uint64_t>(0, std::uint64_t(1) << 62);
  const Problem p = test::randomProblem(seed, g);
  RC_PRE(p.totalRows() <= 8);
  const auto bf = test::bruteForce(p);
  Solver s;
  s.setup(p);
  const Result& r = s.solve(p);
  RC_ASSERT(r.status == Status::Solved);
  for (int l = 0; l < p.levelCount(); ++l) {
    RC_LOG() << "level " << l << ": solver " << r.violation_norm(l) << " brute force " << bf[static_cast<size_t>(l)];
    RC_ASSERT(std::abs(r.violation_norm(l) - bf[static_cast<size_t>(l)]) <= 1e-7 * (1 + bf[static_cast<size_t>(l)]));
  }
}

RC_GTEST_PROP(SolverProperty, EqualityHierarchiesMatchNullSpaceRecursion, ()) {
  GenOptions g = genOptions(10, 6, 7);
  g.inequalities = false;
  g.boundsLevel = false;
  const auto seed = *rc::gen::inRange<std::uint64_t>(0, std::uint64_t(1) << 62);
  const Problem p = test::randomProblem(seed, g);
  const auto ref = test::nullSpaceReference(p);
  Options noElim;
  noElim.eliminate_first_level = false;
  for (const Options& o :
       {Options{}, noElim, withLastLevel(Options::LastLevel::Always), withLastLevel(Options::LastLevel::Always, false)}) {
    Solver s;
    s.setup(p, o);
    const Result& r = s.solve(p);
    RC_ASSERT(r.status == Status::Solved);
    RC_ASSERT(r.iterations == 1);
    for (int l = 0; l < p.levelCount(); ++l)
      RC_ASSERT(std::abs(r.violation_norm(l) - ref.residualNorm[static_cast<size_t>(l)]) <=
                1e-8 * (1 + ref.residualNorm[static_cast<size_t>(l)]));
    // Unique optimum, or no elimination: the minimum-norm optimum, as the reference.
    if (ref.nullity == 0 || !o.eliminate_first_level) RC_ASSERT((r.x - ref.x).norm() <= 1e-8 * (1 + ref.x.norm()));
    RC_ASSERT(test::checkKkt(p, r).empty());
  }
}

RC_GTEST_PROP(SolverProperty, WarmStartFromAnyActiveSetGivesTheColdAnswer, ()) {
  GenOptions g = genOptions(10, 6, 6);
  const auto seed = *rc::gen::inRange<std::uint64_t>(0, std::uint64_t(1) << 62);
  Problem p = test::randomProblem(seed, g);
  test::appendMinNorm(p);
  // The warm solver projects the last level (a restart from its raw rows on every change of
  // the active set), the cold one does not.
  Solver cold, warm;
  cold.setup(p, withLastLevel(Options::LastLevel::Never));
  warm.setup(p, withLastLevel(Options::LastLevel::Always));
  const Result rc = cold.solve(p);
  RC_ASSERT(rc.status == Status::Solved);
  // A random (generally inconsistent) active set and x.
  ActiveSet guess = rc.active;
  for (auto& lvl : guess.level)
    for (auto& st : lvl) st = static_cast<RowState>(*rc::gen::inRange(0, 4));
  Eigen::VectorXd x0(p.variables());
  for (int i = 0; i < x0.size(); ++i) x0(i) = *rc::gen::inRange(-300, 300) / 100.0;
  const Result& rw = warm.solve(p, guess, x0);
  RC_ASSERT(rw.status == Status::Solved);
  for (int l = 0; l < p.levelCount(); ++l)
    RC_ASSERT(std::abs(rw.violation_norm(l) - rc.violation_norm(l)) <= 1e-7 * (1 + rc.violation_norm(l)));
  RC_ASSERT((rw.x - rc.x).norm() <= 1e-6 * (1 + rc.x.norm()));
  RC_ASSERT(test::checkKkt(p, rw).empty());
}

RC_GTEST_PROP(SolverProperty, ScalingAndPermutingALevelKeepsTheOptima, ()) {
  GenOptions g = genOptions(8, 5, 6);
  g.levels = std::max(g.levels, 2);
  const auto seed = *rc::gen::inRange<std::uint64_t>(0, std::uint64_t(1) << 62);
  const Problem p = test::randomProblem(seed, g);
  const int l0 = p.levelCount() - 1 - *rc::gen::inRange(0, g.levels);
  RC_PRE(p.level(l0).kind == LevelKind::General);
  const double c = *rc::gen::element(-1000.0, -0.5, 1e-3, 7.0);
  Problem q = p;
  Level& lv = q.level(l0);
  const int m = lv.rows();
  std::vector<int> perm(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) perm[static_cast<size_t>(i)] = (i * 7 + 3) % m;
  std::vector<char> used(static_cast<size_t>(m), 0);
  bool isPerm = true;
  for (int v : perm) isPerm = isPerm && !used[static_cast<size_t>(v)]++;
  if (!isPerm)
    for (int i = 0; i < m; ++i) perm[static_cast<size_t>(i)] = m - 1 - i;
  const Level orig = p.level(l0);
  for (int i = 0; i < m; ++i) {
    const int j = perm[static_cast<size_t>(i)];
    lv.A.row(i) = c * orig.A.row(j);
    lv.lower(i) = c > 0 ? c * orig.lower(j) : c * orig.upper(j);
    lv.upper(i) = c > 0 ? c * orig.upper(j) : c * orig.lower(j);
  }
  Solver s1, s2;
  s1.setup(p);
  s2.setup(q);
  const Result r1 = s1.solve(p);
  const Result& r2 = s2.solve(q);
  for (int l = 0; l < p.levelCount(); ++l) {
    const double f = (l == l0) ? std::abs(c) : 1.0;
    RC_LOG() << "level " << l << ": " << r1.violation_norm(l) << " vs " << r2.violation_norm(l) << " (factor " << f << ")";
    RC_ASSERT(std::abs(r2.violation_norm(l) - f * r1.violation_norm(l)) <= 1e-7 * (1 + f * r1.violation_norm(l)));
  }
}

}  // namespace
}  // namespace lexdyn::solver
