#include "lexdyn/solver/solver.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <random>
#include <utility>
#include <string>

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/input_ranges.hpp"
#include "lexdyn/solver/detail/hls_factorization.hpp"

namespace lexdyn::solver {

namespace {

// names[e], the names listed in the order of E's enumerators (0, 1, ...); "unknown" past them.
template <class E, size_t N>
const char* enumName(E e, const char* const (&names)[N]) {
  const auto i = static_cast<size_t>(e);
  return i < N ? names[i] : "unknown";
}

// Eigen's allFinite(), in one vectorised pass: x * 0 is 0 for a finite x and NaN for an infinite
// or NaN one, so the sum is finite exactly when every entry is (Eigen's own version compares the
// entries one at a time). Used on the multipliers, a mostly zero matrix of every row by every level.
template <class Derived>
bool allFiniteFast(const Eigen::DenseBase<Derived>& m) {
  return std::isfinite((m.derived().array() * 0.0).sum());
}

// A motion no larger than this times the size of what moves is rounding: about 64 units in the
// last place.
constexpr double kRoundingMotion = 64.0 * std::numeric_limits<double>::epsilon();
// Working sets remembered for cycle detection (run()); a cold restart comes after as many repeats
// at the largest tolerances.
constexpr int kRecentWorkingSets = 64;

}  // namespace

const char* toString(Status s) {
  static const char* const kNames[] = {"solved", "stopped_early", "iteration_limit", "non_finite_input", "non_finite_result"};
  static_assert(std::size(kNames) == static_cast<size_t>(Status::NonFiniteResult) + 1);
  return enumName(s, kNames);
}

const char* toString(StopReason r) {
  static const char* const kNames[] = {
      "optimal",          "slack_below_threshold", "optimality_phase_limit", "total_iteration_limit", "hard_iteration_cap",
      "non_finite_input", "non_finite_result"};
  static_assert(std::size(kNames) == static_cast<size_t>(StopReason::NonFiniteResult) + 1);
  return enumName(r, kNames);
}

const char* toString(RowState s) {
  static const char* const kNames[] = {"inactive", "lower", "upper", "equality"};
  static_assert(std::size(kNames) == static_cast<size_t>(RowState::Equality) + 1);
  return enumName(s, kNames);
}

Options Options::paper(double dt) {
  Options o;
  o.stop_slack_norm = 1e-12 * dt * dt;
  o.stop_optimality_iterations = 10;
  o.stop_total_iterations = 30;
  return o;
}

void Options::validate() const {
  namespace R = lexdyn::ranges;
  auto fail = [](const char* field, const std::string& expected, double found) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.17g", found);
    throw InputError("solver options", std::string(field) + ": expected " + expected + ", found " + buf);
  };
  auto tolerance = [&](const char* field, double v, bool positive) {
    if (!(std::isfinite(v) && (positive ? v > 0.0 : v >= 0.0) && v <= R::kMaxSolverTolerance)) {
      fail(field, std::string(positive ? "a number in (0, " : "a number in [0, ") + "0.01]", v);
    }
  };
  auto count = [&](const char* field, int v, int lo) {
    if (v < lo || v > R::kMaxSolverIterations) fail(field, "an integer in [" + std::to_string(lo) + ", 1000000]", v);
  };
  tolerance("rank_tolerance", rank_tolerance, true);
  tolerance("feasibility_tolerance", feasibility_tolerance, false);
  tolerance("zero_tolerance", zero_tolerance, false);
  tolerance("dual_tolerance", dual_tolerance, false);
  if (!(elimination_tolerance > 0.0 && elimination_tolerance <= 1.0))
    fail("elimination_tolerance", "a number in (0, 1]", elimination_tolerance);
  if (split_from_variable < -1) fail("split_from_variable", "-1 (off) or a variable index", split_from_variable);
  count("max_iterations", max_iterations, 1);
  count("bland_after_degenerate_steps", bland_after_degenerate_steps, 1);
  if (!(std::isfinite(cycle_tolerance_factor) && cycle_tolerance_factor >= 1.0)) {
    fail("cycle_tolerance_factor", "a finite number >= 1", cycle_tolerance_factor);
  }
  if (!std::isfinite(stop_slack_norm)) fail("stop_slack_norm", "a finite number (<= 0: the rule is off)", stop_slack_norm);
  count("stop_optimality_iterations", stop_optimality_iterations, 0);
  count("stop_total_iterations", stop_total_iterations, 0);
  if (stop_after_level < -1) fail("stop_after_level", "-1 (any level) or a level index >= 0", stop_after_level);
  if (last_level_projection != LastLevel::Auto && last_level_projection != LastLevel::Never && last_level_projection != LastLevel::Always) {
    fail("last_level_projection", "Auto, Never or Always", static_cast<int>(last_level_projection));
  }
}

int ActiveSet::activeCount() const {
  int c = 0;
  for (const auto& l : level)
    for (RowState s : l) c += (s != RowState::Inactive);
  return c;
}

struct Solver::Impl {
  Options opt;
  bool isSetup = false;
  int n = 0, p = 0, lg = 0, first = 0;
  bool hasBounds = false;
  std::vector<int> rowsOf;    // rows per problem level
  std::vector<int> stackOff;  // offset of each problem level in the stacked row numbering
  std::vector<LevelKind> kinds;

  HlsFactorization fact;
  int M = 0;        // general rows
  int allRows = 0;  // every row of the problem, bounds included (the multipliers' rows)
  // Per general row (gid).
  Eigen::VectorXd lo, up, Ax, Adx, v, dv, res, mu, b, rowNorm;
  std::vector<RowState> state;
  // Per variable.
  Eigen::VectorXd xlo, xup, x, dx, xs, xFree;
  // Multipliers of every level's problem for the current equality solution, computed lazily.
  Eigen::MatrixXd muAll;     // M x lg
  Eigen::MatrixXd muVarAll;  // n x lg
  std::vector<char> multDone, levelNz;
  std::vector<char> muFinite;  // per level: its active rows' multipliers of the level being computed are finite
  bool multValid = false;      // multDone / levelNz describe the current equality solution
  Eigen::VectorXd levelS;
  // Constraints that re-blocked immediately after being released (anti-cycling), cleared on progress.
  std::vector<char> tabooRow, tabooVar;
  int lastDropKind = -1, lastDropIdx = -1;
  RowState lastDropState = RowState::Inactive;
  // Cycle detection: Zobrist hash of the working set (fixed seed), recent hashes.
  std::vector<std::uint64_t> zRow, zVar;  // per gid / var: 3 keys (Lower, Upper, Equality)
  std::uint64_t wsHash = 0;
  // A cold restart's starting point (run()): x, the working set, the levels known optimal.
  Eigen::VectorXd savedX;
  std::vector<RowState> savedVstate, savedState;
  int savedThrough = -1;
  std::vector<std::uint64_t> recent;
  int recentPos = 0, recentCount = 0;
  double rankTol = 1e-9, dualTol = 1e-10;
  void hashFlip(int kind, int idx, RowState st) {
    if (st == RowState::Inactive) return;
    const int k = static_cast<int>(st) - 1;
    wsHash ^= (kind == 0 ? zVar : zRow)[static_cast<size_t>(3 * idx + k)];
  }
  std::vector<RowState> vstate;
  std::vector<int> boundRow;  // var -> row of the bounds level or -1
  std::vector<int> freeVar;
  std::vector<int> fixedVar;
  int nFixed = 0;

  Result out;
  // Warm-start copies (the caller may pass our own result).
  std::vector<RowState> warmRow, warmVar;
  Eigen::VectorXd warmX;

  const Problem* prob = nullptr;
  StageTimes* times = nullptr;  // setStageTimes
  // Hands `times` to the factorisation, sized to the problem's levels (after setup).
  void attachStageTimes() {
    if (times && isSetup) {
      const size_t levels = static_cast<size_t>(p);
      if (times->stage_us.size() < levels) times->stage_us.resize(levels, 0.0);
      if (times->stage_count.size() < levels) times->stage_count.resize(levels, 0);
    }
    fact.setStageTimes(isSetup ? times : nullptr, first);
  }

  void setup(const Problem& problem, const Options& o);
  void checkCompatible(const Problem& problem) const;
  bool scanNonFinite(const Problem& problem);
  void loadData(const Problem& problem);
  void initCold();
  void initWarm(const ActiveSet& warm, const Eigen::VectorXd& xw);
  void startFromStates();
  void updateFreeVariables();
  void computeAx(const Eigen::VectorXd& xx, Eigen::VectorXd& out) const;
  // Per general level kf, runs [begin, end) of its rows (level-relative) that computeAx
  // multiplies: axRuns[axRunsOff[kf] .. axRunsOff[kf + 1]) in pairs. Rows outside them are free
  // (lower -inf, upper +inf: never active, never blocking, violation 0 whatever A x is), such as
  // the reserved rows of a level that is not augmented; their A x is set to 0, and their norms
  // are not computed (HlsFactorization::computeRowNorms). Set by loadData().
  std::vector<int> axRuns, axRunsOff;
  void findAxRuns();
  // Row gid constrains nothing: lower -inf and upper +inf.
  bool freeRow(int gid) const { return lo(gid) == -kInf && up(gid) == kInf; }
  double target(int gid) const;
  void buildTargets();
  // buildTargets' values kept between the active-set iterations of a solve: b(gid) is recomputed
  // only when its inputs changed. bEpoch[gid]: the epoch of the fixed variables (their set and
  // values, the problem's data) it was computed in (-1: none); bTarget: the target it started
  // from; bWhole: whether every fixed variable's term was summed (a level with a -0 target).
  std::vector<long> bEpoch;
  std::vector<double> bTarget;
  std::vector<char> bWhole;
  std::vector<char> bLevelWhole;  // per level: its flag at its last call
  std::vector<int> bTodo;         // the active rows of a level to compute
  Eigen::VectorXd fixedX;         // the fixed variables' values in the current epoch (fixedVar's order)
  long fixedEpoch = 0;
  bool fixedXValid = false;  // fixedX holds them (false: a new epoch begins at the next call)
  void solveEquality();
  // level: the factored level whose multiplier releases the constraint (the levels before it are
  // optimal).
  bool dualCheck(bool bland, int& kind, int& idx, int& level);
  void prepareLevels();
  void ensureMult(int kf);
  bool isHeld(int kind, int idx, int levelH, int kf);
  int unitRowHolding(int i, int kf) const;
  double correctSign(int kind, int idx, double value) const;
  void run();
  void finish();
  void checkFiniteResult();
  // `out` has the problem's shape (every array sized for its levels and rows); shapeResult()
  // gives it that shape (zeros).
  bool resultShaped() const;
  void shapeResult();
  // out.lambda's column l is zero past the rows of level l (every stage of finish() writes a
  // column's rows of its own and earlier levels only), as shapeResult() leaves it; false after
  // swapResult() handed in buffers of unknown content.
  bool lambdaTailsZero = false;
  // The result's counters and flags as before any work (a solve sets them as it goes).
  void resetCounters();
  // One solve, from the warm start (warm, xw) or, when warm is null, from a cold start.
  const Result& solve(const Problem& problem, const ActiveSet* warm, const Eigen::VectorXd* xw);
  double rowScale(int gid, double xnorm) const { return std::abs(target(gid)) + rowNorm(gid) * xnorm; }
  const Eigen::MatrixXd& A(int kf) const { return prob->level(kf + first).A; }
};

void Solver::Impl::setup(const Problem& problem, const Options& o) {
  problem.validate("problem");
  o.validate();
  opt = o;
  n = problem.variables();
  p = problem.levelCount();
  hasBounds = p > 0 && problem.level(0).kind == LevelKind::Bounds;
  first = hasBounds ? 1 : 0;
  lg = p - first;
  rowsOf.resize(static_cast<size_t>(p));
  stackOff.resize(static_cast<size_t>(p));
  kinds.resize(static_cast<size_t>(p));
  int off = 0;
  for (int l = 0; l < p; ++l) {
    rowsOf[static_cast<size_t>(l)] = problem.level(l).rows();
    kinds[static_cast<size_t>(l)] = problem.level(l).kind;
    stackOff[static_cast<size_t>(l)] = off;
    off += rowsOf[static_cast<size_t>(l)];
  }
  std::vector<int> gen;
  for (int l = first; l < p; ++l) gen.push_back(rowsOf[static_cast<size_t>(l)]);
  fact.setup(n, gen);
  M = 0;
  for (int r : gen) M += r;
  for (Eigen::VectorXd* vec : {&lo, &up, &Ax, &Adx, &v, &dv, &res, &mu, &b, &rowNorm}) vec->setZero(std::max(M, 1));
  axRuns.clear();
  axRuns.reserve(static_cast<size_t>(M + 2 * lg + 2));  // at most (rows + 1) / 2 runs a level
  axRunsOff.assign(static_cast<size_t>(lg + 1), 0);
  state.assign(static_cast<size_t>(M), RowState::Inactive);
  for (Eigen::VectorXd* vec : {&xlo, &xup, &x, &dx, &xs, &xFree, &fixedX}) vec->setZero(n);
  bEpoch.assign(static_cast<size_t>(std::max(M, 1)), -1);
  bTarget.assign(static_cast<size_t>(std::max(M, 1)), 0.0);
  bWhole.assign(static_cast<size_t>(std::max(M, 1)), 0);
  bLevelWhole.assign(static_cast<size_t>(std::max(lg, 1)), 0);
  bTodo.assign(static_cast<size_t>(std::max(M, 1)), 0);
  fixedXValid = false;
  muAll.setZero(std::max(M, 1), std::max(lg, 1));
  muVarAll.setZero(n, std::max(lg, 1));
  multDone.assign(static_cast<size_t>(std::max(lg, 1)), 0);
  levelNz.assign(static_cast<size_t>(std::max(lg, 1)), 0);
  muFinite.assign(static_cast<size_t>(std::max(lg, 1)), 0);
  levelS.setZero(std::max(lg, 1));
  tabooRow.assign(static_cast<size_t>(std::max(M, 1)), 0);
  tabooVar.assign(static_cast<size_t>(n), 0);
  vstate.assign(static_cast<size_t>(n), RowState::Inactive);
  boundRow.assign(static_cast<size_t>(n), -1);
  freeVar.assign(static_cast<size_t>(n), 0);
  fixedVar.assign(static_cast<size_t>(n), 0);
  warmRow.assign(static_cast<size_t>(M), RowState::Inactive);
  {
    std::mt19937_64 rng(0x9e3779b97f4a7c15ULL);
    zRow.resize(static_cast<size_t>(3 * std::max(M, 1)));
    zVar.resize(static_cast<size_t>(3 * std::max(n, 1)));
    for (auto& v : zRow) v = rng();
    for (auto& v : zVar) v = rng();
    recent.assign(kRecentWorkingSets, 0);
  }
  warmVar.assign(static_cast<size_t>(n), RowState::Inactive);
  warmX.setZero(n);

  allRows = off;
  out = Result{};
  shapeResult();
  isSetup = true;
  attachStageTimes();
}

bool Solver::Impl::resultShaped() const {
  if (out.x.size() != n || out.violation.size() != static_cast<size_t>(p) || out.violation_norm.size() != p ||
      out.lambda.rows() != allRows || out.lambda.cols() != p || out.active.level.size() != static_cast<size_t>(p) ||
      out.rank.size() != static_cast<size_t>(p))
    return false;
  for (size_t l = 0; l < static_cast<size_t>(p); ++l) {
    if (out.violation[l].size() != rowsOf[l] || out.active.level[l].size() != static_cast<size_t>(rowsOf[l])) return false;
  }
  return true;
}

void Solver::Impl::resetCounters() {
  out.iterations = out.factorizations = out.bound_change_restarts = out.optimality_iterations = out.activations = out.deactivations = 0;
  out.held_after_reblock = out.cycles_broken = out.cold_restarts = out.projected_levels = out.spanning_stages = out.structured_stages = 0;
  out.optimal_through = -1;
  out.last_level_projected = out.split_applied = false;
}

void Solver::Impl::shapeResult() {
  out.x.setZero(n);
  out.violation.resize(static_cast<size_t>(p));
  for (int l = 0; l < p; ++l) out.violation[static_cast<size_t>(l)].setZero(rowsOf[static_cast<size_t>(l)]);
  out.violation_norm.setZero(p);
  out.lambda.setZero(allRows, p);
  lambdaTailsZero = true;
  out.active.level.resize(static_cast<size_t>(p));
  for (int l = 0; l < p; ++l)
    out.active.level[static_cast<size_t>(l)].assign(static_cast<size_t>(rowsOf[static_cast<size_t>(l)]), RowState::Inactive);
  out.rank.assign(static_cast<size_t>(p), 0);
}

void Solver::Impl::checkCompatible(const Problem& problem) const {
  if (!isSetup) throw InputError("solver", "solve() called before setup()");
  bool ok = problem.variables() == n && problem.levelCount() == p;
  for (int l = 0; ok && l < p; ++l) {
    const Level& lv = problem.level(l);
    ok = lv.rows() == rowsOf[static_cast<size_t>(l)] && lv.kind == kinds[static_cast<size_t>(l)] && lv.upper.size() == lv.rows() &&
         (lv.kind == LevelKind::Bounds ? (static_cast<int>(lv.variable.size()) == lv.rows() && lv.coefficient.size() == lv.rows())
                                       : (lv.A.rows() == lv.rows() && lv.A.cols() == n));
  }
  if (!ok) throw InputError("solver", "the problem's sizes differ from those given to setup(); call setup() again");
}

bool Solver::Impl::scanNonFinite(const Problem& problem) {
  // Fast path: the row norms (computed by loadData) are finite exactly when the rows are finite,
  // barring overflow; the rows whose norms were not computed (free rows outside axRuns) are
  // checked here, over the declared columns; the row-by-row scan below only runs to locate a
  // problem.
  for (int l = 0; l < p; ++l) {
    const Level& lv = problem.level(l);
    const bool boundsOk = !lv.lower.hasNaN() && !lv.upper.hasNaN() && (lv.lower.array() <= lv.upper.array()).all();
    bool dataOk;
    if (lv.kind == LevelKind::General) {
      const int kf = l - first;
      const int off = fact.rowOffset(kf);
      dataOk = lv.rows() == 0 || allFiniteFast(rowNorm.segment(off, lv.rows()));
      const int c = lv.columns >= 1 ? lv.columns : n;
      // The gaps between the runs [from, to), the last one up to the level's end.
      const int q1 = axRunsOff[static_cast<size_t>(kf + 1)];
      int from = 0;
      for (int q = axRunsOff[static_cast<size_t>(kf)]; dataOk && q <= q1; q += 2) {
        const int to = q < q1 ? axRuns[static_cast<size_t>(q)] : lv.rows();
        if (to > from) dataOk = allFiniteFast(lv.A.block(from, 0, to - from, c));
        if (q < q1) from = axRuns[static_cast<size_t>(q + 1)];
      }
    } else {
      dataOk = lv.coefficient.allFinite() && (lv.coefficient.array() != 0.0).all();
    }
    if (boundsOk && dataOk) continue;
    for (int r = 0; r < lv.rows(); ++r) {
      bool bad = std::isnan(lv.lower(r)) || std::isnan(lv.upper(r)) || lv.lower(r) > lv.upper(r);
      if (lv.kind == LevelKind::General) {
        bad = bad || !lv.A.row(r).allFinite();
      } else {
        bad = bad || !std::isfinite(lv.coefficient(r)) || lv.coefficient(r) == 0.0;
      }
      if (bad) {
        out.bad_level = l;
        out.bad_row = r;
        return true;
      }
    }
  }
  out.bad_level = out.bad_row = -1;
  return false;
}

void Solver::Impl::loadData(const Problem& problem) {
  prob = &problem;
  fixedXValid = false;  // new rows and bounds: every target is computed again
#ifndef NDEBUG
  // Level::columns is the caller's promise (validate() checks it at setup): a debug build checks
  // it at every solve, a release build reads nothing past the declared columns.
  for (int kf = 0; kf < lg; ++kf) {
    const Level& lv = problem.level(kf + first);
    LEXDYN_ALWAYS_ASSERT(lv.columns < 0 || (lv.A.rightCols(n - lv.columns).array() == 0.0).all(),
                         "level \"" + lv.name + "\" has nonzero entries past its declared columns");
  }
#endif
  for (int kf = 0; kf < lg; ++kf) fact.setLevelMatrix(kf, &problem.level(kf + first).A, problem.level(kf + first).columns);
  for (int kf = 0; kf < lg; ++kf) {
    const Level& lv = problem.level(kf + first);
    const int off = fact.rowOffset(kf);
    lo.segment(off, lv.rows()) = lv.lower;
    up.segment(off, lv.rows()) = lv.upper;
  }
  findAxRuns();
  // The norms of free rows are never read (they are never active, and never block a step).
  fact.computeRowNorms(&axRuns, &axRunsOff);
  if (M > 0) rowNorm.head(M) = fact.rowNorms().head(M);
  // The elimination stage needs a first general level of equality rows only.
  bool allEq = lg > 0 && rowsOf[static_cast<size_t>(first)] > 0;
  if (allEq) {
    const Level& l0 = problem.level(first);
    allEq = (l0.lower.array() == l0.upper.array()).all();
  }
  fact.setElimination(opt.eliminate_first_level && allEq, opt.elimination_tolerance);
  fact.setSplit(opt.split_from_variable);
  fact.setSpanning(opt.spanning_stages, opt.spanning_any_rows, opt.spanning_structured);
  fact.setLazySnapshots(opt.lazy_snapshots);
  fact.setProjectUnitSuffix(opt.project_unit_suffix);
  fact.setBoundChangeRestarts(opt.restart_after_bound_change);
  fact.setSwapReflectors(opt.swap_reflectors);
  fact.setLastLevelMode(opt.last_level_projection == Options::LastLevel::Never    ? HlsFactorization::LastLevel::Standard
                        : opt.last_level_projection == Options::LastLevel::Always ? HlsFactorization::LastLevel::Projected
                                                                                  : HlsFactorization::LastLevel::Auto);
  for (int kf = 0; kf < lg; ++kf) {
    const Level& lv = problem.level(kf + first);
    fact.setStaticLevel(kf, (lv.lower.array() == lv.upper.array()).all());
  }
  xlo.setConstant(-kInf);
  xup.setConstant(kInf);
  std::fill(boundRow.begin(), boundRow.end(), -1);
  if (hasBounds) {
    const Level& lv = problem.level(0);
    for (int r = 0; r < lv.rows(); ++r) {
      const int i = lv.variable[static_cast<size_t>(r)];
      const double c = lv.coefficient(r);
      boundRow[static_cast<size_t>(i)] = r;
      if (c > 0) {
        xlo(i) = lv.lower(r) / c;
        xup(i) = lv.upper(r) / c;
      } else {
        xlo(i) = lv.upper(r) / c;
        xup(i) = lv.lower(r) / c;
      }
      if (lv.lower(r) == lv.upper(r)) xup(i) = xlo(i);
    }
  }
}

double Solver::Impl::target(int gid) const {
  switch (state[static_cast<size_t>(gid)]) {
    case RowState::Lower:
      return lo(gid);
    case RowState::Upper:
    case RowState::Equality:
      return up(gid);
    default:
      return 0.0;
  }
}

void Solver::Impl::initCold() {
  for (int i = 0; i < n; ++i) {
    x(i) = std::min(std::max(0.0, xlo(i)), xup(i));
    vstate[static_cast<size_t>(i)] = (xlo(i) == xup(i)) ? RowState::Equality : RowState::Inactive;
  }
  for (int g = 0; g < M; ++g) state[static_cast<size_t>(g)] = (lo(g) == up(g)) ? RowState::Equality : RowState::Inactive;
}

void Solver::Impl::initWarm(const ActiveSet& warm, const Eigen::VectorXd& xw) {
  // Copy first: `warm` may alias out.active.
  for (int i = 0; i < n; ++i) warmVar[static_cast<size_t>(i)] = RowState::Inactive;
  for (int g = 0; g < M; ++g) warmRow[static_cast<size_t>(g)] = RowState::Inactive;
  const bool shapeOk = static_cast<int>(warm.level.size()) == p;
  if (shapeOk) {
    for (int l = 0; l < p; ++l) {
      const auto& ws = warm.level[static_cast<size_t>(l)];
      if (static_cast<int>(ws.size()) != rowsOf[static_cast<size_t>(l)]) continue;
      if (l == 0 && hasBounds) {
        const Level& lv = prob->level(0);
        for (int r = 0; r < lv.rows(); ++r) {
          RowState s = ws[static_cast<size_t>(r)];
          if (lv.coefficient(r) < 0 && (s == RowState::Lower || s == RowState::Upper))
            s = (s == RowState::Lower) ? RowState::Upper : RowState::Lower;
          warmVar[static_cast<size_t>(lv.variable[static_cast<size_t>(r)])] = s;
        }
      } else {
        const int off = fact.rowOffset(l - first);
        for (int r = 0; r < static_cast<int>(ws.size()); ++r) warmRow[static_cast<size_t>(off + r)] = ws[static_cast<size_t>(r)];
      }
    }
  }
  const bool xOk = xw.size() == n && xw.allFinite();
  if (xOk) warmX = xw;
  for (int i = 0; i < n; ++i) {
    x(i) = std::min(std::max(xOk ? warmX(i) : 0.0, xlo(i)), xup(i));
    RowState s = warmVar[static_cast<size_t>(i)];
    if (xlo(i) == xup(i)) {
      s = RowState::Equality;
    } else if (s == RowState::Lower && std::isfinite(xlo(i))) {
      x(i) = xlo(i);
    } else if (s == RowState::Upper && std::isfinite(xup(i))) {
      x(i) = xup(i);
    } else {
      s = RowState::Inactive;
    }
    vstate[static_cast<size_t>(i)] = s;
  }
  for (int g = 0; g < M; ++g) {
    RowState s = warmRow[static_cast<size_t>(g)];
    if (lo(g) == up(g)) {
      s = RowState::Equality;
    } else if ((s == RowState::Lower && !std::isfinite(lo(g))) || (s == RowState::Upper && !std::isfinite(up(g))) ||
               s == RowState::Equality) {
      s = RowState::Inactive;
    }
    state[static_cast<size_t>(g)] = s;
  }
}

void Solver::Impl::updateFreeVariables() {
  int nf = 0;
  nFixed = 0;
  for (int i = 0; i < n; ++i) {
    if (vstate[static_cast<size_t>(i)] == RowState::Inactive) {
      freeVar[static_cast<size_t>(nf++)] = i;
    } else {
      fixedVar[static_cast<size_t>(nFixed++)] = i;
    }
  }
  fixedXValid = false;  // another set of fixed variables: every target is computed again
  fact.setFreeVariables(freeVar, nf);
}

void Solver::Impl::findAxRuns() {
  // Free rows between constraining ones are multiplied too when fewer than kGap of them lie
  // between (one product instead of two). A run has two rows at least (a free neighbour joins a
  // lone row): Eigen multiplies a single row as a dot product, whose sum can differ from the
  // matrix-vector product's (seen with 130 columns).
  constexpr int kGap = 4;
  axRuns.clear();
  for (int kf = 0; kf < lg; ++kf) {
    axRunsOff[static_cast<size_t>(kf)] = static_cast<int>(axRuns.size());
    const int off = fact.rowOffset(kf);
    const int m = rowsOf[static_cast<size_t>(kf + first)];
    int begin = -1, end = -1;
    auto push = [&] {
      if (end - begin == 1 && m >= 2) {
        if (end < m) {
          ++end;
        } else {
          --begin;
        }
      }
      axRuns.insert(axRuns.end(), {begin, end});
    };
    for (int r = 0; r < m; ++r) {
      if (freeRow(off + r)) continue;
      if (begin >= 0 && r - end < kGap) {
        end = r + 1;
        continue;
      }
      if (begin >= 0) push();
      begin = r;
      end = r + 1;
    }
    if (begin >= 0) push();
  }
  axRunsOff[static_cast<size_t>(lg)] = static_cast<int>(axRuns.size());
}

void Solver::Impl::computeAx(const Eigen::VectorXd& xx, Eigen::VectorXd& outv) const {
  for (int kf = 0; kf < lg; ++kf) {
    const int off = fact.rowOffset(kf);
    const int m = rowsOf[static_cast<size_t>(kf + first)];
    if (m == 0) continue;
    // A level declared zero past its first c columns (Level::columns) multiplies those only.
    // Eigen's matrix-vector product sums each row over the columns in order (in one block of
    // columns below 128 of them) from +0 and adds the sum to a zeroed result, so the terms left
    // out, exact zeros at the end, change no bit (DeclaredLeadingColumnsKeepEveryBit; it fails
    // without the limit of 128). Each row's sum is the same whichever rows are multiplied with
    // it, so the free rows are left out (axRuns; FreeRowsLeftOutOfAxKeepEveryBit).
    const int c = prob->level(kf + first).columns;
    const bool lead = c >= 1 && c < n && n < 128;
    const int r0 = axRunsOff[static_cast<size_t>(kf)], r1 = axRunsOff[static_cast<size_t>(kf + 1)];
    if (r1 - r0 == 2 && axRuns[static_cast<size_t>(r0)] == 0 && axRuns[static_cast<size_t>(r0 + 1)] == m) {
      if (lead) {
        outv.segment(off, m).noalias() = A(kf).leftCols(c) * xx.head(c);
      } else {
        outv.segment(off, m).noalias() = A(kf) * xx;
      }
      continue;
    }
    outv.segment(off, m).setZero();
    for (int q = r0; q < r1; q += 2) {
      const int b = axRuns[static_cast<size_t>(q)], e = axRuns[static_cast<size_t>(q + 1)];
      if (lead) {
        outv.segment(off + b, e - b).noalias() = A(kf).middleRows(b, e - b).leftCols(c) * xx.head(c);
      } else {
        outv.segment(off + b, e - b).noalias() = A(kf).middleRows(b, e - b) * xx;
      }
    }
  }
}

void Solver::Impl::startFromStates() {
  fact.clearActive();
  for (int g = 0; g < M; ++g) {
    if (state[static_cast<size_t>(g)] != RowState::Inactive) {
      const int kf = fact.levelOf(g);
      fact.activate(kf, g - fact.rowOffset(kf));
    }
  }
  updateFreeVariables();
  computeAx(x, Ax);
  for (int g = 0; g < M; ++g) {
    if (state[static_cast<size_t>(g)] == RowState::Inactive) {
      v(g) = Ax(g) - std::min(std::max(Ax(g), lo(g)), up(g));
    } else {
      v(g) = Ax(g) - target(g);
    }
  }
}

void Solver::Impl::buildTargets() {
  // b = target - A_fixed x_fixed on the active rows. Column by column (the fixed variables in
  // order), so that each column is read where it is stored; every row takes the same operations in
  // the same order as a row-by-row sum. Past a level's declared columns the entries are zeros, so
  // with a finite fixed value each such term is a signed zero, and t - (+-0) is t to the bit unless
  // t is -0. A sum that does not start at -0 never becomes -0 (an exact cancellation gives +0):
  // the terms of a finite value are left out unless a row's target is -0.
  //
  // A row's b is kept from an earlier iteration of this solve when its inputs are the same: the
  // fixed variables (set and values, compared to the bit: a new epoch otherwise), its target (to
  // the bit) and whether its level sums every term. It is then the value computed here, bit for
  // bit; only the rows activated or changed since are computed.
  const auto sameBits = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  bool same = fixedXValid;
  for (int q = 0; q < nFixed && same; ++q) same = sameBits(fixedX(q), x(fixedVar[static_cast<size_t>(q)]));
  if (!same) {
    ++fixedEpoch;
    for (int q = 0; q < nFixed; ++q) fixedX(q) = x(fixedVar[static_cast<size_t>(q)]);
    fixedXValid = true;
  }
  for (int kf = 0; kf < lg; ++kf) {
    const std::vector<int>& act = fact.activeList(kf);
    if (act.empty()) continue;
    const Eigen::MatrixXd& Ak = A(kf);
    const int off = fact.rowOffset(kf);
    int cols = prob->level(kf + first).columns;
    // The rows to compute: those whose epoch, target or whole-sum flag changed. The flag is the
    // level's, known once every target is seen: the rows are checked against the level's flag of
    // its last call, and all of them are computed when it changed.
    const char wasWhole = bLevelWhole[static_cast<size_t>(kf)];
    int todo = 0;
    for (int gid : act) {
      const size_t g = static_cast<size_t>(gid);
      const double t = target(gid);
      if (t == 0.0 && std::signbit(t)) cols = -1;
      const bool kept = bEpoch[g] == fixedEpoch && bWhole[g] == wasWhole && sameBits(bTarget[g], t);
      bTarget[g] = t;
      if (!kept) bTodo[static_cast<size_t>(todo++)] = gid;
    }
    const char whole = cols < 0 ? 1 : 0;
    bLevelWhole[static_cast<size_t>(kf)] = whole;
    if (whole != wasWhole) {
      todo = 0;
      for (int gid : act) bTodo[static_cast<size_t>(todo++)] = gid;
    }
    for (int r = 0; r < todo; ++r) {
      const size_t g = static_cast<size_t>(bTodo[static_cast<size_t>(r)]);
      bEpoch[g] = fixedEpoch;
      bWhole[g] = whole;
      b(static_cast<Eigen::Index>(g)) = bTarget[g];
    }
    if (todo == 0) continue;
    for (int q = 0; q < nFixed; ++q) {
      const int i = fixedVar[static_cast<size_t>(q)];
      const double xi = x(i);
      if (cols >= 0 && i >= cols && std::isfinite(xi)) continue;
      const double* col = Ak.col(i).data();
      for (int r = 0; r < todo; ++r) {
        const int gid = bTodo[static_cast<size_t>(r)];
        b(gid) -= col[gid - off] * xi;
      }
    }
  }
}

void Solver::Impl::solveEquality() {
  multValid = false;
  buildTargets();
  fact.factorize(rankTol);
  xs = x;  // fixed variables keep their (bound) values; the free ones are overwritten
  fact.solve(b, xs, res);
}

void Solver::Impl::prepareLevels() {
  multValid = true;
  const double xnorm = xs.lpNorm<Eigen::Infinity>();
  for (int kf = 0; kf < lg; ++kf) {
    double S = 0.0;
    bool nonzero = false;
    for (int gid : fact.activeList(kf)) {
      const double rj = res(gid);
      S += std::abs(rj) * rowNorm(gid);
      if (std::abs(rj) > opt.zero_tolerance * rowScale(gid, xnorm)) nonzero = true;
    }
    // A level whose only nonzero residuals sit on zero rows exerts no force on earlier levels.
    levelS(kf) = S > 0.0 ? S : 1.0;
    levelNz[static_cast<size_t>(kf)] = nonzero ? 1 : 0;
    multDone[static_cast<size_t>(kf)] = 0;
  }
}

void Solver::Impl::ensureMult(int kf) {
  if (multDone[static_cast<size_t>(kf)]) return;
  multDone[static_cast<size_t>(kf)] = 1;
  auto col = muAll.col(kf);
  col.setZero();
  fact.multipliers(kf, res, col);
  // Fixed variables: mu_i = -sum_j A_ji mu_j over the active rows of levels <= kf, summed in the
  // order of the levels and their active rows. Variable by variable, so that A's column i is read
  // where it is stored. Past a level's declared columns the entries are zeros: with finite
  // multipliers each such term is a signed zero, and m - (+-0) is m to the bit unless m is -0,
  // which a sum starting at +0 never is (an exact cancellation gives +0). Such a level is left out
  // when its multipliers are finite.
  auto mv = muVarAll.col(kf);
  mv.setZero();
  if (nFixed == 0) return;
  for (int j = 0; j <= kf; ++j) {
    bool finite = true;
    for (int gid : fact.activeList(j)) finite = finite && std::isfinite(col(gid));
    muFinite[static_cast<size_t>(j)] = finite ? 1 : 0;
  }
  for (int q = 0; q < nFixed; ++q) {
    const int i = fixedVar[static_cast<size_t>(q)];
    double m = 0.0;
    for (int j = 0; j <= kf; ++j) {
      const int cols = prob->level(j + first).columns;
      if (cols >= 0 && i >= cols && muFinite[static_cast<size_t>(j)]) continue;
      const double* ai = A(j).col(i).data();
      const int off = fact.rowOffset(j);
      for (int gid : fact.activeList(j)) {
        const double mj = col(gid);
        if (mj == 0.0) continue;
        m -= ai[gid - off] * mj;
      }
    }
    mv(i) = m;
  }
}

// Value of a multiplier counted positive when its sign is the correct one for the constraint's
// state (>= 0 at an upper bound, <= 0 at a lower bound).
double Solver::Impl::correctSign(int kind, int idx, double value) const {
  const RowState s = (kind == 0) ? vstate[static_cast<size_t>(idx)] : state[static_cast<size_t>(idx)];
  return (s == RowState::Upper) ? value : -value;
}

// A constraint whose multiplier for the level-kf problem has the wrong sign is still held if an
// intermediate level i (between the constraint's level and kf) with a nonzero residual holds it
// with the correct sign: the level-kf multipliers are only defined up to adding t * mu^(i),
// t >= 0, and mu^(i) is a sign-valid certificate, so a valid certificate for level kf exists.
bool Solver::Impl::isHeld(int kind, int idx, int levelH, int kf) {
  for (int i = kf - 1; i > levelH; --i) {
    if (!levelNz[static_cast<size_t>(i)]) continue;
    ensureMult(i);
    const double v = (kind == 0) ? muVarAll(idx, i) : muAll(idx, i);
    const double norm = (kind == 0) ? 1.0 : rowNorm(idx);
    if (correctSign(kind, idx, v) * norm > dualTol * levelS(i)) return true;
  }
  return false;
}

// A fixed variable i whose bound's multiplier for the level-kf problem has the wrong sign is still
// held when an active row of an earlier level reads x_i alone and is satisfied (a regularisation
// target equal to the bound, say): that row constrains x_i as the bound does, and the bound's
// multiplier can pass to it (an equality's takes either sign, an inequality's must keep its
// correct sign). The factorisation gives such a row, a zero row in reduced coordinates, a zero
// multiplier and the bound the whole of it; releasing the bound then moves nothing, and rounding
// makes it block again (a cycle). Returns the row's id, or -1.
int Solver::Impl::unitRowHolding(int i, int kf) const {
  const double mi = muVarAll(i, kf);
  for (int j = 0; j < kf; ++j) {
    const Eigen::MatrixXd& Aj = A(j);
    const int off = fact.rowOffset(j);
    for (int gid : fact.activeList(j)) {
      const int r = gid - off;
      const double a = Aj(r, i);
      if (a == 0.0) continue;
      bool alone = true;
      for (int c = 0; c < Aj.cols() && alone; ++c) alone = c == i || Aj(r, c) == 0.0;
      if (!alone) continue;
      // Satisfied on its own scale (a x = a x_i): another variable's size must not hide a
      // residual that a later level could still remove by releasing the bound.
      if (std::abs(res(gid)) > opt.zero_tolerance * (std::abs(target(gid)) + std::abs(a * xs(i)))) continue;
      const RowState st = state[static_cast<size_t>(gid)];
      if (st == RowState::Equality || correctSign(1, gid, muAll(gid, kf) + mi / a) >= 0.0) return gid;
    }
  }
  return -1;
}

bool Solver::Impl::dualCheck(bool bland, int& kind, int& idx, int& level) {
  // kind: 0 = variable bound, 1 = general row. Returns true when a constraint must leave.
  const double xnorm = xs.lpNorm<Eigen::Infinity>();
  prepareLevels();
  for (int kf = 0; kf < lg; ++kf) {
    if (!levelNz[static_cast<size_t>(kf)]) continue;  // the level is satisfied: its multipliers vanish
    ensureMult(kf);
    const double S = levelS(kf);
    const auto mu = muAll.col(kf);
    const auto muVar = muVarAll.col(kf);

    double best = 0.0;
    int bestKind = -1, bestIdx = std::numeric_limits<int>::max();
    auto consider = [&](int k, int i, double measure) {
      if (bland) {
        // Smallest index, variables first.
        if (bestKind < 0 || k < bestKind || (k == bestKind && i < bestIdx)) {
          bestKind = k;
          bestIdx = i;
          best = measure;
        }
      } else if (measure > best) {
        best = measure;
        bestKind = k;
        bestIdx = i;
      }
    };
    // Rows of this level: the multiplier is the residual.
    for (int gid : fact.activeList(kf)) {
      const RowState s = state[static_cast<size_t>(gid)];
      if (s != RowState::Lower && s != RowState::Upper) continue;
      if (tabooRow[static_cast<size_t>(gid)]) continue;
      const double viol = -correctSign(1, gid, res(gid));
      if (viol > opt.zero_tolerance * rowScale(gid, xnorm)) consider(1, gid, rowNorm(gid) > 0.0 ? viol * rowNorm(gid) / S : 1.0);
    }
    // Rows of earlier levels that are satisfied (not frozen at a nonzero violation).
    for (int j = 0; j < kf; ++j) {
      for (int gid : fact.activeList(j)) {
        const RowState s = state[static_cast<size_t>(gid)];
        if (s != RowState::Lower && s != RowState::Upper) continue;
        if (tabooRow[static_cast<size_t>(gid)]) continue;
        if (std::abs(res(gid)) > opt.zero_tolerance * rowScale(gid, xnorm)) continue;  // frozen
        const double measure = -correctSign(1, gid, mu(gid)) * rowNorm(gid) / S;
        if (measure > dualTol && !isHeld(1, gid, j, kf)) consider(1, gid, measure);
      }
    }
    // Active variable bounds.
    for (int q = 0; q < nFixed; ++q) {
      const int i = fixedVar[static_cast<size_t>(q)];
      const RowState s = vstate[static_cast<size_t>(i)];
      if (s != RowState::Lower && s != RowState::Upper) continue;
      if (tabooVar[static_cast<size_t>(i)]) continue;
      const double measure = -correctSign(0, i, muVar(i)) / S;
      if (measure > dualTol && !isHeld(0, i, -1, kf) && unitRowHolding(i, kf) < 0) consider(0, i, measure);
    }
    if (bestKind >= 0) {
      kind = bestKind;
      idx = bestIdx;
      level = kf;
      if (opt.trace) {
        std::fprintf(stderr, "   dual level %d: release %d:%d measure %.3e res %.3e mu %.3e S %.3e\n", kf, kind, idx, best,
                     kind == 1 ? res(idx) : 0.0, kind == 1 ? mu(idx) : muVar(idx), S);
      }
      return true;
    }
  }
  return false;
}

void Solver::Impl::run() {
  resetCounters();
  const long stages0 = fact.stagesFactorized(), restarts0 = fact.boundChangeRestarts();
  bool optPhase = false;
  int degenerateRun = 0;
  bool bland = false;
  bool pending = false;  // the working set changed after the last equality solve
  bool forceBland = false;
  bool restartedCold = false;
  int repeatsRaised = 0;  // working sets repeated with the tolerances raised as far as they go
  // The search's own state, from the working set in vstate / state.
  auto beginSearch = [&]() {
    degenerateRun = 0;
    bland = forceBland = false;
    std::fill(tabooRow.begin(), tabooRow.end(), 0);
    std::fill(tabooVar.begin(), tabooVar.end(), 0);
    lastDropKind = lastDropIdx = -1;
    rankTol = opt.rank_tolerance;
    dualTol = opt.dual_tolerance;
    wsHash = 0;
    for (int i = 0; i < n; ++i) hashFlip(0, i, vstate[static_cast<size_t>(i)]);
    for (int g = 0; g < M; ++g) hashFlip(1, g, state[static_cast<size_t>(g)]);
    recentCount = recentPos = 0;
  };
  beginSearch();
  out.status = Status::Solved;
  out.reason = StopReason::Optimal;

  for (;;) {
    if (out.iterations >= opt.max_iterations) {
      out.status = Status::IterationLimit;
      out.reason = StopReason::HardIterationCap;
      break;
    }
    solveEquality();
    pending = false;
    ++out.iterations;
    if (optPhase) ++out.optimality_iterations;

    dx = xs - x;
    computeAx(dx, Adx);
    const double dxNorm = dx.norm();
    for (int g = 0; g < M; ++g) dv(g) = (state[static_cast<size_t>(g)] == RowState::Inactive) ? -v(g) : res(g) - v(g);

    // Right after a release, the released constraint does not block a step that moves it by
    // rounding only (over the full step, at most kRoundingMotion times its own size: its bound
    // plus its row norm times |x|): the equality solution keeps it where it was because another
    // active row holds it (e.g. its duplicate on a later level). Blocking, it would be activated
    // again at once and kept by the anti-cycling rule below with its wrong-sign multiplier, the
    // release hidden; instead it stays released (every other constraint still blocks the step),
    // and the dual check goes on (it releases the duplicate next).
    bool releasedStays = false;
    if (lastDropKind >= 0) {
      const int k = lastDropIdx;
      const double xnorm = x.lpNorm<Eigen::Infinity>();
      if (lastDropKind == 0) {
        const double bound = lastDropState == RowState::Lower ? xlo(k) : xup(k);
        releasedStays = std::abs(dx(k)) <= kRoundingMotion * (std::abs(bound) + xnorm);
      } else {
        const double bound = lastDropState == RowState::Lower ? lo(k) : up(k);
        releasedStays = std::abs(Adx(k) - dv(k)) <= kRoundingMotion * (std::abs(bound) + rowNorm(k) * xnorm);
      }
    }

    // Ratio test over inactive bounds and rows.
    double alpha = 1.0;
    int blockKind = -1, blockIdx = -1;
    RowState blockState = RowState::Inactive;
    const double tiny = 1e-15;
    auto offer = [&](double a, int k, int i, RowState s) {
      if (a < 0.0) a = 0.0;
      const bool better =
          bland ? (a < alpha - tiny || (a <= alpha + tiny && blockKind >= 0 && (k < blockKind || (k == blockKind && i < blockIdx))))
                : (a < alpha);
      if (better || (blockKind < 0 && a < alpha)) {
        alpha = std::min(a, alpha);
        blockKind = k;
        blockIdx = i;
        blockState = s;
      }
    };
    for (int i = 0; i < n; ++i) {
      if (vstate[static_cast<size_t>(i)] != RowState::Inactive) continue;
      if (releasedStays && lastDropKind == 0 && i == lastDropIdx) continue;
      const double d = dx(i);
      const double thr = opt.feasibility_tolerance * dxNorm;
      if (d > thr && std::isfinite(xup(i)))
        offer((xup(i) - x(i)) / d, 0, i, RowState::Upper);
      else if (d < -thr && std::isfinite(xlo(i)))
        offer((xlo(i) - x(i)) / d, 0, i, RowState::Lower);
    }
    for (int g = 0; g < M; ++g) {
      if (state[static_cast<size_t>(g)] != RowState::Inactive) continue;
      if (releasedStays && lastDropKind == 1 && g == lastDropIdx) continue;
      const double den = Adx(g) - dv(g);
      const double thr = opt.feasibility_tolerance * (rowNorm(g) * dxNorm + std::abs(dv(g)));
      const double s = Ax(g) - v(g);
      if (den > thr && std::isfinite(up(g)))
        offer((up(g) - s) / den, 1, g, RowState::Upper);
      else if (den < -thr && std::isfinite(lo(g)))
        offer((lo(g) - s) / den, 1, g, RowState::Lower);
    }

    // Step.
    const bool full = blockKind < 0;
    if (full) alpha = 1.0;
    if (full) {
      x = xs;
      Ax += Adx;
      for (int g = 0; g < M; ++g) v(g) = (state[static_cast<size_t>(g)] == RowState::Inactive) ? 0.0 : res(g);
    } else if (alpha > 0.0) {
      x += alpha * dx;
      Ax += alpha * Adx;
      v += alpha * dv;
    }
    // Progress in the (x, v) space: a step that only moves slacks (a row switching sides) counts.
    const double moved = alpha * std::max(dx.lpNorm<Eigen::Infinity>(), dv.head(M).lpNorm<Eigen::Infinity>());
    // After a release that left its constraint where it was, a step of rounding size is no
    // progress either.
    const double scale = 1.0 + x.lpNorm<Eigen::Infinity>() + v.head(M).lpNorm<Eigen::Infinity>();
    const bool stalled = moved <= 1e-15 * scale || (releasedStays && moved <= kRoundingMotion * scale);
    if (stalled) {
      ++degenerateRun;
      if (degenerateRun >= opt.bland_after_degenerate_steps) bland = true;
      // The constraint just released blocks again at once: keep it (it is held).
      if (!full && blockKind == lastDropKind && blockIdx == lastDropIdx && blockState == lastDropState) {
        (blockKind == 0 ? tabooVar : tabooRow)[static_cast<size_t>(blockIdx)] = 1;
        ++out.held_after_reblock;
      }
    } else {
      degenerateRun = 0;
      bland = false;
      std::fill(tabooRow.begin(), tabooRow.end(), 0);
      std::fill(tabooVar.begin(), tabooVar.end(), 0);
    }
    lastDropKind = lastDropIdx = -1;

    if (opt.trace) {
      std::fprintf(stderr, "it %d alpha %.3e |dx| %.3e block %d:%d(%s) bland %d x=", out.iterations, alpha, dxNorm, blockKind, blockIdx,
                   toString(blockState), bland ? 1 : 0);
      for (int i = 0; i < std::min(n, 8); ++i) std::fprintf(stderr, " %.6g", x(i));
      std::fprintf(stderr, "\n");
    }
    if (!full) {
      // Activate the blocking constraint exactly at its bound.
      hashFlip(blockKind, blockIdx, blockState);
      if (blockKind == 0) {
        const int i = blockIdx;
        x(i) = (blockState == RowState::Upper) ? xup(i) : xlo(i);
        vstate[static_cast<size_t>(i)] = blockState;
        updateFreeVariables();
      } else {
        const int g = blockIdx;
        state[static_cast<size_t>(g)] = blockState;
        v(g) = Ax(g) - target(g);
        const int kf = fact.levelOf(g);
        fact.activate(kf, g - fact.rowOffset(kf));
      }
      ++out.activations;
      pending = true;
    } else {
      int kind = -1, idx = -1, level = -1;
      if (!dualCheck(bland, kind, idx, level)) {
        out.status = Status::Solved;
        out.reason = StopReason::Optimal;
        out.optimal_through = p - 1;
        break;
      }
      // The levels before the releasing one are optimal; they stay so while it is optimised
      // (its steps keep the earlier levels' objectives), until a later dual check says otherwise.
      out.optimal_through = level + first - 1;
      if (opt.trace) std::fprintf(stderr, "   deactivate %d:%d\n", kind, idx);
      lastDropKind = kind;
      lastDropIdx = idx;
      lastDropState = (kind == 0) ? vstate[static_cast<size_t>(idx)] : state[static_cast<size_t>(idx)];
      hashFlip(kind, idx, lastDropState);
      if (kind == 0) {
        vstate[static_cast<size_t>(idx)] = RowState::Inactive;
        updateFreeVariables();
      } else {
        state[static_cast<size_t>(idx)] = RowState::Inactive;
        // v keeps the current residual; as an inactive row its target slack is 0.
        const int kf = fact.levelOf(idx);
        fact.deactivate(kf, idx - fact.rowOffset(kf));
      }
      ++out.deactivations;
      optPhase = true;
      pending = true;
    }

    // Cycle detection: the new working set was already visited in this solve.
    bool repeated = false;
    for (int q = 0; q < recentCount; ++q) repeated = repeated || recent[static_cast<size_t>(q)] == wsHash;
    recent[static_cast<size_t>(recentPos)] = wsHash;
    recentPos = (recentPos + 1) % static_cast<int>(recent.size());
    recentCount = std::min(recentCount + 1, static_cast<int>(recent.size()));
    const bool raisedFully = rankTol >= 1e-6 && dualTol >= 1e-6;
    if (repeated && raisedFully) ++repeatsRaised;
    if (repeated && raisedFully && !restartedCold && repeatsRaised >= kRecentWorkingSets) {
      // Working sets keep repeating with the tolerances already raised as far as they go (as
      // many repeats as the hash window holds): a cycle among degenerate constraints that Bland's
      // rule and the held constraints do not break (a warm start at a degenerate point can lead
      // into one). The search starts again from the cold start, once per solve; the iterations
      // before it are counted. A search that the paper's stop rules end sooner is not affected.
      ++out.cycles_broken;
      ++out.cold_restarts;
      restartedCold = true;
      // The point reached, kept in case the iteration budget ends the cold search before it is
      // as far (below).
      savedX = x;
      savedVstate = vstate;
      savedState = state;
      savedThrough = out.optimal_through;
      initCold();
      startFromStates();
      fact.invalidateAll();
      beginSearch();
      optPhase = false;
      out.optimal_through = -1;
      out.optimality_iterations = 0;  // the cold search's optimality phase counts afresh
      pending = true;
      if (opt.trace) std::fprintf(stderr, "   cycle at the largest tolerances: the search starts again cold\n");
    } else if (repeated && !raisedFully) {
      ++out.cycles_broken;
      rankTol = std::min(1e-6, std::max(rankTol, rankTol * opt.cycle_tolerance_factor));
      dualTol = std::min(1e-6, std::max(dualTol, dualTol * opt.cycle_tolerance_factor));
      fact.invalidateAll();
      forceBland = true;
      recentCount = recentPos = 0;
      if (opt.trace) std::fprintf(stderr, "   cycle detected: tolerances raised to %.1e / %.1e\n", rankTol, dualTol);
    }
    if (forceBland) bland = true;

    // Paper termination rules (sec. VIII-B).
    if (opt.stop_slack_norm > 0.0 && v.head(M).squaredNorm() <= opt.stop_slack_norm) {
      out.status = Status::Solved;
      out.reason = StopReason::SlackBelowThreshold;
      break;
    }
    const bool mayStop = opt.stop_after_level < 0 || out.optimal_through >= opt.stop_after_level;
    if (mayStop && opt.stop_optimality_iterations > 0 && out.optimality_iterations >= opt.stop_optimality_iterations) {
      out.status = Status::StoppedEarly;
      out.reason = StopReason::OptimalityPhaseLimit;
      break;
    }
    if (mayStop && opt.stop_total_iterations > 0 && out.iterations >= opt.stop_total_iterations) {
      out.status = Status::StoppedEarly;
      out.reason = StopReason::TotalIterationLimit;
      break;
    }
  }

  // A cold restart that the iteration budget (max_iterations, the paper's stop rules) cut before
  // the cold search was as far as the point it left: that point is the answer, with its working
  // set.
  if (restartedCold && out.status != Status::Solved && out.optimal_through < savedThrough) {
    x = savedX;
    vstate = savedVstate;
    state = savedState;
    startFromStates();
    out.optimal_through = savedThrough;
    pending = true;
  }
  if (opt.compute_multipliers && pending) {
    // Multipliers of the current working set (its equality solution; x itself is not moved).
    solveEquality();
  }
  (void)pending;
  out.factorizations = static_cast<int>(fact.stagesFactorized() - stages0);
  out.bound_change_restarts = static_cast<int>(fact.boundChangeRestarts() - restarts0);
}

// Arithmetic that left the double range (coefficients near 1e300, a near-singular level scaled
// beyond it) must never pass for a solution: x, the violations and the multipliers must be finite.
void Solver::Impl::checkFiniteResult() {
  const bool finite = allFiniteFast(out.x) && allFiniteFast(out.violation_norm) && (!opt.compute_multipliers || allFiniteFast(out.lambda));
  if (!finite) {
    out.status = Status::NonFiniteResult;
    out.reason = StopReason::NonFiniteResult;
    out.optimal_through = -1;
    lambdaTailsZero = false;  // the next solve zeroes every multiplier
  }
}

void Solver::Impl::finish() {
  const Problem& problem = *prob;
  out.x = x;
  out.last_level_projected = fact.lastLevelProjected();
  out.projected_levels = fact.projectedLevels();
  out.split_applied = fact.splitApplied();
  out.spanning_stages = fact.spanningStages();
  out.structured_stages = fact.structuredStages();
  // True violations at the final x (Ax is kept up to date along the steps).
  if (hasBounds) {
    const Level& lv = problem.level(0);
    for (int r = 0; r < lv.rows(); ++r) {
      const double ax = lv.coefficient(r) * x(lv.variable[static_cast<size_t>(r)]);
      out.violation[0](r) = ax - std::min(std::max(ax, lv.lower(r)), lv.upper(r));
    }
  }
  for (int kf = 0; kf < lg; ++kf) {
    const int off = fact.rowOffset(kf);
    auto& vl = out.violation[static_cast<size_t>(kf + first)];
    for (int r = 0; r < vl.size(); ++r) {
      // A free row's violation is 0 (also where its a x, formed within a run, overflowed).
      const double ax = Ax(off + r);
      vl(r) = freeRow(off + r) ? 0.0 : ax - std::min(std::max(ax, lo(off + r)), up(off + r));
    }
  }
  for (int l = 0; l < p; ++l) out.violation_norm(l) = out.violation[static_cast<size_t>(l)].norm();

  // Active set.
  if (hasBounds) {
    const Level& lv = problem.level(0);
    for (int r = 0; r < lv.rows(); ++r) {
      RowState s = vstate[static_cast<size_t>(lv.variable[static_cast<size_t>(r)])];
      if (lv.coefficient(r) < 0 && (s == RowState::Lower || s == RowState::Upper))
        s = (s == RowState::Lower) ? RowState::Upper : RowState::Lower;
      out.active.level[0][static_cast<size_t>(r)] = s;
    }
    out.rank[0] = nFixed;
  }
  for (int kf = 0; kf < lg; ++kf) {
    const int off = fact.rowOffset(kf);
    auto& al = out.active.level[static_cast<size_t>(kf + first)];
    for (int r = 0; r < static_cast<int>(al.size()); ++r) al[static_cast<size_t>(r)] = state[static_cast<size_t>(off + r)];
    out.rank[static_cast<size_t>(kf + first)] = fact.rank(kf);
  }

  // Multipliers, one column per level: a valid KKT certificate of each level's problem. The raw
  // multipliers of level l are corrected by adding t_i >= 0 times the (corrected) certificate of
  // an earlier level i that holds a row whose raw multiplier has the wrong sign (see isHeld).
  // Column l can be nonzero in the rows of levels 0..l only (the earlier levels' active rows,
  // the bound rows, the level's own; the corrections add earlier columns), so only those rows
  // need zeroing when the rest is known to be zero.
  if (lambdaTailsZero) {
    for (int l = 0; l < p; ++l) out.lambda.col(l).head(stackOff[static_cast<size_t>(l)] + rowsOf[static_cast<size_t>(l)]).setZero();
  } else {
    out.lambda.setZero();
    lambdaTailsZero = true;
  }
  if (!opt.compute_multipliers) return;
  if (!multValid) prepareLevels();
  const Level* bl = hasBounds ? &problem.level(0) : nullptr;
  auto rowOf = [&](int gid) {
    const int j = fact.levelOf(gid);
    return stackOff[static_cast<size_t>(j + first)] + gid - fact.rowOffset(j);
  };
  for (int kf = 0; kf < lg; ++kf) {
    const int l = kf + first;
    if (!levelNz[static_cast<size_t>(kf)]) continue;
    ensureMult(kf);
    auto col = out.lambda.col(l);
    const int colRows = stackOff[static_cast<size_t>(l)] + rowsOf[static_cast<size_t>(l)];
    for (int j = 0; j <= kf; ++j)
      for (int gid : fact.activeList(j)) col(rowOf(gid)) = muAll(gid, kf);
    for (int q = 0; q < nFixed; ++q) {
      const int i = fixedVar[static_cast<size_t>(q)];
      const int r = boundRow[static_cast<size_t>(i)];
      if (r < 0) continue;
      col(stackOff[0] + r) = muVarAll(i, kf) / bl->coefficient(r);
      // A bound that the dual check kept because a row reading x_i alone holds it
      // (unitRowHolding) passes its multiplier to that row.
      const RowState s = vstate[static_cast<size_t>(i)];
      if (s != RowState::Lower && s != RowState::Upper) continue;
      if (!(-correctSign(0, i, muVarAll(i, kf)) / levelS(kf) > dualTol) || isHeld(0, i, -1, kf)) continue;
      const int h = unitRowHolding(i, kf);
      if (h < 0) continue;
      const int j = fact.levelOf(h);
      col(rowOf(h)) += muVarAll(i, kf) / A(j)(h - fact.rowOffset(j), i);
      col(stackOff[0] + r) = 0.0;
    }
    // Corrections.
    for (int i = kf - 1; i >= 0; --i) {
      if (!levelNz[static_cast<size_t>(i)]) continue;
      const auto ci = out.lambda.col(i + first);
      double t = 0.0;
      auto need = [&](int row, RowState st, double a) {
        // Current value in column l and in column i, oriented so that >= 0 is correct.
        const double cur = (st == RowState::Upper) ? col(row) : -col(row);
        const double hold = (st == RowState::Upper) ? ci(row) : -ci(row);
        if (cur < 0.0 && hold > 0.0 && hold * a > opt.dual_tolerance * levelS(i)) t = std::max(t, -cur / hold);
      };
      for (int j = 0; j < i; ++j)
        for (int gid : fact.activeList(j)) {
          const RowState st = state[static_cast<size_t>(gid)];
          if (st == RowState::Lower || st == RowState::Upper) need(rowOf(gid), st, rowNorm(gid));
        }
      if (bl) {
        for (int q = 0; q < nFixed; ++q) {
          const int v = fixedVar[static_cast<size_t>(q)];
          RowState st = vstate[static_cast<size_t>(v)];
          const int r = boundRow[static_cast<size_t>(v)];
          if (r < 0 || (st != RowState::Lower && st != RowState::Upper)) continue;
          if (bl->coefficient(r) < 0) st = (st == RowState::Lower) ? RowState::Upper : RowState::Lower;
          need(stackOff[0] + r, st, std::abs(bl->coefficient(r)));
        }
      }
      // Over the column's own rows only: below them both columns hold +0 (t * 0 adds +0 to +0),
      // and an infinite t would put NaN there, which the next solve would not clear.
      if (t > 0.0) col.head(colRows) += t * ci.head(colRows);
    }
  }
}

Solver::Solver() : impl_(std::make_unique<Impl>()) {}
Solver::~Solver() = default;
Solver::Solver(Solver&&) noexcept = default;
Solver& Solver::operator=(Solver&&) noexcept = default;

void Solver::setup(const Problem& problem, const Options& options) { impl_->setup(problem, options); }
const Options& Solver::options() const { return impl_->opt; }
void Solver::setOptions(const Options& options) {
  options.validate();
  impl_->opt = options;
}
const Result& Solver::result() const { return impl_->out; }

const Result& Solver::Impl::solve(const Problem& problem, const ActiveSet* warm, const Eigen::VectorXd* xw) {
  checkCompatible(problem);
  // A result given away by swapResult() leaves buffers of any shape here.
  if (!resultShaped()) shapeResult();
  loadData(problem);
  if (scanNonFinite(problem)) {
    // Nothing is solved: no figure of an earlier solve (or of the buffers swapResult() gave
    // back) may pass for this one's. x, the violations and the multipliers are zeros, the
    // active set is empty, the counters are 0; bad_level and bad_row say where.
    shapeResult();
    resetCounters();
    out.status = Status::NonFiniteInput;
    out.reason = StopReason::NonFiniteInput;
    return out;
  }
  if (warm != nullptr) {
    initWarm(*warm, *xw);
  } else {
    initCold();
  }
  startFromStates();
  run();
  finish();
  checkFiniteResult();
  return out;
}

const Result& Solver::solve(const Problem& problem) { return impl_->solve(problem, nullptr, nullptr); }

void Solver::swapResult(Result& r) {
  std::swap(impl_->out, r);
  impl_->lambdaTailsZero = false;
}

void Solver::setStageTimes(StageTimes* times) {
  impl_->times = times;
  impl_->attachStageTimes();
}

const Result& Solver::solve(const Problem& problem, const ActiveSet& warm, const Eigen::VectorXd& xWarm) {
  return impl_->solve(problem, &warm, &xWarm);
}

}  // namespace lexdyn::solver
