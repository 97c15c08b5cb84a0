#include "lexdyn/control/methods/lexdyn_bfgs.hpp"

#include <algorithm>
#include <cmath>

#include "lexdyn/control/methods/detail/velocity_domain.hpp"
#include "lexdyn/hessian/bfgs.hpp"

namespace lexdyn::control::methods {

namespace {

class LexDynBfgs final : public VelocityDomainMethod {
 public:
  explicit LexDynBfgs(const ControllerParams& p) : VelocityDomainMethod(p) {}

 protected:
  bool newtonRows() const override { return true; }

  void setupLevel(size_t k, NewtonLevel& level) override {
    (void)k;
    if (qn_.empty()) {
      // First augmentable level: the per-tick buffers.
      for (Eigen::VectorXd* v : {&u_prev_, &s_, &y_, &rhs_, &acc_}) v->setZero(nv_);
      q_prev_ = model_->neutralConfiguration();
      J_prev_.resize(config_->tasks.size());
      for (size_t t = 0; t < config_->tasks.size(); ++t)
        if (config_->tasks[t]->geometric()) J_prev_[t].setZero(config_->tasks[t]->rows(), nv_);
      guard_.setup(nv_);
    }
    const double dt2 = params_.dt * params_.dt;
    hessian::QuasiNewtonOptions qo;
    qo.update = params_.sr1 ? hessian::QuasiNewtonUpdate::Sr1 : hessian::QuasiNewtonUpdate::Bfgs;
    qo.xi = params_.xi_dt2 * dt2;
    qo.eps = params_.eps_dt2 * dt2;
    qo.identity_weight = params_.newton_identity_weight;
    qn_.push_back(hessian::makeQuasiNewton(nv_, qo));
    initialized_.push_back(0);
    // full_difference: the multipliers of the previous tick, stacked over the level's terms.
    int rows = 0;
    for (const GeomTerm& g : level.terms) rows += g.rows;
    lambda_prev_.emplace_back(Eigen::VectorXd::Zero(rows));
    lambda_prev_valid_.push_back(0);
  }

  void resetLevels() override {
    std::fill(initialized_.begin(), initialized_.end(), 0);
    std::fill(lambda_prev_valid_.begin(), lambda_prev_valid_.end(), 0);
    guard_.reset();
  }

  void beginTick(const MethodTick& tick) override {
    if (qn_.empty() || !have_prev_) return;
    // Step actually taken since the previous tick, and the sign-change guard (sec. VIII-A).
    model_->difference(q_prev_, tick.state.q, s_);
    if (params_.sign_change_guard) {
      acc_ = (tick.state.u - u_prev_) / params_.dt;
      guard_.observe(acc_);
    }
  }

  void prepareLevel(size_t k, NewtonLevel& a, const SolverLevel& L, const MethodTick& tick, bool have_lambda, TickRecord& rec) override {
    const ControllerParams& p = params_;
    const double dt2 = p.dt * p.dt;
    hessian::QuasiNewtonMatrix& B = *qn_[k];
    if (!initialized_[k]) {
      // eq. 89: max(zeta, 1/2 ||dt edot_PD,i||^2) on the chain of every active task.
      rhs_.setZero();
      for (const GeomTerm& g : a.terms) {
        const tasks::TaskData& d = *tick.td[z(g.task)];
        if (!engaged(g, d)) continue;
        // edot_PD = -(target of the row) (eq. 61): the rows read J u(k+1) = -edot_PD.
        double e2 = 0.0;
        for (int r = 0; r < g.rows; ++r) {
          const double t = std::isfinite(d.lower(r)) && d.lower(r) == d.upper(r) ? d.lower(r) : 0.0;
          e2 += t * t;
        }
        const double v = std::max(p.zeta_dt2 * dt2, 0.5 * dt2 * e2);
        for (int i : g.chain) rhs_(i) += v;
      }
      B.initialize(rhs_);
      initialized_[k] = 1;
      storeMultipliers(k, a, L, tick, have_lambda);
      return;
    }
    if (have_lambda) {
      // eq. 88 (sign: y = grad L(k) - grad L(k-1) = sum_i (J_i(k) - J_i(k-1))^T lambda_i).
      y_.setZero();
      const bool full = p.bfgs_secant == BfgsSecant::FullDifference && lambda_prev_valid_[k];
      int off = 0;
      for (const GeomTerm& g : a.terms) {
        const tasks::TaskData& d = *tick.td[z(g.task)];
        const auto lambda = multipliers(g, L, tick, have_lambda);
        hessian::accumulateGradientChange(d.J, J_prev_[z(g.task)], lambda, y_);
        // full_difference: + J_i(k-1)^T (lambda_i - lambda_i(prev)).
        if (full) hessian::accumulateMultiplierChange(J_prev_[z(g.task)], lambda, lambda_prev_[k].segment(off, g.rows), y_);
        off += g.rows;
      }
      // gauss_newton: + J_l^T J_l s, the secant pair of J^T J + H.
      if (p.bfgs_secant == BfgsSecant::GaussNewton) accumulateLevelGaussNewtonStep(L, tick, s_, y_);
      if (B.update(s_, y_)) rec.level_hessian_updated[z(L.config_level)] = 1;
    }
    storeMultipliers(k, a, L, tick, have_lambda);
    B.setOccupied(a.occupied, p.new_dof_diagonal_dt2 * dt2);  // sec. VII
    if (p.sign_change_guard) {
      for (int dof : guard_.triggered())
        if (a.occupied[z(dof)]) B.addDiagonal(dof, p.zeta_dt2 * dt2);  // sec. VIII-A
    }
  }

  double identityDiagonal(size_t k) const override {
    // factor(): B + alpha I*, or Higham + eps when rounding made B indefinite.
    return params_.newton_identity_weight + (qn_[k]->lastFactorRegularized() ? qn_[k]->options().eps : 0.0);
  }

  int factorLevel(size_t k, NewtonLevel& level, const SolverLevel& sl, const MethodTick& tick, bool have_lambda,
                  Eigen::MatrixXd& R) override {
    (void)level, (void)sl, (void)tick, (void)have_lambda;
    return qn_[k]->factor(R);  // eq. 35: R^T R = B (+ alpha I*) on the occupied block
  }

  void storePrevious(const MethodTick& tick) override {
    if (qn_.empty()) return;
    for (size_t t = 0; t < J_prev_.size(); ++t)
      if (J_prev_[t].size() > 0) J_prev_[t] = tick.td[t]->J;
    q_prev_ = tick.state.q;
    u_prev_ = tick.state.u;
  }

 private:
  // full_difference: keeps this tick's multipliers (the previous ones at the next tick).
  void storeMultipliers(size_t k, const NewtonLevel& a, const SolverLevel& L, const MethodTick& tick, bool have_lambda) {
    if (params_.bfgs_secant != BfgsSecant::FullDifference) return;
    lambda_prev_valid_[k] = have_lambda ? 1 : 0;
    if (!have_lambda) return;
    int off = 0;
    for (const GeomTerm& g : a.terms) {
      lambda_prev_[k].segment(off, g.rows) = multipliers(g, L, tick, have_lambda);
      off += g.rows;
    }
  }

  std::vector<std::unique_ptr<hessian::QuasiNewtonMatrix>> qn_;  // per level with reserved rows
  std::vector<char> initialized_;                                // per level: eq. 89 done
  std::vector<Eigen::VectorXd> lambda_prev_;                     // per level (full_difference)
  std::vector<char> lambda_prev_valid_;
  std::vector<Eigen::MatrixXd> J_prev_;  // per task (geometric tasks only)
  model::Configuration q_prev_;
  Eigen::VectorXd u_prev_, s_, y_, rhs_, acc_;
  hessian::SignChangeGuard guard_;
};

}  // namespace

MethodInfo lexDynBfgsMethod() {
  return {"bfgs", "LexDynBFGS: velocity domain, Newton rows from per-level BFGS (sec. VI-A)", false, &makeMethodOf<LexDynBfgs>};
}

}  // namespace lexdyn::control::methods
