#include "lexdyn/hessian/higham.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "lexdyn/common/error.hpp"

namespace lexdyn::hessian {

// =============================================================================================
// Symmetric eigendecomposition
// =============================================================================================

namespace {

// sqrt(x^2 + z^2) of the QR rotations: a plain square root where the sum of squares can neither
// overflow nor lose the larger term to underflow (always, at the scale of the Newton rows'
// Hessians), std::hypot (several times slower, and the QR iteration's main cost with it)
// otherwise.
inline double pythag(double x, double z) {
  const double s = x * x + z * z;
  if (s > 1e-290 && s < 1e290) return std::sqrt(s);
  return std::hypot(x, z);
}

// [a b] <- [a b] G for two columns a, b of n entries, G = [c s; -s c].
inline void rotateColumns(double* a, double* b, int n, double c, double s) {
  for (int row = 0; row < n; ++row) {
    const double x = a[row], y = b[row];
    a[row] = c * x - s * y;
    b[row] = s * x + c * y;
  }
}

}  // namespace

SymmetricEigenSolver::SymmetricEigenSolver(int capacity) { setup(capacity); }

void SymmetricEigenSolver::setup(int capacity) {
  n_ = 0;
  iterations_ = 0;
  LEXDYN_ALWAYS_ASSERT(capacity >= 0, "SymmetricEigenSolver: negative capacity");
  work_.setZero(capacity, capacity);
  z_.setZero(capacity, capacity);
  d_.setZero(capacity);
  e_.setZero(capacity);
  tau_.setZero(capacity);
  tmp_.setZero(capacity);
}

bool SymmetricEigenSolver::compute(const Eigen::Ref<const Eigen::MatrixXd>& A) {
  const int n = static_cast<int>(A.rows());
  LEXDYN_ALWAYS_ASSERT(A.cols() == n, "SymmetricEigenSolver::compute: A must be square");
  LEXDYN_ALWAYS_ASSERT(n <= capacity(), "SymmetricEigenSolver::compute: A exceeds the capacity");
  n_ = n;
  iterations_ = 0;
  if (n == 0) return true;
  auto W = work_.topLeftCorner(n, n);
  auto Z = z_.topLeftCorner(n, n);
  // The lower triangle is all that is read and updated.
  for (int c = 0; c < n; ++c) {
    for (int r = c; r < n; ++r) W(r, c) = A(r, c);
  }

  // 1. Householder tridiagonalisation W = Q T Q^T, Q = P_0 P_1 ... P_{n-3},
  //    P_k = I - tau_k v_k v_k^T acting on rows/columns k+1 .. n-1.
  for (int k = 0; k + 2 < n; ++k) {
    const int L = n - k - 1;
    auto x = W.col(k).segment(k + 1, L);
    const double sigma = x.tail(L - 1).squaredNorm();
    const double x0 = x[0];
    if (sigma == 0.0) {
      tau_[k] = 0.0;
      e_[k] = x0;
      continue;
    }
    const double alpha = -std::copysign(std::sqrt(x0 * x0 + sigma), x0);
    const double v0 = x0 - alpha;  // no cancellation: alpha has the opposite sign of x0
    x[0] = v0;                     // x now holds v
    const double tau = 2.0 / (v0 * v0 + sigma);
    tau_[k] = tau;
    e_[k] = alpha;
    // Two-sided update of the trailing block S <- P S P = S - v q^T - q v^T with
    // p = tau S v, q = p - (tau/2) (p^T v) v, on the lower triangle of S only (S symmetric:
    // S v reads each stored entry for its row and, off the diagonal, for its column).
    auto S = W.bottomRightCorner(L, L);
    auto p = tmp_.head(L);
    for (int r = 0; r < L; ++r) p[r] = 0.0;
    // Two columns at a time: p[r] receives column c's term, then column c+1's, and each column's
    // sum runs in the order of r, as one column at a time would (the same bits); the two sums are
    // independent chains that overlap.
    int c = 0;
    for (; c + 1 < L; c += 2) {
      const double v0 = x[c], v1 = x[c + 1];
      const double* s0 = &S(0, c);
      const double* s1 = &S(0, c + 1);
      double pc0 = s0[c] * v0;
      p[c + 1] += s0[c + 1] * v0;  // row c+1: column c's term only (column c+1 starts on its diagonal)
      pc0 += s0[c + 1] * x[c + 1];
      double pc1 = s1[c + 1] * v1;
      for (int r = c + 2; r < L; ++r) {
        const double a0 = s0[r], a1 = s1[r], xr = x[r];
        p[r] = (p[r] + a0 * v0) + a1 * v1;
        pc0 += a0 * xr;
        pc1 += a1 * xr;
      }
      p[c] += pc0;
      p[c + 1] += pc1;
    }
    for (; c < L; ++c) {
      const double vc = x[c];
      double pc = S(c, c) * vc;
      for (int r = c + 1; r < L; ++r) {
        p[r] += S(r, c) * vc;
        pc += S(r, c) * x[r];
      }
      p[c] += pc;
    }
    p *= tau;
    const double K = 0.5 * tau * p.dot(x);
    for (int r = 0; r < L; ++r) p[r] -= K * x[r];
    for (int c = 0; c < L; ++c) {
      const double vc = x[c], qc = p[c];
      for (int r = c; r < L; ++r) S(r, c) -= x[r] * qc + p[r] * vc;
    }
  }
  for (int k = 0; k < n; ++k) d_[k] = W(k, k);
  if (n >= 2) e_[n - 2] = W(n - 1, n - 2);
  e_[n - 1] = 0.0;

  // 2. Accumulate Q (backwards, so that each reflector touches only its trailing block).
  Z.setIdentity();
  for (int k = n - 3; k >= 0; --k) {
    if (tau_[k] == 0.0) continue;
    const int L = n - k - 1;
    auto v = W.col(k).segment(k + 1, L);
    auto Zb = Z.bottomRightCorner(L, L);
    auto t = tmp_.head(L);
    for (int c = 0; c < L; ++c) t[c] = Zb.col(c).dot(v);  // t = Zb^T v
    for (int c = 0; c < L; ++c) {
      const double tc = tau_[k] * t[c];
      for (int r = 0; r < L; ++r) Zb(r, c) -= v[r] * tc;
    }
  }

  // 3. Implicit symmetric QR steps with Wilkinson shifts on the tridiagonal (d, e), the
  //    rotations accumulated into Z (Golub & Van Loan, algorithm 8.3.3).
  //    An off-diagonal entry is deflated when it is below the rounding level of the whole
  //    matrix (eps ||T||, the accuracy the tridiagonalisation leaves every eigenvalue with), not
  //    of its two neighbours on the diagonal: a cluster of eigenvalues near zero (the task
  //    Hessians' null directions) then deflates without sweeps that cannot improve it.
  const double eps = std::numeric_limits<double>::epsilon();
  const double tiny = std::numeric_limits<double>::min();
  double tnorm = 0.0;
  for (int i = 0; i < n; ++i) {
    const double row = std::abs(d_[i]) + (i + 1 < n ? std::abs(e_[i]) : 0.0) + (i > 0 ? std::abs(e_[i - 1]) : 0.0);
    tnorm = std::max(tnorm, row);
  }
  const double deflate = eps * tnorm;
  int h = n - 1;
  const int max_iterations = 30 * n;
  while (h > 0) {
    for (int i = 0; i < h; ++i) {
      const double ae = std::abs(e_[i]);
      if (ae <= deflate || ae <= tiny) e_[i] = 0.0;
    }
    while (h > 0 && e_[h - 1] == 0.0) --h;
    if (h == 0) break;
    int l = h - 1;
    while (l > 0 && e_[l - 1] != 0.0) --l;
    if (++iterations_ > max_iterations) return false;
    // Wilkinson shift: the eigenvalue of the trailing 2 x 2 block closer to d[h].
    const double delta = 0.5 * (d_[h - 1] - d_[h]);
    const double b = e_[h - 1];
    const double denom = delta + std::copysign(pythag(delta, b), delta);
    const double mu = d_[h] - b * b / denom;
    double x = d_[l] - mu;
    double z = e_[l];
    int pk = -1;  // the rotation not yet applied to Z: columns (pk, pk + 1), cosine pc, sine ps
    double pc = 1.0, ps = 0.0;
    for (int k = l; k < h; ++k) {
      // Rotation G on (k, k+1) with G^T [x; z] = [r; 0], G = [c s; -s c].
      const double r = pythag(x, z);
      double c = 1.0, s = 0.0;
      if (r > 0.0) {
        c = x / r;
        s = -z / r;
      }
      if (k > l) e_[k - 1] = r;
      const double a = d_[k], bb = d_[k + 1], f = e_[k];
      const double cc = c * c, ss = s * s, cs = c * s;
      d_[k] = cc * a - 2.0 * cs * f + ss * bb;
      d_[k + 1] = ss * a + 2.0 * cs * f + cc * bb;
      e_[k] = (a - bb) * cs + f * (cc - ss);
      if (k + 1 < h) {
        z = -s * e_[k + 1];  // the bulge T(k+2, k)
        e_[k + 1] = c * e_[k + 1];
        x = e_[k];
      }
      // The previous rotation goes into Z now, after this one's scalar recurrence: the two are
      // independent, and the recurrence (a chain of square roots and divisions) starts first.
      // Each rotation still reaches Z in order, so Z takes the same bits.
      if (pk >= 0) rotateColumns(&Z(0, pk), &Z(0, pk + 1), n, pc, ps);
      pk = k;
      pc = c;
      ps = s;
    }
    if (pk >= 0) rotateColumns(&Z(0, pk), &Z(0, pk + 1), n, pc, ps);
  }

  // 4. Ascending order (selection sort, swapping eigenvector columns).
  for (int i = 0; i + 1 < n; ++i) {
    int best = i;
    for (int j = i + 1; j < n; ++j) {
      if (d_[j] < d_[best]) best = j;
    }
    if (best != i) {
      std::swap(d_[i], d_[best]);
      Z.col(i).swap(Z.col(best));
    }
  }
  return true;
}

// =============================================================================================
// Cholesky
// =============================================================================================

int choleskyUpperInPlace(Eigen::Ref<Eigen::MatrixXd> A, int m, double pivot_tolerance) {
  LEXDYN_ALWAYS_ASSERT(m >= 0 && m <= A.rows() && m <= A.cols(), "choleskyUpperInPlace: bad size");
  int zero_pivots = 0;
  const Eigen::Index ld = A.outerStride();
  double* a = A.data();
  for (int k = 0; k < m; ++k) {
    double* ck = a + k * ld;  // column k: U(0 .. k-1, k) above the pivot
    double dkk = ck[k];
    for (int i = 0; i < k; ++i) dkk -= ck[i] * ck[i];
    if (!(dkk > pivot_tolerance)) {
      ++zero_pivots;
      for (int j = k; j < m; ++j) a[k + j * ld] = 0.0;
    } else {
      const double ukk = std::sqrt(dkk);
      ck[k] = ukk;
      // Row k of U: U(k, j) = (A(k, j) - sum_i U(i, k) U(i, j)) / U(k, k), each sum in the order
      // of i. Four columns at a time: four independent sums overlap (the same operations in the
      // same order as one column at a time, so the same bits).
      int j = k + 1;
      for (; j + 4 <= m; j += 4) {
        double* c0 = a + j * ld;
        double* c1 = c0 + ld;
        double* c2 = c1 + ld;
        double* c3 = c2 + ld;
        double s0 = c0[k], s1 = c1[k], s2 = c2[k], s3 = c3[k];
        for (int i = 0; i < k; ++i) {
          const double u = ck[i];
          s0 -= u * c0[i];
          s1 -= u * c1[i];
          s2 -= u * c2[i];
          s3 -= u * c3[i];
        }
        c0[k] = s0 / ukk;
        c1[k] = s1 / ukk;
        c2[k] = s2 / ukk;
        c3[k] = s3 / ukk;
      }
      for (; j < m; ++j) {
        double* cj = a + j * ld;
        double sj = cj[k];
        for (int i = 0; i < k; ++i) sj -= ck[i] * cj[i];
        cj[k] = sj / ukk;
      }
    }
    for (int i = k + 1; i < m; ++i) ck[i] = 0.0;
  }
  return zero_pivots;
}

// =============================================================================================
// Higham
// =============================================================================================

HighamRegularizer::HighamRegularizer(int n) { setup(n); }

void HighamRegularizer::setup(int n) {
  LEXDYN_ALWAYS_ASSERT(n >= 0, "HighamRegularizer: negative size");
  n_ = n;
  m_ = 0;
  zero_pivots_ = 0;
  min_eig_ = 0.0;
  eig_.setup(n);
  block_.setZero(n, n);
  last_.setZero(n, n);
  compact_.setZero(n, n);
  scaled_.setZero(n, n);
  product_.setZero(n, n);
  index_.assign(static_cast<size_t>(n), 0);
  nonzero_.assign(static_cast<size_t>(n), 0);
}

int HighamRegularizer::decomposeNonzeroPart(const Eigen::Ref<const Eigen::MatrixXd>& B) {
  const int m = static_cast<int>(B.rows());
  // A row and column of B that are exactly zero (the lower triangle is read: the row left of
  // the diagonal and the column from it down) make e_j an eigenvector of eigenvalue 0, which
  // the clipping removes: they are left out of the eigenproblem (the floating base's
  // translation in the humanoid's task Hessians, on which no second derivative depends).
  int p = 0;
  for (int c = 0; c < m; ++c) {
    const bool zero = (B.col(c).tail(m - c).array() == 0.0).all() && (B.row(c).head(c).array() == 0.0).all();
    if (!zero) nonzero_[static_cast<size_t>(p++)] = c;
  }
  auto C = compact_.topLeftCorner(p, p);
  for (int c = 0; c < p; ++c) {
    const int bc = nonzero_[static_cast<size_t>(c)];
    for (int r = c; r < p; ++r) C(r, c) = B(nonzero_[static_cast<size_t>(r)], bc);
  }
  if (!eig_.compute(C)) return -1;
  min_eig_ = p > 0 ? eig_.eigenvalues()[0] : 0.0;
  if (p < m) min_eig_ = std::min(min_eig_, 0.0);
  return p;
}

bool HighamRegularizer::clippedBlock(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::Ref<Eigen::MatrixXd> X) {
  const int p = decomposeNonzeroPart(B);
  if (p < 0) return false;
  const auto lambda = eig_.eigenvalues();
  const auto V = eig_.eigenvectors();
  // V max(Lambda, 0) V^T = S S^T with S = V_+ Lambda_+^(1/2): exactly symmetric (the lower
  // triangle is mirrored), positive semi-definite up to rounding, and formed column by column
  // (contiguous axpy updates of the lower triangle).
  int first = 0;
  while (first < p && !(lambda[first] > 0.0)) ++first;
  const int kp = p - first;
  auto S = scaled_.topLeftCorner(p, kp);
  for (int l = 0; l < kp; ++l) S.col(l) = V.col(first + l) * std::sqrt(lambda[first + l]);
  auto Y = product_.topLeftCorner(p, p);
  for (int c = 0; c < p; ++c) {
    auto y = Y.col(c).tail(p - c);
    y.setZero();
    for (int l = 0; l < kp; ++l) y += S(c, l) * S.col(l).tail(p - c);
  }
  X.setZero();
  for (int c = 0; c < p; ++c) {
    const int bc = nonzero_[static_cast<size_t>(c)];
    for (int r = c; r < p; ++r) {
      const int br = nonzero_[static_cast<size_t>(r)];
      X(br, bc) = Y(r, c);
      X(bc, br) = Y(r, c);
    }
  }
  return true;
}

bool HighamRegularizer::nearestPsd(const Eigen::Ref<const Eigen::MatrixXd>& H, Eigen::Ref<Eigen::MatrixXd> X) {
  const int k = static_cast<int>(H.rows());
  LEXDYN_ALWAYS_ASSERT(H.cols() == k && X.rows() == k && X.cols() == k && k <= n_, "HighamRegularizer::nearestPsd: bad sizes");
  failed_ = !H.allFinite() || !clippedBlock(H, X);
  if (failed_) {
    X.setConstant(std::numeric_limits<double>::quiet_NaN());
    min_eig_ = std::numeric_limits<double>::quiet_NaN();
    return false;
  }
  return true;
}

int HighamRegularizer::gatherOccupied(const char* caller, const Eigen::Ref<const Eigen::MatrixXd>& H, const std::vector<char>& occupied,
                                      double eps, Eigen::Ref<Eigen::MatrixXd> R) {
  // (the messages are built only when a check fails: nothing is allocated per call)
  LEXDYN_ALWAYS_ASSERT(H.rows() == n_ && H.cols() == n_, std::string(caller) + ": H must be n x n");
  LEXDYN_ALWAYS_ASSERT(static_cast<int>(occupied.size()) == n_, std::string(caller) + ": mask must have n entries");
  LEXDYN_ALWAYS_ASSERT(R.cols() == n_, std::string(caller) + ": R must have n columns");
  LEXDYN_ALWAYS_ASSERT(eps >= 0.0, std::string(caller) + ": eps must be >= 0");
  int m = 0;
  for (int i = 0; i < n_; ++i) {
    if (occupied[static_cast<size_t>(i)]) index_[static_cast<size_t>(m++)] = i;
  }
  LEXDYN_ALWAYS_ASSERT(R.rows() >= m, std::string(caller) + ": R has fewer rows than occupied dofs");
  m_ = m;
  R.setZero();
  zero_pivots_ = 0;
  min_eig_ = 0.0;
  failed_ = false;
  auto Hb = block_.topLeftCorner(m, m);
  for (int c = 0; c < m; ++c) {
    for (int r = 0; r < m; ++r) Hb(r, c) = H(index_[static_cast<size_t>(r)], index_[static_cast<size_t>(c)]);
  }
  return m;
}

int HighamRegularizer::failed() {
  failed_ = true;
  m_ = 0;
  min_eig_ = std::numeric_limits<double>::quiet_NaN();
  return 0;
}

void HighamRegularizer::listOccupied(const char* caller, std::vector<int>& occupied_list, int m) const {
  LEXDYN_ALWAYS_ASSERT(occupied_list.capacity() >= static_cast<size_t>(n_),
                       std::string(caller) + ": reserve n entries in occupied_list (no allocation per tick)");
  occupied_list.clear();  // (empty when the block was not finite)
  for (int k = 0; k < m; ++k) occupied_list.push_back(index_[static_cast<size_t>(k)]);
}

int HighamRegularizer::regularizeAndFactor(const Eigen::Ref<const Eigen::MatrixXd>& H, const std::vector<char>& occupied, double eps,
                                           Eigen::Ref<Eigen::MatrixXd> R) {
  const int m = gatherOccupied("regularizeAndFactor", H, occupied, eps, R);
  if (m == 0) return 0;
  auto Hb = block_.topLeftCorner(m, m);
  auto X = last_.topLeftCorner(m, m);
  if (!Hb.allFinite() || !clippedBlock(Hb, X)) return failed();  // eq. 91 without eps
  double max_diag = 0.0;
  for (int i = 0; i < m; ++i) {
    X(i, i) += eps;  // eps I* on the occupied dofs
    max_diag = std::max(max_diag, X(i, i));
  }
  Hb = X;
  // Pivots below the rounding level of the block are semi-definite directions (eps == 0).
  const double tol = static_cast<double>(m) * std::numeric_limits<double>::epsilon() * max_diag;
  zero_pivots_ = choleskyUpperInPlace(Hb, m, tol);
  for (int r = 0; r < m; ++r) {
    for (int c = r; c < m; ++c) R(r, index_[static_cast<size_t>(c)]) = Hb(r, c);
  }
  return m;
}

int HighamRegularizer::regularizedRows(const Eigen::Ref<const Eigen::MatrixXd>& H, const std::vector<char>& occupied, double eps,
                                       Eigen::Ref<Eigen::MatrixXd> R, std::vector<int>& occupied_list) {
  const int m = gatherOccupied("regularizedRows", H, occupied, eps, R);
  m_ = 0;  // lastRegularized() is not formed here
  listOccupied("regularizedRows", occupied_list, 0);
  if (m == 0) return 0;
  auto Hb = block_.topLeftCorner(m, m);
  const int p = Hb.allFinite() ? decomposeNonzeroPart(Hb) : -1;  // eq. 91
  if (p < 0) return failed();
  // The zero rows and columns: eigenvalue 0, unit vectors.
  int row = 0;
  const double root_eps = std::sqrt(eps);
  for (int c = 0, q = 0; c < m; ++c) {
    if (q < p && nonzero_[static_cast<size_t>(q)] == c) {
      ++q;
      continue;
    }
    R(row++, index_[static_cast<size_t>(c)]) = root_eps;
  }
  const auto lambda = eig_.eigenvalues();
  const auto V = eig_.eigenvectors();
  for (int l = 0; l < p; ++l, ++row) {
    const double w = std::sqrt(std::max(lambda[l], 0.0) + eps);
    for (int c = 0; c < p; ++c) R(row, index_[static_cast<size_t>(nonzero_[static_cast<size_t>(c)])]) = w * V(c, l);
  }
  listOccupied("regularizedRows", occupied_list, m);
  return m;
}

int HighamRegularizer::regularizeAndFactor(const Eigen::Ref<const Eigen::MatrixXd>& H, const std::vector<char>& occupied, double eps,
                                           Eigen::Ref<Eigen::MatrixXd> R, std::vector<int>& occupied_list) {
  const int m = regularizeAndFactor(H, occupied, eps, R);
  listOccupied("regularizeAndFactor", occupied_list, m);
  return m;
}

}  // namespace lexdyn::hessian
