// Per-level BFGS / SR1 approximations (lexdyn/hessian/bfgs.hpp): positive definiteness, secant
// equations, skip rules, occupancy changes (sec. VII), the factor, and the sign-change guard
// (sec. VIII-A).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "hessian_test_utils.hpp"
#include "lexdyn/hessian/bfgs.hpp"

namespace lexdyn::hessian {
namespace {

using testing::Rng;

constexpr double kDt = 0.005;
constexpr double kDt2 = kDt * kDt;

Eigen::MatrixXd occupiedBlock(const Eigen::MatrixXd& B, const std::vector<char>& mask, std::vector<int>* idx_out = nullptr) {
  std::vector<int> idx;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) idx.push_back(static_cast<int>(i));
  Eigen::MatrixXd Bo(idx.size(), idx.size());
  for (size_t a = 0; a < idx.size(); ++a)
    for (size_t b = 0; b < idx.size(); ++b) Bo(a, b) = B(idx[a], idx[b]);
  if (idx_out) *idx_out = idx;
  return Bo;
}

double minEigenvalue(const Eigen::MatrixXd& A) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A, Eigen::EigenvaluesOnly).eigenvalues()[0];
}

Eigen::VectorXd masked(const Eigen::VectorXd& v, const std::vector<char>& mask) {
  Eigen::VectorXd out = v;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!mask[static_cast<size_t>(i)]) out[i] = 0.0;
  return out;
}

// The secant sums and B s run several sums at a time; each must keep the bits of the plain
// loop (one sum at a time, over its terms in order from +0): the closed loop's traces depend on
// them. Sizes around the four-at-a-time blocks, signed zeros among the data; the secant sums
// skip the rows whose multiplier (change) is zero, which must change no bit either (half the
// multipliers zero in every other trial, J and J(k-1) differing there).
TEST(Bfgs, SumsKeepThePlainLoopsBits) {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto value = [&]() {
    const std::uint64_t r = rng() % 8;
    return r == 0 ? 0.0 : r == 1 ? -0.0 : u(rng) * std::pow(10.0, static_cast<int>(rng() % 7) - 3);
  };
  auto same = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
  };
  for (int trial = 0; trial < 40; ++trial) {
    for (int rows = 0; rows <= 9; ++rows) {
      for (int cols = 1; cols <= 9; ++cols) {
        Eigen::MatrixXd J(rows, cols), Jp(rows, cols);
        Eigen::VectorXd l(rows), lp(rows), y0(cols);
        for (Eigen::Index k = 0; k < J.size(); ++k) J.data()[k] = value(), Jp.data()[k] = value();
        for (int r = 0; r < rows; ++r) l[r] = value(), lp[r] = value();
        if (trial % 2 == 1) {
          for (int r = 0; r < rows; ++r) {
            if (rng() % 2 == 0) continue;
            l[r] = rng() % 2 ? 0.0 : -0.0;
            lp[r] = rng() % 2 ? l[r] : value();
          }
        }
        for (int c = 0; c < cols; ++c) y0[c] = value();
        Eigen::VectorXd y = y0, ref = y0;
        accumulateGradientChange(J, Jp, l, y);
        for (int c = 0; c < cols; ++c) {
          double sum = 0.0;
          for (int r = 0; r < rows; ++r) sum += (J(r, c) - Jp(r, c)) * l[r];
          ref[c] += sum;
        }
        EXPECT_TRUE(same(y, ref)) << "gradient change, " << rows << " x " << cols;
        y = y0, ref = y0;
        accumulateMultiplierChange(Jp, l, lp, y);
        for (int c = 0; c < cols; ++c) {
          double sum = 0.0;
          for (int r = 0; r < rows; ++r) sum += Jp(r, c) * (l[r] - lp[r]);
          ref[c] += sum;
        }
        EXPECT_TRUE(same(y, ref)) << "multiplier change, " << rows << " x " << cols;
      }
    }
  }
  // B s inside the BFGS update (eq. 87), against the update written with plain loops, for
  // occupied blocks of 1 to 9 dofs among 11.
  for (int m = 1; m <= 9; ++m) {
    const int n = 11;
    std::vector<char> occ(n, 0);
    for (int k = 0; k < m; ++k) occ[static_cast<size_t>((3 * k + 1) % n)] = 1;
    auto B = makeBfgs(n, QuasiNewtonOptions{});
    Eigen::VectorXd diag = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i)
      if (occ[static_cast<size_t>(i)]) diag[i] = 0.5 + std::abs(u(rng));
    B->initialize(diag, occ);
    for (int step = 0; step < 4; ++step) {
      Eigen::VectorXd sv(n), yv(n);
      for (int i = 0; i < n; ++i) sv[i] = u(rng), yv[i] = sv[i] * (1.0 + 0.5 * std::abs(u(rng))) + 0.01 * u(rng);
      const Eigen::MatrixXd before = B->matrix();
      std::vector<int> idx;
      for (int i = 0; i < n; ++i)
        if (occ[static_cast<size_t>(i)]) idx.push_back(i);
      Eigen::VectorXd so(m), yo(m), Bs(m);
      for (int a = 0; a < m; ++a) so[a] = sv[idx[static_cast<size_t>(a)]], yo[a] = yv[idx[static_cast<size_t>(a)]];
      for (int a = 0; a < m; ++a) {
        double v = 0.0;
        for (int b = 0; b < m; ++b) v += before(idx[static_cast<size_t>(a)], idx[static_cast<size_t>(b)]) * so[b];
        Bs[a] = v;
      }
      const double ys = yo.dot(so), sBs = so.dot(Bs);
      ASSERT_TRUE(B->update(sv, yv)) << "m " << m << " step " << step;
      Eigen::MatrixXd ref = before;
      for (int b = 0; b < m; ++b)
        for (int a = b; a < m; ++a) {
          const int i = idx[static_cast<size_t>(a)], j = idx[static_cast<size_t>(b)];
          ref(i, j) = ref(j, i) = before(i, j) + (yo[a] * (yo[b] / ys) - Bs[a] * (Bs[b] / sBs));
        }
      ASSERT_EQ(std::memcmp(ref.data(), B->matrix().data(), sizeof(double) * static_cast<size_t>(n * n)), 0)
          << "m " << m << " step " << step;
    }
  }
}

TEST(Bfgs, Eq89InitialisationHelpers) {
  EXPECT_DOUBLE_EQ(initialDiagonalValue(1e-3 * kDt2, Eigen::Vector3d(0.0, 0.0, 0.0)), 1e-3 * kDt2);
  EXPECT_DOUBLE_EQ(initialDiagonalValue(1e-3 * kDt2, Eigen::Vector3d(0.1, 0.2, 0.2)), 0.5 * 0.09);
  Eigen::VectorXd diag = Eigen::VectorXd::Zero(5);
  addOnChain({1, 1, 0, 0, 1}, 2.0, diag);
  addOnChain({0, 1, 1, 0, 0}, 0.5, diag);
  EXPECT_EQ(diag, (Eigen::VectorXd(5) << 2.0, 2.5, 0.5, 0.0, 2.0).finished());
  BfgsMatrix B(5);
  B.initialize(diag);
  EXPECT_EQ(B.occupied(), (std::vector<char>{1, 1, 1, 0, 1}));
  EXPECT_EQ(B.matrix(), Eigen::MatrixXd(diag.asDiagonal()));
  // Eq. 88 for one task block.
  Rng rng(201);
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(3, 5), Jp = Eigen::MatrixXd::Random(3, 5);
  const Eigen::VectorXd lambda = rng.uniformVector(3), y0 = rng.uniformVector(5);
  Eigen::VectorXd y = y0;
  accumulateGradientChange(J, Jp, lambda, y);
  const Eigen::MatrixXd dJ = J - Jp;
  const Eigen::VectorXd expected = y0 + dJ.transpose() * lambda;
  EXPECT_LE((y - expected).norm(), 1e-15);
  // The full difference of the gradient (bfgs_secant: full_difference) adds the change of the
  // multipliers at the previous Jacobian: J^T lambda - J_prev^T lambda_prev in all.
  const Eigen::VectorXd lambda_prev = rng.uniformVector(3);
  accumulateMultiplierChange(Jp, lambda, lambda_prev, y);
  const Eigen::VectorXd full = y0 + J.transpose() * lambda - Jp.transpose() * lambda_prev;
  EXPECT_LE((y - full).norm(), 1e-14);
  // Unchanged multipliers add nothing.
  const Eigen::VectorXd y1 = y;
  accumulateMultiplierChange(Jp, lambda, lambda, y);
  EXPECT_EQ(y, y1);
}

// Random sequences. With curvature pairs of a positive definite model (y = A s + noise, A SPD)
// BFGS keeps B strictly positive definite (exact arithmetic: B+ is PD whenever B is and
// y^T s > 0). With an indefinite model the curvature test must skip the negative-curvature
// pairs; the accepted pairs are inconsistent with any fixed Hessian and drive B towards
// singularity (condition numbers ~1e14 after a few dozen updates, as in flat-curvature phases),
// where positive definiteness can only hold to working precision: lambda_min >= -4 n eps
// lambda_max. factor() must then still produce R with R^T R = B up to that rounding plus the
// eps of its Higham fallback.
TEST(Bfgs, StaysPositiveDefiniteSatisfiesSecantAndSkipsOnCurvature) {
  Rng rng(202);
  const int n = 12;
  const double unit = std::numeric_limits<double>::epsilon();
  int regularized_factors = 0;
  for (int run = 0; run < 10; ++run) {
    const bool spd_model = run % 2 == 0;
    BfgsMatrix B(n);
    B.initialize(rng.uniformVector(n, 0.1, 2.0), std::vector<char>(n, 1));
    Eigen::MatrixXd A = rng.symmetric(n);
    if (spd_model) A = A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    int updates = 0, skips = 0;
    Eigen::MatrixXd R(n, n);
    for (int k = 0; k < 200; ++k) {
      const Eigen::VectorXd s = rng.uniformVector(n) * (k % 5 == 0 ? 1e-3 : 1.0);
      const Eigen::VectorXd y = A * s + 0.05 * rng.uniformVector(n);
      const Eigen::MatrixXd before = B.matrix();
      const bool updated = B.update(s, y);
      EXPECT_EQ(updated, y.dot(s) > B.options().xi) << "run " << run << " k " << k;
      if (updated) {
        ++updates;
        // Rounding of B s: ~ n eps |B| |s|.
        const Eigen::VectorXd residual = B.matrix() * s - y;
        EXPECT_LE(residual.norm(), 1e-12 * (B.matrix().norm() * s.norm() + y.norm())) << "secant, run " << run << " k " << k;
      } else {
        ++skips;
        EXPECT_EQ(B.matrix(), before);  // B kept exactly
      }
      EXPECT_EQ((B.matrix() - B.matrix().transpose()).cwiseAbs().maxCoeff(), 0.0);
      const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(B.matrix(), Eigen::EigenvaluesOnly).eigenvalues();
      if (spd_model) {
        ASSERT_GT(lambda[0], 0.0) << "run " << run << " k " << k;
        ASSERT_EQ(Eigen::LLT<Eigen::MatrixXd>(B.matrix()).info(), Eigen::Success);
      } else {
        ASSERT_GE(lambda[0], -4.0 * n * unit * lambda[n - 1]) << "run " << run << " k " << k;
      }
      ASSERT_EQ(B.factor(R), n);
      if (spd_model) {
        EXPECT_FALSE(B.lastFactorRegularized());
      }
      regularized_factors += B.lastFactorRegularized() ? 1 : 0;
      const Eigen::MatrixXd RtR = R.transpose() * R;
      EXPECT_LE((RtR - B.matrix()).norm(), 1e-12 * B.matrix().norm() + n * B.options().eps) << "run " << run << " k " << k;
    }
    EXPECT_GT(updates, 0);
    if (!spd_model) {
      EXPECT_GT(skips, 0);  // the indefinite model must trigger the guard
    }
  }
  std::printf("factors through the Higham fallback (indefinite models only): %d of 1000\n", regularized_factors);
}

TEST(Bfgs, CurvatureThresholdIsStrict) {
  QuasiNewtonOptions o;
  o.xi = 1e-12 * kDt2;
  BfgsMatrix B(3, o);
  B.initialize(Eigen::Vector3d(1, 1, 1), std::vector<char>(3, 1));
  const Eigen::Vector3d s(1, 0, 0);
  // y^T s == xi exactly: skipped; above: updated; negative: skipped.
  EXPECT_FALSE(B.update(s, Eigen::Vector3d(o.xi, 0.3, 0)));
  EXPECT_FALSE(B.update(s, Eigen::Vector3d(-1.0, 0, 0)));
  EXPECT_FALSE(B.update(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0)));
  EXPECT_EQ(B.matrix(), Eigen::Matrix3d::Identity());
  EXPECT_TRUE(B.update(s, Eigen::Vector3d(2.0 * o.xi, 0.3, 0)));
}

TEST(Bfgs, OccupancyChangesKeepTheRestAndNeverReinitialise) {
  Rng rng(203);
  const int n = 10;
  BfgsMatrix B(n);
  std::vector<char> m1 = {1, 1, 1, 1, 1, 0, 0, 1, 0, 0};
  B.initialize(rng.uniformVector(n, 0.5, 1.0), m1);
  EXPECT_EQ(B.occupiedCount(), 6);
  for (int k = 0; k < 20; ++k) {
    const Eigen::VectorXd s = rng.uniformVector(n);  // components off the mask are ignored
    B.update(s, 2.0 * s + 0.1 * rng.uniformVector(n));
  }
  for (int i = 0; i < n; ++i) {
    if (m1[static_cast<size_t>(i)]) continue;
    EXPECT_EQ(B.matrix().row(i).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(B.matrix().col(i).cwiseAbs().maxCoeff(), 0.0);
  }
  const Eigen::MatrixXd before = B.matrix();
  // Free dofs 1 and 7, occupy 5 and 8.
  std::vector<char> m2 = m1;
  m2[1] = 0;
  m2[7] = 0;
  m2[5] = 1;
  m2[8] = 1;
  const double small = 1e-3 * kDt2;
  EXPECT_EQ(B.setOccupied(m2, small), 4);
  const Eigen::MatrixXd& after = B.matrix();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const bool keep =
          m1[static_cast<size_t>(i)] && m2[static_cast<size_t>(i)] && m1[static_cast<size_t>(j)] && m2[static_cast<size_t>(j)];
      const bool fresh_i = !m1[static_cast<size_t>(i)] && m2[static_cast<size_t>(i)];
      if (keep) {
        EXPECT_EQ(after(i, j), before(i, j)) << i << "," << j;
      } else if (fresh_i && i == j) {
        EXPECT_EQ(after(i, j), small) << i;
      } else {
        EXPECT_EQ(after(i, j), 0.0) << i << "," << j;
      }
    }
  }
  EXPECT_GT(minEigenvalue(occupiedBlock(after, m2)), 0.0);
  EXPECT_EQ(B.setOccupied(m2, small), 0);  // unchanged occupancy: nothing happens
  EXPECT_EQ(B.matrix(), after);
  // Per-dof values for newly occupied dofs.
  std::vector<char> m3 = m2;
  m3[9] = 1;
  Eigen::VectorXd values = Eigen::VectorXd::Constant(n, 3.0);
  values[9] = 0.25;
  EXPECT_EQ(B.setOccupied(m3, values), 1);
  EXPECT_EQ(B.matrix()(9, 9), 0.25);
}

TEST(Bfgs, FactorIsTheCholeskyFactorOfTheOccupiedBlock) {
  Rng rng(204);
  const int n = 9;
  BfgsMatrix B(n);
  const std::vector<char> mask = {0, 1, 1, 0, 1, 1, 1, 0, 1};
  B.initialize(rng.uniformVector(n, 0.5, 1.0), mask);
  for (int k = 0; k < 30; ++k) {
    const Eigen::VectorXd s = masked(rng.uniformVector(n), mask);
    B.update(s, 1.5 * s + 0.2 * rng.uniformVector(n));
  }
  Eigen::MatrixXd R = Eigen::MatrixXd::Constant(n + 2, n, 5.0);
  ASSERT_EQ(B.factor(R), 6);
  EXPECT_FALSE(B.lastFactorRegularized());
  EXPECT_LE((R.transpose() * R - B.matrix()).norm(), 1e-13 * B.matrix().norm());
  EXPECT_EQ(R.bottomRows(n + 2 - 6).cwiseAbs().maxCoeff(), 0.0);
  std::vector<int> idx;
  occupiedBlock(B.matrix(), mask, &idx);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < r; ++c) EXPECT_EQ(R(r, idx[static_cast<size_t>(c)]), 0.0);
  // The free function gives the same rows.
  Eigen::MatrixXd R2(n, n);
  std::vector<int> list;
  list.reserve(n);
  ASSERT_EQ(choleskyOfOccupied(B.matrix(), mask, R2, list), 6);
  EXPECT_EQ(list, idx);
  EXPECT_EQ(R2, R.topRows(n));
}

// The paper's weighted identity alpha I* (sec. IX-A): factor() factors B + alpha I* on the
// occupied block only, and B itself (the quasi-Newton state) is left unchanged.
TEST(Bfgs, IdentityWeightIsAddedToTheFactoredMatrixOnly) {
  Rng rng(205);
  const int n = 7;
  const std::vector<char> mask = {1, 0, 1, 1, 0, 1, 1};
  QuasiNewtonOptions with;
  with.identity_weight = 0.25;
  BfgsMatrix A(n), B(n, with);
  const Eigen::VectorXd d0 = rng.uniformVector(n, 0.5, 1.0);
  A.initialize(d0, mask);
  B.initialize(d0, mask);
  for (int k = 0; k < 20; ++k) {
    const Eigen::VectorXd s = masked(rng.uniformVector(n), mask);
    const Eigen::VectorXd y = 1.2 * s + 0.1 * rng.uniformVector(n);
    EXPECT_EQ(A.update(s, y), B.update(s, y));
  }
  EXPECT_EQ(A.matrix(), B.matrix());  // same updates: the weight never enters B
  Eigen::MatrixXd RA = Eigen::MatrixXd::Zero(n, n), RB = Eigen::MatrixXd::Zero(n, n);
  ASSERT_EQ(A.factor(RA), 5);
  ASSERT_EQ(B.factor(RB), 5);
  Eigen::MatrixXd expected = A.matrix();
  for (int i = 0; i < n; ++i)
    if (mask[static_cast<size_t>(i)]) expected(i, i) += 0.25;
  EXPECT_LE((RB.transpose() * RB - expected).norm(), 1e-13 * expected.norm());
  EXPECT_GT((RB.transpose() * RB - A.matrix()).norm(), 0.4);  // 0.25 on 5 diagonal entries
  EXPECT_EQ(B.matrix(), A.matrix());                          // factor() left B alone
}

TEST(Sr1, SecantEquationSkipRuleAndIndefiniteFactor) {
  Rng rng(205);
  const int n = 8;
  QuasiNewtonOptions o;
  o.eps = 1e-6;
  Sr1Matrix B(n, o);
  B.initialize(Eigen::VectorXd::Constant(n, 1.0), std::vector<char>(n, 1));
  // An indefinite curvature: SR1 may (and here does) become indefinite.
  const Eigen::MatrixXd A = rng.symmetric(n);
  int updates = 0;
  for (int k = 0; k < 40; ++k) {
    const Eigen::VectorXd s = rng.uniformVector(n);
    const Eigen::VectorXd y = A * s;
    const Eigen::VectorXd r = y - B.matrix() * s;
    const bool expect = r.norm() > 0.0 && std::abs(r.dot(s)) >= o.sr1_tolerance * r.norm() * s.norm();
    const Eigen::MatrixXd before = B.matrix();
    const bool updated = B.update(s, y);
    EXPECT_EQ(updated, expect);
    if (updated) {
      ++updates;
      EXPECT_LE((B.matrix() * s - y).norm(), 1e-12 * (B.matrix().norm() * s.norm() + y.norm())) << "k " << k;
    } else {
      EXPECT_EQ(B.matrix(), before);
    }
    EXPECT_EQ((B.matrix() - B.matrix().transpose()).cwiseAbs().maxCoeff(), 0.0);
  }
  EXPECT_GT(updates, 0);
  // After n independent updates on a quadratic, SR1 recovers A (its hereditary property).
  EXPECT_LE((B.matrix() - A).norm(), 1e-6 * A.norm());
  ASSERT_LT(minEigenvalue(B.matrix()), 0.0);
  Eigen::MatrixXd R(n, n);
  ASSERT_EQ(B.factor(R), n);
  EXPECT_TRUE(B.lastFactorRegularized());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(B.matrix());
  const Eigen::MatrixXd expected = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose() +
                                   o.eps * Eigen::MatrixXd::Identity(n, n);
  EXPECT_LE((R.transpose() * R - expected).norm(), 1e-12 * A.norm());

  // Skip rule: r orthogonal to s (r^T s = 0) is skipped; a tiny relative r^T s is skipped.
  Sr1Matrix C(3, o);
  C.initialize(Eigen::Vector3d(1, 1, 1), std::vector<char>(3, 1));
  const Eigen::Vector3d s(1, 0, 0);
  EXPECT_FALSE(C.update(s, Eigen::Vector3d(1, 1, 0)));                          // r = (0,1,0)
  EXPECT_FALSE(C.update(s, Eigen::Vector3d(1 + 0.5 * o.sr1_tolerance, 1, 0)));  // |r^T s| < tol |r||s|
  EXPECT_FALSE(C.update(s, Eigen::Vector3d(1, 0, 0)));                          // r = 0
  EXPECT_EQ(C.matrix(), Eigen::Matrix3d::Identity());
  EXPECT_TRUE(C.update(s, Eigen::Vector3d(1 + 2.0 * o.sr1_tolerance, 1e-3, 0)));
}

TEST(QuasiNewton, FactoriesAndReset) {
  QuasiNewtonOptions o;
  auto b = makeBfgs(4, o);
  auto s = makeSr1(4, o);
  o.update = QuasiNewtonUpdate::Sr1;
  auto q = makeQuasiNewton(4, o);
  EXPECT_EQ(b->kind(), QuasiNewtonUpdate::Bfgs);
  EXPECT_EQ(s->kind(), QuasiNewtonUpdate::Sr1);
  EXPECT_EQ(q->kind(), QuasiNewtonUpdate::Sr1);
  b->initialize(Eigen::Vector4d(1, 0, 2, 0));
  EXPECT_TRUE(b->initialized());
  EXPECT_EQ(b->occupiedCount(), 2);
  EXPECT_TRUE(b->addDiagonal(2, 0.5));
  EXPECT_FALSE(b->addDiagonal(1, 0.5));  // unoccupied: untouched
  EXPECT_EQ(b->matrix()(2, 2), 2.5);
  EXPECT_EQ(b->matrix()(1, 1), 0.0);
  b->reset();
  EXPECT_FALSE(b->initialized());
  EXPECT_EQ(b->occupiedCount(), 0);
  EXPECT_EQ(b->matrix().cwiseAbs().maxCoeff(), 0.0);
}

TEST(SignChangeGuard, TriggersOnTheSecondConsecutiveSignChangeOnly) {
  // Columns: ticks; rows: dofs.
  //  dof 0: + - +        -> flagged at tick 2 (second consecutive change), not at tick 1
  //  dof 1: + - - +      -> changes at ticks 1 and 3 are not consecutive: never
  //  dof 2: + - + - +    -> flagged at ticks 2 and 4 (the run restarts after a flag)
  //  dof 3: + 0 - 0 +    -> zeros carry no sign: changes at ticks 2 and 4 are consecutive
  //  dof 4: + + + + +    -> never
  //  dof 5: - + + - +    -> flagged at tick 4 only
  const double a[6][5] = {{1, -1, 1, 1, 1}, {1, -1, -1, 1, 1}, {1, -1, 1, -1, 1}, {1, 0, -1, 0, 1}, {1, 1, 1, 1, 1}, {-1, 1, 1, -1, 1}};
  const std::vector<std::vector<int>> expected = {{}, {}, {0, 2}, {}, {2, 3, 5}};
  SignChangeGuard g(6);
  for (int t = 0; t < 5; ++t) {
    Eigen::VectorXd acc(6);
    for (int d = 0; d < 6; ++d) acc[d] = a[d][t];
    const int count = g.observe(acc);
    EXPECT_EQ(g.triggered(), expected[static_cast<size_t>(t)]) << "tick " << t;
    EXPECT_EQ(count, static_cast<int>(expected[static_cast<size_t>(t)].size()));
    for (int d = 0; d < 6; ++d) {
      const bool in = std::find(expected[static_cast<size_t>(t)].begin(), expected[static_cast<size_t>(t)].end(), d) !=
                      expected[static_cast<size_t>(t)].end();
      EXPECT_EQ(g.flags()[static_cast<size_t>(d)] != 0, in) << "tick " << t << " dof " << d;
    }
  }
  g.reset();
  Eigen::VectorXd acc(6);
  acc.setConstant(-1.0);
  EXPECT_EQ(g.observe(acc), 0);
  // Dead band: small accelerations carry no sign.
  SignChangeGuard h(1, 2, 0.1);
  EXPECT_EQ(h.observe(Eigen::VectorXd::Constant(1, 1.0)), 0);
  EXPECT_EQ(h.observe(Eigen::VectorXd::Constant(1, -0.05)), 0);
  EXPECT_EQ(h.observe(Eigen::VectorXd::Constant(1, 1.0)), 0);  // no change seen yet
  EXPECT_EQ(h.observe(Eigen::VectorXd::Constant(1, -1.0)), 0);
  EXPECT_EQ(h.observe(Eigen::VectorXd::Constant(1, 1.0)), 1);
}

TEST(SignChangeGuard, AddsZetaToTheFlaggedOccupiedDofs) {
  const int n = 4;
  BfgsMatrix B(n);
  B.initialize(Eigen::Vector4d(1, 1, 1, 0));
  SignChangeGuard g(n);
  const double zeta = 1e-3 * kDt2;
  const Eigen::Vector4d p(1, 1, 1, 1);
  g.observe(p);
  g.observe(-p);
  ASSERT_EQ(g.observe(p), n);
  int added = 0;
  for (int dof : g.triggered()) added += B.addDiagonal(dof, zeta) ? 1 : 0;
  EXPECT_EQ(added, 3);
  EXPECT_EQ(B.matrix().diagonal(), Eigen::Vector4d(1 + zeta, 1 + zeta, 1 + zeta, 0));
}

}  // namespace
}  // namespace lexdyn::hessian
