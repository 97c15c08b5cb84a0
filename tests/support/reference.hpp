// Independent references for the hierarchical least-squares solver, written for the tests only:
//  - nullSpaceReference: equality-only hierarchies by the classical null-space recursion (SVD);
//  - bruteForce: tiny problems with inequalities by enumerating every active set, level by level;
//  - checkKkt: a KKT certificate of every level from the result's x and multipliers alone;
//  - random problem generators (seeded std::mt19937_64).
#pragma once

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/solver.hpp"

namespace lexdyn::solver::test {

// ---------------------------------------------------------------------------------------------
// Null-space recursion for equality hierarchies (x of minimum norm among the optima).
// ---------------------------------------------------------------------------------------------
struct EqualityReference {
  Eigen::VectorXd x;
  std::vector<double> residualNorm;  // per level
  int nullity = 0;                   // dimension of the final solution set
};

inline EqualityReference nullSpaceReference(const Problem& p, double relTol = 1e-9) {
  const int n = p.variables();
  EqualityReference ref;
  ref.x = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd Z = Eigen::MatrixXd::Identity(n, n);
  for (int l = 0; l < p.levelCount(); ++l) {
    const Level& lv = p.level(l);
    Eigen::MatrixXd A = lv.A;
    Eigen::VectorXd b = lv.lower;  // equality: lower == upper
    if (Z.cols() > 0 && A.rows() > 0) {
      Eigen::MatrixXd AZ = A * Z;
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(AZ, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Eigen::VectorXd& s = svd.singularValues();
      // Per-row relative threshold is what the solver uses; for generic data a global relative
      // threshold on the singular values gives the same rank.
      const double scale = A.rowwise().norm().maxCoeff();
      int r = 0;
      while (r < s.size() && s(r) > relTol * scale) ++r;
      Eigen::VectorXd rhs = b - A * ref.x;
      Eigen::VectorXd y = Eigen::VectorXd::Zero(Z.cols());
      if (r > 0) {
        Eigen::VectorXd c = svd.matrixU().leftCols(r).transpose() * rhs;
        for (int i = 0; i < r; ++i) c(i) /= s(i);
        y = svd.matrixV().leftCols(r) * c;
      }
      ref.x += Z * y;
      Z = (Z * svd.matrixV().rightCols(Z.cols() - r)).eval();
    }
    ref.residualNorm.push_back((A * ref.x - b).norm());
  }
  ref.nullity = static_cast<int>(Z.cols());
  return ref;
}

// ---------------------------------------------------------------------------------------------
// Violation of a row value against its bounds.
// ---------------------------------------------------------------------------------------------
inline double violationOf(double ax, double lo, double up) { return ax - std::min(std::max(ax, lo), up); }

// Rows of a problem in a uniform form (bounds level expanded to rows).
struct RowSet {
  Eigen::MatrixXd A;
  Eigen::VectorXd lo, up;
  std::vector<int> level;
};

inline RowSet expandRows(const Problem& p) {
  const int n = p.variables();
  const int M = p.totalRows();
  RowSet rs;
  rs.A = Eigen::MatrixXd::Zero(M, n);
  rs.lo.resize(M);
  rs.up.resize(M);
  int k = 0;
  for (int l = 0; l < p.levelCount(); ++l) {
    const Level& lv = p.level(l);
    for (int r = 0; r < lv.rows(); ++r, ++k) {
      if (lv.kind == LevelKind::General) {
        rs.A.row(k) = lv.A.row(r);
      } else {
        rs.A(k, lv.variable[static_cast<size_t>(r)]) = lv.coefficient(r);
      }
      rs.lo(k) = lv.lower(r);
      rs.up(k) = lv.upper(r);
      rs.level.push_back(l);
    }
  }
  return rs;
}

// ---------------------------------------------------------------------------------------------
// Brute force for tiny problems: level by level, enumerate for every row of levels <= k a status
// (inactive / held at lower / held at upper); solve the equality-constrained least squares of the
// held level-k rows subject to the held earlier rows and the frozen rows; keep feasible
// candidates; the smallest true objective is the level's optimum. Returns per-level optimal
// violation norms. Exponential: rows of levels <= k with inequalities must stay small.
// ---------------------------------------------------------------------------------------------
inline std::vector<double> bruteForce(const Problem& p, double feasTol = 1e-9) {
  const RowSet rs = expandRows(p);
  const int n = p.variables();
  const int M = static_cast<int>(rs.level.size());
  std::vector<double> optimum;
  // frozen[j]: row j must equal rowValue[j] exactly (earlier level, nonzero optimal violation).
  std::vector<char> frozen(static_cast<size_t>(M), 0);
  Eigen::VectorXd frozenValue = Eigen::VectorXd::Zero(M);

  for (int k = 0; k < p.levelCount(); ++k) {
    std::vector<int> rows;  // rows of levels <= k that are not frozen
    for (int j = 0; j < M; ++j)
      if (rs.level[static_cast<size_t>(j)] <= k && !frozen[static_cast<size_t>(j)]) rows.push_back(j);
    const int R = static_cast<int>(rows.size());
    std::vector<int> st(static_cast<size_t>(R), 0);  // 0 inactive, 1 lower, 2 upper
    double best = std::numeric_limits<double>::infinity();
    Eigen::VectorXd bestX;
    for (;;) {
      // Build: equality constraints C x = d (frozen + held earlier rows), objective rows F x ~ g.
      std::vector<int> cons, obj;
      std::vector<double> cval, oval;
      bool skip = false;
      for (int j = 0; j < M; ++j)
        if (frozen[static_cast<size_t>(j)] && rs.level[static_cast<size_t>(j)] < k) {
          cons.push_back(j);
          cval.push_back(frozenValue(j));
        }
      for (int q = 0; q < R; ++q) {
        const int j = rows[static_cast<size_t>(q)];
        const int s = st[static_cast<size_t>(q)];
        if (s == 0) continue;
        const double t = (s == 1) ? rs.lo(j) : rs.up(j);
        if (!std::isfinite(t)) {
          skip = true;
          break;
        }
        if (rs.level[static_cast<size_t>(j)] < k) {
          cons.push_back(j);
          cval.push_back(t);
        } else {
          obj.push_back(j);
          oval.push_back(t);
        }
      }
      if (!skip) {
        // Solve min ||F x - g|| s.t. C x = d (C consistent or least-squares), min-norm x.
        Eigen::MatrixXd C(cons.size(), n);
        Eigen::VectorXd d(cons.size());
        for (size_t i = 0; i < cons.size(); ++i) {
          C.row(static_cast<Eigen::Index>(i)) = rs.A.row(cons[i]);
          d(static_cast<Eigen::Index>(i)) = cval[i];
        }
        Eigen::MatrixXd F(obj.size(), n);
        Eigen::VectorXd g(obj.size());
        for (size_t i = 0; i < obj.size(); ++i) {
          F.row(static_cast<Eigen::Index>(i)) = rs.A.row(obj[i]);
          g(static_cast<Eigen::Index>(i)) = oval[i];
        }
        Problem sub(n);
        if (C.rows() > 0) sub.addLevel("c", C, d, d);
        if (F.rows() > 0) sub.addLevel("f", F, g, g);
        Eigen::VectorXd xc = Eigen::VectorXd::Zero(n);
        bool consOk = true;
        if (sub.levelCount() > 0) {
          const EqualityReference er = nullSpaceReference(sub);
          xc = er.x;
          if (C.rows() > 0 && er.residualNorm[0] > feasTol * (1.0 + d.norm())) consOk = false;
        }
        if (consOk) {
          // Feasibility: earlier non-frozen rows within bounds; true objective of level k.
          bool feasible = true;
          double objv = 0.0;
          for (int j = 0; j < M && feasible; ++j) {
            const int lj = rs.level[static_cast<size_t>(j)];
            if (lj > k) continue;
            const double ax = rs.A.row(j).dot(xc);
            const double scale = 1.0 + std::abs(ax);
            if (lj < k) {
              if (frozen[static_cast<size_t>(j)]) {
                if (std::abs(ax - frozenValue(j)) > feasTol * scale) feasible = false;
              } else if (std::abs(violationOf(ax, rs.lo(j), rs.up(j))) > feasTol * scale) {
                feasible = false;
              }
            } else {
              const double vj = violationOf(ax, rs.lo(j), rs.up(j));
              objv += vj * vj;
            }
          }
          if (feasible && objv < best) {
            best = objv;
            bestX = xc;
          }
        }
      }
      // Next status assignment.
      int q = 0;
      while (q < R) {
        if (++st[static_cast<size_t>(q)] <= 2) break;
        st[static_cast<size_t>(q)] = 0;
        ++q;
      }
      if (q == R) break;
    }
    optimum.push_back(std::sqrt(best));
    // Freeze the rows of level k that are violated at the optimum (their violation is unique).
    for (int j = 0; j < M; ++j) {
      if (rs.level[static_cast<size_t>(j)] != k) continue;
      const double ax = rs.A.row(j).dot(bestX);
      const double vj = violationOf(ax, rs.lo(j), rs.up(j));
      if (std::abs(vj) > 1e-9 * (1.0 + std::abs(ax))) {
        frozen[static_cast<size_t>(j)] = 1;
        frozenValue(j) = ax;
      }
    }
  }
  return optimum;
}

// ---------------------------------------------------------------------------------------------
// KKT certificate from x and lambda only. For every level l:
//   stationarity  sum_{i<=l} A_i^T lambda_{i,l} = 0,
//   own rows      lambda_{l,l} = violation of level l at x,
//   earlier rows  lambda = 0 when strictly inside; >= 0 held at upper; <= 0 held at lower;
//                 any sign when violated (frozen) or an equality.
// An earlier row counts as frozen when its violation exceeds `frozen_tol` times its scale (the
// rounding of a x is about n eps of it): a genuine violation of 1e-7 at a level's optimum is
// frozen (any multiplier sign), although it is below the loose `tol` of the other tests. Treating
// such a row as "at its bound" made the check fail correct results (docs/solver.md, the sweep;
// the exact reference tests/support/exact_reference.hpp decides such cases).
// Returns an empty string when the certificate holds, else a description of the first failure.
// ---------------------------------------------------------------------------------------------
inline std::string checkKkt(const Problem& p, const Result& r, double tol = 1e-7, double frozen_tol = 1e-12) {
  const RowSet rs = expandRows(p);
  const int M = static_cast<int>(rs.level.size());
  const Eigen::VectorXd ax = rs.A * r.x;
  const double xs = 1.0 + r.x.lpNorm<Eigen::Infinity>();
  for (int l = 0; l < p.levelCount(); ++l) {
    const Eigen::VectorXd lam = r.lambda.col(l);
    double scale = 0.0;
    Eigen::VectorXd g = Eigen::VectorXd::Zero(p.variables());
    for (int j = 0; j < M; ++j) {
      if (rs.level[static_cast<size_t>(j)] > l) {
        if (lam(j) != 0.0) return "level " + std::to_string(l) + ": multiplier on a later row " + std::to_string(j);
        continue;
      }
      g += rs.A.row(j).transpose() * lam(j);
      scale += std::abs(lam(j)) * rs.A.row(j).norm();
    }
    if (g.lpNorm<Eigen::Infinity>() > tol * (scale + 1e-12)) {
      std::ostringstream os;
      os << "level " << l << ": stationarity residual " << g.lpNorm<Eigen::Infinity>() << " (scale " << scale << ")";
      return os.str();
    }
    for (int j = 0; j < M; ++j) {
      const int lj = rs.level[static_cast<size_t>(j)];
      if (lj > l) continue;
      const double rowScale = 1.0 + std::abs(ax(j)) + rs.A.row(j).norm() * xs;
      const double viol = violationOf(ax(j), rs.lo(j), rs.up(j));
      std::ostringstream os;
      os << "level " << l << ", row " << j << " (level " << lj << "): ";
      if (lj == l) {
        if (std::abs(lam(j) - viol) > tol * rowScale) {
          os << "own multiplier " << lam(j) << " differs from the violation " << viol;
          return os.str();
        }
        continue;
      }
      const double lamScale = tol * (scale + 1e-12) / std::max(rs.A.row(j).norm(), 1e-300);
      if (std::abs(viol) > frozen_tol * rowScale || rs.lo(j) == rs.up(j)) continue;  // frozen or equality
      const bool atUp = std::isfinite(rs.up(j)) && std::abs(ax(j) - rs.up(j)) <= tol * rowScale;
      const bool atLo = std::isfinite(rs.lo(j)) && std::abs(ax(j) - rs.lo(j)) <= tol * rowScale;
      if (!atUp && !atLo) {
        if (std::abs(lam(j)) > lamScale) {
          os << "strictly satisfied row has multiplier " << lam(j);
          return os.str();
        }
      } else if (atUp && !atLo && lam(j) < -lamScale) {
        os << "row at its upper bound has multiplier " << lam(j) << " < 0";
        return os.str();
      } else if (atLo && !atUp && lam(j) > lamScale) {
        os << "row at its lower bound has multiplier " << lam(j) << " > 0";
        return os.str();
      }
    }
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Random problems.
// ---------------------------------------------------------------------------------------------
struct GenOptions {
  int n = 6;
  int levels = 4;
  int maxRows = 5;
  bool inequalities = true;
  bool boundsLevel = true;
  double pRankDeficient = 0.25;
  double pDuplicate = 0.15;
  double pZeroRow = 0.05;
  double pConflict = 0.2;
  double pEquality = 0.3;
  /// Every random number on the grid of 2^-10: then the products of rank-deficient levels
  /// (B C, n <= 100) are exact in double, so the stored problem is exactly rank-deficient where
  /// it is meant to be, and an exact (rational) reference agrees with the solver's rank
  /// decisions. Off: the rounded products are nearly, not exactly, dependent.
  bool dyadic = false;
  /// Probability that a level's rows each read a single variable (a regularisation level such
  /// as x_j = c; duplicates and conflicts may still bring other rows). 0 draws nothing more, so
  /// that the problems of every seed stay those of the sweeps before this option.
  double pUnitLevel = 0.0;
};

/// The generator options of lexdyn-solver-sweep's problem `seed`, from its own stream
/// (independent of the other problems of the sweep, so that one problem reruns alone).
inline GenOptions sweepOptions(std::uint64_t seed, int maxN, int maxLevels, int maxRows) {
  std::mt19937_64 meta(seed ^ 0x9e3779b97f4a7c15ULL);
  GenOptions g;
  g.n = 1 + static_cast<int>(meta() % static_cast<unsigned>(maxN));
  g.levels = 1 + static_cast<int>(meta() % static_cast<unsigned>(maxLevels));
  g.maxRows = 1 + static_cast<int>(meta() % static_cast<unsigned>(maxRows));
  g.inequalities = meta() % 4 != 0;
  g.boundsLevel = meta() % 2;
  const double pr[] = {0.0, 0.3, 0.8}, pd[] = {0.0, 0.2, 0.5}, pz[] = {0.0, 0.1}, pe[] = {0.1, 0.4, 0.9};
  g.pRankDeficient = pr[meta() % 3];
  g.pDuplicate = pd[meta() % 3];
  g.pConflict = pd[meta() % 3];
  g.pZeroRow = pz[meta() % 2];
  g.pEquality = pe[meta() % 3];
  g.dyadic = true;  // exactly representable rank deficiency: the exact reference applies
  return g;
}

inline Problem randomProblem(std::uint64_t seed, const GenOptions& o) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u_real(-1.0, 1.0);
  std::uniform_real_distribution<double> u01_real(0.0, 1.0);
  auto grid = [&](double v) { return o.dyadic ? std::round(v * 1024.0) / 1024.0 : v; };
  auto u = [&](std::mt19937_64& g) { return grid(u_real(g)); };
  auto u01 = [&](std::mt19937_64& g) { return grid(u01_real(g)); };
  auto coin = [&](double pr) { return u01_real(rng) < pr; };
  auto rnd = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  Problem p(o.n);
  std::vector<Eigen::RowVectorXd> pool;  // earlier rows, for duplicates and conflicts
  if (o.boundsLevel) {
    std::vector<int> vars;
    for (int i = 0; i < o.n; ++i)
      if (coin(0.6)) vars.push_back(i);
    if (!vars.empty()) {
      const int m = static_cast<int>(vars.size());
      Eigen::VectorXd c(m), lo(m), up(m);
      for (int r = 0; r < m; ++r) {
        c(r) = coin(0.8) ? 1.0 : (coin(0.5) ? -2.0 : 0.5);
        const double a = u(rng), w = 0.2 + u01(rng);
        lo(r) = coin(0.15) ? -kInf : a - w;
        up(r) = coin(0.15) ? kInf : a + w;
        if (coin(0.1)) up(r) = lo(r) = a;  // fixed variable
      }
      p.addBoundsLevel("bounds", vars, c, lo, up);
    }
  }
  for (int l = 0; l < o.levels; ++l) {
    const int m = rnd(1, o.maxRows);
    Eigen::MatrixXd A(m, o.n);
    for (int r = 0; r < m; ++r)
      for (int c = 0; c < o.n; ++c) A(r, c) = u(rng);
    if (m > 1 && coin(o.pRankDeficient)) {
      const int k = rnd(1, std::max(1, std::min(m, o.n) - 1));
      Eigen::MatrixXd B(m, k), C(k, o.n);
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < k; ++j) B(i, j) = u(rng);
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < o.n; ++j) C(i, j) = u(rng);
      A = B * C;
    }
    if (o.pUnitLevel > 0.0 && coin(o.pUnitLevel)) {
      for (int r = 0; r < m; ++r) {
        const int c = rnd(0, o.n - 1);
        const double v = (coin(0.5) ? 1.0 : -1.0) * (0.25 + u01(rng));
        A.row(r).setZero();
        A(r, c) = v;
      }
    }
    Eigen::VectorXd lo(m), up(m);
    for (int r = 0; r < m; ++r) {
      const double t = 2.0 * u(rng);
      if (!pool.empty() && coin(o.pDuplicate)) A.row(r) = pool[static_cast<size_t>(rnd(0, static_cast<int>(pool.size()) - 1))];
      if (coin(o.pZeroRow)) A.row(r).setZero();
      if (!o.inequalities || coin(o.pEquality)) {
        lo(r) = up(r) = t;
      } else {
        const int kind = rnd(0, 3);
        const double w = 0.1 + u01(rng);
        lo(r) = (kind == 1) ? -kInf : t - w;
        up(r) = (kind == 2) ? kInf : t + w;
        if (kind == 3 && coin(0.1)) {
          lo(r) = -kInf;
          up(r) = kInf;
        }
      }
      if (!pool.empty() && coin(o.pConflict)) {
        // Same row as an earlier one, with a different target: an algorithmic conflict.
        A.row(r) = pool[static_cast<size_t>(rnd(0, static_cast<int>(pool.size()) - 1))];
        lo(r) = up(r) = 3.0 * u(rng);
      }
    }
    for (int r = 0; r < m; ++r) pool.push_back(A.row(r));
    p.addLevel("level" + std::to_string(l), A, lo, up);
  }
  return p;
}

/// Appends a full-rank minimum-norm level x = 0 so that x is unique.
inline void appendMinNorm(Problem& p) {
  const int n = p.variables();
  p.addLevel("min-norm", Eigen::MatrixXd::Identity(n, n), Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n));
}

/// The controller's last levels over nv velocities and the forces after them: minimum velocity
/// (unit rows x_j = 0 on the velocities, declared velocity-only) and minimum wrench (unit rows on
/// the forces); or, with `controllerLike` false, the wrench level and a minimum norm over every
/// variable.
inline void appendRegularisationLevels(Problem& p, int nv, bool controllerLike) {
  const int n = p.variables(), nf = n - nv;
  if (controllerLike) {
    Eigen::MatrixXd V = Eigen::MatrixXd::Zero(nv, n);
    V.leftCols(nv).setIdentity();
    p.addLevel("velocity", V, Eigen::VectorXd::Zero(nv), Eigen::VectorXd::Zero(nv));
    p.setLevelColumns(p.levelCount() - 1, nv);
  }
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(nf, n);
  W.rightCols(nf).setIdentity();
  p.addLevel("wrench", W, Eigen::VectorXd::Zero(nf), Eigen::VectorXd::Zero(nf));
  if (!controllerLike) appendMinNorm(p);
}

/// A hierarchy shaped like the controller's (lexdyn-solver-sweep --controller-shaped,
/// docs/solver.md): nv velocities, then nf contact forces (n in [2, maxN]);
///  - a bounds level: the forces' lower bounds (0 or 2^-7), now and then upper ones, now and
///    then bounds on a few velocities;
///  - a first general level of equalities over every variable, the equation of motion's
///    unactuated rows (1 to min(6, n - 1) of them, the velocities' coefficients twice as large; now and then
///    more rows than forces, or a duplicated row, so that split coordinates fall back to the plain
///    elimination or the level is not eliminated);
///  - 1 to maxLevels task levels of 1 to maxRows rows: most over the velocities only (two thirds
///    of them declared so, as the controller declares its geometric tasks), now and then one over
///    every variable or an inequality level over pairs of forces (as friction cones read them);
///    equalities, inequalities, duplicated and zero rows, conflicting targets;
///  - the minimum-velocity and minimum-wrench levels of unit rows (x_j = 0), or a quarter of the
///    time the wrench level and a minimum norm over everything.
/// Every number is dyadic (the grid of 2^-10; the force pairs' coefficients 2^-11), so the exact
/// reference applies. `o` receives the
/// problem's solver options (its other fields are kept): split coordinates from nv, and spanning
/// stages (half of them for levels of any rows, half structured), lazy snapshots, a projected unit suffix and
/// (unless `o` has them off) swap reflectors drawn
/// per problem. The problems of a seed
/// are their own (an independent stream), so one reruns alone.
inline Problem controllerShapedProblem(std::uint64_t seed, int maxN, int maxLevels, int maxRows, Options& o) {
  std::mt19937_64 meta(seed ^ 0xc2b2ae3d27d4eb4fULL), rng(seed);
  std::uniform_real_distribution<double> u_real(-1.0, 1.0), u01_real(0.0, 1.0);
  auto grid = [](double v) { return std::round(v * 1024.0) / 1024.0; };
  auto u = [&]() { return grid(u_real(rng)); };
  auto coin = [&](double pr) { return u01_real(rng) < pr; };
  auto rnd = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  const int n = 2 + static_cast<int>(meta() % static_cast<unsigned>(std::max(1, maxN - 1)));
  const int nv = 1 + static_cast<int>(meta() % static_cast<unsigned>(n - 1)), nf = n - nv;
  const int m0 = 1 + static_cast<int>(meta() % static_cast<unsigned>(std::min(6, n - 1)));
  const int tasks = 1 + static_cast<int>(meta() % static_cast<unsigned>(maxLevels));
  const bool controllerLike = meta() % 4 != 0;
  o.split_from_variable = nv;
  o.lazy_snapshots = meta() % 2 == 0;
  o.spanning_stages = meta() % 3 != 0;
  o.project_unit_suffix = controllerLike && meta() % 4 != 0;
  // Spanning stages for levels of any rows: drawn from a stream of its own, so that each seed's
  // problem and its other options stay those of the sweeps before the option existed.
  {
    std::mt19937_64 extra(seed ^ 0x165667b19e3779f9ULL);
    const std::uint64_t bits = extra();
    o.spanning_any_rows = o.spanning_stages && (bits & 1U) != 0;
    o.spanning_structured = o.spanning_stages && (bits & 2U) != 0;
    // Swap reflectors: kept off where the caller turned them off, else off for a quarter.
    o.swap_reflectors = o.swap_reflectors && (bits & 12U) != 0;
  }
  Problem p(n);
  {
    std::vector<int> vars;
    std::vector<double> lo, up;
    const bool uppers = coin(0.25), velocityBounds = coin(0.3);
    for (int j = 0; j < nv; ++j)
      if (velocityBounds && coin(0.4)) {
        const double w = 0.25 + std::abs(u());
        vars.push_back(j);
        lo.push_back(-w);
        up.push_back(w);
      }
    const double floor = coin(0.5) ? 0.0 : 1.0 / 128.0;
    for (int j = nv; j < n; ++j) {
      vars.push_back(j);
      lo.push_back(floor);
      up.push_back(uppers && coin(0.5) ? 0.5 + 2.0 * std::abs(u()) : kInf);
    }
    const int m = static_cast<int>(vars.size());
    p.addBoundsLevel("bounds", vars, Eigen::VectorXd::Ones(m), Eigen::Map<const Eigen::VectorXd>(lo.data(), m),
                     Eigen::Map<const Eigen::VectorXd>(up.data(), m));
  }
  {
    Eigen::MatrixXd E(m0, n);
    for (int i = 0; i < m0; ++i)
      for (int j = 0; j < n; ++j) E(i, j) = (j < nv ? 2.0 : 1.0) * u();
    if (m0 > 1 && coin(0.05)) E.row(m0 - 1) = E.row(0);
    Eigen::VectorXd e(m0);
    for (int i = 0; i < m0; ++i) e(i) = u();
    p.addLevel("dynamics", E, e, e);
  }
  std::vector<Eigen::RowVectorXd> pool;  // earlier velocity-only rows, for duplicates and conflicts
  for (int l = 0; l < tasks; ++l) {
    const int rows = rnd(1, maxRows);
    const int kind = rnd(0, 5);  // 0-3: velocities only; 4: every variable; 5: pairs of forces
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, n);
    Eigen::VectorXd lo(rows), up(rows);
    for (int r = 0; r < rows; ++r) {
      if (kind == 5) {
        A(r, nv + (2 * r) % nf) = 1.0;
        A(r, nv + (2 * r + 1) % nf) += -0.5 - 0.5 * std::abs(u());
        lo(r) = -1.0 / 64.0;
        up(r) = kInf;
        continue;
      }
      for (int j = 0; j < (kind == 4 ? n : nv); ++j) A(r, j) = u();
      if (kind < 4 && !pool.empty() && coin(0.15)) A.row(r) = pool[static_cast<size_t>(rnd(0, static_cast<int>(pool.size()) - 1))];
      if (coin(0.05)) A.row(r).setZero();
      const double t = 2.0 * u();
      if (coin(0.4)) {
        lo(r) = up(r) = t;
      } else {
        const int side = rnd(0, 2);
        lo(r) = side == 1 ? -kInf : t - 0.5;
        up(r) = side == 2 ? kInf : t + 0.5;
      }
      if (kind < 4 && !pool.empty() && coin(0.1)) {  // an earlier row with another target
        A.row(r) = pool[static_cast<size_t>(rnd(0, static_cast<int>(pool.size()) - 1))];
        lo(r) = up(r) = 3.0 * u();
      }
    }
    if (kind < 4)
      for (int r = 0; r < rows; ++r) pool.push_back(A.row(r));
    p.addLevel("task" + std::to_string(l), A, lo, up);
    if (kind < 4 && rnd(0, 2) != 0) p.setLevelColumns(p.levelCount() - 1, nv);
  }
  appendRegularisationLevels(p, nv, controllerLike);
  return p;
}

}  // namespace lexdyn::solver::test
