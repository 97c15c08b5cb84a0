// Hierarchical factorisation of the active rows of a lexicographic least-squares problem (the
// equality-only sub-problem solved at each active-set iteration; docs/solver.md).
//
// Optional elimination stage. When the first general level is made of equality rows only and
// they are well conditioned with full row rank, it is eliminated by Gaussian elimination with
// partial pivoting: choosing m0 basic variables B, x_B = d - D x_N, and every later row a becomes
// a_N - D^T a_B on the remaining (reduced) variables x_N. This is exact, costs far less than the
// orthogonal factorisation of that level and of its trailing update, and is declined (the level
// is factorised like the others) when a pivot is small relative to its row.
//
// Orthogonal stages. Level by level, the active rows of level k, projected into the null space of
// the active rows of earlier levels, are factorised by a Householder QR with column pivoting of
// their transpose (rank-revealing: a row counts as dependent when its projected norm is at most
// rankTol times its own norm). The reflectors are applied to the rows of all later levels
// (blocked, compact WY). A level whose projected rows are rank deficient gets a second, left
// orthogonal factorisation so that its least-squares residual is exact.
//
// Storage is column-oriented: each active row is a column of `W_` (rows = reduced variables).
// Before each orthogonal stage k, the part of the later columns that stages >= k overwrite is
// saved, so that after an active-set change at level c the factorisation restarts at level c and
// reuses everything computed for levels < c (paper sec. VIII-B).
//
// All storage is allocated in setup(); factorize(), solve() and multipliers() allocate nothing.
#pragma once

#include <Eigen/Core>
#include <vector>
#include <utility>

namespace lexdyn::solver {

struct StageTimes;

class HlsFactorization {
 public:
  /// The projected level's product Z^T A (Z: nr x d, A: nr x m) when Z's columns from t on are
  /// unit vectors (column i at row nr - d + i): how many leading rows the matrix product computes
  /// (the others are rows of A + 0, the same bits), or -1 when it computes them all.
  static int unitColumnProductRows(int nr, int d, int m, int t);
  /// A stage's trailing update in compact-WY form, C <- C - V (T^T (V^T C)) (V: d x r, T: r x r
  /// upper triangular, C: d x n; Y and Y2: r x n scratch). Whole groups of gebp's nr columns
  /// (counted from C's first column) that are exactly zero are left out when the rest can still
  /// go through Eigen's matrix-product kernel: such columns come out unchanged from the full
  /// update (every term is +-0, the kernel sums from +0, and c - (+0) is c, signed zeros
  /// included), and the other columns keep their places in the kernel's panels, hence its order
  /// of summation. Every bit is that of the full update. Returns the columns multiplied.
  static int blockReflectorUpdate(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXd>& T,
                                  Eigen::Ref<Eigen::MatrixXd> C, Eigen::Ref<Eigen::MatrixXd> Y, Eigen::Ref<Eigen::MatrixXd> Y2);

  /// n: variables; rowsPerLevel: rows of each general level. Rows are addressed by a global id
  /// gid = rowOffset(level) + row, and vectors b / res / mu are indexed by gid.
  void setup(int n, const std::vector<int>& rowsPerLevel);

  /// Sets the original rows of general level k (pointer kept; must outlive the calls), with the
  /// count of leading columns that hold its nonzero entries (Level::columns; -1: all of them).
  void setLevelMatrix(int k, const Eigen::MatrixXd* A, int columns = -1) {
    A_[static_cast<size_t>(k)] = A;
    cols_[static_cast<size_t>(k)] = columns;
  }
  /// Adds each factorisation's parts' wall-clock times to `times` (nullptr: none), its stage of
  /// level k at entry k + levelOffset (sized by the caller).
  void setStageTimes(StageTimes* times, int levelOffset) {
    times_ = times;
    timesOffset_ = levelOffset;
  }
  /// rn = the Euclidean norms of the rows of A, whose entries past its first `columns` columns
  /// are zero (-1: no such knowledge). The same bits as over every column: Eigen sums a row's
  /// squares from the first column on in groups of four after the first, so the sum over the
  /// leading 4 q + 1 columns that hold the nonzero ones and lie within the full sum's groups adds
  /// the same terms in the same order, and the full sum only adds exact zeros after them.
  static void rowNorms(const Eigen::Ref<const Eigen::MatrixXd>& A, int columns, Eigen::Ref<Eigen::VectorXd> rn);
  /// Recomputes the original row norms (call after the row data changed). With `runs`, only
  /// the rows of level k's runs [b, e) (level-relative, in pairs at runs[runsOff[k] ..
  /// runsOff[k + 1])) are computed; the others are left 0 or a norm, for rows that no stage or
  /// test reads (free rows). Each run is widened to start and end on a 16-byte boundary of the norms (unless at
  /// the level's ends), so that each row's norm takes the same path (two rows at a time, or
  /// alone) as in the level's whole computation: the same bits (RowNormsOfRunsKeepTheBits).
  void computeRowNorms(const std::vector<int>* runs = nullptr, const std::vector<int>* runsOff = nullptr);
  const Eigen::VectorXd& rowNorms() const { return rowNorm_; }

  /// Allows the elimination stage for general level 0 (all its rows are equalities, always
  /// active). elimTol: smallest accepted pivot relative to the largest entry of its row.
  void setElimination(bool allowed, double elimTol) {
    elimAllowed_ = allowed;
    elimTol_ = elimTol;
  }
  /// Split coordinates from variable `from` on (-1: off; Options::split_from_variable).
  void setSplit(int from) { split_ = from; }
  /// Spanning stages (Options::spanning_stages); anyRows: for levels of any rows too
  /// (Options::spanning_any_rows), not only of rows that read one free variable; structured:
  /// structured spanning stages (Options::spanning_structured).
  void setSpanning(bool allowed, bool anyRows = false, bool structured = false) {
    spanAllowed_ = allowed;
    spanAnyRows_ = anyRows;
    spanStructured_ = structured;
  }
  /// Lazy snapshots (Options::lazy_snapshots): the first factorisation after clearActive() saves
  /// no restart snapshots; a later restart at a level c > 0 then factorises from the first level
  /// again, saving them.
  void setLazySnapshots(bool lazy) { lazy_ = lazy; }
  /// Projected unit suffix (Options::project_unit_suffix): when the last level is projected, the
  /// level before it is projected too if its active rows are unit rows (one nonzero each, on any
  /// variable) and projection pays for it by the same row count (decided per full factorisation).
  void setProjectUnitSuffix(bool on) { unitSuffix_ = on; }
  /// Levels the last factorisation projected (0, 1 or 2).
  int projectedLevels() const { return deferFrom_ < 0 ? 0 : levelCount() - deferFrom_; }
  /// Stages of the last factorisation solved as spanning stages.
  int spanningStages() const;
  /// Of those, the structured ones (Options::spanning_structured).
  int structuredStages() const;
  /// True when the last elimination took its basic variables from the split's preferred ones.
  bool splitApplied() const { return elim_ && splitApplied_; }
  /// How the last level is factorised. Standard: like every other level (each earlier stage's
  /// reflectors are applied to its rows). Projected: its rows are kept in reduced coordinates
  /// and projected once onto the null space left by the earlier levels, Z^T a with Z formed
  /// explicitly; cheaper when the level has more active rows than that null space has dimensions
  /// (a regularisation level over many variables). Auto chooses per full factorisation.
  enum class LastLevel { Auto, Standard, Projected };
  void setLastLevelMode(LastLevel mode) { lastMode_ = mode; }
  /// True when the last factorisation projected the last level.
  bool lastLevelProjected() const { return deferred_ >= 0; }
  /// Declares level k static (only equality rows: its active set never changes, so it is never
  /// a restart point and needs no snapshot).
  void setStaticLevel(int k, bool isStatic) { static_[static_cast<size_t>(k)] = isStatic ? 1 : 0; }
  /// True when the last full factorisation eliminated level 0.
  bool eliminated() const { return elim_; }

  /// Declares the free variables (those not fixed by an active bound, in increasing order).
  /// Invalidates everything, unless the only change since a factorisation is one variable fixed
  /// or freed and restarts after a bound change are on: factorize() then restarts after the
  /// stages the change leaves unchanged, when there are such stages (docs/solver.md, "Restarts
  /// after a bound change").
  void setFreeVariables(const std::vector<int>& freeVar, int nFree);
  /// Restarts after a bound change (Options::restart_after_bound_change); on by default.
  void setBoundChangeRestarts(bool on) { boundRestarts_ = on; }
  /// Swap reflectors (Options::swap_reflectors); on by default.
  void setSwapReflectors(bool on) { swaps_ = on; }

  /// Active-row bookkeeping. Marks the level dirty; factorize() restarts from the lowest dirty level.
  void activate(int k, int row);
  void deactivate(int k, int row);
  void clearActive();
  bool isActive(int gid) const { return inList_[static_cast<size_t>(gid)] != 0; }
  /// Forces a full refactorisation (the row data changed).
  void invalidateAll();

  /// Factorises from the lowest dirty level.
  void factorize(double rankTol);
  /// The level the last factorize() restarted from (levelCount() when nothing was redone).
  int lastRestartLevel() const { return lastRestart_; }
  /// Level stages factorised since setup (the elimination of the first level counts as one):
  /// a deterministic measure of the factorisation work (Result::factorizations).
  long stagesFactorized() const { return stages_; }
  /// Restarts after a bound change taken since setup (Result::bound_change_restarts).
  long boundChangeRestarts() const { return restartsTaken_; }

  /// Solves the equality hierarchy of the active rows with targets b(gid) (fixed-variable
  /// contributions already removed): writes the free variables' entries of x (variable space;
  /// fixed entries untouched) and the residual A x - b of every active row into res(gid)
  /// (exactly 0 on levels of full rank).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, Eigen::VectorXd& res);

  /// Multipliers of the level-k problem (paper eq. 19-21): mu(gid) for the active rows of levels
  /// j <= k, with mu = res on level k and sum_j A_j^T mu_j = 0 on the free variables (min-norm
  /// multipliers on rank-deficient levels). Entries of other rows are left untouched.
  void multipliers(int k, const Eigen::VectorXd& res, Eigen::Ref<Eigen::VectorXd> mu);

  int levelCount() const { return static_cast<int>(m_.size()); }
  int rowOffset(int k) const { return rowOff_[static_cast<size_t>(k)]; }
  int levelOf(int gid) const { return levelOf_[static_cast<size_t>(gid)]; }
  int activeCount(int k) const { return static_cast<int>(active_[static_cast<size_t>(k)].size()); }
  int rank(int k) const { return rank_[static_cast<size_t>(k)]; }
  int totalRank() const;
  int freeCount() const { return nf_; }
  /// Active rows of level k in the solver's order (global ids).
  const std::vector<int>& activeList(int k) const { return active_[static_cast<size_t>(k)]; }

 private:
  bool tryEliminate();
  bool eliminateOnce(bool preferSplit);
  void sortReducedVariables(int m0, int nr);
  bool updateElimination();
  void gatherLevel(int j, int p0, int p1, Eigen::MatrixXd& S, Eigen::MatrixXd& SB);
  int colGidTmp(int q) const { return tmpGid_[static_cast<size_t>(q)]; }
  /// x <- H x for the reflector of physical column col, whose segment starts at row top (len
  /// rows): the exact swap where unitAt_ names one, else the generic arithmetic.
  template <typename X>
  void applyStageReflector(int col, int top, int len, X&& x) const;
  /// col <- Q_{<stages}^T col (the reflectors of the orthogonal stages before `stages`).
  void applyEarlierStagesTo(Eigen::Ref<Eigen::VectorXd> col, int stages) const;
  /// col <- Q_{<stages} col.
  void applyEarlierStagesQ(Eigen::Ref<Eigen::VectorXd> col, int stages) const;
  void relayout(int c);
  /// factorize() after setFreeVariables() changed variable v alone: 1 when a restart at a level
  /// after the first general one is prepared (dirtyFrom_), 0 when not applicable (nothing
  /// changed), -1 when declined after the elimination changed (everything is to be redone).
  int fixedNonBasicRestart(int v);
  int forceChangeRestart(int v);
  int firstStageReaching(int from) const;
  template <class F>
  void editSnapshotsUpTo(int c, F&& fn);
  bool sameLayoutAfterElimination(int deferredOld, int deferFromOld);
  /// shareWith >= 0: a snapshot taken earlier in this factorisation, with only stages without
  /// active rows since (the same columns and entries): its storage is shared, not copied.
  void saveSnapshot(int k, int shareWith);
  /// Swaps columns a and b of the layout; W_'s entries in their first `rows` rows only (the
  /// stage's rows below are zero in both).
  void swapColumns(int a, int b, int rows);
  /// The column-pivoted QRs' norm downdates after a reflector (orig and ratio may be null: no
  /// pivot ratios).
  static void downdateNorms(int cnt, const double* w, double* nrm, const double* ref, const double* orig, double* ratio, char* recompute);
  void factorLevel(int k, double rankTol);
  /// Stage k (rows c0 .. c0 + d of its m >= d columns) as a spanning stage: the QR of its rows
  /// B^T (m x d) into left_[k], column-pivoted, or structured (Options::spanning_structured: a row
  /// of its own per coordinate first, no pivoting); false (the stage's columns unchanged) when a
  /// pivot is too small for rankTol. structured: set when it took the structured QR.
  bool factorSpanning(int k, int d, double rankTol, bool& structured);
  void projectDeferredLevel(int k);
  /// Projected level k's raw rows in RawP_, in its current column order.
  Eigen::Block<Eigen::MatrixXd> projectedRaw(int k);
  /// G.head(c0) += the first c0 = col0_[k] coordinates of Q_{<k}^T (A_k^T u): from level k's
  /// transformed rows, or from a projected level's raw rows (multipliers()).
  void addLeading(int k, const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> G);
  void decideDeferral();

  int n_ = 0;
  int nf_ = 0;  // free variables
  int nr_ = 0;  // reduced variables (rows of W_ in use): nf_ - m0 when level 0 is eliminated
  int mTot_ = 0;
  std::vector<int> m_, rowOff_, levelOf_;
  std::vector<const Eigen::MatrixXd*> A_;
  std::vector<int> cols_;  ///< per level: leading columns that hold the nonzero entries (-1: all)
  std::vector<int> gatherIdx_;
  std::vector<Eigen::Index> gatherOff_;  ///< gatherLevel: column offsets in A of the variables read
  std::vector<int> gatherPos_;           ///< gatherLevel: their positions, then those of declared zeros
  std::vector<char> static_;
  Eigen::VectorXd rowNorm_;
  std::vector<int> freeVar_;

  // Current active lists (solver order).
  std::vector<char> inList_;
  std::vector<std::vector<int>> active_;

  // Elimination of level 0: P G = [L1; L2] U with G = A_0^T (free variables x active rows);
  // the lower part of G_ holds D^T = L2 L1^{-1} after factorisation.
  bool elimAllowed_ = false;
  int split_ = -1;
  bool splitApplied_ = false;
  double elimTol_ = 1e-6;
  bool elim_ = false;
  int m0_ = 0;
  int firstStage_ = 0;
  Eigen::MatrixXd G_;
  std::vector<int> varPerm_;  // position -> variable id; first m0_ basic, then reduced coordinates
  std::vector<char> isFree_, flag_;
  std::vector<int> newOrder_, varTmp_;
  Eigen::MatrixXd DTs_;
  bool elimDataValid_ = false;
  int nrElim_ = 0;
  std::vector<int> transp_;  // LU row transpositions
  Eigen::MatrixXd WB_;       // basic-variable part of each active row (per physical column)
  Eigen::VectorXd d_, gB_;

  // Layout of the last factorisation: active columns of levels >= firstStage_, contiguous.
  Eigen::MatrixXd W_;
  std::vector<int> start_, act_, col0_, rank_;
  std::vector<int> stageEnd_;  // stage k works on rows col0_[k] .. stageEnd_[k] (nr_ unless split)
  // Spanning stages: span_[k] set when stage k is one (2: a structured one) (then it stores no reflectors in W_: its
  // columns keep the rows B of the stage's coordinates, and left_[k] holds the QR of B^T with the
  // coordinate order spanPerm_[k]); refl_[k] reflectors stored in W_ (rank_[k], or 0).
  bool spanAllowed_ = false;
  bool spanAnyRows_ = false;
  std::vector<char> spanDeclined_;  // per level: its spanning attempt declined in this solve (new data clears it)
  bool spanStructured_ = false;
  std::vector<char> span_;
  std::vector<int> refl_;
  std::vector<std::vector<int>> spanPerm_;
  std::vector<char> unitRow_;                        // per gid: the row's original entries have a single nonzero
  Eigen::VectorXd spanNorm_, spanRef_;               // factorSpanning: column norms (current, at the last recomputation)
  std::vector<int> spanOrder_, spanWhere_, spanAt_;  // factorSpanning: the stage's column order
  std::vector<int> spanUnitAt_;                      // factorSpanning: per column, its single nonzero's coordinate (-1 none, -2 several)
  // Stage k of that layout: m active columns from physical column s, its rows from c0, rank r.
  struct Stage {
    int m, s, c0, r;
  };
  Stage stage(int k) const;
  std::vector<int> colGid_;  // physical column -> gid
  std::vector<int> pos_;     // gid -> physical column or -1
  Eigen::VectorXd tau_, colNorm_, colNormRef_, colOrig_;
  // Per physical column, like tau_: a stage's reflector that swaps two coordinates (its column was
  // a unit vector there): the offset j >= 1 of ess's one nonzero, +-1, in the reflector's segment,
  // with tau 1; 0 for any other reflector.
  std::vector<int> unitAt_;

  // Snapshot k: rows [col0_k, nr) of the columns of levels >= k before stage k.
  std::vector<Eigen::MatrixXd> snap_;
  std::vector<std::vector<int>> snapCol_;   // [k][gid] -> snapshot column or -1
  std::vector<std::vector<int>> snapGids_;  // [k] gids present in snapshot k
  std::vector<char> snapValid_;
  std::vector<int> snapStore_;   // [k] whose storage (snap_) snapshot k's columns are in
  std::vector<char> storeDone_;  // bound-change restarts: snapshot storage already updated
  std::vector<int> velOrder_;    // forceChangeRestart: the velocities' reduced order before
  int pendingVar_ = -1;          // the variable setFreeVariables() fixed or freed since the last factorize() (-1: none)
  bool pendingFixed_ = false;    // ... fixed (else freed)
  bool boundRestarts_ = true;
  bool swaps_ = true;  // Options::swap_reflectors

  // Rank-deficient levels: L = R^T (m x r) = V [U; 0], stored Householder-style.
  std::vector<Eigen::MatrixXd> left_;
  std::vector<Eigen::VectorXd> leftTau_;

  // Workspaces.
  Eigen::MatrixXd S_, SB_, Vw_, T_, Y_, Y2_;
  Eigen::VectorXd work_, work2_, g_, t_, u_;
  Eigen::VectorXd ratio_, pivotRow_;  // factorLevel: pivot ratios, the reflector row's entries
  std::vector<char> recompute_;       // factorLevel: norms to compute again
  std::vector<int> tmpGid_;           // relayout: gid of each scratch column
  std::vector<int> sparseB_;          // per loaded column: -2 dense basic part, -1 zero, else its one index

  // Projected levels, deferFrom_ .. L-1 (deferred_ = the last level's index when it is
  // projected, deferFrom_ = the first projected level; -1: none): raw reduced rows by row from the
  // first projected level's first row (RawB_: their basic part), valid where rawHave_; RawP_: the
  // raw rows in their current physical column order, from the first projected level's first
  // column; Z_: the null-space basis of the earlier levels of the level being projected (rows
  // c0.. of Q).
  LastLevel lastMode_ = LastLevel::Auto;
  int deferred_ = -1;
  int deferFrom_ = -1;
  bool unitSuffix_ = false;  // Options::project_unit_suffix
  bool projected(int k) const { return deferFrom_ >= 0 && k >= deferFrom_; }
  bool projectionPays(int k) const;  // decideDeferral's row-count test for level k
  // Every active row of level k has at most one nonzero (over its declared columns), on any
  // variable (a reduced one, a basic one of the elimination, or one fixed by a bound: a zero row
  // in reduced coordinates). A row with a second nonzero on a fixed variable is refused
  // (conservative).
  bool unitRows(int k) const;
  Eigen::MatrixXd Raw_, RawB_, RawP_, Z_, P_;
  std::vector<char> rawHave_;
  Eigen::VectorXd zvec_;

  bool fullLayout_ = false;     // the next relayout follows a full reset
  bool lazy_ = false;           // Options::lazy_snapshots
  bool snapshotsOn_ = true;     // the next full factorisation saves restart snapshots
  bool haveSnapshots_ = false;  // the current layout's stages saved theirs
  int dirtyFrom_ = 0;
  int lastRestart_ = 0;
  long stages_ = 0;
  long restartsTaken_ = 0;
  StageTimes* times_ = nullptr;  // setStageTimes
  int timesOffset_ = 0;
};

}  // namespace lexdyn::solver
