#include "lexdyn/hessian/bfgs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lexdyn/common/error.hpp"

namespace lexdyn::hessian {

double initialDiagonalValue(double zeta, const Eigen::Ref<const Eigen::VectorXd>& dt_edot) {
  return std::max(zeta, 0.5 * dt_edot.squaredNorm());  // eq. 89
}

void addOnChain(const std::vector<char>& chain, double value, Eigen::Ref<Eigen::VectorXd> diag) {
  LEXDYN_ALWAYS_ASSERT(static_cast<Eigen::Index>(chain.size()) == diag.size(), "addOnChain: sizes differ");
  for (Eigen::Index i = 0; i < diag.size(); ++i) {
    if (chain[static_cast<size_t>(i)]) diag[i] += value;
  }
}

namespace {

// y[c] += sum over r of a(r, c) w(r), each column's sum over the rows in order from +0. Four
// columns at a time, so that four independent sums overlap instead of each add waiting for the
// previous one; the bits are those of one column at a time. Rows with w(r) == 0 are skipped:
// their terms are zeros (a finite a), and adding a zero of either sign to a sum that starts at
// +0 changes no bit (the sum is never -0: x + y is -0 only when both are), so the result is
// that of the full sum. A task's rows held by no solve (free or inactive inequalities) have
// zero multipliers.
template <class Entry, class Weight>
void addColumnSums(Eigen::Index rows, Eigen::Index cols, const Entry& a, const Weight& w, Eigen::Ref<Eigen::VectorXd> y) {
  Eigen::Index c = 0;
  for (; c + 4 <= cols; c += 4) {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    for (Eigen::Index r = 0; r < rows; ++r) {
      const double wr = w(r);
      if (wr == 0.0) continue;
      s0 += a(r, c) * wr;
      s1 += a(r, c + 1) * wr;
      s2 += a(r, c + 2) * wr;
      s3 += a(r, c + 3) * wr;
    }
    y[c] += s0;
    y[c + 1] += s1;
    y[c + 2] += s2;
    y[c + 3] += s3;
  }
  for (; c < cols; ++c) {
    double s = 0.0;
    for (Eigen::Index r = 0; r < rows; ++r) {
      const double wr = w(r);
      if (wr != 0.0) s += a(r, c) * wr;
    }
    y[c] += s;
  }
}

}  // namespace

void accumulateGradientChange(const Eigen::Ref<const Eigen::MatrixXd>& J, const Eigen::Ref<const Eigen::MatrixXd>& J_prev,
                              const Eigen::Ref<const Eigen::VectorXd>& lambda, Eigen::Ref<Eigen::VectorXd> y) {
  LEXDYN_ALWAYS_ASSERT(J.rows() == J_prev.rows() && J.cols() == J_prev.cols() && J.rows() == lambda.size() && J.cols() == y.size(),
                       "accumulateGradientChange: sizes differ");
  // eq. 88: y_l = grad L_l(k) - grad L_l(k-1) = sum_i (J_i - J_i(k-1))^T lambda_{i,l}
  addColumnSums(
      J.rows(), J.cols(), [&](Eigen::Index r, Eigen::Index c) { return J(r, c) - J_prev(r, c); }, [&](Eigen::Index r) { return lambda[r]; },
      y);
}

void accumulateMultiplierChange(const Eigen::Ref<const Eigen::MatrixXd>& J_prev, const Eigen::Ref<const Eigen::VectorXd>& lambda,
                                const Eigen::Ref<const Eigen::VectorXd>& lambda_prev, Eigen::Ref<Eigen::VectorXd> y) {
  LEXDYN_ALWAYS_ASSERT(J_prev.rows() == lambda.size() && lambda.size() == lambda_prev.size() && J_prev.cols() == y.size(),
                       "accumulateMultiplierChange: sizes differ");
  addColumnSums(
      J_prev.rows(), J_prev.cols(), [&](Eigen::Index r, Eigen::Index c) { return J_prev(r, c); },
      [&](Eigen::Index r) { return lambda[r] - lambda_prev[r]; }, y);
}

int choleskyOfOccupied(const Eigen::Ref<const Eigen::MatrixXd>& B, const std::vector<char>& occupied, Eigen::Ref<Eigen::MatrixXd> R,
                       std::vector<int>& occupied_list, int* zero_pivots) {
  const Eigen::Index n = B.rows();
  LEXDYN_ALWAYS_ASSERT(B.cols() == n && static_cast<Eigen::Index>(occupied.size()) == n && R.cols() == n,
                       "choleskyOfOccupied: sizes differ");
  LEXDYN_ALWAYS_ASSERT(occupied_list.capacity() >= static_cast<size_t>(n),
                       "choleskyOfOccupied: reserve n entries in occupied_list (no allocation per tick)");
  occupied_list.clear();
  for (Eigen::Index i = 0; i < n; ++i) {
    if (occupied[static_cast<size_t>(i)]) occupied_list.push_back(static_cast<int>(i));
  }
  const int m = static_cast<int>(occupied_list.size());
  LEXDYN_ALWAYS_ASSERT(R.rows() >= m, "choleskyOfOccupied: R has fewer rows than occupied dofs");
  R.setZero();
  // Occupied block into the leading m x m corner of R (upper triangle), factor in place.
  for (int c = 0; c < m; ++c) {
    for (int r = 0; r <= c; ++r) R(r, c) = B(occupied_list[static_cast<size_t>(r)], occupied_list[static_cast<size_t>(c)]);
  }
  const int zp = choleskyUpperInPlace(R, m, 0.0);
  if (zero_pivots) *zero_pivots = zp;
  // Scatter column c to column occupied_list[c] >= c, from the right (no source is overwritten
  // before it is read: destinations of later columns are beyond every earlier column).
  for (int c = m - 1; c >= 0; --c) {
    const int dst = occupied_list[static_cast<size_t>(c)];
    if (dst == c) continue;
    for (int r = 0; r <= c; ++r) {
      R(r, dst) = R(r, c);
      R(r, c) = 0.0;
    }
  }
  return m;
}

// =============================================================================================
// QuasiNewtonMatrix
// =============================================================================================

QuasiNewtonMatrix::QuasiNewtonMatrix(int n, const QuasiNewtonOptions& options) : n_(n), options_(options), higham_(n) {
  LEXDYN_ALWAYS_ASSERT(n >= 0, "QuasiNewtonMatrix: negative size");
  LEXDYN_ALWAYS_ASSERT(options.xi >= 0.0 && options.sr1_tolerance >= 0.0 && options.eps >= 0.0 && options.identity_weight >= 0.0,
                       "QuasiNewtonMatrix: thresholds must be >= 0");
  B_.setZero(n, n);
  if (options.identity_weight > 0.0) W_.setZero(n, n);
  s_.setZero(n);
  y_.setZero(n);
  Bs_.setZero(n);
  occupied_.assign(static_cast<size_t>(n), 0);
  index_.assign(static_cast<size_t>(n), 0);
  list_.reserve(static_cast<size_t>(n));
}

void QuasiNewtonMatrix::reset() {
  B_.setZero();
  for (char& o : occupied_) o = 0;
  initialized_ = false;
  last_regularized_ = false;
}

int QuasiNewtonMatrix::occupiedCount() const {
  int m = 0;
  for (char o : occupied_) m += o ? 1 : 0;
  return m;
}

void QuasiNewtonMatrix::initialize(const Eigen::Ref<const Eigen::VectorXd>& diagonal, const std::vector<char>& occupied) {
  LEXDYN_ALWAYS_ASSERT(diagonal.size() == n_ && static_cast<int>(occupied.size()) == n_, "QuasiNewtonMatrix::initialize: sizes differ");
  B_.setZero();
  for (int i = 0; i < n_; ++i) {
    const bool o = occupied[static_cast<size_t>(i)] != 0;
    occupied_[static_cast<size_t>(i)] = o ? 1 : 0;
    if (o) {
      LEXDYN_ALWAYS_ASSERT(diagonal[i] > 0.0, "QuasiNewtonMatrix::initialize: diagonal must be > 0 on occupied dofs");
      B_(i, i) = diagonal[i];  // eq. 89
    }
  }
  initialized_ = true;
  last_regularized_ = false;
}

void QuasiNewtonMatrix::initialize(const Eigen::Ref<const Eigen::VectorXd>& diagonal) {
  LEXDYN_ALWAYS_ASSERT(diagonal.size() == n_, "QuasiNewtonMatrix::initialize: sizes differ");
  B_.setZero();
  for (int i = 0; i < n_; ++i) {
    const bool o = diagonal[i] > 0.0;
    occupied_[static_cast<size_t>(i)] = o ? 1 : 0;
    if (o) B_(i, i) = diagonal[i];  // eq. 89
  }
  initialized_ = true;
  last_regularized_ = false;
}

int QuasiNewtonMatrix::setOccupied(const std::vector<char>& occupied, double new_diagonal) {
  LEXDYN_ALWAYS_ASSERT(initialized_, "QuasiNewtonMatrix::setOccupied: initialize first");
  LEXDYN_ALWAYS_ASSERT(static_cast<int>(occupied.size()) == n_, "QuasiNewtonMatrix::setOccupied: sizes differ");
  LEXDYN_ALWAYS_ASSERT(new_diagonal > 0.0, "QuasiNewtonMatrix::setOccupied: new diagonal must be > 0");
  int changed = 0;
  for (int i = 0; i < n_; ++i) {
    const bool was = occupied_[static_cast<size_t>(i)] != 0;
    const bool now = occupied[static_cast<size_t>(i)] != 0;
    if (was && !now) {  // sec. VII: freed dof, zero row and column
      B_.row(i).setZero();
      B_.col(i).setZero();
      ++changed;
    } else if (!was && now) {  // sec. VII: newly occupied dof (its row and column are zero)
      B_(i, i) = new_diagonal;
      ++changed;
    }
    occupied_[static_cast<size_t>(i)] = now ? 1 : 0;
  }
  return changed;
}

int QuasiNewtonMatrix::setOccupied(const std::vector<char>& occupied, const Eigen::Ref<const Eigen::VectorXd>& new_diagonal) {
  LEXDYN_ALWAYS_ASSERT(initialized_, "QuasiNewtonMatrix::setOccupied: initialize first");
  LEXDYN_ALWAYS_ASSERT(static_cast<int>(occupied.size()) == n_ && new_diagonal.size() == n_,
                       "QuasiNewtonMatrix::setOccupied: sizes differ");
  int changed = 0;
  for (int i = 0; i < n_; ++i) {
    const bool was = occupied_[static_cast<size_t>(i)] != 0;
    const bool now = occupied[static_cast<size_t>(i)] != 0;
    if (was && !now) {
      B_.row(i).setZero();
      B_.col(i).setZero();
      ++changed;
    } else if (!was && now) {
      LEXDYN_ALWAYS_ASSERT(new_diagonal[i] > 0.0, "QuasiNewtonMatrix::setOccupied: new diagonal must be > 0");
      B_(i, i) = new_diagonal[i];
      ++changed;
    }
    occupied_[static_cast<size_t>(i)] = now ? 1 : 0;
  }
  return changed;
}

bool QuasiNewtonMatrix::addDiagonal(int dof, double value) {
  LEXDYN_ALWAYS_ASSERT(dof >= 0 && dof < n_, "QuasiNewtonMatrix::addDiagonal: dof out of range");
  if (!occupied_[static_cast<size_t>(dof)]) return false;
  B_(dof, dof) += value;  // sec. VIII-A
  return true;
}

int QuasiNewtonMatrix::pack(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& y) {
  LEXDYN_ALWAYS_ASSERT(initialized_, "QuasiNewtonMatrix::update: initialize first");
  LEXDYN_ALWAYS_ASSERT(s.size() == n_ && y.size() == n_, "QuasiNewtonMatrix::update: sizes differ");
  int m = 0;
  for (int i = 0; i < n_; ++i) {
    if (occupied_[static_cast<size_t>(i)]) index_[static_cast<size_t>(m++)] = i;
  }
  for (int a = 0; a < m; ++a) {
    const int i = index_[static_cast<size_t>(a)];
    s_[a] = s[i];
    y_[a] = y[i];
  }
  // B s on the occupied block: each entry's sum in column order, four rows at a time (four
  // independent sums overlap).
  int a = 0;
  for (; a + 4 <= m; a += 4) {
    const Eigen::Index i0 = index_[static_cast<size_t>(a)], i1 = index_[static_cast<size_t>(a + 1)];
    const Eigen::Index i2 = index_[static_cast<size_t>(a + 2)], i3 = index_[static_cast<size_t>(a + 3)];
    double v0 = 0.0, v1 = 0.0, v2 = 0.0, v3 = 0.0;
    for (int b = 0; b < m; ++b) {
      const double* col = B_.col(index_[static_cast<size_t>(b)]).data();
      const double sb = s_[b];
      v0 += col[i0] * sb;
      v1 += col[i1] * sb;
      v2 += col[i2] * sb;
      v3 += col[i3] * sb;
    }
    Bs_[a] = v0;
    Bs_[a + 1] = v1;
    Bs_[a + 2] = v2;
    Bs_[a + 3] = v3;
  }
  for (; a < m; ++a) {
    double v = 0.0;
    for (int b = 0; b < m; ++b) v += B_(index_[static_cast<size_t>(a)], index_[static_cast<size_t>(b)]) * s_[b];
    Bs_[a] = v;
  }
  return m;
}

int QuasiNewtonMatrix::factor(Eigen::Ref<Eigen::MatrixXd> R) {
  LEXDYN_ALWAYS_ASSERT(R.cols() == n_, "QuasiNewtonMatrix::factor: R must have n columns");
  last_regularized_ = false;
  const Eigen::MatrixXd* B = &B_;
  if (options_.identity_weight > 0.0) {
    W_ = B_;  // same size: no allocation
    for (int i = 0; i < n_; ++i)
      if (occupied_[static_cast<size_t>(i)]) W_(i, i) += options_.identity_weight;
    B = &W_;
  }
  if (kind() == QuasiNewtonUpdate::Bfgs) {
    int zero_pivots = 0;
    const int m = choleskyOfOccupied(*B, occupied_, R, list_, &zero_pivots);
    if (zero_pivots == 0) return m;
    // Rounding made B indefinite on the occupied block: Higham + eps instead.
  }
  last_regularized_ = true;
  return higham_.regularizeAndFactor(*B, occupied_, options_.eps, R);
}

bool BfgsMatrix::update(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& y) {
  const int m = pack(s, y);
  if (m == 0) return false;
  const auto s_o = s_.head(m);
  const auto y_o = y_.head(m);
  const auto Bs = Bs_.head(m);
  const double ys = y_o.dot(s_o);
  const double sBs = s_o.dot(Bs);
  // Curvature guard (sec. VI-A): no update unless y^T s > xi.
  if (!(ys > options_.xi) || !(sBs > 0.0) || !std::isfinite(ys) || !std::isfinite(sBs)) return false;
  // eq. 87 on the lower triangle, mirrored (B stays exactly symmetric).
  for (int b = 0; b < m; ++b) {
    const int j = index_[static_cast<size_t>(b)];
    const double yj = y_o[b] / ys, Bsj = Bs[b] / sBs;
    for (int a = b; a < m; ++a) {
      const int i = index_[static_cast<size_t>(a)];
      const double v = B_(i, j) + (y_o[a] * yj - Bs[a] * Bsj);
      B_(i, j) = v;
      B_(j, i) = v;
    }
  }
  return true;
}

bool Sr1Matrix::update(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& y) {
  const int m = pack(s, y);
  if (m == 0) return false;
  const auto s_o = s_.head(m);
  auto r = Bs_.head(m);
  for (int a = 0; a < m; ++a) r[a] = y_[a] - r[a];  // r = y - B s
  const double rs = r.dot(s_o);
  const double rn = r.norm(), sn = s_o.norm();
  // Skip rule: |r^T s| >= tol |r| |s| (and r != 0: B already satisfies the secant equation).
  if (!(rn > 0.0) || !std::isfinite(rs) || rs == 0.0 || !(std::abs(rs) >= options_.sr1_tolerance * rn * sn)) return false;
  for (int b = 0; b < m; ++b) {
    const int j = index_[static_cast<size_t>(b)];
    const double rj = r[b] / rs;
    for (int a = b; a < m; ++a) {
      const int i = index_[static_cast<size_t>(a)];
      const double v = B_(i, j) + r[a] * rj;
      B_(i, j) = v;
      B_(j, i) = v;
    }
  }
  return true;
}

std::unique_ptr<QuasiNewtonMatrix> makeBfgs(int n, const QuasiNewtonOptions& options) { return std::make_unique<BfgsMatrix>(n, options); }
std::unique_ptr<QuasiNewtonMatrix> makeSr1(int n, const QuasiNewtonOptions& options) { return std::make_unique<Sr1Matrix>(n, options); }
std::unique_ptr<QuasiNewtonMatrix> makeQuasiNewton(int n, const QuasiNewtonOptions& options) {
  return options.update == QuasiNewtonUpdate::Sr1 ? makeSr1(n, options) : makeBfgs(n, options);
}

// =============================================================================================
// SignChangeGuard
// =============================================================================================

SignChangeGuard::SignChangeGuard(int n, int consecutive, double dead_band) { setup(n, consecutive, dead_band); }

void SignChangeGuard::setup(int n, int consecutive, double dead_band) {
  LEXDYN_ALWAYS_ASSERT(n >= 0 && consecutive >= 1 && dead_band >= 0.0, "SignChangeGuard: bad parameters");
  n_ = n;
  consecutive_ = consecutive;
  dead_band_ = dead_band;
  last_sign_.assign(static_cast<size_t>(n), 0);
  run_.assign(static_cast<size_t>(n), 0);
  flags_.assign(static_cast<size_t>(n), 0);
  triggered_.clear();
  triggered_.reserve(static_cast<size_t>(n));
}

void SignChangeGuard::reset() {
  for (int i = 0; i < n_; ++i) {
    last_sign_[static_cast<size_t>(i)] = 0;
    run_[static_cast<size_t>(i)] = 0;
    flags_[static_cast<size_t>(i)] = 0;
  }
  triggered_.clear();
}

int SignChangeGuard::observe(const Eigen::Ref<const Eigen::VectorXd>& acceleration) {
  LEXDYN_ALWAYS_ASSERT(acceleration.size() == n_, "SignChangeGuard::observe: size differs");
  triggered_.clear();  // keeps the capacity reserved in setup()
  for (int i = 0; i < n_; ++i) {
    const size_t k = static_cast<size_t>(i);
    flags_[k] = 0;
    const double a = acceleration[i];
    if (!(std::abs(a) > dead_band_)) continue;  // no sign (also NaN)
    const signed char sign = a > 0.0 ? 1 : -1;
    if (last_sign_[k] != 0) {
      if (sign != last_sign_[k]) {
        if (++run_[k] >= consecutive_) {
          flags_[k] = 1;
          triggered_.push_back(i);
          run_[k] = 0;
        }
      } else {
        run_[k] = 0;
      }
    }
    last_sign_[k] = sign;
  }
  return static_cast<int>(triggered_.size());
}

}  // namespace lexdyn::hessian
