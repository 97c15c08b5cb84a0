// Per-level quasi-Newton approximation B of J^T J + H of the level's Lagrangian (LexDynBFGS,
// paper sec. VI-A, eq. 87-89; occupancy changes sec. VII; model-mismatch guard sec. VIII-A), and
// the SR1 alternative the paper suggests (sec. VI-C), behind the same interface.
//
// Per level and tick, the controller
//   1. initialises B once (eq. 89): initialize(diag, occupied) with
//        diag = sum over the level's active tasks of initialDiagonalValue(zeta, dt edot_PD) on the
//        dofs of each task's chain (addOnChain), zeta = 1e-3 dt^2;
//   2. afterwards never re-initialises on a GN <-> Newton switch or an active-set change
//      (sec. VII): setOccupied(occupied, value) zeroes the rows and columns of dofs no longer
//      occupied and puts `value` on the diagonal of newly occupied dofs;
//   3. updates B with s the step actually taken (dt u(k)) and y the change of the Lagrangian's
//      gradient sum_i J_i^T lambda_{i,l} with the current multipliers (eq. 88,
//      accumulateGradientChange; sign as in docs/controller.md, "Newton augmentation"):
//      update(s, y) returns whether B changed;
//   4. adds zeta on the diagonal of the dofs flagged by a SignChangeGuard (sec. VIII-A);
//   5. factor(R): Newton rows R with R^T R = B on the occupied block (eq. 35).
//
// B lives in the nv x nv space of u and is zero outside the occupied dofs: update() uses the
// occupied components of s and y only, so B stays block-structured and positive definite on the
// occupied block (BFGS with the curvature guard y^T s > xi keeps it so, given a positive definite
// start). SR1 may become indefinite: its factor goes through Higham's regularisation plus eps
// (higham.hpp). Every member function after construction allocates nothing.
#pragma once

#include <Eigen/Core>

#include <memory>
#include <vector>

#include "lexdyn/hessian/higham.hpp"

namespace lexdyn::hessian {

enum class QuasiNewtonUpdate {
  Bfgs,  ///< eq. 87 (the paper's LexDynBFGS)
  Sr1,   ///< symmetric rank one (beyond the paper; sec. VI-C suggests it)
};

struct QuasiNewtonOptions {
  QuasiNewtonUpdate update = QuasiNewtonUpdate::Bfgs;
  /// BFGS curvature threshold: update only when y^T s > xi (paper: 1e-12 dt^2).
  double xi = 1e-12 * 0.005 * 0.005;
  /// SR1 skip rule: update only when |r^T s| >= sr1_tolerance |r| |s|, r = y - B s.
  double sr1_tolerance = 1e-8;
  /// eps added on the occupied diagonal after Higham's regularisation: always for SR1, and for
  /// BFGS only when rounding made B numerically indefinite (not observed).
  double eps = 1e-3 * 0.005 * 0.005;
  /// alpha of the paper's "weighted identity alpha I*" (sec. IX-A: added to B when the motion is
  /// too jerky): factor() factors B + alpha I* on the occupied block; B itself is unchanged.
  /// 0 (the paper's experiments) by default.
  double identity_weight = 0.0;
};

/// Eq. 89 value of one active task: max(zeta, 1/2 ||dt edot_PD||^2) (`dt_edot` = dt edot_PD).
double initialDiagonalValue(double zeta, const Eigen::Ref<const Eigen::VectorXd>& dt_edot);
/// diag[i] += value for every dof i with chain[i] != 0 (the I* of eq. 89).
void addOnChain(const std::vector<char>& chain, double value, Eigen::Ref<Eigen::VectorXd> diag);
/// Eq. 88 for one task block: y += (J - J_prev)^T lambda (J, J_prev: rows x nv; lambda: rows), the
/// change of the Lagrangian's gradient sum_i J_i^T lambda_i (eq. 20) at fixed multipliers. (The
/// paper prints y_l with a leading minus, which contradicts eq. 20; docs/controller.md.)
void accumulateGradientChange(const Eigen::Ref<const Eigen::MatrixXd>& J, const Eigen::Ref<const Eigen::MatrixXd>& J_prev,
                              const Eigen::Ref<const Eigen::VectorXd>& lambda, Eigen::Ref<Eigen::VectorXd> y);
/// The multiplier part of the full difference of the Lagrangian's gradient (eq. 88 read as
/// grad L(k) - grad L(k-1) with each gradient's own multipliers, ControllerParams::bfgs_secant
/// full_difference): y += J_prev^T (lambda - lambda_prev) (J_prev: rows x nv).
void accumulateMultiplierChange(const Eigen::Ref<const Eigen::MatrixXd>& J_prev, const Eigen::Ref<const Eigen::VectorXd>& lambda,
                                const Eigen::Ref<const Eigen::VectorXd>& lambda_prev, Eigen::Ref<Eigen::VectorXd> y);

/// Cholesky factor of the occupied block of a positive (semi-)definite B, scattered to the
/// occupied columns: R (rows >= m, cols == B.cols()) gets U (m x m upper triangular, U^T U = B_o)
/// in rows 0..m-1, zero elsewhere; `occupied_list` receives the m occupied dofs (its capacity
/// must be >= n so that nothing is allocated). The factor is computed in place in R. A pivot
/// <= 0 gives a zero row (counted in *zero_pivots when given). Returns m.
int choleskyOfOccupied(const Eigen::Ref<const Eigen::MatrixXd>& B, const std::vector<char>& occupied, Eigen::Ref<Eigen::MatrixXd> R,
                       std::vector<int>& occupied_list, int* zero_pivots = nullptr);

/// The per-level approximation B (n x n). One interface, two update rules (makeBfgs, makeSr1).
class QuasiNewtonMatrix {
 public:
  QuasiNewtonMatrix(int n, const QuasiNewtonOptions& options);
  virtual ~QuasiNewtonMatrix() = default;
  QuasiNewtonMatrix(const QuasiNewtonMatrix&) = delete;
  QuasiNewtonMatrix& operator=(const QuasiNewtonMatrix&) = delete;

  virtual QuasiNewtonUpdate kind() const = 0;
  int size() const { return n_; }
  const QuasiNewtonOptions& options() const { return options_; }

  /// Back to the uninitialised state (B = 0, nothing occupied).
  void reset();
  bool initialized() const { return initialized_; }
  /// Eq. 89: B = diag(diagonal) on the occupied dofs, 0 elsewhere; diagonal[i] > 0 is required
  /// on every occupied dof. The one-argument form occupies the dofs with diagonal[i] > 0.
  void initialize(const Eigen::Ref<const Eigen::VectorXd>& diagonal, const std::vector<char>& occupied);
  void initialize(const Eigen::Ref<const Eigen::VectorXd>& diagonal);
  /// Sec. VII (requires initialized()): dofs occupied before but not in `occupied` get a zero
  /// row and column; dofs newly occupied get B(i,i) = new_diagonal (> 0); the rest of B is
  /// kept. Returns the number of dofs whose occupancy changed.
  int setOccupied(const std::vector<char>& occupied, double new_diagonal);
  int setOccupied(const std::vector<char>& occupied, const Eigen::Ref<const Eigen::VectorXd>& new_diagonal);
  const std::vector<char>& occupied() const { return occupied_; }
  int occupiedCount() const;

  /// One quasi-Newton update with the occupied components of s and y (see the subclasses).
  /// Returns true when B changed (false: skipped, B kept).
  virtual bool update(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& y) = 0;
  /// Sec. VIII-A: B(dof, dof) += value when the dof is occupied (returns whether it was).
  bool addDiagonal(int dof, double value);

  /// Newton rows of the level: R (rows >= occupiedCount(), cols == size()) with R^T R = B on
  /// the occupied block, rows as choleskyOfOccupied. BFGS: plain Cholesky of the occupied
  /// block; should rounding make it fail, Higham + eps instead. SR1: always Higham + eps
  /// (HighamRegularizer::regularizeAndFactor). Returns the number of rows written.
  int factor(Eigen::Ref<Eigen::MatrixXd> R);
  /// Whether the last factor() went through Higham's regularisation.
  bool lastFactorRegularized() const { return last_regularized_; }

  const Eigen::MatrixXd& matrix() const { return B_; }

 protected:
  /// Packs the occupied components of s and y (index_, s_, y_) and B s (Bs_); returns m.
  int pack(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& y);
  int n_ = 0;
  QuasiNewtonOptions options_;
  Eigen::MatrixXd B_;
  Eigen::VectorXd s_, y_, Bs_;
  std::vector<int> index_;

 private:
  bool initialized_ = false;
  bool last_regularized_ = false;
  Eigen::MatrixXd W_;  // B + alpha I* (identity_weight > 0 only)
  std::vector<char> occupied_;
  std::vector<int> list_;
  HighamRegularizer higham_;
};

/// Eq. 87: B+ = B + y y^T / (y^T s) - B s s^T B / (s^T B s), skipped unless y^T s > xi (and
/// s^T B s > 0). Keeps B positive definite on the occupied block.
class BfgsMatrix final : public QuasiNewtonMatrix {
 public:
  explicit BfgsMatrix(int n, const QuasiNewtonOptions& options = {}) : QuasiNewtonMatrix(n, options) {}
  QuasiNewtonUpdate kind() const override { return QuasiNewtonUpdate::Bfgs; }
  bool update(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& y) override;
};

/// SR1: B+ = B + r r^T / (r^T s), r = y - B s, skipped unless |r^T s| >= tol |r| |s| (r != 0).
/// B may become indefinite.
class Sr1Matrix final : public QuasiNewtonMatrix {
 public:
  explicit Sr1Matrix(int n, const QuasiNewtonOptions& options = {}) : QuasiNewtonMatrix(n, options) {}
  QuasiNewtonUpdate kind() const override { return QuasiNewtonUpdate::Sr1; }
  bool update(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& y) override;
};

std::unique_ptr<QuasiNewtonMatrix> makeBfgs(int n, const QuasiNewtonOptions& options = {});
std::unique_ptr<QuasiNewtonMatrix> makeSr1(int n, const QuasiNewtonOptions& options = {});
/// makeBfgs or makeSr1 after options.update.
std::unique_ptr<QuasiNewtonMatrix> makeQuasiNewton(int n, const QuasiNewtonOptions& options);

/// Model-mismatch guard (sec. VIII-A): watches the sign of each dof's measured acceleration
/// and flags a dof when its acceleration has changed sign at `consecutive` successive ticks
/// (default two: a(k-2), a(k-1), a(k) alternate in sign); the first change alone never flags.
/// The run restarts after a flag, so an ongoing oscillation flags the dof every `consecutive`
/// ticks. Samples with |a| <= dead_band carry no sign: they neither count as a change nor
/// break a run. observe() allocates nothing.
class SignChangeGuard {
 public:
  explicit SignChangeGuard(int n = 0, int consecutive = 2, double dead_band = 0.0);
  /// (Re)sizes and resets (allocates).
  void setup(int n, int consecutive = 2, double dead_band = 0.0);
  void reset();
  int size() const { return n_; }
  /// Feeds the accelerations of one tick (n); returns the number of dofs flagged at this tick.
  int observe(const Eigen::Ref<const Eigen::VectorXd>& acceleration);
  /// The dofs flagged by the last observe(), ascending.
  const std::vector<int>& triggered() const { return triggered_; }
  /// The same as flags per dof (n).
  const std::vector<char>& flags() const { return flags_; }

 private:
  int n_ = 0, consecutive_ = 2;
  double dead_band_ = 0.0;
  std::vector<signed char> last_sign_;  ///< -1, +1, 0 (none yet)
  std::vector<int> run_;                ///< consecutive sign changes so far
  std::vector<int> triggered_;          ///< capacity n, size = flagged count
  std::vector<char> flags_;
};

}  // namespace lexdyn::hessian
