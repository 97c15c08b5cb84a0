// An exact reference for the hierarchical least-squares solver, in rational arithmetic (GMP):
// given a problem and a solver result, it decides whether the result's per-level violations are
// the exact lexicographic optimum of the problem as stored in doubles (every double is an exact
// rational). Written for the verification sweep (harness/bench/solver_sweep.cpp) and its tests.
//
// Method, level by level (docs/solver.md, "Verification"):
//  1. the working set starts from the solver's active set; earlier rows whose exact optimal
//     violation is nonzero are frozen at their exact value (equalities);
//  2. the equality sub-problem (held rows of the level as least-squares targets, frozen and held
//     earlier rows as equalities) is solved exactly: reduced row echelon form of the constraints,
//     then the normal equations on their null space;
//  3. primal repairs, one at a time, until the point is exactly feasible and every held row of the
//     level is on the side of the bound it is held at (an earlier row out of its bounds is held,
//     a level row violated while inactive is held, a level row held on the wrong side is
//     released), at most a few times the number of rows;
//  4. the dual check is an exact linear program (phase 1 of the simplex method, Bland's rule):
//     multipliers of the earlier rows that are tight at the point (frozen and equality rows: any
//     sign; at an upper bound: >= 0; at a lower bound: <= 0) must cancel the level's gradient
//     sum_j a_j v_j. Its feasibility proves the point optimal for the level (convex problem,
//     KKT), so the level's violation vector is exactly the optimal one. While it is infeasible,
//     an earlier row held at a bound whose release (then repairs) lowers the level's objective
//     exactly is released: a descent that ends at a proven optimum or gives up (undecided).
// Verdict: Optimal when every level was proven and the solver's violation norms equal the exact
// ones to 1e-9 relative; NotOptimal when a proven level differs; Undecided when a level could not
// be proven from the solver's active set within the repair budget or the dual program is
// infeasible (the exact method does not search other active sets).
//
// Rational arithmetic grows: on problems of 100 variables one check can run for many minutes.
// exactCheck takes a work budget (deterministic: the same verdict on any machine; a pivot's
// work is the limbs of its row times the rows it clears, which tracks its time as the numbers
// grow), a time limit (machine-dependent) and a stop flag, checked at every pivot; a check that
// reaches one is Undecided (`out_of_work`, `out_of_time`, `interrupted`), never a pass.
#pragma once

#include <gmpxx.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/solver.hpp"

namespace lexdyn::solver::test {

struct ExactVerdict {
  enum Kind { Optimal, NotOptimal, Undecided };
  Kind kind = Undecided;
  std::string detail;
  std::vector<double> violation_norm;  ///< exact optimum per proven level (rounded to double)
  std::vector<double> x;               ///< the exact point of the last proven level (rounded)
  bool out_of_time = false;            ///< Undecided: the time limit was reached
  bool out_of_work = false;            ///< Undecided: the work budget was spent
  bool interrupted = false;            ///< Undecided: the stop flag was raised
  long work = 0;                       ///< their work (limbs of the pivot row x rows cleared)
};

inline const char* toString(ExactVerdict::Kind k) {
  return k == ExactVerdict::Optimal ? "optimal" : (k == ExactVerdict::NotOptimal ? "not_optimal" : "undecided");
}

namespace exact {

using Q = mpq_class;
using Mat = std::vector<std::vector<Q>>;

/// The running check's limits (one check at a time per thread), checked at every pivot.
struct Budget {
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  const std::atomic<int>* stop = nullptr;
  long work = 0;        ///< the pivots' work so far
  long work_limit = 0;  ///< > 0: at most that much
};
inline Budget& budget() {
  static thread_local Budget b;
  return b;
}
struct OutOfTime {};
struct OutOfWork {};
struct Interrupted {};
inline void checkBudget() {
  Budget& b = budget();
  if (b.stop && b.stop->load() != 0) throw Interrupted{};
  if (b.work_limit > 0 && b.work >= b.work_limit) throw OutOfWork{};
  if (b.deadline != std::chrono::steady_clock::time_point::max() && std::chrono::steady_clock::now() > b.deadline) throw OutOfTime{};
}

/// Gauss-Jordan pivot on m[row][col]: that row scaled to a 1 there, the column cleared in every
/// other row.
inline void pivot(Mat& m, int row, int col) {
  checkBudget();
  auto& pr = m[static_cast<size_t>(row)];
  const Q inv = 1 / pr[static_cast<size_t>(col)];
  long limbs = 0;
  for (auto& v : pr) {
    v *= inv;
    limbs += 1 + static_cast<long>(mpz_size(v.get_num_mpz_t()) + mpz_size(v.get_den_mpz_t()));
  }
  long cleared = 0;
  for (size_t r = 0; r < m.size(); ++r) {
    if (r == static_cast<size_t>(row)) continue;
    auto& rr = m[r];
    const Q f = rr[static_cast<size_t>(col)];
    if (sgn(f) == 0) continue;
    ++cleared;
    for (size_t k = 0; k < rr.size(); ++k) rr[k] -= f * pr[k];
  }
  budget().work += limbs * (1 + cleared);
}

/// Reduced row echelon form in place; returns the pivot column of each pivot row.
inline std::vector<int> rref(Mat& m, int cols) {
  std::vector<int> pivots;
  int row = 0;
  const int rows = static_cast<int>(m.size());
  for (int c = 0; c < cols && row < rows; ++c) {
    int p = -1;
    for (int r = row; r < rows; ++r) {
      if (sgn(m[static_cast<size_t>(r)][static_cast<size_t>(c)]) != 0) {
        p = r;
        break;
      }
    }
    if (p < 0) continue;
    std::swap(m[static_cast<size_t>(p)], m[static_cast<size_t>(row)]);
    pivot(m, row, c);
    pivots.push_back(c);
    ++row;
  }
  return pivots;
}

/// Solves M y = b (M: rows x n) exactly: false when inconsistent; otherwise y with the free
/// variables 0, and the null space basis in `null` (n x f, columns).
inline bool solveLinear(const Mat& M, const std::vector<Q>& b, int n, std::vector<Q>& y, Mat* null) {
  Mat aug = M;
  for (size_t r = 0; r < aug.size(); ++r) aug[r].push_back(b[r]);
  const std::vector<int> piv = rref(aug, n);
  for (size_t r = piv.size(); r < aug.size(); ++r) {
    if (sgn(aug[r][static_cast<size_t>(n)]) != 0) return false;
  }
  y.assign(static_cast<size_t>(n), Q(0));
  for (size_t r = 0; r < piv.size(); ++r) y[static_cast<size_t>(piv[r])] = aug[r][static_cast<size_t>(n)];
  if (null) {
    null->clear();
    std::vector<char> is_piv(static_cast<size_t>(n), 0);
    for (int c : piv) is_piv[static_cast<size_t>(c)] = 1;
    for (int f = 0; f < n; ++f) {
      if (is_piv[static_cast<size_t>(f)]) continue;
      std::vector<Q> z(static_cast<size_t>(n), Q(0));
      z[static_cast<size_t>(f)] = 1;
      for (size_t r = 0; r < piv.size(); ++r) z[static_cast<size_t>(piv[r])] = -aug[r][static_cast<size_t>(f)];
      null->push_back(z);
    }
  }
  return true;
}

/// Feasibility of { z >= 0 : A z = b } (A: m x k) by phase 1 of the simplex method (Bland).
inline bool lpFeasible(const Mat& A, const std::vector<Q>& b, int k) {
  const int m = static_cast<int>(A.size());
  // Tableau with artificials: [A | I | b] with rows sign-flipped so that b >= 0.
  Mat T(static_cast<size_t>(m), std::vector<Q>(static_cast<size_t>(k + m + 1), Q(0)));
  std::vector<int> basis(static_cast<size_t>(m));
  for (int r = 0; r < m; ++r) {
    const bool flip = sgn(b[static_cast<size_t>(r)]) < 0;
    for (int c = 0; c < k; ++c)
      T[static_cast<size_t>(r)][static_cast<size_t>(c)] =
          flip ? -A[static_cast<size_t>(r)][static_cast<size_t>(c)] : A[static_cast<size_t>(r)][static_cast<size_t>(c)];
    T[static_cast<size_t>(r)][static_cast<size_t>(k + r)] = 1;
    T[static_cast<size_t>(r)][static_cast<size_t>(k + m)] = flip ? -b[static_cast<size_t>(r)] : b[static_cast<size_t>(r)];
    basis[static_cast<size_t>(r)] = k + r;
  }
  const int cols = k + m;
  for (int iter = 0; iter < 100000; ++iter) {
    // Reduced costs of phase 1 (minimise the sum of artificials): c_j = -sum_r T[r][j] for
    // non-artificial j (artificials have cost 1).
    int enter = -1;
    for (int j = 0; j < cols && enter < 0; ++j) {
      if (std::find(basis.begin(), basis.end(), j) != basis.end()) continue;
      Q rc = j >= k ? Q(1) : Q(0);
      for (int r = 0; r < m; ++r) {
        if (basis[static_cast<size_t>(r)] >= k) rc -= T[static_cast<size_t>(r)][static_cast<size_t>(j)];
      }
      if (sgn(rc) < 0) enter = j;  // Bland: the smallest improving index
    }
    if (enter < 0) break;
    int leave = -1;
    Q best;
    for (int r = 0; r < m; ++r) {
      const Q& a = T[static_cast<size_t>(r)][static_cast<size_t>(enter)];
      if (sgn(a) <= 0) continue;
      const Q ratio = T[static_cast<size_t>(r)][static_cast<size_t>(cols)] / a;
      if (leave < 0 || ratio < best || (ratio == best && basis[static_cast<size_t>(r)] < basis[static_cast<size_t>(leave)])) {
        leave = r;
        best = ratio;
      }
    }
    if (leave < 0) break;  // unbounded direction: cannot happen in phase 1 (objective >= 0)
    pivot(T, leave, enter);
    basis[static_cast<size_t>(leave)] = enter;
  }
  Q infeas(0);
  for (int r = 0; r < m; ++r) {
    if (basis[static_cast<size_t>(r)] >= k) infeas += T[static_cast<size_t>(r)][static_cast<size_t>(cols)];
  }
  return sgn(infeas) == 0;
}

}  // namespace exact

/// The exact verdict on `r` for `p` without limits (see exactCheck).
inline ExactVerdict exactCheckUnlimited(const Problem& p, const Result& r, int repairs_per_row) {
  using exact::Q;
  ExactVerdict out;
  const int n = p.variables();
  struct Row {
    std::vector<Q> a;
    bool has_lo = false, has_up = false;
    Q lo, up;
    int level = 0;
    RowState state = RowState::Inactive;
    bool equality() const { return has_lo && has_up && lo == up; }
  };
  std::vector<Row> rows;
  for (int l = 0; l < p.levelCount(); ++l) {
    const Level& lv = p.level(l);
    for (int k = 0; k < lv.rows(); ++k) {
      Row row;
      row.a.assign(static_cast<size_t>(n), Q(0));
      if (lv.kind == LevelKind::General) {
        for (int c = 0; c < n; ++c) row.a[static_cast<size_t>(c)] = Q(lv.A(k, c));
      } else {
        row.a[static_cast<size_t>(lv.variable[static_cast<size_t>(k)])] = Q(lv.coefficient(k));
      }
      row.has_lo = std::isfinite(lv.lower(k));
      row.has_up = std::isfinite(lv.upper(k));
      if (row.has_lo) row.lo = Q(lv.lower(k));
      if (row.has_up) row.up = Q(lv.upper(k));
      row.level = l;
      row.state = r.active.level[static_cast<size_t>(l)][static_cast<size_t>(k)];
      rows.push_back(std::move(row));
    }
  }
  const int M = static_cast<int>(rows.size());
  auto dot = [&](const std::vector<Q>& a, const std::vector<Q>& x) {
    Q s(0);
    for (int c = 0; c < n; ++c) {
      if (sgn(a[static_cast<size_t>(c)]) != 0) s += a[static_cast<size_t>(c)] * x[static_cast<size_t>(c)];
    }
    return s;
  };
  auto violation = [](const Row& row, const Q& ax) {
    if (row.has_up && ax > row.up) return Q(ax - row.up);
    if (row.has_lo && ax < row.lo) return Q(ax - row.lo);
    return Q(0);
  };
  // held[j]: 0 not held, 1 held at lower, 2 held at upper (equality rows: at lower == upper).
  std::vector<int> held(static_cast<size_t>(M), 0);
  for (int j = 0; j < M; ++j) {
    const Row& row = rows[static_cast<size_t>(j)];
    if (row.equality() || row.state == RowState::Equality)
      held[static_cast<size_t>(j)] = 1;
    else if (row.state == RowState::Lower && row.has_lo)
      held[static_cast<size_t>(j)] = 1;
    else if (row.state == RowState::Upper && row.has_up)
      held[static_cast<size_t>(j)] = 2;
  }
  const std::vector<int> solver_held = held;  // every level starts from the solver's active set
  std::vector<char> frozen(static_cast<size_t>(M), 0);
  std::vector<Q> frozen_value(static_cast<size_t>(M));

  // The equality sub-problem of level k for a working set: earlier frozen rows and held rows are
  // equalities (a held row exactly dependent on the ones before it and inconsistent with them is
  // left out: the solver keeps dependent rows in its active set without imposing them), held
  // rows of level k are least-squares targets. False when the frozen rows are inconsistent.
  auto solveEquality = [&](int k, const std::vector<int>& h, std::vector<Q>& x) {
    exact::Mat C, F;
    std::vector<Q> d, g;
    for (int pass = 0; pass < 2; ++pass) {  // frozen rows first, then held ones
      for (int j = 0; j < M; ++j) {
        const Row& row = rows[static_cast<size_t>(j)];
        if (row.level >= k) break;
        const bool is_frozen = frozen[static_cast<size_t>(j)] != 0;
        if (pass == 0 ? !is_frozen : (is_frozen || h[static_cast<size_t>(j)] == 0)) continue;
        C.push_back(row.a);
        d.push_back(is_frozen ? frozen_value[static_cast<size_t>(j)] : (h[static_cast<size_t>(j)] == 1 ? row.lo : row.up));
        std::vector<Q> y;
        if (!exact::solveLinear(C, d, n, y, nullptr)) {
          if (is_frozen) return false;
          C.pop_back();
          d.pop_back();
        }
      }
    }
    for (int j = 0; j < M; ++j) {
      const Row& row = rows[static_cast<size_t>(j)];
      if (row.level != k || h[static_cast<size_t>(j)] == 0) continue;
      F.push_back(row.a);
      g.push_back(h[static_cast<size_t>(j)] == 1 ? row.lo : row.up);
    }
    std::vector<Q> x0;
    exact::Mat Z;
    if (!exact::solveLinear(C, d, n, x0, &Z)) return false;
    x = x0;
    if (F.empty() || Z.empty()) return true;
    // min || F (x0 + Z y) - g ||: normal equations (F Z)^T (F Z) y = (F Z)^T (g - F x0).
    const int f = static_cast<int>(Z.size());
    exact::Mat FZ(F.size(), std::vector<Q>(static_cast<size_t>(f), Q(0)));
    std::vector<Q> rhs0(F.size());
    for (size_t i = 0; i < F.size(); ++i) {
      for (int c = 0; c < f; ++c) FZ[i][static_cast<size_t>(c)] = dot(F[i], Z[static_cast<size_t>(c)]);
      rhs0[i] = g[i] - dot(F[i], x0);
    }
    exact::Mat N(static_cast<size_t>(f), std::vector<Q>(static_cast<size_t>(f), Q(0)));
    std::vector<Q> rhs(static_cast<size_t>(f), Q(0));
    for (int a = 0; a < f; ++a) {
      for (size_t i = 0; i < F.size(); ++i) {
        const Q& fa = FZ[i][static_cast<size_t>(a)];
        if (sgn(fa) == 0) continue;
        rhs[static_cast<size_t>(a)] += fa * rhs0[i];
        for (int b = 0; b < f; ++b) N[static_cast<size_t>(a)][static_cast<size_t>(b)] += fa * FZ[i][static_cast<size_t>(b)];
      }
    }
    std::vector<Q> y;
    if (!exact::solveLinear(N, rhs, f, y, nullptr)) return false;  // cannot happen: normal equations
    for (int c = 0; c < f; ++c) {
      if (sgn(y[static_cast<size_t>(c)]) == 0) continue;
      for (int i = 0; i < n; ++i)
        x[static_cast<size_t>(i)] += y[static_cast<size_t>(c)] * Z[static_cast<size_t>(c)][static_cast<size_t>(i)];
    }
    return true;
  };
  // Solves and repairs the working set until the point is feasible and every held level row is
  // on the side of its bound (one change per solve). False when it does not settle.
  const int budget = repairs_per_row * std::max(1, M) + 10;
  auto solveRepaired = [&](int k, std::vector<int>& h, std::vector<Q>& x) {
    for (int attempt = 0; attempt < budget; ++attempt) {
      if (!solveEquality(k, h, x)) return false;
      bool changed = false;
      for (int j = 0; j < M && !changed; ++j) {
        const Row& row = rows[static_cast<size_t>(j)];
        if (row.level > k) break;
        if (row.level < k && frozen[static_cast<size_t>(j)]) continue;
        const Q ax = dot(row.a, x);
        const int hj = h[static_cast<size_t>(j)];
        if (hj == 0 || row.level < k) {
          // Out of its bounds (an earlier row, or an inactive level row): hold it there. An
          // earlier row already held there was left out as inconsistent with the rows before it:
          // the working set has no feasible point.
          const bool above = row.has_up && ax > row.up, below = row.has_lo && ax < row.lo;
          if ((above && hj == 2) || (below && hj == 1)) return false;
          if (above)
            h[static_cast<size_t>(j)] = 2, changed = true;
          else if (below)
            h[static_cast<size_t>(j)] = 1, changed = true;
        } else if (!row.equality()) {
          // A level row held on the wrong side of its bound: release it.
          if ((hj == 2 && ax < row.up) || (hj == 1 && ax > row.lo)) h[static_cast<size_t>(j)] = 0, changed = true;
        }
      }
      if (!changed) return true;
    }
    return false;
  };
  auto objective = [&](int k, const std::vector<Q>& x) {
    Q s(0);
    for (int j = 0; j < M; ++j) {
      const Row& row = rows[static_cast<size_t>(j)];
      if (row.level != k) continue;
      const Q v = violation(row, dot(row.a, x));
      s += v * v;
    }
    return s;
  };
  // The dual check: multipliers of the earlier rows tight at x cancel the level's gradient.
  auto dualFeasible = [&](int k, const std::vector<Q>& x) {
    std::vector<Q> grad(static_cast<size_t>(n), Q(0));
    for (int j = 0; j < M; ++j) {
      const Row& row = rows[static_cast<size_t>(j)];
      if (row.level != k) continue;
      const Q v = violation(row, dot(row.a, x));
      if (sgn(v) == 0) continue;
      for (int c = 0; c < n; ++c) grad[static_cast<size_t>(c)] += v * row.a[static_cast<size_t>(c)];
    }
    exact::Mat A(static_cast<size_t>(n));
    for (int j = 0; j < M; ++j) {
      const Row& row = rows[static_cast<size_t>(j)];
      if (row.level >= k) break;
      int sign = 0;  // 0 any sign, +1 >= 0 (at upper), -1 <= 0 (at lower), 2 not tight
      if (!frozen[static_cast<size_t>(j)]) {
        const Q ax = dot(row.a, x);
        const bool at_up = row.has_up && ax == row.up, at_lo = row.has_lo && ax == row.lo;
        sign = at_up && at_lo ? 0 : (at_up ? 1 : (at_lo ? -1 : 2));
      }
      if (sign == 2) continue;
      for (int c = 0; c < n; ++c) {
        const Q& a = row.a[static_cast<size_t>(c)];
        if (sign >= 0) A[static_cast<size_t>(c)].push_back(a);
        if (sign <= 0) A[static_cast<size_t>(c)].push_back(-a);
      }
    }
    std::vector<Q> b(static_cast<size_t>(n));
    for (int c = 0; c < n; ++c) b[static_cast<size_t>(c)] = -grad[static_cast<size_t>(c)];
    const int cols = A.empty() ? 0 : static_cast<int>(A[0].size());
    if (cols == 0) return std::all_of(grad.begin(), grad.end(), [](const Q& v) { return sgn(v) == 0; });
    return exact::lpFeasible(A, b, cols);
  };

  std::vector<Q> x(static_cast<size_t>(n), Q(0));
  for (int k = 0; k < p.levelCount(); ++k) {
    held = solver_held;
    if (!solveRepaired(k, held, x)) {
      out.detail = "level " + std::to_string(k) + ": the primal repairs of the solver's active set did not settle";
      return out;
    }
    // Descent on the earlier rows held at a bound: while the dual check fails, release one (or,
    // when no single one helps, two: duplicated rows block each other) whose release lowers the
    // level's objective exactly; each step strictly decreases it.
    for (int step = 0; !dualFeasible(k, x); ++step) {
      const Q current = objective(k, x);
      std::vector<int> releasable;
      for (int i = 0; i < M; ++i) {
        const Row& row = rows[static_cast<size_t>(i)];
        if (row.level >= k) break;
        if (!frozen[static_cast<size_t>(i)] && held[static_cast<size_t>(i)] != 0 && !row.equality()) releasable.push_back(i);
      }
      bool improved = false;
      const size_t R = releasable.size();
      for (size_t a = 0; a < R && !improved && step < budget; ++a) {
        for (size_t b = a; b < R && !improved; ++b) {
          std::vector<int> h = held;
          h[static_cast<size_t>(releasable[a])] = 0;
          h[static_cast<size_t>(releasable[b])] = 0;
          std::vector<Q> xi;
          if (!solveRepaired(k, h, xi) || !(objective(k, xi) < current)) continue;
          held = h;
          x = xi;
          improved = true;
        }
      }
      if (!improved) {
        out.detail = "level " + std::to_string(k) + ": no sign-valid multipliers and no release of one or two rows improves the level";
        return out;
      }
    }
    // The exact optimal violation of level k; rows violated at it are frozen.
    Q norm2(0);
    for (int j = 0; j < M; ++j) {
      const Row& row = rows[static_cast<size_t>(j)];
      if (row.level != k) continue;
      const Q ax = dot(row.a, x);
      const Q v = violation(row, ax);
      norm2 += v * v;
      if (sgn(v) != 0) {
        frozen[static_cast<size_t>(j)] = 1;
        frozen_value[static_cast<size_t>(j)] = ax;
      }
    }
    out.violation_norm.push_back(std::sqrt(norm2.get_d()));
    out.x.assign(static_cast<size_t>(n), 0.0);
    for (int i = 0; i < n; ++i) out.x[static_cast<size_t>(i)] = x[static_cast<size_t>(i)].get_d();
  }
  for (int l = 0; l < p.levelCount(); ++l) {
    const double e = out.violation_norm[static_cast<size_t>(l)], s = r.violation_norm(l);
    if (std::abs(s - e) > 1e-9 * (1.0 + e)) {
      std::ostringstream os;
      os.precision(17);
      os << "level " << l << ": the solver's violation " << s << " differs from the exact optimum " << e;
      out.kind = ExactVerdict::NotOptimal;
      out.detail = os.str();
      return out;
    }
  }
  out.kind = ExactVerdict::Optimal;
  return out;
}

/// The exact verdict on `r` for `p` (see the header comment). `repairs_per_row` bounds the
/// primal repairs per level (times the number of rows). `work_limit` > 0 bounds the check's
/// work (the same verdict on any machine), `time_limit_s` > 0 its time, and `stop` (when
/// non-null and nonzero) ends it early: each leaves it Undecided, saying so.
inline ExactVerdict exactCheck(const Problem& p, const Result& r, int repairs_per_row = 4, double time_limit_s = 0.0,
                               const std::atomic<int>* stop = nullptr, long work_limit = 0) {
  exact::Budget& b = exact::budget();
  // The caller's budget comes back however the check ends (an exception too).
  struct Restore {
    exact::Budget& b;
    exact::Budget saved;
    ~Restore() { b = saved; }
  } restore{b, b};
  b.stop = stop;
  b.work = 0;
  b.work_limit = work_limit;
  b.deadline = time_limit_s > 0.0
                   ? std::chrono::steady_clock::now() +
                         std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(time_limit_s))
                   : std::chrono::steady_clock::time_point::max();
  ExactVerdict out;
  try {
    out = exactCheckUnlimited(p, r, repairs_per_row);
  } catch (const exact::OutOfWork&) {
    out = ExactVerdict{};
    out.out_of_work = true;
    out.detail = "the exact check reached its work budget of " + std::to_string(work_limit);
  } catch (const exact::OutOfTime&) {
    out = ExactVerdict{};
    out.out_of_time = true;
    std::ostringstream os;
    os << "the exact check took longer than its time limit of " << time_limit_s << " s";
    out.detail = os.str();
  } catch (const exact::Interrupted&) {
    out = ExactVerdict{};
    out.interrupted = true;
    out.detail = "the exact check was interrupted";
  }
  out.work = b.work;
  return out;
}

}  // namespace lexdyn::solver::test
