#include "lexdyn/solver/hls_factorization.hpp"

#include <Eigen/Householder>
#include <algorithm>
#include <cmath>
#include <limits>

#include "lexdyn/common/error.hpp"

namespace lexdyn::solver {

namespace {

// x <- (I - tau v v^T) x with v = [1; ess] (x and v of the same length).
template <typename Ess, typename X>
inline void applyReflector(const Ess& ess, double tau, X&& x) {
  if (tau == 0.0) return;
  const Eigen::Index len = x.size();
  double w = x(0);
  if (len > 1) w += ess.dot(x.tail(len - 1));
  w *= tau;
  x(0) -= w;
  if (len > 1) x.tail(len - 1).noalias() -= w * ess;
}

}  // namespace

// Global row ids: gid = rowOff[level] + row. The layout keeps the active columns of all levels
// contiguous, level after level.

void HlsFactorization::setup(int n, const std::vector<int>& rowsPerLevel) {
  n_ = n;
  nf_ = n;
  m_ = rowsPerLevel;
  const int L = static_cast<int>(m_.size());
  mTot_ = 0;
  rowOff_.assign(static_cast<size_t>(L), 0);
  for (int k = 0; k < L; ++k) {
    rowOff_[static_cast<size_t>(k)] = mTot_;
    mTot_ += m_[static_cast<size_t>(k)];
  }
  levelOf_.assign(static_cast<size_t>(mTot_), 0);
  for (int k = 0; k < L; ++k)
    for (int r = 0; r < m_[static_cast<size_t>(k)]; ++r) levelOf_[static_cast<size_t>(rowOff_[static_cast<size_t>(k)] + r)] = k;

  A_.assign(static_cast<size_t>(L), nullptr);
  rowNorm_ = Eigen::VectorXd::Zero(mTot_);
  freeVar_.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) freeVar_[static_cast<size_t>(i)] = i;

  inList_.assign(static_cast<size_t>(mTot_), 0);
  active_.assign(static_cast<size_t>(L), {});
  for (int k = 0; k < L; ++k) active_[static_cast<size_t>(k)].reserve(static_cast<size_t>(m_[static_cast<size_t>(k)]));

  const int colsW = std::max(mTot_, 1);
  W_.setZero(std::max(n, 1), colsW);
  start_.assign(static_cast<size_t>(L), 0);
  act_.assign(static_cast<size_t>(L), 0);
  col0_.assign(static_cast<size_t>(L + 1), 0);
  rank_.assign(static_cast<size_t>(L), 0);
  colGid_.assign(static_cast<size_t>(colsW), -1);
  pos_.assign(static_cast<size_t>(mTot_), -1);
  tau_.setZero(colsW);
  colNorm_.setZero(colsW);
  colNormRef_.setZero(colsW);
  colOrig_.setZero(colsW);

  snap_.assign(static_cast<size_t>(L), Eigen::MatrixXd());
  snapCol_.assign(static_cast<size_t>(L), std::vector<int>(static_cast<size_t>(mTot_), -1));
  snapGids_.assign(static_cast<size_t>(L), {});
  snapValid_.assign(static_cast<size_t>(L), 0);
  for (int k = 1; k < L; ++k) {
    int later = 0;
    for (int j = k; j < L; ++j) later += m_[static_cast<size_t>(j)];
    snap_[static_cast<size_t>(k)].setZero(std::max(n, 1), std::max(later, 1));
    snapGids_[static_cast<size_t>(k)].reserve(static_cast<size_t>(later));
  }

  left_.resize(static_cast<size_t>(L));
  leftTau_.resize(static_cast<size_t>(L));
  for (int k = 0; k < L; ++k) {
    const int mk = std::max(m_[static_cast<size_t>(k)], 1);
    left_[static_cast<size_t>(k)].setZero(mk, std::min(mk, std::max(n, 1)));
    leftTau_[static_cast<size_t>(k)].setZero(mk);
  }

  S_.setZero(std::max(n, 1), colsW);
  int maxLevelRows = 1;
  for (int mk : m_) maxLevelRows = std::max(maxLevelRows, mk);
  const int rcap = std::max(1, std::min(n, maxLevelRows));
  Vw_.setZero(std::max(n, 1), rcap);
  T_.setZero(rcap, rcap);
  Y_.setZero(rcap, colsW);
  Y2_.setZero(rcap, colsW);
  work_.setZero(std::max({n, mTot_, 1}));
  work2_.setZero(std::max({n, mTot_, 1}));
  g_.setZero(std::max(n, 1));
  t_.setZero(std::max(maxLevelRows, 1));
  u_.setZero(std::max(maxLevelRows, 1));
  dirtyFrom_ = 0;
  lastRestart_ = 0;
}

void HlsFactorization::computeRowNorms() {
  for (int k = 0; k < levelCount(); ++k) {
    const Eigen::MatrixXd& A = *A_[static_cast<size_t>(k)];
    for (int r = 0; r < m_[static_cast<size_t>(k)]; ++r) rowNorm_(rowOff_[static_cast<size_t>(k)] + r) = A.row(r).norm();
  }
}

void HlsFactorization::setFreeVariables(const std::vector<int>& freeVar, int nFree) {
  nf_ = nFree;
  for (int i = 0; i < nFree; ++i) freeVar_[static_cast<size_t>(i)] = freeVar[static_cast<size_t>(i)];
  invalidateAll();
}

void HlsFactorization::invalidateAll() {
  dirtyFrom_ = 0;
  std::fill(snapValid_.begin(), snapValid_.end(), 0);
}

void HlsFactorization::activate(int k, int row) {
  const int gid = rowOff_[static_cast<size_t>(k)] + row;
  LEXDYN_DEBUG_ASSERT(!inList_[static_cast<size_t>(gid)]);
  inList_[static_cast<size_t>(gid)] = 1;
  active_[static_cast<size_t>(k)].push_back(gid);
  dirtyFrom_ = std::min(dirtyFrom_, k);
}

void HlsFactorization::deactivate(int k, int row) {
  const int gid = rowOff_[static_cast<size_t>(k)] + row;
  LEXDYN_DEBUG_ASSERT(inList_[static_cast<size_t>(gid)]);
  inList_[static_cast<size_t>(gid)] = 0;
  auto& lst = active_[static_cast<size_t>(k)];
  lst.erase(std::find(lst.begin(), lst.end(), gid));  // keeps the order; no reallocation
  dirtyFrom_ = std::min(dirtyFrom_, k);
}

void HlsFactorization::clearActive() {
  for (int k = 0; k < levelCount(); ++k) {
    for (int gid : active_[static_cast<size_t>(k)]) inList_[static_cast<size_t>(gid)] = 0;
    active_[static_cast<size_t>(k)].clear();
  }
  invalidateAll();
}

int HlsFactorization::totalRank() const {
  int r = 0;
  for (int k = 0; k < levelCount(); ++k) r += rank_[static_cast<size_t>(k)];
  return r;
}

void HlsFactorization::applyEarlierStagesTo(Eigen::Ref<Eigen::VectorXd> col, int stages) const {
  // col holds a gathered row (free-variable coordinates); apply Q_k^T for k < stages.
  for (int k = 0; k < stages; ++k) {
    const int c0 = col0_[static_cast<size_t>(k)];
    const int s = start_[static_cast<size_t>(k)];
    for (int i = 0; i < rank_[static_cast<size_t>(k)]; ++i) {
      const int len = nf_ - c0 - i;
      applyReflector(W_.col(s + i).segment(c0 + i + 1, len - 1), tau_(s + i), col.segment(c0 + i, len));
    }
  }
}

void HlsFactorization::relayout(int c) {
  // Rebuild the columns of levels >= c in the solver's active order, in their pre-stage-c state.
  const int L = levelCount();
  const int sc = (c == 0) ? 0 : start_[static_cast<size_t>(c - 1)] + act_[static_cast<size_t>(c - 1)];
  const int c0 = col0_[static_cast<size_t>(c)];
  const bool useSnap = (c > 0) && snapValid_[static_cast<size_t>(c)];
  int p = 0;
  for (int j = c; j < L; ++j) {
    for (int gid : active_[static_cast<size_t>(j)]) {
      const int old = pos_[static_cast<size_t>(gid)];
      const int sCol = useSnap ? snapCol_[static_cast<size_t>(c)][static_cast<size_t>(gid)] : -1;
      if (old >= 0 && sCol >= 0) {
        S_.col(p).head(c0) = W_.col(old).head(c0);
        S_.col(p).segment(c0, nf_ - c0) = snap_[static_cast<size_t>(c)].col(sCol).head(nf_ - c0);
      } else {
        const int k = levelOf_[static_cast<size_t>(gid)];
        const int row = gid - rowOff_[static_cast<size_t>(k)];
        const Eigen::MatrixXd& A = *A_[static_cast<size_t>(k)];
        for (int f = 0; f < nf_; ++f) S_(f, p) = A(row, freeVar_[static_cast<size_t>(f)]);
        applyEarlierStagesTo(S_.col(p).head(nf_), c);
      }
      ++p;
    }
  }
  // Forget the old positions of levels >= c (rows that left the active set included).
  for (int q = sc; q < mTot_; ++q) {
    const int gid = colGid_[static_cast<size_t>(q)];
    if (gid >= 0) pos_[static_cast<size_t>(gid)] = -1;
    colGid_[static_cast<size_t>(q)] = -1;
  }
  W_.block(0, sc, nf_, p) = S_.block(0, 0, nf_, p);
  int q = sc;
  for (int j = c; j < L; ++j) {
    start_[static_cast<size_t>(j)] = q;
    act_[static_cast<size_t>(j)] = static_cast<int>(active_[static_cast<size_t>(j)].size());
    for (int gid : active_[static_cast<size_t>(j)]) {
      colGid_[static_cast<size_t>(q)] = gid;
      pos_[static_cast<size_t>(gid)] = q;
      ++q;
    }
  }
}

void HlsFactorization::saveSnapshot(int k) {
  const int L = levelCount();
  auto& sc = snapCol_[static_cast<size_t>(k)];
  for (int gid : snapGids_[static_cast<size_t>(k)]) sc[static_cast<size_t>(gid)] = -1;
  snapGids_[static_cast<size_t>(k)].clear();
  const int s = start_[static_cast<size_t>(k)];
  int cnt = 0;
  for (int j = k; j < L; ++j) cnt += act_[static_cast<size_t>(j)];
  const int c0 = col0_[static_cast<size_t>(k)];
  const int d = nf_ - c0;
  if (cnt > 0 && d > 0) snap_[static_cast<size_t>(k)].block(0, 0, d, cnt) = W_.block(c0, s, d, cnt);
  for (int p = 0; p < cnt; ++p) {
    const int gid = colGid_[static_cast<size_t>(s + p)];
    sc[static_cast<size_t>(gid)] = p;
    snapGids_[static_cast<size_t>(k)].push_back(gid);
  }
  snapValid_[static_cast<size_t>(k)] = 1;
}

void HlsFactorization::swapColumns(int a, int b) {
  if (a == b) return;
  W_.col(a).head(nf_).swap(W_.col(b).head(nf_));
  std::swap(colNorm_(a), colNorm_(b));
  std::swap(colNormRef_(a), colNormRef_(b));
  std::swap(colOrig_(a), colOrig_(b));
  const int ga = colGid_[static_cast<size_t>(a)];
  const int gb = colGid_[static_cast<size_t>(b)];
  colGid_[static_cast<size_t>(a)] = gb;
  colGid_[static_cast<size_t>(b)] = ga;
  pos_[static_cast<size_t>(gb)] = a;
  pos_[static_cast<size_t>(ga)] = b;
}

void HlsFactorization::factorLevel(int k, double rankTol) {
  const int L = levelCount();
  const int s = start_[static_cast<size_t>(k)];
  const int m = act_[static_cast<size_t>(k)];
  const int c0 = col0_[static_cast<size_t>(k)];
  const int d = nf_ - c0;
  static const double kSqrtEps = std::sqrt(std::numeric_limits<double>::epsilon());

  // Column norms of the projected rows and their original norms.
  for (int j = 0; j < m; ++j) {
    const double nr = (d > 0) ? W_.col(s + j).segment(c0, d).norm() : 0.0;
    colNorm_(s + j) = nr;
    colNormRef_(s + j) = nr;
    colOrig_(s + j) = rowNorm_(colGid_[static_cast<size_t>(s + j)]);
  }

  int r = 0;
  const int maxRank = std::min(m, d);
  while (r < maxRank) {
    // Pivot: largest projected norm relative to the original row norm (ties: lowest index).
    int best = -1;
    double bestRatio = 0.0;
    for (int j = r; j < m; ++j) {
      const double orig = colOrig_(s + j);
      const double ratio = orig > 0.0 ? colNorm_(s + j) / orig : 0.0;
      if (ratio > bestRatio) {
        bestRatio = ratio;
        best = j;
      }
    }
    if (best < 0 || bestRatio <= rankTol) break;
    swapColumns(s + r, s + best);
    // Householder reflector annihilating W(c0+r+1 : nf, s+r).
    auto x = W_.col(s + r).segment(c0 + r, d - r);
    double tau = 0.0, beta = 0.0;
    x.makeHouseholderInPlace(tau, beta);
    x(0) = beta;
    tau_(s + r) = tau;
    const auto ess = W_.col(s + r).segment(c0 + r + 1, d - r - 1);
    for (int j = r + 1; j < m; ++j) {
      applyReflector(ess, tau, W_.col(s + j).segment(c0 + r, d - r));
      // Norm downdate with recomputation on cancellation (LAPACK xLAQP2).
      double& nr = colNorm_(s + j);
      if (nr != 0.0) {
        double temp = std::abs(W_(c0 + r, s + j)) / nr;
        temp = std::max(0.0, (1.0 + temp) * (1.0 - temp));
        const double ratio = nr / colNormRef_(s + j);
        if (temp * ratio * ratio <= kSqrtEps) {
          nr = (d - r - 1 > 0) ? W_.col(s + j).segment(c0 + r + 1, d - r - 1).norm() : 0.0;
          colNormRef_(s + j) = nr;
        } else {
          nr *= std::sqrt(temp);
        }
      }
    }
    ++r;
  }
  rank_[static_cast<size_t>(k)] = r;
  col0_[static_cast<size_t>(k + 1)] = c0 + r;

  // Trailing update of the later levels' columns: C <- Q_k^T C (compact WY, blocked).
  int rest = 0;
  for (int j = k + 1; j < L; ++j) rest += act_[static_cast<size_t>(j)];
  if (rest > 0 && r > 0) {
    auto C = W_.block(c0, s + m, d, rest);
    if (r == 1) {
      for (int q = 0; q < rest; ++q) applyReflector(W_.col(s).segment(c0 + 1, d - 1), tau_(s), C.col(q));
    } else {
      auto V = Vw_.block(0, 0, d, r);
      V.setZero();
      for (int i = 0; i < r; ++i) {
        V(i, i) = 1.0;
        if (d - i - 1 > 0) V.col(i).segment(i + 1, d - i - 1) = W_.col(s + i).segment(c0 + i + 1, d - i - 1);
      }
      auto T = T_.block(0, 0, r, r);
      T.setZero();
      for (int i = 0; i < r; ++i) {
        const double ti = tau_(s + i);
        T(i, i) = ti;
        if (i > 0) {
          auto tmp = work_.head(i);
          tmp.noalias() = V.block(i, 0, d - i, i).transpose() * V.col(i).segment(i, d - i);
          auto out = work2_.head(i);
          out.noalias() = T.topLeftCorner(i, i).triangularView<Eigen::Upper>() * tmp;
          T.col(i).head(i) = -ti * out;
        }
      }
      auto Y = Y_.block(0, 0, r, rest);
      auto Y2 = Y2_.block(0, 0, r, rest);
      Y.noalias() = V.transpose() * C;
      Y2.noalias() = T.transpose().triangularView<Eigen::Lower>() * Y;
      C.noalias() -= V * Y2;
    }
  }

  // Rank-deficient level: left factorisation of L = R^T (m x r) = V [U; 0].
  if (r < m) {
    auto Lm = left_[static_cast<size_t>(k)].block(0, 0, m, r);
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < r; ++i) Lm(j, i) = (i <= j) ? W_(c0 + i, s + j) : 0.0;
    auto& lt = leftTau_[static_cast<size_t>(k)];
    for (int i = 0; i < r; ++i) {
      auto x = Lm.col(i).segment(i, m - i);
      double tau = 0.0, beta = 0.0;
      x.makeHouseholderInPlace(tau, beta);
      x(0) = beta;
      lt(i) = tau;
      for (int j = i + 1; j < r; ++j) applyReflector(Lm.col(i).segment(i + 1, m - i - 1), tau, Lm.col(j).segment(i, m - i));
    }
  }
}

void HlsFactorization::factorize(double rankTol) {
  const int L = levelCount();
  if (dirtyFrom_ >= L) {
    lastRestart_ = L;
    return;
  }
  const int c = dirtyFrom_;
  lastRestart_ = c;
  if (c == 0) {
    for (int q = 0; q < mTot_; ++q) {
      const int gid = colGid_[static_cast<size_t>(q)];
      if (gid >= 0) pos_[static_cast<size_t>(gid)] = -1;
      colGid_[static_cast<size_t>(q)] = -1;
    }
    col0_[0] = 0;
  }
  relayout(c);
  for (int k = c; k < L; ++k) {
    if (k > 0) saveSnapshot(k);
    factorLevel(k, rankTol);
  }
  dirtyFrom_ = L;
}

void HlsFactorization::solve(const Eigen::VectorXd& b, Eigen::VectorXd& xFree, Eigen::VectorXd& res) {
  const int L = levelCount();
  auto y = xFree.head(nf_);
  y.setZero();
  for (int k = 0; k < L; ++k) {
    const int m = act_[static_cast<size_t>(k)];
    if (m == 0) continue;
    const int s = start_[static_cast<size_t>(k)];
    const int c0 = col0_[static_cast<size_t>(k)];
    const int r = rank_[static_cast<size_t>(k)];
    auto t = t_.head(m);
    for (int j = 0; j < m; ++j) t(j) = b(colGid_[static_cast<size_t>(s + j)]);
    if (c0 > 0) t.noalias() -= W_.block(0, s, c0, m).transpose() * y.head(c0);
    if (r == m) {
      // R^T y_seg = t, R = W(c0:c0+r, s:s+r) upper triangular.
      W_.block(c0, s, r, r).triangularView<Eigen::Upper>().transpose().solveInPlace(t);
      y.segment(c0, r) = t;
      for (int j = 0; j < m; ++j) res(colGid_[static_cast<size_t>(s + j)]) = 0.0;
    } else {
      const auto Lm = left_[static_cast<size_t>(k)].block(0, 0, m, r);
      const auto& lt = leftTau_[static_cast<size_t>(k)];
      for (int i = 0; i < r; ++i) applyReflector(Lm.col(i).segment(i + 1, m - i - 1), lt(i), t.segment(i, m - i));
      if (r > 0) {
        auto seg = t.head(r);
        Lm.topLeftCorner(r, r).triangularView<Eigen::Upper>().solveInPlace(seg);
        y.segment(c0, r) = seg;
      }
      // Residual A x - b = -V [0; z_bottom].
      auto w = u_.head(m);
      w.head(r).setZero();
      w.tail(m - r) = -t.tail(m - r);
      for (int i = r - 1; i >= 0; --i) applyReflector(Lm.col(i).segment(i + 1, m - i - 1), lt(i), w.segment(i, m - i));
      for (int j = 0; j < m; ++j) res(colGid_[static_cast<size_t>(s + j)]) = w(j);
    }
  }
  // x = Q_1 ... Q_L y.
  for (int k = L - 1; k >= 0; --k) {
    const int s = start_[static_cast<size_t>(k)];
    const int c0 = col0_[static_cast<size_t>(k)];
    for (int i = rank_[static_cast<size_t>(k)] - 1; i >= 0; --i) {
      const int len = nf_ - c0 - i;
      applyReflector(W_.col(s + i).segment(c0 + i + 1, len - 1), tau_(s + i), y.segment(c0 + i, len));
    }
  }
}

void HlsFactorization::multipliers(int k, const Eigen::VectorXd& res, Eigen::Ref<Eigen::VectorXd> mu) {
  auto G = g_.head(nf_);
  G.setZero();
  {
    const int m = act_[static_cast<size_t>(k)];
    const int s = start_[static_cast<size_t>(k)];
    const int c0 = col0_[static_cast<size_t>(k)];
    auto u = u_.head(m);
    for (int j = 0; j < m; ++j) {
      const int gid = colGid_[static_cast<size_t>(s + j)];
      u(j) = res(gid);
      mu(gid) = res(gid);
    }
    if (m > 0 && c0 > 0) G.head(c0).noalias() += W_.block(0, s, c0, m) * u;
  }
  for (int j = k - 1; j >= 0; --j) {
    const int m = act_[static_cast<size_t>(j)];
    if (m == 0) continue;
    const int s = start_[static_cast<size_t>(j)];
    const int c0 = col0_[static_cast<size_t>(j)];
    const int r = rank_[static_cast<size_t>(j)];
    auto u = u_.head(m);
    if (r == m) {
      u = -G.segment(c0, r);
      W_.block(c0, s, r, r).triangularView<Eigen::Upper>().solveInPlace(u);
    } else {
      const auto Lm = left_[static_cast<size_t>(j)].block(0, 0, m, r);
      const auto& lt = leftTau_[static_cast<size_t>(j)];
      u.setZero();
      if (r > 0) {
        auto top = u.head(r);
        top = -G.segment(c0, r);
        Lm.topLeftCorner(r, r).triangularView<Eigen::Upper>().transpose().solveInPlace(top);
      }
      for (int i = r - 1; i >= 0; --i) applyReflector(Lm.col(i).segment(i + 1, m - i - 1), lt(i), u.segment(i, m - i));
    }
    for (int i = 0; i < m; ++i) mu(colGid_[static_cast<size_t>(s + i)]) = u(i);
    if (c0 > 0) G.head(c0).noalias() += W_.block(0, s, c0, m) * u;
  }
}

}  // namespace lexdyn::solver
