#include "lexdyn/control/methods/wls.hpp"

#include <algorithm>
#include <cmath>

#include "lexdyn/common/error.hpp"
#include "lexdyn/control/methods/detail/velocity_domain.hpp"

namespace lexdyn::control::methods {

namespace {

class Wls final : public ControlMethod {
 public:
  explicit Wls(const ControllerParams& p) : params_(p) {}

  tasks::Domain domain() const override { return tasks::Domain::Acceleration; }
  // Each tick's rows only: no second-order term from earlier ticks.
  bool readsPreviousJacobians() const override { return false; }

  void checkLevels(const ControllerConfig& cfg) const override {
    if (cfg.levels.size() != 2) {
      throw InputError("controller.levels", "the WLS baseline needs exactly two levels (hard constraints, weighted objective)");
    }
  }

  double rowScale(const LevelSpec& ls, size_t level, size_t k) const override {
    if (level != 1) return 1.0;
    const double w = ls.weights.empty() ? 1.0 : ls.weights[k];
    if (!(w > 0.0)) throw InputError("level \"" + ls.name + "\"", "weights must be positive");
    return std::sqrt(w);
  }

  bool reservesRows(size_t level, bool geometric) const override {
    (void)geometric;
    return params_.damping > 0.0 && level == 1;  // eq. 50 on the objective
  }

  void setup(const MethodSetup& s) override {
    model_ = &s.model;
    nv_ = s.model.nv();
    ng_ = s.layout.ng();
    for (size_t k = 0; k < s.levels.size(); ++k) {
      if (s.levels[k].config_level == 0 && hard_level_ < 0) hard_level_ = s.levels[k].problem_level;
      if (s.levels[k].augmentable) damped_.push_back(static_cast<int>(k));
    }
    q_step_.setZero(nv_);
  }

  void reset() override {}

  void addRows(const MethodTick& tick, solver::Problem& problem, TickRecord& rec) override {
    for (int k : damped_) {
      const SolverLevel& L = tick.levels[z(k)];
      ReservedRows spare = clearReservedRows(problem, L, nv_);
      writeDampingRows(spare, params_.damping, nullptr);  // eq. 50: mu udot = 0
      rec.level_augmented[z(L.config_level)] = 1;
    }
  }

  void command(const RobotState& s, const Eigen::VectorXd& x, Command& cmd) override {
    const double dt = params_.dt;
    cmd.udot = x.head(nv_);
    cmd.gamma = x.tail(ng_);
    cmd.u = s.u + dt * cmd.udot;
    q_step_ = s.u + 0.5 * dt * cmd.udot;  // eq. 57: q + dt u + dt^2/2 udot
    model_->integrate(s.q, q_step_, dt, cmd.q);
  }

  TickStatus checkSolution(const solver::Problem& problem, const solver::Result& r, TickStatus st) const override {
    if (hard_level_ < 0) return st;
    // The hard level must be feasible (the paper's LSSOL has no relaxation).
    const int hl = hard_level_;
    const double viol = r.violation_norm(hl);
    // Relative to the size of the level's finite bounds.
    const solver::Level& pl = problem.level(hl);
    double scale = 1.0;
    for (int k = 0; k < pl.rows(); ++k) {
      if (std::isfinite(pl.lower(k))) scale = std::max(scale, std::abs(pl.lower(k)));
      if (std::isfinite(pl.upper(k))) scale = std::max(scale, std::abs(pl.upper(k)));
    }
    if (viol > params_.wls_infeasibility_tolerance * scale) return TickStatus::Infeasible;
    return st;
  }

 private:
  ControllerParams params_;
  const model::RobotModel* model_ = nullptr;
  int nv_ = 0, ng_ = 0;
  int hard_level_ = -1;      // problem level of the hard constraints (configured level 0)
  std::vector<int> damped_;  // solver levels with reserved rows
  Eigen::VectorXd q_step_;
};

}  // namespace

MethodInfo wlsMethod() {
  return {"wls", "WLS: acceleration domain, two-level weighted QP (the paper's LSSOL baseline)", true, &makeMethodOf<Wls>};
}

}  // namespace lexdyn::control::methods
