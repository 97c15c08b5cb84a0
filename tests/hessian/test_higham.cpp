// The symmetric eigensolver, the Cholesky factor and Higham's nearest positive semi-definite
// matrix (lexdyn/hessian/higham.hpp), against Eigen's decompositions and against the defining
// property (no positive semi-definite matrix is closer in the Frobenius norm).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <vector>

#include "hessian_test_utils.hpp"
#include "lexdyn/hessian/higham.hpp"

namespace lexdyn::hessian {
namespace {

using testing::Rng;

/// The eigenvalue-clipping definition with Eigen's own solver: Q max(Lambda, 0) Q^T.
Eigen::MatrixXd clipReference(const Eigen::MatrixXd& H) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
  return es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose();
}

/// Higham's eq. 91-92 literally: 1/2 (H + P), P = V Sigma V^T from the SVD H = U Sigma V^T.
Eigen::MatrixXd polarReference(const Eigen::MatrixXd& H) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::MatrixXd P = svd.matrixV() * svd.singularValues().asDiagonal() * svd.matrixV().transpose();
  return 0.5 * (H + P);
}

double minEigenvalue(const Eigen::MatrixXd& A) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A, Eigen::EigenvaluesOnly).eigenvalues()[0];
}

/// A random symmetric matrix with prescribed eigenvalues.
Eigen::MatrixXd withEigenvalues(const Eigen::VectorXd& lambda, Rng& rng) {
  const Eigen::Index n = lambda.size();
  Eigen::MatrixXd G(n, n);
  for (Eigen::Index i = 0; i < n; ++i) G.col(i) = rng.uniformVector(n);
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(G).householderQ();
  Eigen::MatrixXd A = Q * lambda.asDiagonal() * Q.transpose();
  return 0.5 * (A + A.transpose());
}

/// The eigenvalues of an indefinite Hessian (two negative curvature directions), the typical
/// input of eq. 91, and what eq. 91 makes of them: max(lambda, 0) + eps.
Eigen::VectorXd indefiniteSpectrum() {
  Eigen::VectorXd lambda(6);
  lambda << -2.0, -0.5, 0.0, 0.3, 1.0, 4.0;
  return lambda;
}
Eigen::VectorXd clippedPlusEps(const Eigen::VectorXd& lambda, double eps) { return (lambda.cwiseMax(0.0).array() + eps).matrix(); }

std::vector<Eigen::MatrixXd> testMatrices(Rng& rng) {
  std::vector<Eigen::MatrixXd> out;
  for (int n : {1, 2, 3, 4, 7, 12, 20, 38}) {
    for (int k = 0; k < 4; ++k) out.push_back(rng.symmetric(n));
    out.push_back(rng.symmetric(n, 1e-8));  // Hessians scaled by dt^2 are small
    out.push_back(rng.symmetric(n, 1e3));
    // Far from the Newton rows' scale: the rotations' square roots fall back to std::hypot.
    out.push_back(rng.symmetric(n, 1e150));
    out.push_back(rng.symmetric(n, 1e-150));
    Eigen::VectorXd lambda = rng.uniformVector(n);
    for (int i = 0; i < n; i += 3) lambda[i] = 0.0;  // rank deficient
    out.push_back(withEigenvalues(lambda, rng));
    Eigen::VectorXd clustered = Eigen::VectorXd::Constant(n, 1.0);
    for (int i = 0; i < n; i += 2) clustered[i] = -2.0;  // repeated eigenvalues
    out.push_back(withEigenvalues(clustered, rng));
  }
  out.push_back(Eigen::MatrixXd::Zero(6, 6));
  out.push_back(Eigen::MatrixXd::Identity(9, 9));
  Eigen::MatrixXd tri = Eigen::MatrixXd::Zero(8, 8);  // already tridiagonal, with a split
  for (int i = 0; i < 8; ++i) tri(i, i) = i - 3.5;
  for (int i = 0; i < 7; ++i) tri(i + 1, i) = tri(i, i + 1) = (i == 3 ? 0.0 : 0.7);
  out.push_back(tri);
  Eigen::MatrixXd block = Eigen::MatrixXd::Zero(10, 10);  // a zero block in the middle
  block.topLeftCorner(4, 4) = rng.symmetric(4);
  block.bottomRightCorner(3, 3) = rng.symmetric(3);
  out.push_back(block);
  // The humanoid's velocity-domain task Hessians: the base translation's rows and columns are
  // zero (nothing's second derivative involves a translation), the rest couples through the base
  // rotation; left out of the eigenproblem, they must still give the clipped matrix.
  Eigen::MatrixXd arrow = rng.symmetric(38, 1e-6);
  arrow.middleRows(3, 3).setZero();
  arrow.middleCols(3, 3).setZero();
  out.push_back(arrow);
  return out;
}

TEST(SymmetricEigenSolver, DecomposesAgainstEigen) {
  Rng rng(101);
  SymmetricEigenSolver es(38);
  for (const Eigen::MatrixXd& A : testMatrices(rng)) {
    const Eigen::Index n = A.rows();
    ASSERT_TRUE(es.compute(A));
    ASSERT_EQ(es.size(), n);
    const double scale = std::max(1e-300, A.norm());
    const Eigen::MatrixXd V = es.eigenvectors();
    const Eigen::VectorXd lambda = es.eigenvalues();
    EXPECT_LE((A * V - V * lambda.asDiagonal()).norm(), 1e-13 * scale * n) << "n = " << n;
    EXPECT_LE((V.transpose() * V - Eigen::MatrixXd::Identity(n, n)).norm(), 1e-13 * n) << "n = " << n;
    for (Eigen::Index i = 0; i + 1 < n; ++i) EXPECT_LE(lambda[i], lambda[i + 1]);
    const Eigen::VectorXd ref = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues();
    EXPECT_LE((lambda - ref).cwiseAbs().maxCoeff(), 1e-13 * scale * n) << "n = " << n;
    EXPECT_LE(es.iterations(), 3 * n + 5) << "n = " << n;  // typical: about 2 sweeps per eigenvalue
  }
}

TEST(SymmetricEigenSolver, ReadsOnlyTheLowerTriangle) {
  Rng rng(102);
  const Eigen::MatrixXd A = rng.symmetric(9);
  Eigen::MatrixXd B = A;
  B.triangularView<Eigen::StrictlyUpper>().setConstant(1e6);
  SymmetricEigenSolver es(9);
  ASSERT_TRUE(es.compute(B));
  const Eigen::VectorXd ref = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues();
  EXPECT_LE((es.eigenvalues() - ref).cwiseAbs().maxCoeff(), 1e-13 * A.norm() * 9);
}

TEST(Cholesky, UpperFactorAndSemidefinitePivots) {
  Rng rng(103);
  for (int n : {1, 3, 10, 38}) {
    Eigen::MatrixXd G(n, n);
    for (int i = 0; i < n; ++i) G.col(i) = rng.uniformVector(n);
    const Eigen::MatrixXd A = G.transpose() * G + 1e-3 * Eigen::MatrixXd::Identity(n, n);
    Eigen::MatrixXd U = A;
    EXPECT_EQ(choleskyUpperInPlace(U, n), 0);
    EXPECT_TRUE(U.isUpperTriangular(0.0));
    EXPECT_LE((U.transpose() * U - A).norm(), 1e-13 * A.norm() * n);
    const Eigen::MatrixXd Ueigen = A.llt().matrixU();
    EXPECT_LE((U - Ueigen).norm(), 1e-10 * Ueigen.norm());
  }
  // Positive semi-definite of rank 2 with exactly zero pivots.
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(4, 4);
  S.topLeftCorner(2, 2) << 4, 2, 2, 5;
  Eigen::MatrixXd U = S;
  EXPECT_EQ(choleskyUpperInPlace(U, 4), 2);
  EXPECT_LE((U.transpose() * U - S).norm(), 1e-14);
  // An indefinite matrix is reported.
  Eigen::MatrixXd N(2, 2);
  N << 1, 2, 2, 1;
  EXPECT_EQ(choleskyUpperInPlace(N, 2), 1);
}

TEST(Higham, NearestPsdMatchesEigenvalueClippingAndPolarForm) {
  Rng rng(104);
  HighamRegularizer hr(38);
  for (const Eigen::MatrixXd& H : testMatrices(rng)) {
    const Eigen::Index n = H.rows();
    const double scale = std::max(1e-300, H.norm());
    Eigen::MatrixXd X(n, n);
    hr.nearestPsd(H, X);
    EXPECT_EQ((X - X.transpose()).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_LE((X - clipReference(H)).norm(), 1e-13 * scale * n) << "n = " << n;
    EXPECT_LE((X - polarReference(H)).norm(), 1e-12 * scale * n) << "n = " << n;
    EXPECT_GE(minEigenvalue(X), -1e-14 * scale * n) << "n = " << n;
  }
}

TEST(Higham, NoPositiveSemidefiniteMatrixIsCloser) {
  // Higham (1988): ||H - X||_F = sqrt(sum of the squared negative eigenvalues), and every
  // positive semi-definite Y is at least as far from H.
  Rng rng(105);
  HighamRegularizer hr(12);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 2 + trial % 11;
    const Eigen::MatrixXd H = rng.symmetric(n);
    Eigen::MatrixXd X(n, n);
    hr.nearestPsd(H, X);
    const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues();
    const double expected = lambda.cwiseMin(0.0).norm();
    const double d = (H - X).norm();
    EXPECT_NEAR(d, expected, 1e-12 * H.norm());
    for (int k = 0; k < 200; ++k) {
      // Nearby PSD candidates (X plus a PSD perturbation, or X's nearest PSD after a symmetric
      // perturbation) and random PSD matrices.
      Eigen::MatrixXd Y;
      const Eigen::MatrixXd E = rng.symmetric(n, k % 2 ? 1e-3 : 1e-1);
      if (k % 3 == 0) {
        Y = X + E * E.transpose();
      } else if (k % 3 == 1) {
        Y = clipReference(X + E);
      } else {
        Y = E * E.transpose() * 10.0;
      }
      EXPECT_GE((H - Y).norm(), d - 1e-12) << "trial " << trial << " candidate " << k;
    }
  }
}

TEST(Higham, IdempotentOnPositiveSemidefiniteInput) {
  Rng rng(106);
  HighamRegularizer hr(20);
  for (int n : {1, 5, 20}) {
    Eigen::VectorXd lambda = rng.uniformVector(n, 0.0, 2.0);
    lambda[0] = 0.0;
    const Eigen::MatrixXd A = withEigenvalues(lambda, rng);
    Eigen::MatrixXd X(n, n), XX(n, n);
    hr.nearestPsd(A, X);
    EXPECT_LE((X - A).norm(), 1e-14 * A.norm() * n);
    hr.nearestPsd(X, XX);
    EXPECT_LE((XX - X).norm(), 1e-14 * X.norm() * n);
    // In place (X aliases H).
    Eigen::MatrixXd H = rng.symmetric(n);
    Eigen::MatrixXd ref(n, n);
    hr.nearestPsd(H, ref);
    hr.nearestPsd(H, H);
    EXPECT_EQ((H - ref).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(Higham, RegularizeAndFactorOnTheOccupiedDofs) {
  Rng rng(107);
  const int n = 15;
  HighamRegularizer hr(n);
  for (int trial = 0; trial < 30; ++trial) {
    std::vector<char> mask(n, 0);
    std::vector<int> idx;
    for (int i = 0; i < n; ++i) {
      mask[static_cast<size_t>(i)] = rng.uniform(0, 1) < 0.6 ? 1 : 0;
      if (mask[static_cast<size_t>(i)]) idx.push_back(i);
    }
    const int m = static_cast<int>(idx.size());
    Eigen::MatrixXd H = rng.symmetric(n);
    if (trial % 2 == 1 && m >= 3) {
      // Exactly zero rows of the occupied block (the first, an inner and the last occupied dof),
      // which are left out of the eigenproblem.
      for (int a : {0, m / 2, m - 1}) {
        H.row(idx[static_cast<size_t>(a)]).setZero();
        H.col(idx[static_cast<size_t>(a)]).setZero();
      }
    }
    const double eps = trial % 3 == 0 ? 0.0 : 1e-3;
    Eigen::MatrixXd Ho(m, m);
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) Ho(a, b) = H(idx[static_cast<size_t>(a)], idx[static_cast<size_t>(b)]);
    const Eigen::MatrixXd expected = clipReference(Ho) + eps * Eigen::MatrixXd::Identity(m, m);
    // Entries outside the occupied block are ignored.
    for (int i = 0; i < n; ++i) {
      if (mask[static_cast<size_t>(i)]) continue;
      H.row(i).setConstant(123.0);
      H.col(i).setConstant(123.0);
    }
    Eigen::MatrixXd R = Eigen::MatrixXd::Constant(n, n, 7.0);
    std::vector<int> list;
    list.reserve(n);
    ASSERT_EQ(hr.regularizeAndFactor(H, mask, eps, R, list), m);
    EXPECT_EQ(list, idx);
    EXPECT_LE((hr.lastRegularized() - expected).norm(), 1e-13 * n * (1.0 + Ho.norm()));
    if (m > 0) {
      EXPECT_NEAR(hr.lastMinEigenvalue(), minEigenvalue(Ho), 1e-13 * n * (1.0 + Ho.norm())) << "trial " << trial;
    }
    // R^T R: the regularised block on the occupied dofs, zero elsewhere; rows >= m zero.
    Eigen::MatrixXd full = Eigen::MatrixXd::Zero(n, n);
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) full(idx[static_cast<size_t>(a)], idx[static_cast<size_t>(b)]) = expected(a, b);
    EXPECT_LE((R.transpose() * R - full).norm(), 1e-12 * n * (1.0 + Ho.norm())) << "trial " << trial;
    EXPECT_EQ(R.bottomRows(n - m).cwiseAbs().maxCoeff(), 0.0);
    for (int i = 0; i < n; ++i) {
      if (!mask[static_cast<size_t>(i)]) {
        EXPECT_EQ(R.col(i).cwiseAbs().maxCoeff(), 0.0);
      }
    }
    // Upper triangular in the order of the occupied dofs.
    for (int r = 0; r < m; ++r)
      for (int c = 0; c < r; ++c) EXPECT_EQ(R(r, idx[static_cast<size_t>(c)]), 0.0);
    if (eps > 0.0) {
      EXPECT_EQ(hr.lastZeroPivots(), 0);
    }
    // The eigen-rows (LexDynAH's Newton rows): the same R^T R from dense rows, the same
    // occupied list and smallest eigenvalue, nothing outside the occupied columns and rows.
    Eigen::MatrixXd E = Eigen::MatrixXd::Constant(n, n, 7.0);
    std::vector<int> list2;
    list2.reserve(n);
    ASSERT_EQ(hr.regularizedRows(H, mask, eps, E, list2), m) << "trial " << trial;
    EXPECT_EQ(list2, idx);
    EXPECT_FALSE(hr.lastFailed());
    if (m > 0) {
      EXPECT_NEAR(hr.lastMinEigenvalue(), minEigenvalue(Ho), 1e-13 * n * (1.0 + Ho.norm())) << "trial " << trial;
    }
    EXPECT_LE((E.transpose() * E - full).norm(), 1e-12 * n * (1.0 + Ho.norm())) << "trial " << trial;
    EXPECT_EQ(E.bottomRows(n - m).cwiseAbs().maxCoeff(), 0.0);
    for (int i = 0; i < n; ++i) {
      if (!mask[static_cast<size_t>(i)]) {
        EXPECT_EQ(E.col(i).cwiseAbs().maxCoeff(), 0.0);
      }
    }
  }
}

TEST(Higham, EigenRowsOfAnIndefiniteHessian) {
  // Row l is sqrt(max(lambda_l, 0) + eps) v_l^T: the negative curvature is clipped to eps, and
  // the rows are orthogonal with the eigenvalues' square roots as norms, in ascending order.
  Rng rng(110);
  const Eigen::VectorXd lambda = indefiniteSpectrum();
  const int n = static_cast<int>(lambda.size());
  const Eigen::MatrixXd H = withEigenvalues(lambda, rng);
  HighamRegularizer hr(n);
  Eigen::MatrixXd R(n, n);
  std::vector<int> list;
  list.reserve(n);
  const double eps = 1e-6;
  ASSERT_EQ(hr.regularizedRows(H, std::vector<char>(n, 1), eps, R, list), n);
  EXPECT_NEAR(hr.lastMinEigenvalue(), -2.0, 1e-12);
  const Eigen::VectorXd want = clippedPlusEps(lambda, eps);
  const Eigen::MatrixXd RRt = R * R.transpose();
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(RRt(i, i), want(i), 1e-12) << i;
    for (int j = 0; j < i; ++j) EXPECT_NEAR(RRt(i, j), 0.0, 1e-12) << i << " " << j;
  }
  // Zero rows and columns of the block come first, as sqrt(eps) on their dof.
  Eigen::MatrixXd Hz = Eigen::MatrixXd::Zero(n + 1, n + 1);
  Hz.bottomRightCorner(n, n) = H;
  HighamRegularizer hz(n + 1);
  Eigen::MatrixXd Rz(n + 1, n + 1);
  list.reserve(n + 1);
  ASSERT_EQ(hz.regularizedRows(Hz, std::vector<char>(n + 1, 1), eps, Rz, list), n + 1);
  EXPECT_EQ(Rz(0, 0), std::sqrt(eps));
  EXPECT_EQ(Rz.row(0).tail(n).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(Rz.col(0).tail(n).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE((Rz.bottomRightCorner(n, n).transpose() * Rz.bottomRightCorner(n, n) - R.transpose() * R).norm(), 1e-12);
  // A non-finite occupied block gives no rows.
  Eigen::MatrixXd Hn = H;
  Hn(1, 2) = Hn(2, 1) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(hr.regularizedRows(Hn, std::vector<char>(n, 1), eps, R, list), 0);
  EXPECT_TRUE(hr.lastFailed());
  EXPECT_EQ(R.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(list.empty());
}

TEST(Higham, ZeroRowsOfAPositiveDefiniteBlockReportEigenvalueZero) {
  // The rows left out of the eigenproblem are eigenvalue-0 directions: a block that is positive
  // definite elsewhere has the smallest eigenvalue 0, exactly, and is kept as it is.
  Rng rng(109);
  const int n = 7;
  Eigen::VectorXd lambda(n - 2);
  lambda << 0.5, 1.0, 2.0, 3.0, 4.0;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  H.block(1, 1, n - 2, n - 2) = withEigenvalues(lambda, rng);
  HighamRegularizer hr(n);
  Eigen::MatrixXd R(n, n);
  const std::vector<char> all(n, 1);
  ASSERT_EQ(hr.regularizeAndFactor(H, all, 0.0, R), n);
  EXPECT_EQ(hr.lastMinEigenvalue(), 0.0);
  EXPECT_LE((hr.lastRegularized() - H).norm(), 1e-14 * n * H.norm());
}

// The spectrum of one of exp1's task Hessians (35 x 35 after its zero rows): a cluster of tiny
// eigenvalues of both signs, down to 1e-7 of the largest. The QR iteration deflates an
// off-diagonal entry below eps ||T|| (the tridiagonalisation's own rounding level), so the
// cluster takes no sweeps that cannot improve it: fewer than with the test against the two
// neighbouring diagonal entries (493 against 519 sweeps over the ten bases below), and every
// eigenvalue within a few eps ||A|| of the true one. Two equal diagonal entries with small
// couplings (|d_i| + |d_i+1| above every row sum) still converge to full accuracy.
TEST(SymmetricEigenSolver, TinyEigenvalueClusterDeflatesAtTheMatrixRoundingLevel) {
  Rng rng(111);
  Eigen::VectorXd lambda(35);
  lambda << -4.89265311e-09, -2.56548414e-09, -4.43330961e-10, -4.40677466e-10, 2.09320192e-12, 3.63947141e-10, 3.66476612e-10,
      1.67572919e-09, 4.85218311e-09, 3.88926478e-08, 4.19545009e-08, 2.33272683e-07, 2.34444529e-07, 2.36815887e-07, 2.40952321e-07,
      2.80124806e-07, 2.80443092e-07, 3.66570040e-07, 4.96601689e-07, 6.70049757e-07, 7.07640412e-07, 7.62404118e-07, 9.54269705e-07,
      1.06561482e-06, 1.23791476e-06, 1.34442818e-06, 1.85795860e-06, 2.67226158e-06, 3.69628192e-06, 4.12508573e-06, 4.88765419e-06,
      9.01812810e-06, 1.34833985e-05, 2.99238592e-05, 3.19734372e-05;
  // Ten random eigenvector bases: the sweeps summed (each basis's own count moves by a few with
  // the rounding of the tridiagonalisation).
  SymmetricEigenSolver es(35);
  int sweeps = 0;
  const double scale = std::numeric_limits<double>::epsilon() * lambda.cwiseAbs().maxCoeff();
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::MatrixXd A = withEigenvalues(lambda, rng);
    ASSERT_TRUE(es.compute(A));
    sweeps += es.iterations();
    EXPECT_LE((es.eigenvalues() - lambda).cwiseAbs().maxCoeff(), 50.0 * scale) << "trial " << trial;
    const Eigen::MatrixXd V = es.eigenvectors();
    EXPECT_LE((A * V - V * es.eigenvalues().asDiagonal()).norm(), 50.0 * scale) << "trial " << trial;
    EXPECT_LE((V.transpose() * V - Eigen::MatrixXd::Identity(35, 35)).norm(), 1e-13) << "trial " << trial;
    // The negative ones keep their sign (they are what the Higham clipping removes).
    for (int i = 0; i < 4; ++i) EXPECT_LT(es.eigenvalues()[i], 0.0) << "trial " << trial << ", " << i;
  }
  EXPECT_LE(sweeps, 505);  // 493 with this deflation, 519 with the test against the neighbours

  // Equal diagonal entries, small couplings: the threshold eps ||T|| is below eps (|d_i| +
  // |d_i+1|) here, and the iteration still converges.
  Eigen::MatrixXd B = Eigen::MatrixXd::Identity(8, 8);
  for (int i = 0; i + 1 < 8; ++i) B(i, i + 1) = B(i + 1, i) = 1e-9 * (i + 1);
  SymmetricEigenSolver eb(8);
  ASSERT_TRUE(eb.compute(B));
  const Eigen::VectorXd ref = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(B).eigenvalues();
  EXPECT_LE((eb.eigenvalues() - ref).cwiseAbs().maxCoeff(), 1e-14);
  const Eigen::MatrixXd W = eb.eigenvectors();
  EXPECT_LE((B * W - W * eb.eigenvalues().asDiagonal()).norm(), 1e-14);
}

TEST(SymmetricEigenSolver, RotationsBelowTheSquaresRange) {
  // At 1e-170 the squares of a rotation's entries underflow to zero: without std::hypot the QR
  // iteration would make no progress (no Householder step for 2 x 2, so only the rotations act).
  Eigen::Matrix2d M;
  M << 1.0, 0.7, 0.7, -0.4;
  const double scale = 1e-170;
  SymmetricEigenSolver es(2);
  ASSERT_TRUE(es.compute(scale * M));
  const Eigen::Vector2d ref = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(M).eigenvalues();
  EXPECT_NEAR(es.eigenvalues()[0] / scale, ref[0], 1e-14);
  EXPECT_NEAR(es.eigenvalues()[1] / scale, ref[1], 1e-14);
  HighamRegularizer hr(2);
  Eigen::MatrixXd X(2, 2);
  ASSERT_TRUE(hr.nearestPsd(scale * M, X));
  EXPECT_LE(((X / scale) - clipReference(M)).norm(), 1e-14);
}

TEST(Higham, IndefiniteHessianWithEpsIsFactored) {
  // An indefinite Hessian (a negative curvature direction), the typical input of eq. 91.
  Rng rng(108);
  const Eigen::VectorXd lambda = indefiniteSpectrum();
  const int n = static_cast<int>(lambda.size());
  const Eigen::MatrixXd H = withEigenvalues(lambda, rng);
  HighamRegularizer hr(n);
  Eigen::MatrixXd R(n, n);
  const std::vector<char> all(n, 1);
  const double eps = 1e-6;
  ASSERT_EQ(hr.regularizeAndFactor(H, all, eps, R), n);
  EXPECT_NEAR(hr.lastMinEigenvalue(), -2.0, 1e-12);
  const Eigen::VectorXd got = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(R.transpose() * R).eigenvalues();
  EXPECT_LE((got - clippedPlusEps(lambda, eps)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_TRUE(R.isUpperTriangular(0.0));
}

TEST(Higham, NonFiniteInputGivesNoRows) {
  const int n = 5;
  HighamRegularizer hr(n);
  Eigen::MatrixXd H = Eigen::MatrixXd::Identity(n, n);
  H(1, 2) = H(2, 1) = std::numeric_limits<double>::quiet_NaN();
  Eigen::MatrixXd R = Eigen::MatrixXd::Constant(n, n, 3.0);
  EXPECT_EQ(hr.regularizeAndFactor(H, std::vector<char>(n, 1), 1e-6, R), 0);
  EXPECT_TRUE(hr.lastFailed());
  EXPECT_EQ(R.cwiseAbs().maxCoeff(), 0.0);
  // A non-finite entry outside the occupied block is ignored.
  EXPECT_EQ(hr.regularizeAndFactor(H, {1, 0, 0, 1, 1}, 1e-6, R), 3);
  EXPECT_FALSE(hr.lastFailed());
  Eigen::MatrixXd X(n, n);
  EXPECT_FALSE(hr.nearestPsd(H, X));
  EXPECT_TRUE(hr.lastFailed());
  EXPECT_TRUE(hr.nearestPsd(Eigen::MatrixXd::Identity(n, n), X));
}

}  // namespace
}  // namespace lexdyn::hessian
