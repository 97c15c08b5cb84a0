#include "lexdyn/solver/detail/hls_factorization.hpp"
#include "lexdyn/solver/solver.hpp"

#include <Eigen/Householder>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "lexdyn/common/error.hpp"

#ifndef LEXDYN_DIRECT_REFLECTORS
#define LEXDYN_DIRECT_REFLECTORS 8
#endif

namespace lexdyn::solver {

namespace {

// Split coordinates: the largest multiplier of a disfavoured variable's row accepted in the
// preferred elimination (threshold pivoting).
constexpr double kSplitMaxMultiplier = 1e4;

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

// A reflector v = [1; ess] whose ess has one nonzero, ess(j - 1) = sg = +-1, with tau = 1 (|v|^2 = 2):
// I - v v^T swaps x(0) and x(j) and negates them times sg. The generic arithmetic of
// applyReflector rounds (x(0) - (x(0) + sg x(j))); this is exact, and it reads two entries.
template <typename X>
inline void applySwapReflector(int j, double sg, X&& x) {
  const double a = x(0);
  x(0) = -sg * x(j);
  x(j) = -sg * a;
}

// The offset of a reflector's one other nonzero when it swaps two coordinates (tau 1, ess a
// single +-1: the stage's column was a unit vector on them), else 0.
template <typename Ess>
inline int swapOffset(const Ess& ess, double tau) {
  if (tau != 1.0) return 0;
  int at = 0;
  for (Eigen::Index i = 0; i < ess.size(); ++i) {
    if (ess(i) == 0.0) continue;
    if (at != 0 || std::abs(ess(i)) != 1.0) return 0;
    at = static_cast<int>(i) + 1;
  }
  return at;
}

inline size_t z(int i) { return static_cast<size_t>(i); }

// The one nonzero of v[0 .. n): its index; -1 when all are zero, -2 when there are several.
int singleNonzero(const double* v, int n) {
  int at = -1;
  for (int i = 0; i < n; ++i) {
    if (v[i] == 0.0) continue;
    if (at >= 0) return -2;
    at = i;
  }
  return at;
}

// dst[pos[k]] = row[off[k]] for k < nk and dst[zero[i]] = 0 for i < nzero (the positions past a
// level's declared columns: zeros, not read), and what singleNonzero(dst, nk + nzero) returns: the
// position of the one nonzero (when there is one, the last nonzero met is it, in any order of the
// positions), -1 for none, -2 for several. The nonzeros are counted without a branch on each value
// (whether a row's entry is zero follows no pattern the branch predictor could learn).
int gatherClassified(const double* row, const Eigen::Index* off, const int* pos, int nk, const int* zero, int nzero, double* dst) {
  for (int i = 0; i < nzero; ++i) dst[zero[i]] = 0.0;
  int count = 0, at = -1;
  for (int k = 0; k < nk; ++k) {
    const double v = row[off[k]];
    dst[pos[k]] = v;
    const bool nonzero = !(v == 0.0);
    count += nonzero ? 1 : 0;
    at = nonzero ? pos[k] : at;
  }
  return count == 0 ? -1 : (count == 1 ? at : -2);
}

// The same for R (2 or 4) adjacent rows of a column-major matrix (row, row + 1, ...: one 16-byte
// load per two of them and column) into dst[0 .. R), with what each returns in out[0 .. R). Each
// value is stored as read and classified as gatherClassified does (!(v == 0): a NaN counts as
// nonzero, -0 as zero).
template <int R>
void gatherClassifiedRows(const double* row, const Eigen::Index* off, const int* pos, int nk, const int* zero, int nzero,
                          double* const* dst, int* out) {
#if defined(__SSE2__) && defined(__x86_64__)
  constexpr int P = R / 2;
  for (int i = 0; i < nzero; ++i)
    for (int r = 0; r < R; ++r) dst[r][zero[i]] = 0.0;
  const __m128d zeros = _mm_setzero_pd();
  __m128i count[P], at[P];
  for (int h = 0; h < P; ++h) {
    count[h] = _mm_setzero_si128();
    at[h] = _mm_set1_epi64x(-1);
  }
  for (int k = 0; k < nk; ++k) {
    const __m128i f = _mm_set1_epi64x(pos[k]);
    for (int h = 0; h < P; ++h) {
      const __m128d v = _mm_loadu_pd(row + off[k] + 2 * h);
      _mm_storel_pd(dst[2 * h] + pos[k], v);
      _mm_storeh_pd(dst[2 * h + 1] + pos[k], v);
      const __m128i nonzero = _mm_castpd_si128(_mm_cmpneq_pd(v, zeros));  // all ones where v != 0 or NaN
      count[h] = _mm_sub_epi64(count[h], nonzero);
      at[h] = _mm_or_si128(_mm_and_si128(nonzero, f), _mm_andnot_si128(nonzero, at[h]));
    }
  }
  for (int h = 0; h < P; ++h) {
    const long long c[2] = {_mm_cvtsi128_si64(count[h]), _mm_cvtsi128_si64(_mm_unpackhi_epi64(count[h], count[h]))};
    const long long a[2] = {_mm_cvtsi128_si64(at[h]), _mm_cvtsi128_si64(_mm_unpackhi_epi64(at[h], at[h]))};
    for (int l = 0; l < 2; ++l) out[2 * h + l] = c[l] == 0 ? -1 : (c[l] == 1 ? static_cast<int>(a[l]) : -2);
  }
#else
  for (int r = 0; r < R; ++r) out[r] = gatherClassified(row + r, off, pos, nk, zero, nzero, dst[r]);
#endif
}

// A column's pivot ratio: its projected norm relative to its row's own norm (0 for a zero row).
inline double pivotRatio(double nrm, double orig) { return orig > 0.0 ? nrm / orig : 0.0; }

// Rows of the widest micro-kernel of Eigen's matrix product for doubles (gebp's mr): a product
// over a multiple of it of leading rows sums each of them in the same order as a longer one.
constexpr int kProductRows = Eigen::internal::gebp_traits<double, double>::mr;
// Columns of its widest micro-kernel (gebp's nr): the panels of the right-hand side.
constexpr int kProductCols = Eigen::internal::gebp_traits<double, double>::nr;

// Below this many reflectors, trailing updates apply them one by one (see factorLevel).
constexpr int kDirectReflectors = LEXDYN_DIRECT_REFLECTORS;

// Spanning stages: the smallest pivot accepted, relative to the level's largest row norm times
// the square root of its row count, and at least kSpanningMargin times the rank tolerance.
constexpr double kSpanningPivot = 1e-6;
constexpr double kSpanningMargin = 1e3;

}  // namespace

// Both products must be Eigen's matrix-product kernel: not its coefficient-wise product for small
// sizes, whose sum does not start at +0, nor the matrix-vector product of m = 1.
int HlsFactorization::unitColumnProductRows(int nr, int d, int m, int t) {
  const int lead = (t + kProductRows - 1) / kProductRows * kProductRows;
  const bool ok = m >= 2 && nr + d + m >= EIGEN_GEMM_TO_COEFFBASED_THRESHOLD &&
                  (t == 0 || (lead <= d / kProductRows * kProductRows && nr + lead + m >= EIGEN_GEMM_TO_COEFFBASED_THRESHOLD));
  return ok ? lead : -1;
}

int HlsFactorization::blockReflectorUpdate(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXd>& T,
                                           Eigen::Ref<Eigen::MatrixXd> C, Eigen::Ref<Eigen::MatrixXd> Y, Eigen::Ref<Eigen::MatrixXd> Y2) {
  const int d = static_cast<int>(C.rows()), r = static_cast<int>(V.cols()), n = static_cast<int>(C.cols());
  // A part of a product stays in the matrix-product kernel when it has at least two columns
  // (one column would go to the matrix-vector product) and is not small enough for Eigen's
  // coefficient-wise product; the whole product must be in the kernel too.
  const auto inKernel = [&](int cols) { return cols >= 2 && d + r + cols >= EIGEN_GEMM_TO_COEFFBASED_THRESHOLD; };
  const auto zeroGroup = [&](int g) {
    for (int j = g * kProductCols; j < (g + 1) * kProductCols; ++j)
      for (int i = 0; i < d; ++i)
        if (C(i, j) != 0.0) return false;
    return true;
  };
  // f(first column, columns) for each run of columns between the zero groups.
  const auto forRuns = [&](auto&& f) {
    int start = 0;
    for (int g = 0; g < n / kProductCols; ++g) {
      if (!zeroGroup(g)) continue;
      const int b = g * kProductCols;
      if (b > start) f(start, b - start);
      start = b + kProductCols;
    }
    if (start < n) f(start, n - start);
  };
  bool skip = d >= 2 && r >= 2 && inKernel(n);
  int kept = 0;
  if (skip) {
    forRuns([&](int, int cols) {
      skip = skip && inKernel(cols);
      kept += cols;
    });
  }
  if (!skip || kept == n) {
    Y.noalias() = V.transpose() * C;
    Y2.noalias() = T.transpose().triangularView<Eigen::Lower>() * Y;
    C.noalias() -= V * Y2;
    return n;
  }
  // V^T C of a zero column is +0 (the kernel's sums start from +0). The triangular product's
  // order of summation depends on its number of columns, so it always takes all of them.
  Y.setZero();
  forRuns([&](int b, int cols) { Y.middleCols(b, cols).noalias() = V.transpose() * C.middleCols(b, cols); });
  Y2.noalias() = T.transpose().triangularView<Eigen::Lower>() * Y;
  forRuns([&](int b, int cols) { C.middleCols(b, cols).noalias() -= V * Y2.middleCols(b, cols); });
  return kept;
}

void HlsFactorization::setup(int n, const std::vector<int>& rowsPerLevel) {
  n_ = n;
  nf_ = n;
  nr_ = n;
  m_ = rowsPerLevel;
  const int L = static_cast<int>(m_.size());
  mTot_ = 0;
  rowOff_.assign(z(L), 0);
  for (int k = 0; k < L; ++k) {
    rowOff_[z(k)] = mTot_;
    mTot_ += m_[z(k)];
  }
  levelOf_.assign(z(mTot_), 0);
  for (int k = 0; k < L; ++k)
    for (int r = 0; r < m_[z(k)]; ++r) levelOf_[z(rowOff_[z(k)] + r)] = k;

  A_.assign(z(L), nullptr);
  cols_.assign(z(L), -1);
  gatherIdx_.assign(z(2 * std::max(mTot_, 1)), 0);
  gatherOff_.assign(z(std::max(n, 1)), 0);
  gatherPos_.assign(z(std::max(n, 1)), 0);
  static_.assign(z(L), 0);
  rowNorm_ = Eigen::VectorXd::Zero(std::max(mTot_, 1));
  freeVar_.resize(z(n));
  for (int i = 0; i < n; ++i) freeVar_[z(i)] = i;

  inList_.assign(z(mTot_), 0);
  active_.assign(z(L), {});
  for (int k = 0; k < L; ++k) active_[z(k)].reserve(z(m_[z(k)]));

  const int nn = std::max(n, 1);
  const int colsW = std::max(mTot_, 1);
  const int m0max = L > 0 ? std::max(1, std::min(m_[0], n)) : 1;
  G_.setZero(nn, m0max);
  varPerm_.assign(z(nn), 0);
  isFree_.assign(z(nn), 1);
  flag_.assign(z(nn), 0);
  newOrder_.assign(z(nn), 0);
  varTmp_.assign(z(nn), 0);
  DTs_.setZero(nn, m0max);
  transp_.assign(z(nn), 0);
  WB_.setZero(m0max, colsW);
  SB_.setZero(m0max, colsW);
  d_.setZero(m0max);
  gB_.setZero(m0max);

  W_.setZero(nn, colsW);
  start_.assign(z(L), 0);
  act_.assign(z(L), 0);
  col0_.assign(z(L + 1), 0);
  rank_.assign(z(L), 0);
  stageEnd_.assign(z(L), 0);
  colGid_.assign(z(colsW), -1);
  pos_.assign(z(mTot_), -1);
  tau_.setZero(colsW);
  unitAt_.assign(z(colsW), 0);
  colNorm_.setZero(colsW);
  colNormRef_.setZero(colsW);
  colOrig_.setZero(colsW);

  snap_.assign(z(L), Eigen::MatrixXd());
  snapCol_.assign(z(L), std::vector<int>(z(mTot_), -1));
  snapGids_.assign(z(L), {});
  snapValid_.assign(z(L), 0);
  snapStore_.assign(z(L), 0);
  storeDone_.assign(z(L), 0);
  velOrder_.assign(z(std::max(n, 1)), 0);
  pendingVar_ = -1;
  for (int k = 0; k < L; ++k) snapStore_[z(k)] = k;
  for (int k = 1; k < L; ++k) {
    int later = 0;
    for (int j = k; j < L; ++j) later += m_[z(j)];
    snap_[z(k)].setZero(nn, std::max(later, 1));
    snapGids_[z(k)].reserve(z(later));
  }

  left_.resize(z(L));
  leftTau_.resize(z(L));
  span_.assign(z(L), 0);
  spanDeclined_.assign(z(L), 0);
  refl_.assign(z(L), 0);
  spanPerm_.assign(z(L), {});
  unitRow_.assign(z(mTot_), 0);
  int maxLevelRows = 1;
  for (int k = 0; k < L; ++k) {
    const int mk = std::max(m_[z(k)], 1);
    maxLevelRows = std::max(maxLevelRows, mk);
    left_[z(k)].setZero(mk, std::min(mk, nn));
    leftTau_[z(k)].setZero(mk);
    spanPerm_[z(k)].assign(z(std::min(mk, nn)), 0);
  }

  // Projected levels: the last, and with a projected unit suffix the one before it.
  const int mLast = L > 0 ? std::max(m_[z(L - 1)], 1) : 1;
  const int mBefore = L > 1 ? m_[z(L - 2)] : 0;
  const int mProj = mLast + mBefore;
  Raw_.setZero(nn, mProj);
  RawB_.setZero(m0max, mProj);
  RawP_.setZero(nn, mProj);
  P_.setZero(nn, std::max(mLast, mBefore));
  Z_.setZero(nn, nn);
  rawHave_.assign(z(mProj), 0);
  zvec_.setZero(nn);
  deferred_ = -1;
  deferFrom_ = -1;

  S_.setZero(nn, colsW);
  sparseB_.assign(z(colsW), -2);
  tmpGid_.assign(z(colsW), -1);
  const int rcap = std::max(1, std::min(n, maxLevelRows));
  Vw_.setZero(nn, rcap);
  T_.setZero(rcap, rcap);
  Y_.setZero(rcap, colsW);
  Y2_.setZero(rcap, colsW);
  work_.setZero(std::max({n, mTot_, 1}));
  work2_.setZero(std::max({n, mTot_, 1}));
  g_.setZero(nn);
  t_.setZero(maxLevelRows);
  ratio_.setZero(maxLevelRows);
  spanNorm_.setZero(nn);
  spanRef_.setZero(nn);
  spanOrder_.assign(z(maxLevelRows), 0);
  spanWhere_.assign(z(maxLevelRows), 0);
  spanAt_.assign(z(maxLevelRows), 0);
  spanUnitAt_.assign(z(maxLevelRows), 0);
  pivotRow_.setZero(maxLevelRows);
  recompute_.assign(z(maxLevelRows), 0);
  u_.setZero(maxLevelRows);
  elim_ = false;
  m0_ = 0;
  firstStage_ = 0;
  dirtyFrom_ = 0;
  lastRestart_ = 0;
}

void HlsFactorization::rowNorms(const Eigen::Ref<const Eigen::MatrixXd>& A, int columns, Eigen::Ref<Eigen::VectorXd> rn) {
  const int n = static_cast<int>(A.cols());
  // The full sum adds column 0, then columns 1..4, 5..8, ... as groups through column
  // ((n - 1) & ~3), then the rest one by one (Eigen's packetwise_redux_impl): 4 q + 1 leading
  // columns (q groups), when there are that many, are summed in the same groups.
  int lead = n;
  if (columns >= 1 && columns < n) lead = std::min(4 * ((columns - 1 + 3) / 4) + 1, n);
  // Column-wise accumulation: contiguous reads of the column-major matrix.
  if (lead < n) {
    rn = A.leftCols(lead).cwiseAbs2().rowwise().sum().cwiseSqrt();
  } else {
    rn = A.cwiseAbs2().rowwise().sum().cwiseSqrt();
  }
}

void HlsFactorization::computeRowNorms(const std::vector<int>* runs, const std::vector<int>* runsOff) {
  elimDataValid_ = false;  // new data: the elimination is recomputed
  invalidateAll();         // and nothing of an earlier factorisation is kept
  std::fill(spanDeclined_.begin(), spanDeclined_.end(), 0);
  for (int k = 0; k < levelCount(); ++k) {
    const Eigen::MatrixXd& A = *A_[z(k)];
    const int m = static_cast<int>(A.rows());
    if (m == 0) continue;
    auto rn = rowNorm_.segment(rowOff_[z(k)], m);
    const int q0 = runs ? (*runsOff)[z(k)] : 0, q1 = runs ? (*runsOff)[z(k) + 1] : 0;
    if (!runs || (q1 - q0 == 2 && (*runs)[z(q0)] == 0 && (*runs)[z(q0) + 1] == m)) {
      rowNorms(A, cols_[z(k)], rn);
      continue;
    }
    // Eigen forms the norms of an aligned pair of rows together and an unaligned first or last
    // row alone, each way with its own order of the sums. Pairs: packets of two doubles (SSE2,
    // 16 bytes; the build enables no wider vectors).
    static_assert(Eigen::internal::packet_traits<double>::size == 2, "row-norm runs assume packets of two doubles");
    auto misaligned = [&](int r) { return (reinterpret_cast<std::uintptr_t>(rn.data() + r) % 16) != 0; };
    rn.setZero();
    for (int q = q0; q < q1; q += 2) {
      int b = (*runs)[z(q)], e = (*runs)[z(q) + 1];
      if (b > 0 && misaligned(b)) --b;
      if (e < m && misaligned(e)) ++e;
      rowNorms(A.middleRows(b, e - b), cols_[z(k)], rn.segment(b, e - b));
    }
  }
}

void HlsFactorization::setFreeVariables(const std::vector<int>& freeVar, int nFree) {
  // The one change since a factorisation whose layout is still valid (nothing invalidated it
  // since): a single variable fixed or freed. factorize() may then restart after the stages it
  // leaves unchanged (fixedNonBasicRestart, forceChangeRestart).
  int changed = -1;
  if (pendingVar_ < 0 && dirtyFrom_ > 0 && (nFree == nf_ - 1 || nFree == nf_ + 1) && nFree >= 0) {
    const bool fixed = nFree < nf_;
    const int* longer = fixed ? freeVar_.data() : freeVar.data();
    const int* shorter = fixed ? freeVar.data() : freeVar_.data();
    const int ns = std::min(nFree, nf_);
    int i = 0;
    while (i < ns && longer[i] == shorter[i]) ++i;
    changed = longer[i];
    for (int q = i; q < ns && changed >= 0; ++q)
      if (shorter[q] != longer[q + 1]) changed = -1;
    pendingFixed_ = fixed;
  }
  nf_ = nFree;
  std::fill(isFree_.begin(), isFree_.end(), 0);
  for (int i = 0; i < nFree; ++i) {
    freeVar_[z(i)] = freeVar[z(i)];
    isFree_[z(freeVar[z(i)])] = 1;
  }
  if (changed >= 0 && boundRestarts_) {
    pendingVar_ = changed;
    return;
  }
  invalidateAll();
}

void HlsFactorization::invalidateAll() {
  dirtyFrom_ = 0;
  pendingVar_ = -1;
  std::fill(snapValid_.begin(), snapValid_.end(), 0);
}

// The first stage (from the first general one) that a change of the reduced coordinates from row
// `from` on can alter: one whose rows reach `from` (its reflectors or its columns' nonzeros), or a
// projected level (its null-space basis changes with the coordinates), or a level that is to be
// factorised again anyway.
int HlsFactorization::firstStageReaching(int from) const {
  const int L = levelCount();
  int c = std::min(dirtyFrom_, L);
  for (int k = firstStage_; k < c; ++k)
    if (projected(k) || stageEnd_[z(k)] > from || col0_[z(k)] > from) return k;
  return c;
}

// After the elimination was brought to the new free set: the same projected levels as before (a
// full factorisation decides them anew), and the new count of reduced coordinates.
bool HlsFactorization::sameLayoutAfterElimination(int deferredOld, int deferFromOld) {
  nr_ = nf_ - m0_;
  nrElim_ = nr_;
  decideDeferral();
  return deferred_ == deferredOld && deferFrom_ == deferFromOld;
}

// The restart snapshots a restart at c keeps: fn(storage, j, columns) once per storage of the
// valid snapshots j <= c (a shared storage once; snapshots are saved for levels > 0). Those after
// c are dropped: the restart takes them again when it reaches their stage.
template <class F>
void HlsFactorization::editSnapshotsUpTo(int c, F&& fn) {
  std::fill(storeDone_.begin(), storeDone_.end(), 0);
  for (int j = 1; j < levelCount(); ++j) {
    if (!snapValid_[z(j)]) continue;
    if (j > c) {
      snapValid_[z(j)] = 0;
      continue;
    }
    const int st = snapStore_[z(j)];
    if (storeDone_[z(st)]) continue;
    storeDone_[z(st)] = 1;
    fn(snap_[z(st)], j, static_cast<int>(snapGids_[z(j)].size()));
  }
}

// A variable fixed by its bound, not a basic one of the elimination (case A). When its reduced
// coordinate p is one that the stages before some level c never reach (split coordinates: a
// force that no velocity stage's rows read), those stages are unchanged to the bit: their
// reflectors and R factors lie in rows above p and their columns are zero from p on, and
// updateElimination keeps the other rows of D^T as they are. Then every saved snapshot up to c and
// every kept raw row of a projected level lose row p, and the factorisation restarts at c, as
// after an activation at level c. Returns 1 when done, 0 when not applicable (nothing changed),
// -1 when declined after the elimination was updated (the caller factorises everything).
int HlsFactorization::fixedNonBasicRestart(int v) {
  const int L = levelCount();
  int p = -1;
  for (int f = 0; f < nr_; ++f) {
    if (varPerm_[z(m0_ + f)] == v) {
      p = f;
      break;
    }
  }
  if (p < 0) return 0;  // a basic variable
  const int c = firstStageReaching(p);
  if (c <= firstStage_) return 0;
  const int nrOld = nr_;
  const int deferredOld = deferred_, deferFromOld = deferFrom_;
  if (!updateElimination()) return 0;
  if (!sameLayoutAfterElimination(deferredOld, deferFromOld) || nr_ != nrOld - 1) return -1;
  // Row p leaves the snapshots (rows col0_[j] .. nrOld of their columns) and the projected
  // levels' raw rows.
  editSnapshotsUpTo(c, [&](Eigen::MatrixXd& S, int j, int cnt) {
    const int r = p - col0_[z(j)];
    const int move = nrOld - col0_[z(j)] - r - 1;
    for (int q = 0; q < cnt && move > 0; ++q) {
      double* col = S.col(q).data();
      std::memmove(col + r, col + r + 1, static_cast<size_t>(move) * sizeof(double));
    }
  });
  if (deferFrom_ >= 0) {
    const int move = nrOld - p - 1;
    for (int row = 0; row < static_cast<int>(rawHave_.size()) && move > 0; ++row) {
      if (!rawHave_[z(row)]) continue;
      double* col = Raw_.col(row).data();
      std::memmove(col + p, col + p + 1, static_cast<size_t>(move) * sizeof(double));
    }
  }
  // Spanning stages read unitRow_, set when a row is loaded; restored and kept rows are not
  // loaded again, so a row that read v and one other free variable becomes a unit row here, as
  // it would when loaded.
  if (spanAllowed_) {
    for (int k = c; k < L; ++k) {
      const Eigen::MatrixXd& A = *A_[z(k)];
      const int cols = cols_[z(k)] >= 0 ? cols_[z(k)] : static_cast<int>(A.cols());
      if (v >= cols) continue;
      for (int r = 0; r < A.rows(); ++r) {
        if (A(r, v) == 0.0) continue;
        int free = 0;
        for (int j = 0; j < cols && free < 2; ++j) free += (A(r, j) != 0.0 && isFree_[z(j)]) ? 1 : 0;
        unitRow_[z(rowOff_[z(k)] + r)] = free <= 1 ? 1 : 0;
      }
    }
  }
  ++stages_;  // the elimination was brought to the new free set
  dirtyFrom_ = c;
  return 1;
}

// Split coordinates, a force fixed or freed, a basic one included (case B). The elimination is
// brought to the new free set as a full factorisation does (updateElimination, else a new
// elimination), so that D^T is the full factorisation's. When every level with active rows that
// is not projected reads the velocities only (its declared columns end at the split), its rows
// have no basic part and are zero on every force coordinate: their reduced rows are their entries
// at the velocities whatever the forces' basis, and the stages they make are unchanged as long as
// the velocities' coordinates are (the same free velocities, first, in the same order). Then the
// snapshots' force rows become the new count of zero rows, the projected levels' raw rows are
// loaded again, and the factorisation restarts at the first projected level. Returns as
// fixedNonBasicRestart.
int HlsFactorization::forceChangeRestart(int v) {
  const int L = levelCount();
  if (!splitApplied_ || split_ < 0 || v < split_) return 0;
  for (int k = firstStage_; k < L; ++k) {
    if (projected(k) || active_[z(k)].empty()) continue;
    if (cols_[z(k)] < 0 || cols_[z(k)] > split_) return 0;
  }
  int nv = 0;  // reduced velocity coordinates, first in the split order
  while (nv < nr_ && varPerm_[z(m0_ + nv)] < split_) ++nv;
  const int c = firstStageReaching(nv);
  if (c <= firstStage_) return 0;
  for (int i = 0; i < nv; ++i) velOrder_[z(i)] = varPerm_[z(m0_ + i)];
  const int nrOld = nr_;
  const int deferredOld = deferred_, deferFromOld = deferFrom_;
  if (!(updateElimination() || tryEliminate()) || !splitApplied_) return -1;
  if (!sameLayoutAfterElimination(deferredOld, deferFromOld) || nr_ < nv) return -1;
  for (int i = 0; i < nv; ++i)
    if (varPerm_[z(m0_ + i)] != velOrder_[z(i)]) return -1;
  if (nv < nr_ && varPerm_[z(m0_ + nv)] < split_) return -1;
  // Rows nv.. of the snapshots up to c: zeros, as many as there are force coordinates now.
  editSnapshotsUpTo(c, [&](Eigen::MatrixXd& S, int j, int cnt) {
    if (cnt > 0 && nr_ > nv) S.block(nv - col0_[z(j)], 0, nr_ - nv, cnt).setZero();
  });
  // The earlier stages' columns are zero below their rows (read up to stageEnd_ only); rows that
  // the coordinates gained are cleared all the same.
  const int sc = start_[z(c - 1)] + act_[z(c - 1)];
  if (nr_ > nrOld && sc > 0) W_.block(nrOld, 0, nr_ - nrOld, sc).setZero();
  std::fill(rawHave_.begin(), rawHave_.end(), 0);
  ++stages_;  // the elimination was brought to the new free set
  dirtyFrom_ = c;
  return 1;
}

void HlsFactorization::activate(int k, int row) {
  const int gid = rowOff_[z(k)] + row;
  LEXDYN_DEBUG_ASSERT(!inList_[z(gid)]);
  inList_[z(gid)] = 1;
  active_[z(k)].push_back(gid);
  dirtyFrom_ = std::min(dirtyFrom_, k);
}

void HlsFactorization::deactivate(int k, int row) {
  const int gid = rowOff_[z(k)] + row;
  LEXDYN_DEBUG_ASSERT(inList_[z(gid)]);
  inList_[z(gid)] = 0;
  auto& lst = active_[z(k)];
  lst.erase(std::find(lst.begin(), lst.end(), gid));  // keeps the order; no reallocation
  dirtyFrom_ = std::min(dirtyFrom_, k);
}

void HlsFactorization::clearActive() {
  for (int k = 0; k < levelCount(); ++k) {
    for (int gid : active_[z(k)]) inList_[z(gid)] = 0;
    active_[z(k)].clear();
  }
  invalidateAll();
  snapshotsOn_ = !lazy_;
}

int HlsFactorization::totalRank() const {
  int r = 0;
  for (int k = 0; k < levelCount(); ++k) r += rank_[z(k)];
  return r;
}

// ------------------------------------------------------------------------------------------
// Elimination stage.
// ------------------------------------------------------------------------------------------

bool HlsFactorization::tryEliminate() {
  elim_ = false;
  m0_ = 0;
  splitApplied_ = false;
  if (!elimAllowed_ || levelCount() == 0) return false;
  // Split coordinates: basic variables among those from split_ on (when there are enough of
  // them), else the plain pivoting.
  if (split_ >= 0) {
    int preferred = 0;
    for (int f = 0; f < nf_; ++f) preferred += freeVar_[z(f)] >= split_ ? 1 : 0;
    if (preferred >= static_cast<int>(active_[0].size()) && eliminateOnce(true)) {
      splitApplied_ = true;
      return true;
    }
  }
  return eliminateOnce(false);
}

bool HlsFactorization::eliminateOnce(bool preferSplit) {
  const auto& lst = active_[0];
  const int m0 = static_cast<int>(lst.size());
  if (m0 == 0 || m0 > nf_ || m0 > G_.cols()) return false;
  const Eigen::MatrixXd& A0 = *A_[0];
  // G = A_0^T restricted to the free variables (rows = variables); columns of A_0 are contiguous.
  const Eigen::Index ldG = G_.outerStride();
  for (int f = 0; f < nf_; ++f) {
    const double* col = A0.data() + static_cast<Eigen::Index>(freeVar_[z(f)]) * A0.rows();
    double* g = G_.data() + f;
    for (int i = 0; i < m0; ++i) g[i * ldG] = col[lst[z(i)] - rowOff_[0]];
  }
  // Preferring the variables from split_ on: the others' rows scaled by 2^-20 (exact) lose the
  // partial pivoting's comparisons, and are scaled back in D^T below.
  const double kDisfavour = std::ldexp(1.0, -20);
  if (preferSplit)
    for (int f = 0; f < nf_; ++f)
      if (freeVar_[z(f)] < split_) G_.row(f).head(m0) *= kDisfavour;
  // Blocked LU with partial pivoting of the tall G (Eigen's kernel): P G = [L1; L2] U. The pivot
  // rows are the basic variables.
  int nbTranspositions = 0;
  Eigen::internal::partial_lu_impl<double, Eigen::ColMajor, int>::blocked_lu(nf_, m0, G_.data(), G_.outerStride(), transp_.data(),
                                                                             nbTranspositions);
  for (int f = 0; f < nf_; ++f) varPerm_[z(f)] = freeVar_[z(f)];
  for (int i = 0; i < m0; ++i) std::swap(varPerm_[z(i)], varPerm_[z(transp_[z(i)])]);
  if (preferSplit) {
    for (int i = 0; i < m0; ++i)
      if (varPerm_[z(i)] < split_) return false;  // not enough well-conditioned preferred pivots
    // Threshold pivoting: the disfavoured rows' multipliers (|L2| <= 1 for the others) may not
    // exceed kSplitMaxMultiplier, so that D^T stays moderate (exp1: at most 368, exp2: 291).
    for (int f = m0; f < nf_; ++f)
      if (varPerm_[z(f)] < split_ && G_.row(f).head(m0).cwiseAbs().maxCoeff() > kSplitMaxMultiplier * kDisfavour) return false;
  }
  // Accept only well-conditioned pivots (full row rank, safe for elimination).
  auto rowMax = t_.head(A0.rows());
  rowMax = A0.cwiseAbs().rowwise().maxCoeff();
  for (int i = 0; i < m0; ++i) {
    const double rm = rowMax(lst[z(i)] - rowOff_[0]);
    if (!(std::abs(G_(i, i)) > elimTol_ * rm) || rm == 0.0) return false;
  }
  // D^T = L2 L1^{-1} (in place on the lower block).
  const int nr = nf_ - m0;
  if (nr > 0) {
    auto L1 = G_.topLeftCorner(m0, m0).triangularView<Eigen::UnitLower>();
    auto L2 = G_.block(m0, 0, nr, m0);
    L1.solveInPlace<Eigen::OnTheRight>(L2);
  }
  if (preferSplit && nr > 0) {
    for (int f = m0; f < nf_; ++f)
      if (varPerm_[z(f)] < split_) G_.row(f).head(m0) /= kDisfavour;
    sortReducedVariables(m0, nr);
  }
  elim_ = true;
  elimDataValid_ = true;
  m0_ = m0;
  return true;
}

// Split coordinates: the reduced variables (positions m0 .. m0 + nr of varPerm_, rows of D^T in
// G_) in increasing variable order, so that a level's rows keep their support at the top. An
// insertion sort: the order is nearly sorted, and it allocates nothing.
void HlsFactorization::sortReducedVariables(int m0, int nr) {
  for (int f = 0; f < nr; ++f) {
    const int cur = m0 + f;
    int q = f;
    while (q > 0 && varPerm_[z(newOrder_[z(q - 1)])] > varPerm_[z(cur)]) {
      newOrder_[z(q)] = newOrder_[z(q - 1)];
      --q;
    }
    newOrder_[z(q)] = cur;
  }
  for (int f = 0; f < nr; ++f) DTs_.row(f).head(m0) = G_.row(newOrder_[z(f)]).head(m0);
  for (int f = 0; f < nr; ++f) varTmp_[z(f)] = varPerm_[z(newOrder_[z(f)])];
  for (int f = 0; f < nr; ++f) varPerm_[z(m0 + f)] = varTmp_[z(f)];
  G_.block(m0, 0, nr, m0) = DTs_.topRows(nr).leftCols(m0);
}

// The free set changed but the data did not: if every basic variable is still free, the LU of
// the basic columns stays valid and only the rows of D^T change (kept, dropped for variables now
// fixed, or computed for variables now free: l = U^{-T} g, D^T row = L1^{-T} l).
bool HlsFactorization::updateElimination() {
  if (!elim_ || !elimDataValid_ || !elimAllowed_) return false;
  const int m0 = m0_;
  if (static_cast<int>(active_[0].size()) != m0 || m0 > nf_) return false;
  for (int i = 0; i < m0; ++i)
    if (!isFree_[z(varPerm_[z(i)])]) return false;
  const int nrOld = static_cast<int>(nrElim_);
  for (int i = 0; i < m0; ++i) flag_[z(varPerm_[z(i)])] = 1;  // basic
  int q = 0;
  for (int f = 0; f < nrOld; ++f) {
    const int v = varPerm_[z(m0 + f)];
    flag_[z(v)] = 2;  // was non-basic
    if (!isFree_[z(v)]) continue;
    DTs_.row(q).head(m0) = G_.row(m0 + f).head(m0);
    newOrder_[z(q++)] = v;
  }
  const Eigen::MatrixXd& A0 = *A_[0];
  const auto& lst = active_[0];
  for (int f = 0; f < nf_; ++f) {
    const int v = freeVar_[z(f)];
    if (flag_[z(v)] != 0) continue;
    auto g = d_.head(m0);
    for (int i = 0; i < m0; ++i) g(i) = A0(lst[z(i)] - rowOff_[0], v);
    G_.topLeftCorner(m0, m0).triangularView<Eigen::Upper>().transpose().solveInPlace(g);
    G_.topLeftCorner(m0, m0).triangularView<Eigen::UnitLower>().transpose().solveInPlace(g);
    DTs_.row(q).head(m0) = g.transpose();
    newOrder_[z(q++)] = v;
  }
  for (int i = 0; i < m0; ++i) flag_[z(varPerm_[z(i)])] = 0;
  for (int f = 0; f < nrOld; ++f) flag_[z(varPerm_[z(m0 + f)])] = 0;
  if (q != nf_ - m0) return false;  // cannot happen; be safe
  if (q > 0) G_.block(m0, 0, q, m0) = DTs_.topRows(q).leftCols(m0);
  for (int f = 0; f < q; ++f) varPerm_[z(m0 + f)] = newOrder_[z(f)];
  if (split_ >= 0 && splitApplied_) sortReducedVariables(m0, q);  // a freed variable was appended
  nrElim_ = q;
  return true;
}

// Loads the active rows of level j found at scratch columns [p0, p1) marked as loaded (colNorm_ == 1):
// reduced coordinates into S, basic part into SB; runs of adjacent rows together.
void HlsFactorization::gatherLevel(int j, int p0, int p1, Eigen::MatrixXd& S, Eigen::MatrixXd& SB) {
  const Eigen::MatrixXd& A = *A_[z(j)];
  const Eigen::Index lda = A.rows();
  const int off = rowOff_[z(j)];
  int* qs = gatherIdx_.data();             // loaded scratch columns
  int* rows = qs + gatherIdx_.size() / 2;  // their rows in level j
  int cnt = 0;
  for (int q = p0; q < p1; ++q) {
    if (colNorm_(q) != 1.0) continue;
    qs[cnt] = q;
    rows[cnt++] = tmpGid_[z(q)] - off;
  }
  // Each scratch column is written contiguously, reading its row across A's columns
  // at the reduced (then basic) variables' offsets. A level declared zero past its first columns:
  // the other variables' entries are zeros, not read (each read is a cache line of its own in the
  // column-major matrix). The variables read come first in each part's list of positions.
  const Eigen::Index limit = cols_[z(j)] >= 0 ? static_cast<Eigen::Index>(cols_[z(j)]) * lda : A.size();
  Eigen::Index* vo = gatherOff_.data();
  int* pos = gatherPos_.data();
  auto list = [&](int first, int count, auto variable) {
    int read = 0, zero = count;
    for (int f = 0; f < count; ++f) {
      const Eigen::Index o = static_cast<Eigen::Index>(variable(f)) * lda;
      if (o < limit) {
        vo[first + read] = o;
        pos[first + read++] = f;
      } else {
        pos[first + --zero] = f;
      }
    }
    std::reverse(pos + first + read, pos + first + count);  // the zeros in ascending order too
    return read;
  };
  const int readN = list(0, nr_, [&](int f) { return elim_ ? varPerm_[z(m0_ + f)] : freeVar_[z(f)]; });
  const int readB = elim_ ? list(nr_, m0_, [&](int i) { return varPerm_[z(i)]; }) : 0;
  const Eigen::Index ldS = S.outerStride(), ldB = SB.outerStride();
  // Spanning stages: rows that read at most one free variable (a row on a fixed variable reads
  // none), counted over the reduced and the basic variables together.
  auto classify = [&](int c, int nonzeros, int basic) {
    const int single = spanAllowed_ ? nonzeros : -2;
    if (!elim_) {
      if (spanAllowed_) unitRow_[z(off + rows[c])] = single != -2 ? 1 : 0;
      return;
    }
    sparseB_[z(qs[c])] = basic;
    if (spanAllowed_) unitRow_[z(off + rows[c])] = (single == -1 && basic != -2) || (single >= 0 && basic == -1) ? 1 : 0;
  };
  // Runs of adjacent rows (a task's rows are loaded together) are read 4 or 2 at a time.
  auto run = [&](int c, auto lanes) {
    constexpr int R = decltype(lanes)::value;
    const double* row = A.data() + rows[c];
    double* dst[R];
    int red[R], bas[R] = {};
    for (int r = 0; r < R; ++r) dst[r] = S.data() + qs[c + r] * ldS;
    gatherClassifiedRows<R>(row, vo, pos, readN, pos + readN, nr_ - readN, dst, red);
    if (elim_) {
      for (int r = 0; r < R; ++r) dst[r] = SB.data() + qs[c + r] * ldB;
      gatherClassifiedRows<R>(row, vo + nr_, pos + nr_, readB, pos + nr_ + readB, m0_ - readB, dst, bas);
    }
    for (int r = 0; r < R; ++r) classify(c + r, red[r], elim_ ? bas[r] : -1);
  };
  auto adjacent = [&](int c, int r) {
    if (c + r > cnt) return false;
    for (int i = 1; i < r; ++i)
      if (rows[c + i] != rows[c] + i) return false;
    return true;
  };
  for (int c = 0; c < cnt;) {
    if (adjacent(c, 4)) {
      run(c, std::integral_constant<int, 4>{});
      c += 4;
      continue;
    }
    if (adjacent(c, 2)) {
      run(c, std::integral_constant<int, 2>{});
      c += 2;
      continue;
    }
    const double* row = A.data() + rows[c];
    const int nonzeros = gatherClassified(row, vo, pos, readN, pos + readN, nr_ - readN, S.data() + qs[c] * ldS);
    const int basic =
        elim_ ? gatherClassified(row, vo + nr_, pos + nr_, readB, pos + nr_ + readB, m0_ - readB, SB.data() + qs[c] * ldB) : -1;
    classify(c, nonzeros, basic);
    ++c;
  }
}

template <typename X>
void HlsFactorization::applyStageReflector(int col, int top, int len, X&& x) const {
  const int j = unitAt_[z(col)];
  if (j > 0) {
    applySwapReflector(j, W_(top + j, col), x);
  } else {
    applyReflector(W_.col(col).segment(top + 1, len - 1), tau_(col), x);
  }
}

void HlsFactorization::applyEarlierStagesTo(Eigen::Ref<Eigen::VectorXd> col, int stages) const {
  for (int k = firstStage_; k < stages; ++k) {
    const int c0 = col0_[z(k)];
    const int s = start_[z(k)];
    for (int i = 0; i < refl_[z(k)]; ++i) {
      const int len = stageEnd_[z(k)] - c0 - i;
      applyStageReflector(s + i, c0 + i, len, col.segment(c0 + i, len));
    }
  }
}

void HlsFactorization::applyEarlierStagesQ(Eigen::Ref<Eigen::VectorXd> col, int stages) const {
  for (int k = stages - 1; k >= firstStage_; --k) {
    const int c0 = col0_[z(k)];
    const int s = start_[z(k)];
    for (int i = refl_[z(k)] - 1; i >= 0; --i) {
      const int len = stageEnd_[z(k)] - c0 - i;
      applyStageReflector(s + i, c0 + i, len, col.segment(c0 + i, len));
    }
  }
}

bool HlsFactorization::projectionPays(int k) const {
  // Projection pays when the level has more active rows than the null space left for it
  // (estimated with full-rank earlier levels).
  int earlier = 0;
  for (int j = firstStage_; j < k; ++j) earlier += static_cast<int>(active_[z(j)].size());
  return static_cast<int>(active_[z(k)].size()) > std::max(nr_ - earlier, 0);
}

bool HlsFactorization::unitRows(int k) const {
  const Eigen::MatrixXd& A = *A_[z(k)];
  const int cols = cols_[z(k)] >= 0 ? cols_[z(k)] : static_cast<int>(A.cols());
  for (int gid : active_[z(k)]) {
    const int row = gid - rowOff_[z(k)];
    int at = -1;
    for (int c = 0; c < cols; ++c) {
      if (A(row, c) == 0.0) continue;
      if (at >= 0) return false;
      at = c;
    }
  }
  return !active_[z(k)].empty();
}

void HlsFactorization::decideDeferral() {
  deferred_ = -1;
  deferFrom_ = -1;
  const int k = levelCount() - 1;
  if (lastMode_ == LastLevel::Standard || k <= firstStage_) return;
  if (lastMode_ == LastLevel::Auto && !projectionPays(k)) return;
  deferred_ = k;
  deferFrom_ = k;
  // Projected unit suffix: the level before the last too, when its rows are unit rows (x_j = 0,
  // say) and projection pays for it as well. Its rows then take no earlier stage's reflectors;
  // when the earlier levels leave it only coordinates that no earlier stage reached, the
  // projection of its rows on reduced variables costs copies of exact zeros. A row on a basic
  // variable of the elimination is a column of D^T in reduced coordinates (and its basic part):
  // projected like any row of the last level.
  if (unitSuffix_ && k - 1 > firstStage_ && projectionPays(k - 1) && unitRows(k - 1)) deferFrom_ = k - 1;
}

void HlsFactorization::relayout(int c) {
  // Rebuild the columns of levels >= c in the solver's active order, in their pre-stage-c state.
  const int L = levelCount();
  const int sc = (c <= firstStage_) ? 0 : start_[z(c - 1)] + act_[z(c - 1)];
  const int c0 = col0_[z(c)];
  const bool useSnap = (c > 0) && !static_[z(c)] && snapValid_[z(c)];
  int p = 0, fresh = 0;
  for (int j = c; j < L; ++j) p += static_cast<int>(active_[z(j)].size());
  // After a full reset nothing is restored and the layout starts at column 0: the columns are
  // built in place. Otherwise in scratch, since restored columns are read from their old places:
  // at their final places when the earlier stages have fewer columns than the levels rebuilt
  // (a restart at an early level), and the earlier stages' columns are copied into the scratch,
  // which then becomes the layout (the two matrices swap their storage); else from the scratch's
  // first column, copied back.
  const bool direct = fullLayout_ && c == firstStage_;
  const bool swapIn = !direct && sc < p;
  Eigen::MatrixXd& S = direct ? W_ : S_;
  Eigen::MatrixXd& SB = direct ? WB_ : SB_;
  const int o = swapIn ? sc : 0;  // S's column of the first column of level c (sc is 0 when direct)
  {
    int q = o;  // each column's place in S
    for (int j = c; j < L; ++j) {
      const int q0 = q;
      int freshHere = 0;
      for (int gid : active_[z(j)]) {
        tmpGid_[z(q)] = gid;
        if (projected(j)) {
          // Projected level: its raw reduced rows, kept from an earlier layout or loaded.
          const int row = gid - rowOff_[z(deferFrom_)];
          if (rawHave_[z(row)]) {
            S.col(q).head(nr_) = Raw_.col(row).head(nr_);
            if (elim_) SB.col(q).head(m0_) = RawB_.col(row).head(m0_);
            colNorm_(q) = 0.0;
          } else {
            colNorm_(q) = 1.0;
            ++freshHere;
          }
          ++q;
          continue;
        }
        const int old = pos_[z(gid)];
        const int sCol = useSnap ? snapCol_[z(c)][z(gid)] : -1;
        if (old >= 0 && sCol >= 0) {
          S.col(q).head(c0) = W_.col(old).head(c0);
          S.col(q).segment(c0, nr_ - c0) = snap_[z(snapStore_[z(c)])].col(sCol).head(nr_ - c0);
          if (elim_) SB.col(q).head(m0_) = WB_.col(old).head(m0_);
          colNorm_(q) = 0.0;  // marks a restored column
        } else {
          colNorm_(q) = 1.0;  // marks a loaded column
          ++freshHere;
        }
        ++q;
      }
      if (freshHere > 0) gatherLevel(j, q0, q, S, SB);
      fresh += freshHere;
    }
  }
  // Loaded rows: elimination transform a_N - D^T a_B. Rows whose basic part has at most one
  // nonzero (bounds-like rows: trust region, minimum velocity) take one column of D^T; runs of
  // dense rows are transformed together (matrix product).
  if (elim_ && fresh > 0) {
    const auto DT = G_.block(m0_, 0, nr_, m0_);
    int q = o;
    while (q < o + p) {
      if (colNorm_(q) != 1.0 || sparseB_[z(q)] != -2) {
        if (colNorm_(q) == 1.0 && sparseB_[z(q)] >= 0) {
          const int i = sparseB_[z(q)];
          S.col(q).head(nr_).noalias() -= SB(i, q) * DT.col(i);
        }
        ++q;
        continue;
      }
      int e = q + 1;
      while (e < o + p && colNorm_(e) == 1.0 && sparseB_[z(e)] == -2) ++e;
      S.block(0, q, nr_, e - q).noalias() -= DT * SB.block(0, q, m0_, e - q);
      q = e;
    }
  }
  // Columns of a projected level stay raw (kept for later layouts); the others get the earlier
  // stages' reflectors.
  int pDef = p;
  if (deferFrom_ >= 0)
    for (int j = std::max(c, deferFrom_); j < L; ++j) pDef -= static_cast<int>(active_[z(j)].size());
  for (int q = o + pDef; q < o + p && fresh > 0; ++q) {
    if (colNorm_(q) != 1.0) continue;
    const int row = tmpGid_[z(q)] - rowOff_[z(deferFrom_)];
    Raw_.col(row).head(nr_) = S.col(q).head(nr_);
    if (elim_) RawB_.col(row).head(m0_) = SB.col(q).head(m0_);
    rawHave_[z(row)] = 1;
  }
  if (c > firstStage_ && fresh > 0) {
    for (int q = o; q < o + pDef; ++q)
      if (colNorm_(q) == 1.0) applyEarlierStagesTo(S.col(q).head(nr_), c);
  }
  for (int q = sc; q < mTot_; ++q) {
    const int gid = colGid_[z(q)];
    if (gid >= 0) pos_[z(gid)] = -1;
    colGid_[z(q)] = -1;
  }
  if (swapIn) {
    if (sc > 0) {
      S_.block(0, 0, nr_, sc) = W_.block(0, 0, nr_, sc);
      if (elim_) SB_.block(0, 0, m0_, sc) = WB_.block(0, 0, m0_, sc);
    }
    W_.swap(S_);
    if (elim_) WB_.swap(SB_);
  } else if (p > 0 && !direct) {
    W_.block(0, sc, nr_, p) = S_.block(0, 0, nr_, p);
    if (elim_) WB_.block(0, sc, m0_, p) = SB_.block(0, 0, m0_, p);
  }
  int q = sc;
  for (int j = c; j < L; ++j) {
    start_[z(j)] = q;
    act_[z(j)] = static_cast<int>(active_[z(j)].size());
    for (int gid : active_[z(j)]) {
      colGid_[z(q)] = gid;
      pos_[z(gid)] = q;
      ++q;
    }
  }
}

void HlsFactorization::saveSnapshot(int k, int shareWith) {
  const int L = levelCount();
  auto& sc = snapCol_[z(k)];
  for (int gid : snapGids_[z(k)]) sc[z(gid)] = -1;
  snapGids_[z(k)].clear();
  const int s = start_[z(k)];
  int cnt = 0;
  for (int j = k; j < L; ++j)
    if (!projected(j)) cnt += act_[z(j)];  // a projected level restores from its raw rows
  const int c0 = col0_[z(k)];
  const int d = nr_ - c0;
  // Shared: the same columns, rows and entries as snapshot shareWith (in its storage).
  snapStore_[z(k)] = shareWith >= 0 ? snapStore_[z(shareWith)] : k;
  if (shareWith < 0 && cnt > 0 && d > 0) snap_[z(k)].block(0, 0, d, cnt) = W_.block(c0, s, d, cnt);
  for (int p = 0; p < cnt; ++p) {
    const int gid = colGid_[z(s + p)];
    sc[z(gid)] = p;
    snapGids_[z(k)].push_back(gid);
  }
  snapValid_[z(k)] = 1;
}

void HlsFactorization::swapColumns(int a, int b, int rows) {
  if (a == b) return;
  W_.col(a).head(rows).swap(W_.col(b).head(rows));
  if (elim_) WB_.col(a).head(m0_).swap(WB_.col(b).head(m0_));
  if (projected(levelOf_[z(colGid_[z(a)])])) {
    const int s = start_[z(deferFrom_)];
    RawP_.col(a - s).head(nr_).swap(RawP_.col(b - s).head(nr_));
  }
  std::swap(colNorm_(a), colNorm_(b));
  std::swap(colNormRef_(a), colNormRef_(b));
  std::swap(colOrig_(a), colOrig_(b));
  const int ga = colGid_[z(a)];
  const int gb = colGid_[z(b)];
  colGid_[z(a)] = gb;
  colGid_[z(b)] = ga;
  pos_[z(gb)] = a;
  pos_[z(ga)] = b;
}

// The column norms' downdate after a reflector (LAPACK xLAQP2), for cnt columns: with w the
// column's entry in the reflector's row, nrm *= sqrt(max(0, (1 + t) (1 - t))), t = |w| / nrm,
// unless the downdated norm has lost too much to cancellation (then recompute[q] is set and the
// caller computes it again). With orig, ratio = pivotRatio(nrm, orig). A zero norm stays zero. Two
// columns at a time where SSE2 is there: the same correctly rounded operations as one at a time,
// so the same bits, but the divisions and square roots of two columns overlap.
void HlsFactorization::downdateNorms(int cnt, const double* w, double* nrm, const double* ref, const double* orig, double* ratio,
                                     char* recompute) {
  static const double kSqrtEps = std::sqrt(std::numeric_limits<double>::epsilon());
  int q = 0;
#ifdef __SSE2__
  const __m128d zero = _mm_setzero_pd(), one = _mm_set1_pd(1.0), eps = _mm_set1_pd(kSqrtEps);
  const __m128d absMask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
  for (; q + 2 <= cnt; q += 2) {
    const __m128d n = _mm_loadu_pd(nrm + q);
    const __m128d t = _mm_div_pd(_mm_and_pd(_mm_loadu_pd(w + q), absMask), n);
    // std::max(0.0, x) is x when 0 < x, else 0 (NaN included): maxpd(x, 0) returns its second
    // operand unless x > 0.
    const __m128d temp = _mm_max_pd(_mm_mul_pd(_mm_add_pd(one, t), _mm_sub_pd(one, t)), zero);
    const __m128d rr = _mm_div_pd(n, _mm_loadu_pd(ref + q));
    const __m128d again = _mm_cmple_pd(_mm_mul_pd(_mm_mul_pd(temp, rr), rr), eps);
    const __m128d nonzero = _mm_cmpneq_pd(n, zero);
    const __m128d scaled = _mm_mul_pd(n, _mm_sqrt_pd(temp));
    // Zero norms keep 0; the others are scaled (those to recompute are overwritten by the caller).
    const __m128d out = _mm_or_pd(_mm_and_pd(nonzero, scaled), _mm_andnot_pd(nonzero, n));
    _mm_storeu_pd(nrm + q, out);
    const int mask = _mm_movemask_pd(_mm_and_pd(nonzero, again));
    recompute[q] = static_cast<char>(mask & 1);
    recompute[q + 1] = static_cast<char>((mask >> 1) & 1);
    if (orig == nullptr) continue;
    const __m128d o = _mm_loadu_pd(orig + q);
    const __m128d pos = _mm_cmpgt_pd(o, zero);
    _mm_storeu_pd(ratio + q, _mm_and_pd(pos, _mm_div_pd(out, o)));
  }
#endif
  for (; q < cnt; ++q) {
    recompute[q] = 0;
    double& n = nrm[q];
    if (n != 0.0) {
      double temp = std::abs(w[q]) / n;
      temp = std::max(0.0, (1.0 + temp) * (1.0 - temp));
      const double rr = n / ref[q];
      if (temp * rr * rr <= kSqrtEps) {
        recompute[q] = 1;
      } else {
        n *= std::sqrt(temp);
      }
    }
    if (orig != nullptr) ratio[q] = pivotRatio(n, orig[q]);
  }
}

void HlsFactorization::factorLevel(int k, double rankTol) {
  const int L = levelCount();
  const int s = start_[z(k)];
  const int m = act_[z(k)];
  const int c0 = col0_[z(k)];
  // Split coordinates: the stage works on rows c0 .. e only, e past the last nonzero of its
  // columns (the rows below are exact zeros, and so are its reflectors there).
  int e = nr_;
  if (split_ >= 0) {
    e = c0;
    for (int j = 0; j < m; ++j) {
      const double* col = W_.col(s + j).data();
      for (int i = nr_ - 1; i >= e; --i) {
        if (col[i] != 0.0) {
          e = i + 1;
          break;
        }
      }
    }
  }
  stageEnd_[z(k)] = e;
  const int d = e - c0;
  span_[z(k)] = 0;
  if (spanAllowed_ && d > 0 && m >= d) {
    bool unit = true;
    for (int j = 0; j < m && unit; ++j) unit = unitRow_[z(colGid_[z(s + j)])] != 0;
    // A level of other rows (spanning_any_rows) that does not span its stage, a rank-deficient
    // one, declines after its QR and is not tried again in this solve: an active-set search
    // factorises it many times, and a level that left a direction of its stage unreached mostly
    // leaves one again as bounds and rows come and go (every other count of its rows and
    // coordinates would be a new attempt, and most would decline too).
    const bool eligible = unit || (spanAnyRows_ && !spanDeclined_[z(k)]);
    bool structured = false;
    const bool spanned = eligible && factorSpanning(k, d, rankTol, structured);
    if (eligible && !spanned && !unit) spanDeclined_[z(k)] = 1;
    if (spanned) {
      span_[z(k)] = structured ? 2 : 1;
      rank_[z(k)] = d;
      refl_[z(k)] = 0;
      col0_[z(k + 1)] = c0 + d;
      return;
    }
  }

  for (int j = 0; j < m; ++j) {
    const double nr = (d > 0) ? W_.col(s + j).segment(c0, d).norm() : 0.0;
    colNorm_(s + j) = nr;
    colNormRef_(s + j) = nr;
    colOrig_(s + j) = rowNorm_(colGid_[z(s + j)]);
  }

  // Pivot ratios: projected norm relative to the original row norm (0 for a zero row).
  double* ratio = ratio_.data();
  for (int j = 0; j < m; ++j) ratio[j] = pivotRatio(colNorm_(s + j), colOrig_(s + j));
  int r = 0;
  const int maxRank = std::min(m, d);
  while (r < maxRank) {
    // Pivot: largest ratio (ties: lowest index).
    int best = -1;
    double bestRatio = 0.0;
    for (int j = r; j < m; ++j) {
      if (ratio[j] > bestRatio) {
        bestRatio = ratio[j];
        best = j;
      }
    }
    if (best < 0 || bestRatio <= rankTol) break;
    swapColumns(s + r, s + best, e);
    std::swap(ratio[r], ratio[best]);
    auto x = W_.col(s + r).segment(c0 + r, d - r);
    double tau = 0.0, beta = 0.0;
    x.makeHouseholderInPlace(tau, beta);
    x(0) = beta;
    tau_(s + r) = tau;
    const auto ess = W_.col(s + r).segment(c0 + r + 1, d - r - 1);
    unitAt_[z(s + r)] = swaps_ ? swapOffset(ess, tau) : 0;
    double* top = pivotRow_.data();
    for (int j = r + 1; j < m; ++j) {
      applyStageReflector(s + r, c0 + r, d - r, W_.col(s + j).segment(c0 + r, d - r));
      top[j] = W_(c0 + r, s + j);
    }
    // Norm downdates of the remaining columns and their new ratios, all columns at once.
    const int first = r + 1;
    const int cnt = m - first;
    downdateNorms(cnt, top + first, colNorm_.data() + s + first, colNormRef_.data() + s + first, colOrig_.data() + s + first, ratio + first,
                  recompute_.data());
    for (int q = 0; q < cnt; ++q) {
      if (!recompute_[z(q)]) continue;
      // Cancellation: the norm of the column's remaining rows, computed again (LAPACK xLAQP2).
      const int j = first + q;
      double& nrm = colNorm_(s + j);
      nrm = (d - r - 1 > 0) ? W_.col(s + j).segment(c0 + r + 1, d - r - 1).norm() : 0.0;
      colNormRef_(s + j) = nrm;
      ratio[j] = pivotRatio(nrm, colOrig_(s + j));
    }
    ++r;
  }
  rank_[z(k)] = r;
  refl_[z(k)] = r;
  col0_[z(k + 1)] = c0 + r;

  // Trailing update of the later levels' columns: C <- Q_k^T C (compact WY, blocked).
  int rest = 0;
  for (int j = k + 1; j < L; ++j)
    if (!projected(j)) rest += act_[z(j)];  // a projected level is projected when its turn comes
  // Every reflector a swap of two coordinates or the identity (tau 0: a unit column whose
  // nonzero is already on the pivot row): a stage of unit rows, trust-region rows say.
  bool swaps = swaps_;
  for (int i = 0; i < r && swaps; ++i) swaps = unitAt_[z(s + i)] > 0 || tau_(s + i) == 0.0;
  if (rest > 0 && r > 0) {
    auto C = W_.block(c0, s + m, d, rest);
    if (swaps) {
      // The rows of C swapped and negated, exactly, instead of a product over all d rows.
      for (int i = 0; i < r; ++i) {
        const int j = unitAt_[z(s + i)];
        if (j == 0) continue;  // the identity
        const double sg = W_(c0 + i + j, s + i);
        for (int q = 0; q < rest; ++q) applySwapReflector(j, sg, C.col(q).segment(i, d - i));
      }
    } else if (r <= kDirectReflectors) {
      // Few reflectors: apply them one by one (a matrix-vector product and a rank-one update
      // each); cheaper than forming the compact-WY factor for such small blocks.
      for (int i = 0; i < r; ++i) {
        auto Ci = C.bottomRows(d - i);
        Ci.applyHouseholderOnTheLeft(W_.col(s + i).segment(c0 + i + 1, d - i - 1), tau_(s + i), work_.data());
      }
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
      blockReflectorUpdate(V, T, C, Y_.block(0, 0, r, rest), Y2_.block(0, 0, r, rest));
    }
  }

  // Rank-deficient level: left factorisation of L = R^T (m x r) = V [U; 0].
  if (r < m) {
    auto Lm = left_[z(k)].block(0, 0, m, r);
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < r; ++i) Lm(j, i) = (i <= j) ? W_(c0 + i, s + j) : 0.0;
    auto& lt = leftTau_[z(k)];
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

bool HlsFactorization::factorSpanning(int k, int d, double rankTol, bool& structured) {
  const int s = start_[z(k)];
  const int m = act_[z(k)];
  const int c0 = col0_[z(k)];
  // The pivots' test. The standard factorisation finds the stage's full rank d when, in every
  // direction of its coordinates, some row's component exceeds rankTol times that row's norm;
  // the level's rows reach every direction with at least sigma_min(B) / sqrt(m). The pivots of
  // a column-pivoted QR estimate sigma_min(B), so they must exceed rankTol sqrt(m) times the
  // level's largest row norm by a wide margin (kSpanningMargin), and at least kSpanningPivot.
  double scale = 0.0;
  for (int j = 0; j < m; ++j) scale = std::max(scale, rowNorm_(colGid_[z(s + j)]));
  const double tol = std::max(kSpanningPivot, kSpanningMargin * rankTol) * std::sqrt(static_cast<double>(m)) * scale;
  // Rows that read none of the stage's coordinates (a fixed variable's, say) go last: no reflector
  // then mixes them with the others, so that their residual stays theirs alone and the others'
  // are exact where the standard factorisation has them exact.
  int* order = spanOrder_.data();
  int* zeros = spanAt_.data();  // (reset below, after the QR)
  int* unitAt = spanUnitAt_.data();
  int nonzero = 0, zero = 0;
  for (int j = 0; j < m; ++j) {
    unitAt[j] = singleNonzero(W_.col(s + j).data() + c0, d);
    if (unitAt[j] == -1) {
      zeros[zero++] = j;
    } else {
      order[nonzero++] = j;
    }
  }
  if (nonzero < d) return false;
  std::copy(zeros, zeros + zero, order + nonzero);
  // Structured stage (Options::spanning_structured): every coordinate i has a row that reads it
  // alone, with an entry above the pivot bound, and at most d / 2 rows are left over. The
  // coordinates' own rows go first, in the coordinates' order, then the others, then the zero
  // rows. A Householder QR without pivoting then keeps its reflectors to the coordinate's own row
  // and the other rows (the later own rows are zero in the column), and B^T B >= diag(v_i^2)
  // bounds sigma_min(B) by the smallest own entry from below: the pivot test holds a priori.
  structured = false;
  if (spanStructured_ && 2 * (nonzero - d) <= d) {
    int* owner = spanWhere_.data();  // (reset below, after the QR)
    std::fill(owner, owner + d, -1);
    int owned = 0;
    for (int q = 0; q < nonzero; ++q) {
      const int j = order[q], at = unitAt[j];
      if (at >= 0 && owner[at] < 0 && std::abs(W_(c0 + at, s + j)) > tol) {
        owner[at] = j;
        ++owned;
      }
    }
    if (owned == d) {
      structured = true;
      int* next = spanAt_.data();  // the zero rows are in order already
      std::copy(owner, owner + d, next);
      int q2 = d;
      for (int q = 0; q < nonzero; ++q) {
        const int j = order[q];
        if (unitAt[j] < 0 || owner[unitAt[j]] != j) next[q2++] = j;
      }
      std::copy(next, next + nonzero, order);
    }
  }
  auto Lm = left_[z(k)].block(0, 0, m, d);
  for (int i = 0; i < d; ++i)
    for (int q = 0; q < m; ++q) Lm(q, i) = W_(c0 + i, s + order[q]);
  auto& perm = spanPerm_[z(k)];
  for (int i = 0; i < d; ++i) perm[z(i)] = i;
  auto& lt = leftTau_[z(k)];
  if (structured) {
    const int p = nonzero - d;
    for (int i = 0; i < d; ++i) {
      Eigen::Map<Eigen::VectorXd> x(pivotRow_.data(), p + 1);
      x(0) = Lm(i, i);
      x.tail(p) = Lm.col(i).segment(d, p);
      double tau = 0.0, beta = 0.0;
      x.makeHouseholderInPlace(tau, beta);
      if (!(std::abs(beta) > tol)) return false;  // |beta| >= |v_i| > tol: not expected
      Lm(i, i) = beta;
      Lm.col(i).segment(d, p) = x.tail(p);
      lt(i) = tau;
      const auto ess = Lm.col(i).segment(d, p);
      for (int c = i + 1; c < d; ++c) {
        auto rest = Lm.col(c).segment(d, p);
        const double w = tau * (Lm(i, c) + ess.dot(rest));
        Lm(i, c) -= w;
        rest -= w * ess;
      }
    }
  }
  for (int i = 0; i < d && !structured; ++i) spanNorm_(i) = spanRef_(i) = Lm.col(i).norm();
  for (int i = 0; i < d && !structured; ++i) {
    // Pivot: the coordinate of largest remaining norm (ties: lowest index).
    int best = i;
    for (int c = i + 1; c < d; ++c)
      if (spanNorm_(c) > spanNorm_(best)) best = c;
    if (!(spanNorm_(best) > tol)) return false;
    if (best != i) {
      Lm.col(i).swap(Lm.col(best));
      std::swap(spanNorm_(i), spanNorm_(best));
      std::swap(spanRef_(i), spanRef_(best));
      std::swap(perm[z(i)], perm[z(best)]);
    }
    auto x = Lm.col(i).segment(i, m - i);
    double tau = 0.0, beta = 0.0;
    x.makeHouseholderInPlace(tau, beta);
    x(0) = beta;
    lt(i) = tau;
    if (!(std::abs(beta) > tol)) return false;
    const auto ess = Lm.col(i).segment(i + 1, m - i - 1);
    double* top = pivotRow_.data();
    for (int c = i + 1; c < d; ++c) {
      applyReflector(ess, tau, Lm.col(c).segment(i, m - i));
      top[c] = Lm(i, c);
    }
    const int first = i + 1;
    downdateNorms(d - first, top + first, spanNorm_.data() + first, spanRef_.data() + first, nullptr, nullptr, recompute_.data());
    for (int q = 0; q < d - first; ++q) {
      if (!recompute_[z(q)]) continue;
      const int c = first + q;
      spanNorm_(c) = spanRef_(c) = (m - i - 1 > 0) ? Lm.col(c).segment(i + 1, m - i - 1).norm() : 0.0;
    }
  }
  // The stage's columns in the order of Lm's rows (where[j]: the column now holding the original
  // column j; at[p]: the original column at position p).
  int* where = spanWhere_.data();
  int* at = spanAt_.data();
  for (int j = 0; j < m; ++j) where[j] = at[j] = j;
  for (int q = 0; q < m; ++q) {
    const int p = where[order[q]];
    if (p == q) continue;
    swapColumns(s + q, s + p, c0 + d);
    const int a = at[q];
    at[q] = order[q];
    at[p] = a;
    where[a] = p;
    where[order[q]] = q;
  }
  return true;
}

int HlsFactorization::spanningStages() const {
  int n = 0;
  for (int k = firstStage_; k < levelCount(); ++k) n += span_[z(k)] != 0 ? 1 : 0;
  return n;
}

int HlsFactorization::structuredStages() const {
  int n = 0;
  for (int k = firstStage_; k < levelCount(); ++k) n += span_[z(k)] == 2 ? 1 : 0;
  return n;
}

// Projected level k (the last, or with a projected unit suffix the one before it too): keeps its
// raw rows in column order (RawP_, from the first projected level's first column) for solve() and
// multipliers(), and writes their projection Z^T a onto the null space of the earlier levels,
// Z = Q_{<k} [0; I], into rows c0.. of its columns; factorLevel then factorises them as usual.
// Rows 0..c0 of these columns are not used.
void HlsFactorization::projectDeferredLevel(int k) {
  const int s = start_[z(k)];
  const int m = act_[z(k)];
  const int c0 = col0_[z(k)];
  const int d = nr_ - c0;
  if (m == 0) return;
  auto Raw = projectedRaw(k);
  Raw = W_.block(0, s, nr_, m);
  if (c0 == 0 || d == 0) return;  // no earlier reflector (Z = I), or nothing left to project on
  auto Z = Z_.block(0, 0, nr_, d);
  Z.setZero();
  // A unit vector at or below every earlier stage's last row (split coordinates: a force
  // coordinate that no velocity stage reaches) is left unchanged by all their reflectors, to the
  // bit: each would add exact zeros. It is not multiplied through them.
  int reach = 0;
  for (int j = firstStage_; j < k; ++j)
    if (refl_[z(j)] > 0) reach = std::max(reach, stageEnd_[z(j)]);
  for (int i = 0; i < d; ++i) {
    Z(c0 + i, i) = 1.0;
    if (c0 + i < reach) applyEarlierStagesQ(Z.col(i), k);
  }
  // A row with a single nonzero v at reduced coordinate i (a regularisation row x_j = 0 on a
  // non-basic variable) projects to v Z(i, :) + 0: the same bits as the matrix product Z^T a,
  // whose other terms are exact zeros and whose sum starts at +0 (hence the + 0, which turns a
  // -0 into +0); a zero row (on a variable fixed by its bound) projects to +0. When every row is
  // such a row (exp1's minimum-wrench rows before the Newton switch, its minimum-velocity rows
  // in a projected unit suffix), the product is skipped. Otherwise all rows go through one product: a product of
  // only the other rows would round them differently (Eigen's matrix-product kernel sums a
  // column's terms in an order that depends on its place among the columns). Only where Eigen
  // takes its matrix-product kernel (two or more rows, not a small coefficient-wise product).
  bool allSingle = m >= 2 && nr_ + d + m >= EIGEN_GEMM_TO_COEFFBASED_THRESHOLD;
  for (int j = 0; j < m && allSingle; ++j) {
    const int at = singleNonzero(Raw.col(j).data(), nr_);
    allSingle = at >= -1;
    if (at >= 0) W_.col(s + j).segment(c0, d) = (Raw(at, j) * Z.row(at).transpose()).array() + 0.0;
    if (at == -1) W_.col(s + j).segment(c0, d).setZero();  // a zero row: the product's +0
  }
  if (allSingle) return;
  // Z's columns from t on are unit vectors (at or below `reach`): row i of Z^T A is then row
  // c0 + i of A, + 0, to the bit in any order of summation (every other term is an exact zero,
  // and the product's sum starts at +0). Only the first t rows need the product. Eigen's kernel
  // sums a row's terms in an order that depends on which of its micro-kernels takes the row, so
  // the product keeps the rows of its widest micro-kernel that hold the first t rows (a multiple
  // of kProductRows, all inside that micro-kernel's part of the full product): the same bits as
  // the full product (test_solver, ProductOfLeadingColumnsKeepsTheFullProductsBits).
  const int lead = unitColumnProductRows(nr_, d, m, std::clamp(reach - c0, 0, d));
  if (lead < 0) {
    auto P = P_.block(0, 0, d, m);
    P.noalias() = Z.transpose() * Raw;
    W_.block(c0, s, d, m) = P;
    return;
  }
  if (lead > 0) {
    auto P = P_.block(0, 0, lead, m);
    P.noalias() = Z.leftCols(lead).transpose() * Raw;
    W_.block(c0, s, lead, m) = P;
  }
  W_.block(c0 + lead, s, d - lead, m) = Raw.middleRows(c0 + lead, d - lead).array() + 0.0;
}

void HlsFactorization::factorize(double rankTol) {
  const int L = levelCount();
  // StageTimes: read the clock only when attached (diagnostics; nothing below depends on it).
  using Clock = std::chrono::steady_clock;
  const auto us = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::micro>(b - a).count(); };
  Clock::time_point t0;
  // Adds the time since t0 to `into` and starts the next part there.
  const auto lap = [&t0, &us](double& into) {
    const auto t1 = Clock::now();
    into += us(t0, t1);
    t0 = t1;
  };
  if (times_) {
    t0 = Clock::now();
    ++times_->passes;
  }
  if (pendingVar_ >= 0) {
    // One variable fixed or freed since the last factorisation (setFreeVariables).
    const int v = pendingVar_;
    pendingVar_ = -1;
    int done = 0;
    if (elim_ && haveSnapshots_ && !fullLayout_ && dirtyFrom_ > firstStage_) {
      if (pendingFixed_) done = fixedNonBasicRestart(v);
      if (done == 0) done = forceChangeRestart(v);
    }
    if (done == 1)
      ++restartsTaken_;
    else
      invalidateAll();
  }
  if (dirtyFrom_ >= L) {
    lastRestart_ = L;
    if (times_) lap(times_->preparation_us);
    return;
  }
  // A restart needs the snapshots of its level; without them (lazy snapshots, first pass), the
  // factorisation starts over, saving them this time.
  if (dirtyFrom_ > 0 && !haveSnapshots_) {
    dirtyFrom_ = 0;
    snapshotsOn_ = true;
  }
  int c = dirtyFrom_;
  if (c == 0) {
    haveSnapshots_ = snapshotsOn_;
    snapshotsOn_ = true;
    for (int q = 0; q < static_cast<int>(colGid_.size()); ++q) {
      const int gid = colGid_[z(q)];
      if (gid >= 0) pos_[z(gid)] = -1;
      colGid_[z(q)] = -1;
    }
    std::fill(snapValid_.begin(), snapValid_.end(), 0);
    std::fill(rawHave_.begin(), rawHave_.end(), 0);
    fullLayout_ = true;
    if (updateElimination() || tryEliminate()) {
      ++stages_;
      nrElim_ = nf_ - m0_;
      firstStage_ = 1;
      nr_ = nf_ - m0_;
      rank_[0] = m0_;
      refl_[0] = 0;
      span_[0] = 0;
      act_[0] = m0_;
      start_[0] = 0;
      col0_[0] = 0;
      col0_[1] = 0;
      c = 1;
    } else {
      firstStage_ = 0;
      nr_ = nf_;
      col0_[0] = 0;
    }
    decideDeferral();
  } else if (c < firstStage_) {
    c = firstStage_;
  }
  lastRestart_ = dirtyFrom_;
  if (c < L) {
    if (times_) lap(times_->preparation_us);
    relayout(c);
    if (times_) lap(times_->layout_us);
    // The last snapshot taken in this pass while no stage has had active rows since: such a
    // stage changes nothing, so the next snapshot would hold the same columns with the same
    // entries, and shares its storage instead of copying them again (levels that are rarely
    // active, such as torque limits, trust region and collisions, follow one another).
    int untouchedSince = -1;
    for (int k = c; k < L; ++k) {
      if (projected(k)) {
        projectDeferredLevel(k);
      } else if (k > 0 && !static_[z(k)] && haveSnapshots_) {
        saveSnapshot(k, untouchedSince);
        untouchedSince = k;
      }
      factorLevel(k, rankTol);
      if (act_[z(k)] > 0) untouchedSince = -1;
      ++stages_;
      if (times_) {
        lap(times_->stage_us[z(k + timesOffset_)]);
        ++times_->stage_count[z(k + timesOffset_)];
      }
    }
  } else if (times_) {
    lap(times_->preparation_us);
  }
  fullLayout_ = false;
  dirtyFrom_ = L;
}

HlsFactorization::Stage HlsFactorization::stage(int k) const { return {act_[z(k)], start_[z(k)], col0_[z(k)], rank_[z(k)]}; }

void HlsFactorization::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, Eigen::VectorXd& res) {
  const int L = levelCount();
  auto y = work_.head(nr_);
  y.setZero();
  if (elim_) {
    // d = A_B^{-1} b_0 with A_B = U^T L1^T.
    auto d = d_.head(m0_);
    for (int i = 0; i < m0_; ++i) d(i) = b(active_[0][z(i)]);
    G_.topLeftCorner(m0_, m0_).triangularView<Eigen::Upper>().transpose().solveInPlace(d);
    G_.topLeftCorner(m0_, m0_).triangularView<Eigen::UnitLower>().transpose().solveInPlace(d);
    for (int gid : active_[0]) res(gid) = 0.0;
  }
  for (int k = firstStage_; k < L; ++k) {
    const auto [m, s, c0, r] = stage(k);
    if (m == 0) continue;
    auto t = t_.head(m);
    for (int j = 0; j < m; ++j) t(j) = b(colGid_[z(s + j)]);
    if (elim_) t.noalias() -= WB_.block(0, s, m0_, m).transpose() * d_.head(m0_);
    if (c0 > 0 && projected(k)) {
      // Projected level: a^T Q [y_0..c0; 0] from its raw rows.
      auto zv = zvec_.head(nr_);
      zv.head(c0) = y.head(c0);
      zv.tail(nr_ - c0).setZero();
      applyEarlierStagesQ(zv, k);
      t.noalias() -= projectedRaw(k).transpose() * zv;
    } else if (c0 > 0) {
      t.noalias() -= W_.block(0, s, c0, m).transpose() * y.head(c0);
    }
    if (r == m && !span_[z(k)]) {
      W_.block(c0, s, r, r).triangularView<Eigen::Upper>().transpose().solveInPlace(t);
      y.segment(c0, r) = t;
      for (int j = 0; j < m; ++j) res(colGid_[z(s + j)]) = 0.0;
    } else {
      const auto Lm = left_[z(k)].block(0, 0, m, r);
      const auto& lt = leftTau_[z(k)];
      for (int i = 0; i < r; ++i) applyReflector(Lm.col(i).segment(i + 1, m - i - 1), lt(i), t.segment(i, m - i));
      if (r > 0) {
        auto seg = t.head(r);
        Lm.topLeftCorner(r, r).triangularView<Eigen::Upper>().solveInPlace(seg);
        if (span_[z(k)]) {
          // A spanning stage's unknowns are its coordinates in their pivoted order.
          const auto& perm = spanPerm_[z(k)];
          for (int i = 0; i < r; ++i) y(c0 + perm[z(i)]) = seg(i);
        } else {
          y.segment(c0, r) = seg;
        }
      }
      auto w = u_.head(m);
      w.head(r).setZero();
      w.tail(m - r) = -t.tail(m - r);
      for (int i = r - 1; i >= 0; --i) applyReflector(Lm.col(i).segment(i + 1, m - i - 1), lt(i), w.segment(i, m - i));
      for (int j = 0; j < m; ++j) res(colGid_[z(s + j)]) = w(j);
    }
  }
  // Reduced solution x_N = Q y.
  applyEarlierStagesQ(y, L);
  if (!elim_) {
    for (int f = 0; f < nf_; ++f) x(freeVar_[z(f)]) = y(f);
    return;
  }
  // x_B = d - D x_N, with D^T stored below the pivots of G.
  auto xB = work2_.head(m0_);
  xB = d_.head(m0_);
  if (nr_ > 0) xB.noalias() -= G_.block(m0_, 0, nr_, m0_).transpose() * y;
  for (int i = 0; i < m0_; ++i) x(varPerm_[z(i)]) = xB(i);
  for (int f = 0; f < nr_; ++f) x(varPerm_[z(m0_ + f)]) = y(f);
}

Eigen::Block<Eigen::MatrixXd> HlsFactorization::projectedRaw(int k) {
  return RawP_.block(0, start_[z(k)] - start_[z(deferFrom_)], nr_, act_[z(k)]);
}

void HlsFactorization::addLeading(int k, const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> G) {
  const int m = act_[z(k)];
  const int c0 = col0_[z(k)];
  if (m == 0 || c0 == 0) return;
  if (projected(k)) {
    // A projected level (the last, or an earlier stage of it in a unit suffix): rows 0..c0 of
    // its columns are not formed; the first c0 coordinates of Q_{<k}^T (A_k^T u) from its raw rows.
    auto v = zvec_.head(nr_);
    v.noalias() = projectedRaw(k) * u;
    applyEarlierStagesTo(v, k);
    G.head(c0) += v.head(c0);
  } else {
    G.head(c0).noalias() += W_.block(0, start_[z(k)], c0, m) * u;
  }
}

void HlsFactorization::multipliers(int k, const Eigen::VectorXd& res, Eigen::Ref<Eigen::VectorXd> mu) {
  if (elim_ && k == 0) {
    for (int gid : active_[0]) mu(gid) = res(gid);
    return;
  }
  auto G = g_.head(nr_);
  G.setZero();
  {
    const int m = act_[z(k)];
    const int s = start_[z(k)];
    auto u = u_.head(m);
    for (int j = 0; j < m; ++j) {
      const int gid = colGid_[z(s + j)];
      u(j) = res(gid);
      mu(gid) = res(gid);
    }
    addLeading(k, u, G);
    if (elim_ && m > 0) {
      gB_.head(m0_).setZero();
      gB_.head(m0_).noalias() += WB_.block(0, s, m0_, m) * u;
    }
  }
  if (elim_ && act_[z(k)] == 0) gB_.head(m0_).setZero();
  for (int j = k - 1; j >= firstStage_; --j) {
    const auto [m, s, c0, r] = stage(j);
    if (m == 0) continue;
    auto u = u_.head(m);
    if (r == m && !span_[z(j)]) {
      u = -G.segment(c0, r);
      W_.block(c0, s, r, r).triangularView<Eigen::Upper>().solveInPlace(u);
    } else {
      const auto Lm = left_[z(j)].block(0, 0, m, r);
      const auto& lt = leftTau_[z(j)];
      u.setZero();
      if (r > 0) {
        auto top = u.head(r);
        if (span_[z(j)]) {
          const auto& perm = spanPerm_[z(j)];
          for (int i = 0; i < r; ++i) top(i) = -G(c0 + perm[z(i)]);
        } else {
          top = -G.segment(c0, r);
        }
        Lm.topLeftCorner(r, r).triangularView<Eigen::Upper>().transpose().solveInPlace(top);
      }
      for (int i = r - 1; i >= 0; --i) applyReflector(Lm.col(i).segment(i + 1, m - i - 1), lt(i), u.segment(i, m - i));
    }
    for (int i = 0; i < m; ++i) mu(colGid_[z(s + i)]) = u(i);
    addLeading(j, u, G);
    if (elim_) gB_.head(m0_).noalias() += WB_.block(0, s, m0_, m) * u;
  }
  if (elim_) {
    // Eliminated level: A_B^T mu_0 = -g_B with A_B^T = L1 U.
    auto mu0 = gB_.head(m0_);
    mu0 = -mu0;
    G_.topLeftCorner(m0_, m0_).triangularView<Eigen::UnitLower>().solveInPlace(mu0);
    G_.topLeftCorner(m0_, m0_).triangularView<Eigen::Upper>().solveInPlace(mu0);
    for (int i = 0; i < m0_; ++i) mu(active_[0][z(i)]) = mu0(i);
  }
}

}  // namespace lexdyn::solver
