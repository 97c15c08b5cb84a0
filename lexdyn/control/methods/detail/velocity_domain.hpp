// Internal to lexdyn/control/methods: what the velocity-domain methods (LexDynBFGS, LexDynAH,
// pure Gauss-Newton) share, and the reserved rows every method with second-order rows writes
// (docs/controller.md, "Newton augmentation").
//
// Every solver level holding a geometric task reserves nv rows when the method adds Newton or
// damping rows. VelocityDomainMethod fills them at each tick:
//  - with ControllerParams::damping = mu > 0: the constant Levenberg-Marquardt rows
//    mu u(k+1) = 0 on the occupied dofs (eq. 81);
//  - otherwise, for a method with Newton rows (newtonRows()), while the level is switched to
//    Newton (switchToNewton, eq. 95 on the previous tick's violation): R u(k+1) = 0 (eq. 35) or
//    R u(k) (eq. 62), R from factorLevel() of the subclass; prepareLevel() keeps a running
//    second-order term up to date at every tick (BFGS eq. 87-89), while a term computed afresh
//    (the analytic Hessian, eq. 21, 91) is built in factorLevel(), only for a switched level;
//  - otherwise the rows are free (never active: they cost nothing in the solver).
// The command is u(k+1), gamma = x_gamma / dt and q(k+1) by eq. 32 or eq. 73-76 (q_mod).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "lexdyn/control/method.hpp"

namespace lexdyn::control::methods {

/// A vector index from an int index.
inline size_t z(int i) { return static_cast<size_t>(i); }

/// The nv rows a level reserves, as views into the solver problem.
struct ReservedRows {
  Eigen::MatrixXd::RowsBlockXpr A;
  Eigen::VectorXd::SegmentReturnType lower, upper;
};
/// Views the level's reserved rows and frees them (0 x in [-inf, inf]). `written` >= 0: only the
/// first `written` rows' first nv columns can be nonzero (what the caller wrote since the rows
/// were last cleared), so only they are zeroed; -1: every entry is.
ReservedRows clearReservedRows(solver::Problem& problem, const SolverLevel& level, int nv, int written = -1);
/// Levenberg-Marquardt rows mu v = 0 (eq. 50, 81) on the dofs in `mask` (every dof when null),
/// in order, from the first reserved row.
void writeDampingRows(ReservedRows& rows, double mu, const std::vector<char>* mask);

/// One geometric task contributing to a level's hierarchical Hessian (eq. 21).
struct GeomTerm {
  int task = -1;
  int lambda_row = -1;  ///< first row of the task in the stacked rows of Result::lambda
  int rows = 0;
  bool equality = true;
  std::vector<int> chain;  ///< the task's chain dofs (TaskModel::chainDofs: they depend on the model only)
};

/// A level with reserved rows.
struct NewtonLevel {
  int level = -1;               ///< index into the controller's solver levels
  std::vector<GeomTerm> terms;  ///< geometric tasks of this level and of every earlier level
  std::vector<char> occupied;   ///< the I* of eq. 89, sec. VII (this tick)
  /// Reserved rows written at the last tick (on the velocity columns only); -1: not known.
  int written_rows = -1;
};

/// The Gauss-Newton term of a level's own task rows: the rows of the tasks of `level` with a
/// finite bound (equalities, engaged inequalities), on the velocity columns (nv), as the solver
/// holds them (TaskData::A; velocity-domain row scale 1). trace(J^T J), J^T J s, and J^T J added
/// to a matrix.
double levelGaussNewtonTrace(const SolverLevel& level, const MethodTick& tick, int nv);
void accumulateLevelGaussNewtonStep(const SolverLevel& level, const MethodTick& tick, const Eigen::Ref<const Eigen::VectorXd>& s,
                                    Eigen::Ref<Eigen::VectorXd> y);
void accumulateLevelGaussNewton(const SolverLevel& level, const MethodTick& tick, Eigen::Ref<Eigen::MatrixXd> H);

class VelocityDomainMethod : public ControlMethod {
 public:
  explicit VelocityDomainMethod(const ControllerParams& params) : params_(params) {}

  tasks::Domain domain() const override { return tasks::Domain::Velocity; }
  bool separatesLevels() const override { return true; }
  bool reservesRows(size_t level, bool geometric) const override;
  void setup(const MethodSetup& setup) override;
  void reset() override;
  void addRows(const MethodTick& tick, solver::Problem& problem, TickRecord& rec) override;
  void command(const RobotState& state, const Eigen::VectorXd& x, Command& cmd) override;
  void afterSolve(const MethodTick& tick) override;

 protected:
  /// Whether the method adds Newton rows (pure Gauss-Newton does not).
  virtual bool newtonRows() const { return false; }
  /// Per level at setup (e.g. its quasi-Newton matrix); `k` indexes levels().
  virtual void setupLevel(size_t k, NewtonLevel& level) { (void)k, (void)level; }
  virtual void resetLevels() {}
  /// Once per tick before the levels.
  virtual void beginTick(const MethodTick& tick) { (void)tick; }
  /// Per level with Newton rows, before switching, at every tick: brings a running second-order
  /// term up to date (BFGS). `have_lambda`: the previous tick's multipliers are there
  /// (multipliers()).
  virtual void prepareLevel(size_t k, NewtonLevel& level, const SolverLevel& sl, const MethodTick& tick, bool have_lambda,
                            TickRecord& rec) {
    (void)k, (void)level, (void)sl, (void)tick, (void)have_lambda, (void)rec;
  }
  /// Per augmented level, after prepareLevel() with the same arguments: R (rows x nv, R^T R the
  /// level's Hessian on its occupied dofs); returns rows. A second-order term computed afresh
  /// (the analytic Hessian) is built here, only for the levels that need it.
  virtual int factorLevel(size_t k, NewtonLevel& level, const SolverLevel& sl, const MethodTick& tick, bool have_lambda,
                          Eigen::MatrixXd& R) {
    (void)k, (void)level, (void)sl, (void)tick, (void)have_lambda, (void)R;
    return 0;
  }
  virtual void storePrevious(const MethodTick& tick) { (void)tick; }
  /// Per augmented level after factorLevel(): the value put on the occupied diagonal besides the
  /// method's curvature term (eps, alpha), so that R^T R = curvature + identityDiagonal I*.
  virtual double identityDiagonal(size_t k) const {
    (void)k;
    return 0.0;
  }

  /// Whether a term constrains the solution (equalities always, inequalities while engaged).
  static bool engaged(const GeomTerm& g, const tasks::TaskData& d);
  /// Multipliers of level `sl`'s term `g` at the previous solve in optimisation units (eq. 37:
  /// lambda_optim = dt lambda_ctrl; lambda_ctrl itself with multiplier_scale: one); zero
  /// without them.
  Eigen::VectorXd::SegmentReturnType multipliers(const GeomTerm& g, const SolverLevel& sl, const MethodTick& tick, bool have_lambda);

  ControllerParams params_;
  const model::RobotModel* model_ = nullptr;
  const ControllerConfig* config_ = nullptr;
  int nv_ = 0, ng_ = 0;
  bool have_prev_ = false;  ///< a previous tick exists (afterSolve ran since reset)

 private:
  std::vector<NewtonLevel> lv_;
  std::vector<int> stack_off_;  ///< problem level -> first stacked row (Result::lambda rows)
  Eigen::VectorXd w_;           ///< multipliers of one term
  Eigen::VectorXd qmod_;        ///< eq. 73-76
  Eigen::MatrixXd R_;
};

}  // namespace lexdyn::control::methods
