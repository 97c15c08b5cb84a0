// Lexicographic least-squares solver with equalities and inequalities on every level
// (docs/solver.md). Primal active-set method on the slack formulation
//     lexmin ||v_1||^2, ..., ||v_p||^2   s.t.  lower <= A x - v <= upper,
// whose equality sub-problems are hierarchical least-squares problems factorised by
// HlsFactorization. Warm start from a previous active set and x; the factorisation restarts
// from the level whose active set changed; optional termination rules of the paper
// (sec. VIII-B) and a hard iteration cap.
//
// Lifecycle (as OSQP): setup() validates and allocates; solve() allocates nothing for a problem
// of the sizes given to setup().
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lexdyn/solver/problem.hpp"

namespace lexdyn::solver {

/// State of one row in the active set. Lower / Upper: the row is held at that bound (it is
/// violated beyond it, or exactly on it). Equality rows (lower == upper) are always active.
enum class RowState : std::int8_t { Inactive = 0, Lower = 1, Upper = 2, Equality = 3 };

enum class Status {
  Solved,          ///< lexicographic optimum reached (or all slacks below the stop threshold)
  StoppedEarly,    ///< a paper termination rule stopped the search: earlier levels optimal, later sub-optimal
  IterationLimit,  ///< hard cap reached: x is the best feasible iterate (monotone primal iterates)
  NonFiniteInput,  ///< NaN in A or bounds, or infinite A: nothing solved (see Result::bad_level/bad_row)
  /// The arithmetic left the double range (x, a violation or a multiplier is inf or NaN, e.g.
  /// coefficients near 1e300): the result is not a solution and is never reported as optimal.
  NonFiniteResult,
};

enum class StopReason {
  Optimal,
  SlackBelowThreshold,
  OptimalityPhaseLimit,
  TotalIterationLimit,
  HardIterationCap,
  NonFiniteInput,
  NonFiniteResult,
};

const char* toString(Status s);
const char* toString(StopReason r);
const char* toString(RowState s);

struct Options {
  /// A row whose norm after projection into the null space of the earlier active rows is at most
  /// rank_tolerance times its own norm counts as linearly dependent. Rows with singular values
  /// down to ~1e-8 relative are treated exactly (no damping).
  double rank_tolerance = 1e-9;
  /// Blocking test: a row blocks the step only if its rate of change exceeds this, relative to
  /// |a| |dx| + |dv|.
  double feasibility_tolerance = 1e-12;
  /// A residual below zero_tolerance * (|b| + |a| |x|) counts as zero (the row is satisfied and
  /// stays an inequality for later levels); above, the row is frozen at its optimal violation.
  double zero_tolerance = 1e-10;
  /// A multiplier counts as having the wrong sign when it exceeds dual_tolerance relative to the
  /// level's gradient scale sum_j |v_j| |a_j|.
  double dual_tolerance = 1e-10;
  /// Eliminate a first general level made only of equality rows by Gaussian elimination with
  /// partial pivoting when every pivot exceeds elimination_tolerance times the largest entry of
  /// its row (well conditioned, full row rank); otherwise it is factorised orthogonally like the
  /// other levels. Exact either way; much cheaper for an equation-of-motion level.
  bool eliminate_first_level = true;
  double elimination_tolerance = 1e-6;
  /// Split coordinates (off: -1). When >= 0, the elimination stage prefers basic variables with
  /// index >= split_from_variable (in a controller's problem: the contact forces, which follow
  /// the velocities), falling back to the plain pivoting when they are not well conditioned; the
  /// reduced variables keep their order; and each level's stage works only on the rows its
  /// active rows reach. A level over velocities only then leaves the force coordinates alone.
  /// Exact up to rounding either way; it changes the rounding. Off in these defaults; on in the
  /// controller's (control::defaultSolverOptions: kSplitAtControllerForces, which the controller
  /// turns into its number of velocities); a case turns it off with
  /// `solver: {split_force_coordinates: false}`.
  int split_from_variable = -1;
  static constexpr int kSplitAtControllerForces = -2;
  /// How the last general level is factorised. Never: like the others (every earlier stage's
  /// reflectors are applied to its active rows). Always: its rows are projected once onto the
  /// null space left by the earlier levels through an explicit basis of it. Auto: projected when
  /// it has more active rows than that null space has dimensions (a regularisation level over
  /// many variables, where this saves most of the trailing updates). Exact either way.
  enum class LastLevel { Auto, Never, Always };
  LastLevel last_level_projection = LastLevel::Auto;
  /// Spanning stages. A level whose active rows each read one variable (a regularisation level
  /// such as x_j = 0 over a set of variables) and that spans every coordinate left to its stage
  /// (its rows determine them all: nothing is left for later levels there) is solved by one
  /// column-pivoted QR of its projected rows (the least-squares problem of the stage) instead of
  /// a rank-revealing QR of their transpose followed by a second, left QR, and its stage applies
  /// no reflectors to later levels. Accepted only when every pivot exceeds
  /// max(1e-6, 1e3 rank_tolerance) sqrt(rows) times the level's largest row norm (else the level
  /// is factorised as any other), so that both ways decide the rank alike; the answers then agree
  /// up to rounding. It changes the rounding.
  bool spanning_stages = false;
  /// Spanning stages for levels of any rows (with spanning_stages): a level whose active rows
  /// read several variables (a level of Newton rows over the velocities, say) is taken as a
  /// spanning stage too when it spans every coordinate left to its stage, under the same pivot
  /// test. The test's argument holds for any rows: every direction of the stage's coordinates is
  /// reached by some row with at least sigma_min / sqrt(rows) of it, relative to that row's norm.
  /// A level that declines (it does not span its stage) is not tried again within the solve as a
  /// level of such rows. It changes the rounding of such levels.
  bool spanning_any_rows = false;
  /// Structured spanning stages (with spanning_stages): a spanning stage whose rows hold, for
  /// each of its d coordinates, one row that reads that coordinate alone, and at most d / 2 other
  /// rows (the minimum-wrench level with split coordinates: a row per non-basic force, a dense
  /// row per basic one), is factorised by a Householder QR without pivoting, the coordinates' own
  /// rows first: each reflector then reads the coordinate's own row and the other rows only,
  /// 1 + d / 2 entries or fewer instead of up to m. Taken when every such row's entry exceeds the
  /// spanning stages' pivot bound: B^T B >= diag(entries^2), so the smallest entry bounds
  /// sigma_min(B) from below. It changes the rounding of such stages.
  bool spanning_structured = false;
  /// Lazy snapshots. A solve whose warm start is already optimal (most controller ticks)
  /// factorises once and never restarts, so the copies of the later levels' rows saved before
  /// each stage for restarts are not needed. With this option the first factorisation of a solve
  /// saves none; the first restart of the solve factorises from the first level again, saving
  /// them, and later restarts use them. The same bits on solves of one iteration; on the others,
  /// the restarted stages' rows are transformed as in a full factorisation rather than restored
  /// (rounding), and Result::factorizations counts the full factorisation.
  bool lazy_snapshots = false;
  /// Projected unit suffix. When the last level is projected (last_level_projection), the level
  /// before it is projected as well if its active rows have one nonzero each (x_j = 0, say; on
  /// any variable: a row on a basic variable of the first level's elimination is a column of D^T
  /// in reduced coordinates with its basic part), and it has more active rows than the null space
  /// that the earlier levels leave, counted as for the last level. Its rows then take none of the
  /// earlier stages' reflectors; they are projected once, Z^T a, when its turn comes. When the
  /// earlier levels have taken every coordinate that their stages reached (a level of Newton rows
  /// over all velocities, with split coordinates), the projection of its rows on reduced variables
  /// is a copy of exact zeros and they cost nothing. Decided per full factorisation. It changes
  /// the rounding of that level's multipliers, and of its rows where it keeps coordinates.
  bool project_unit_suffix = false;
  /// Restarts after a bound change. When an active-set step fixes a variable at its bound, or a
  /// release frees one, and the stages of the levels before some level c cannot be altered by
  /// the change (split coordinates: a force that no velocity level's rows read), the
  /// factorisation keeps those stages and restarts at c, as after an activation at level c,
  /// instead of factorising every level again (docs/solver.md, "Restarts after a bound change").
  /// The result is the same up to rounding (the restarted stages' rows are restored from the
  /// restart snapshots), and Result::factorizations counts the stages redone.
  bool restart_after_bound_change = true;
  /// Swap reflectors. A stage's Householder reflector of a column with one nonzero (a unit row
  /// on a reduced variable the earlier stages did not mix, as trust-region rows are) is
  /// I - v v^T with v = e_i + s e_j: it swaps coordinates i and j and negates them. With this
  /// option it is applied as that swap, exactly and reading two entries, to the stage's own
  /// columns and wherever the earlier stages are applied, and to the later levels' rows when
  /// every reflector of the stage is a swap (or the identity); without it, by the generic
  /// arithmetic, which rounds and reads the whole segment (docs/solver.md, "Swap reflectors").
  /// It changes the rounding where a stage has such reflectors.
  bool swap_reflectors = true;
  /// Hard cap on active-set iterations (equality sub-problems solved).
  int max_iterations = 1000;
  /// After this many consecutive zero-length steps, ties are broken by smallest index (Bland).
  int bland_after_degenerate_steps = 8;
  /// When a working set repeats within a solve (a cycle: no strict progress, typically numerical
  /// on ill-conditioned levels), the rank and dual tolerances are multiplied by this factor (up to
  /// 1e-6) for the rest of the solve, and ties go to the smallest index.
  double cycle_tolerance_factor = 100.0;
  /// Paper sec. VIII-B rules; disabled when <= 0.
  double stop_slack_norm = 0.0;        ///< stop when sum of squared slacks <= this (paper: 1e-12 dt^2)
  int stop_optimality_iterations = 0;  ///< stop after this many iterations in the optimality phase (paper: 10)
  int stop_total_iterations = 0;       ///< stop after this many iterations in total (paper: 30)
  /// The paper stops the search "once a certain level is optimal enough. Usually this would be the
  /// contact constraints" (sec. VIII-B). With stop_after_level = L >= 0 the two iteration rules
  /// above apply only once problem levels 0..L are known optimal (a dual check passed them);
  /// until then the search goes on (up to max_iterations). -1: they apply at any iteration.
  int stop_after_level = -1;
  bool compute_multipliers = true;  ///< fill Result::lambda
  /// Prints one line per active-set iteration to stderr (debugging; allocates).
  bool trace = false;

  /// The paper's settings for a control period dt: slack 1e-12 dt^2, 10 optimality-phase
  /// iterations, 30 in total.
  static Options paper(double dt);

  /// Throws lexdyn::InputError ("solver options: FIELD: expected ..., found ...") unless every
  /// field is within its range: tolerances finite in [0, 1e-2] (rank_tolerance > 0),
  /// elimination_tolerance in (0, 1], max_iterations and bland_after_degenerate_steps in
  /// [1, 1e6], cycle_tolerance_factor finite >= 1, stop_slack_norm finite, stop_* iteration
  /// counts >= 0, stop_after_level >= -1, a known last_level_projection. Solver::setup and
  /// Solver::setOptions call it.
  void validate() const;
};

struct ActiveSet {
  std::vector<std::vector<RowState>> level;  ///< [level][row]
  int activeCount() const;
};

struct Result {
  Status status = Status::Solved;
  StopReason reason = StopReason::Optimal;
  Eigen::VectorXd x;
  std::vector<Eigen::VectorXd> violation;  ///< [level](row): a x - clamp(a x, lower, upper)
  Eigen::VectorXd violation_norm;          ///< per level, Euclidean norm
  /// Lagrange multipliers (paper eq. 19-21): rows = all problem rows stacked level by level,
  /// column l = multipliers of the level-l problem. Column l holds the level's own residual
  /// (lambda_{l,l} = A_l x - b_l on its active rows) and the multipliers of the earlier levels'
  /// active rows; sum_i A_i^T lambda_{i,l} = 0. Sign: >= 0 on rows held at their upper bound,
  /// <= 0 at their lower bound.
  Eigen::MatrixXd lambda;
  ActiveSet active;
  std::vector<int> rank;  ///< rank of each level's active rows after projection (bounds level: fixed vars)
  int iterations = 0;     ///< active-set iterations (equality sub-problems solved)
  /// Level stages factorised in this solve, over all its iterations (a restart at level c of L
  /// factorises L - c stages; the elimination of the first level counts as one): a deterministic
  /// measure of the solve's work, machine-independent unlike its wall time.
  int factorizations = 0;
  /// Bound changes (a variable fixed or freed) after which this solve restarted after the stages
  /// the change leaves unchanged instead of factorising every level again
  /// (Options::restart_after_bound_change).
  int bound_change_restarts = 0;
  int optimality_iterations = 0;  ///< iterations since the first deactivation
  int activations = 0, deactivations = 0;
  /// Times a released constraint blocked again at once and was kept (anti-cycling safety net).
  int held_after_reblock = 0;
  /// Problem levels 0..optimal_through are optimal at x (known from the last dual check); the
  /// last level when Solved with StopReason::Optimal; -1 when nothing is known (e.g. stopped in
  /// the primal phase).
  int optimal_through = -1;
  /// Cycles detected (a working set repeated) and broken by raising the tolerances, or by a
  /// cold restart (below).
  int cycles_broken = 0;
  /// Searches started again from the cold start within this solve: working sets kept repeating
  /// with the tolerances already raised as far as they go (at most 1; docs/solver.md,
  /// "Anti-cycling").
  int cold_restarts = 0;
  /// The last factorisation projected the last level (Options::last_level_projection).
  bool last_level_projected = false;
  /// Levels the last factorisation projected: 0, 1 (the last) or 2 (with
  /// Options::project_unit_suffix, the level before it too).
  int projected_levels = 0;
  /// The last factorisation's elimination took its basic variables from split_from_variable on.
  bool split_applied = false;
  /// Stages of the last factorisation solved as spanning stages (Options::spanning_stages).
  int spanning_stages = 0;
  /// Of those, the structured ones (Options::spanning_structured).
  int structured_stages = 0;
  int bad_level = -1, bad_row = -1;  ///< NonFiniteInput location
};

/// Wall-clock time of the factorisation's parts, summed over the solves of a solver while it is
/// attached (Solver::setStageTimes): a diagnostic for benchmarks (`lexdyn-solve --bench
/// --stage-times`). The clock is read only while one is attached, and nothing of a solve depends
/// on it. Levels are the problem's; a bounds level has no stage (its rows fix variables).
struct StageTimes {
  long passes = 0;                ///< factorisation passes (each factorises from its first changed stage on)
  double preparation_us = 0.0;    ///< before the stages: the first level's elimination or its update, a restart's bookkeeping
  double layout_us = 0.0;         ///< the active rows of the stages to factorise: gathered, transformed, restored
  std::vector<double> stage_us;   ///< [problem level]: its stage's factorisations (a projected level's projection included)
  std::vector<long> stage_count;  ///< [problem level]: how many times its stage was factorised
};

class Solver {
 public:
  Solver();
  ~Solver();
  Solver(Solver&&) noexcept;
  Solver& operator=(Solver&&) noexcept;

  /// Validates the problem's structure (throws lexdyn::InputError) and allocates everything.
  void setup(const Problem& problem, const Options& options = Options{});
  const Options& options() const;
  void setOptions(const Options& options);

  /// Cold solve (x0 = 0 projected on the bounds; only equality rows active).
  const Result& solve(const Problem& problem);
  /// Warm solve from an active set and an x (e.g. the previous tick's result; passing this
  /// solver's own result() is allowed).
  const Result& solve(const Problem& problem, const ActiveSet& warm, const Eigen::VectorXd& xWarm);
  const Result& result() const;
  /// Exchanges the last result with `r` without copying: `r` gets the result, and result() holds
  /// r's former contents, whose buffers the next solve reuses (giving them the problem's shape
  /// first if they lack it; any Result will do, e.g. an empty one or an earlier result of this
  /// solver). For a caller that keeps every result and recycles their buffers (the Python
  /// bindings); the controller's loop never calls it.
  void swapResult(Result& r);
  /// Attaches `times` (nullptr detaches): each factorisation adds its parts' wall-clock times to it,
  /// sized to the problem's levels at the next solve. Diagnostics only; the solve is the same.
  void setStageTimes(StageTimes* times);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lexdyn::solver
