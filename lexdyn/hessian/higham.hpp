// Nearest positive semi-definite matrix (Higham 1988; paper sec. VI-B, eq. 91-92) and the
// Newton rows R of a level (eq. 35) with R^T R the regularised occupied block: its Cholesky
// factor (regularizeAndFactor: BFGS's fallback, SR1) or rows from its eigendecomposition
// (regularizedRows: LexDynAH).
//
// For a symmetric H with eigendecomposition H = V Lambda V^T, the polar decomposition is
// H = U P with P = V |Lambda| V^T (the SVD H = U Sigma V^T has Sigma = |Lambda|), and Higham's
// nearest symmetric positive semi-definite matrix in the Frobenius norm is
//   H~ = 1/2 (H + P) = V max(Lambda, 0) V^T                                        (eq. 91)
// at distance ||H - H~||_F = sqrt(sum of the squared negative eigenvalues). lexdyn evaluates the
// right-hand form as S S^T with S = V_+ Lambda_+^(1/2), the eigenvectors of the positive
// eigenvalues scaled (exactly symmetric, and positive semi-definite up to rounding, where
// 1/2 (H + P) would carry the rounding of the reconstruction of H). Rows and columns of H that
// are exactly zero (a floating base's translation in the task Hessians) are left out of the
// eigenproblem: they are eigenvectors of eigenvalue 0. Then eps is added on the diagonal of the
// occupied dofs (the eps I* of eq. 91), and the occupied block is factored H~ + eps I = R^T R
// (regularizeAndFactor), or R is taken as rows sqrt(max(lambda, 0) + eps) v^T without forming
// H~ (regularizedRows).
//
// Everything works on the occupied dofs only (the union of the task chains of the level): rows
// and columns of H outside the mask are ignored. The Hessian of a task function vanishes outside
// its chain, so nothing is lost when the mask covers every chain that contributed to H.
//
// The eigendecomposition is lexdyn's own (Householder tridiagonalisation and the implicit
// symmetric QR iteration with Wilkinson shifts, Golub & Van Loan sec. 8.3; the reduction updates
// the lower triangle only, and a QR rotation's length is a plain square root unless its squares
// could overflow or underflow; the reduction itself is unscaled, for entries between about
// 1e-150 and 1e150; the reduction's products run two columns at a time and each QR rotation
// reaches the eigenvectors one rotation late, so that independent chains of operations overlap,
// in the same order per entry): it works in place in
// storage sized once, for any size up to that capacity, whereas Eigen's SelfAdjointEigenSolver
// allocates inside compute() (1 allocation for an unchanged size, 5 when the size changes,
// measured with tests/common/alloc_counter.hpp).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace lexdyn::hessian {

/// Symmetric eigendecomposition A = V diag(lambda) V^T of an n x n matrix, n <= capacity.
/// compute() allocates nothing.
class SymmetricEigenSolver {
 public:
  explicit SymmetricEigenSolver(int capacity = 0);
  /// (Re)sizes the workspaces (allocates).
  void setup(int capacity);
  int capacity() const { return static_cast<int>(work_.rows()); }
  /// Decomposes the symmetric matrix A (its lower triangle is read). Returns false when the QR
  /// iteration did not converge within 30 n sweeps (not observed; the result is then unusable).
  bool compute(const Eigen::Ref<const Eigen::MatrixXd>& A);
  int size() const { return n_; }
  /// Eigenvalues in ascending order (size()).
  Eigen::VectorBlock<const Eigen::VectorXd> eigenvalues() const { return d_.head(n_); }
  /// Orthonormal eigenvectors, column k for eigenvalue k (size() x size()).
  Eigen::Block<const Eigen::MatrixXd> eigenvectors() const { return z_.topLeftCorner(n_, n_); }
  /// QR sweeps of the last compute().
  int iterations() const { return iterations_; }

 private:
  int n_ = 0;
  int iterations_ = 0;
  Eigen::MatrixXd work_, z_;
  Eigen::VectorXd d_, e_, tau_, tmp_;
};

/// In-place upper Cholesky factor of the leading m x m block of A (its upper triangle is read;
/// on return the upper triangle holds U with U^T U = A, the strict lower triangle is zeroed).
/// A pivot <= pivot_tolerance (a semi-definite direction) gives a zero row of U. Returns the
/// number of such pivots (0 for a positive definite block). Allocates nothing.
int choleskyUpperInPlace(Eigen::Ref<Eigen::MatrixXd> A, int m, double pivot_tolerance = 0.0);

/// Higham's regularisation and the Newton-row factor of one level. Sized once for nv dofs.
class HighamRegularizer {
 public:
  explicit HighamRegularizer(int n = 0);
  /// (Re)sizes the workspaces for n dofs (allocates).
  void setup(int n);
  int size() const { return n_; }

  /// X = nearest positive semi-definite matrix of the symmetric H (Frobenius norm), eq. 91-92.
  /// H and X are k x k with k <= size(); X may alias H. Allocates nothing. Returns false (X
  /// filled with NaN) when H is not finite.
  bool nearestPsd(const Eigen::Ref<const Eigen::MatrixXd>& H, Eigen::Ref<Eigen::MatrixXd> X);

  /// Newton rows of a level: with m = number of occupied dofs (mask[i] != 0) and H_o the
  /// occupied block of H, computes H~_o = nearest PSD of H_o plus eps on its diagonal, its
  /// Cholesky factor U (m x m upper triangular, U^T U = H~_o), and writes R = U scattered to the
  /// occupied columns: R.row(r) for r < m, columns = dofs (R.cols() == size()), zero in the
  /// unoccupied columns; rows m .. R.rows()-1 are zeroed (R.rows() >= m). So R^T R equals H~_o
  /// on the occupied block and 0 elsewhere. Returns m. Allocates nothing. A non-finite occupied
  /// block gives no rows: R zeroed, 0 returned, lastFailed() true.
  int regularizeAndFactor(const Eigen::Ref<const Eigen::MatrixXd>& H, const std::vector<char>& occupied, double eps,
                          Eigen::Ref<Eigen::MatrixXd> R);
  /// The same, also listing the m occupied dofs in `occupied_list` (capacity >= size()).
  int regularizeAndFactor(const Eigen::Ref<const Eigen::MatrixXd>& H, const std::vector<char>& occupied, double eps,
                          Eigen::Ref<Eigen::MatrixXd> R, std::vector<int>& occupied_list);

  /// Newton rows of a level from the eigendecomposition instead of a Cholesky factor: with
  /// H_o = V Lambda V^T (eigenvalues of the occupied block, exactly zero rows and columns taking
  /// the unit vectors of eigenvalue 0), row l of R is sqrt(max(lambda_l, 0) + eps) v_l^T scattered
  /// to the occupied columns, so R^T R = V (max(Lambda, 0) + eps I) V^T = H~_o, the matrix that
  /// regularizeAndFactor factorises, without forming it or its Cholesky factor. Row order: first
  /// sqrt(eps) e_j for the exactly zero rows and columns, then one row per eigenpair of the rest in
  /// ascending order of lambda. Rows m .. R.rows()-1 are zeroed; returns m and lists the occupied
  /// dofs as regularizeAndFactor does. lastMinEigenvalue() and lastFailed() are set as there;
  /// lastRegularized() becomes an empty block and lastZeroPivots() 0 (nothing is factorised).
  int regularizedRows(const Eigen::Ref<const Eigen::MatrixXd>& H, const std::vector<char>& occupied, double eps,
                      Eigen::Ref<Eigen::MatrixXd> R, std::vector<int>& occupied_list);

  /// Occupied block of the last regularizeAndFactor before factorisation (H~_o, m x m), and the
  /// number of semi-definite pivots of its Cholesky factor (0 when eps > 0 in practice).
  Eigen::Block<const Eigen::MatrixXd> lastRegularized() const { return last_.topLeftCorner(m_, m_); }
  int lastZeroPivots() const { return zero_pivots_; }
  /// Whether the last call met a non-finite matrix (or, never observed, a QR iteration that did
  /// not converge).
  bool lastFailed() const { return failed_; }
  /// The smallest eigenvalue of the last regularised block before clipping (diagnostics).
  double lastMinEigenvalue() const { return min_eig_; }

 private:
  int n_ = 0, m_ = 0, zero_pivots_ = 0;
  double min_eig_ = 0.0;
  bool failed_ = false;
  /// X = V max(Lambda, 0) V^T of the symmetric block B (lower triangle read; X may alias B);
  /// sets min_eig_. False when the QR iteration did not converge.
  bool clippedBlock(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::Ref<Eigen::MatrixXd> X);
  /// The common start of regularizeAndFactor and regularizedRows (`caller` names it in the
  /// argument checks): lists the occupied dofs in index_, zeroes R, resets the diagnostics, copies
  /// the occupied block of H into block_ and returns its size m (m_ = m).
  int gatherOccupied(const char* caller, const Eigen::Ref<const Eigen::MatrixXd>& H, const std::vector<char>& occupied, double eps,
                     Eigen::Ref<Eigen::MatrixXd> R);
  /// A non-finite block (or an eigenproblem that did not converge): no rows; returns 0.
  int failed();
  /// occupied_list = the first m occupied dofs (capacity >= size(): no allocation).
  void listOccupied(const char* caller, std::vector<int>& occupied_list, int m) const;
  /// Lists the rows and columns of the symmetric block B that are not exactly zero in nonzero_
  /// (lower triangle read), copies that part's lower triangle into compact_ and decomposes it
  /// (eig_); sets min_eig_. Returns the count, or -1 when the QR iteration did not converge.
  int decomposeNonzeroPart(const Eigen::Ref<const Eigen::MatrixXd>& B);

  SymmetricEigenSolver eig_;
  Eigen::MatrixXd block_, last_, compact_, scaled_, product_;
  std::vector<int> index_, nonzero_;
};

}  // namespace lexdyn::hessian
