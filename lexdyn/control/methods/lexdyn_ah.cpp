#include "lexdyn/control/methods/lexdyn_ah.hpp"

#include <cmath>

#include "lexdyn/control/methods/detail/velocity_domain.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/hessian/higham.hpp"

namespace lexdyn::control::methods {

namespace {

class LexDynAh final : public VelocityDomainMethod {
 public:
  explicit LexDynAh(const ControllerParams& p) : VelocityDomainMethod(p) {}

  bool needsKinematicHessians() const override { return true; }

  void setup(const MethodSetup& s) override {
    VelocityDomainMethod::setup(s);
    H_.setZero(nv_, nv_);
    occ_list_.reserve(z(nv_));
    higham_.setup(nv_);
  }

 protected:
  bool newtonRows() const override { return true; }

  // What prepareLevel() noted refers to the tick's data: never kept past it.
  void beginTick(const MethodTick& tick) override {
    (void)tick;
    pending_level_ = nullptr;
    pending_tick_ = nullptr;
  }
  void resetLevels() override {
    pending_level_ = nullptr;
    pending_tick_ = nullptr;
  }

  // The analytic Hessian is needed only by a level that switches to Newton at this tick (most
  // do not): prepareLevel() notes what to build it from, factorLevel() builds it.
  void prepareLevel(size_t k, NewtonLevel& a, const SolverLevel& L, const MethodTick& tick, bool have_lambda,
                    TickRecord& rec) override {
    (void)a, (void)rec;
    pending_k_ = k;
    pending_level_ = &L;
    pending_tick_ = &tick;
    pending_have_lambda_ = have_lambda;
  }

  void buildHessian(const NewtonLevel& a, const SolverLevel& L, const MethodTick& tick, bool have_lambda) {
    const double dt2 = params_.dt * params_.dt;
    // eq. 21, skipping |lambda| <= rho.
    H_.setZero();
    // ah_add_jtj: the Gauss-Newton term of the level's own rows, J^T J + H.
    if (params_.ah_add_jtj) accumulateLevelGaussNewton(L, tick, H_);
    if (!have_lambda) return;
    for (const GeomTerm& g : a.terms) {
      auto wv = multipliers(g, L, tick, have_lambda);
      for (int r = 0; r < g.rows; ++r)
        if (std::abs(wv(r)) <= params_.rho_dt2 * dt2) wv(r) = 0.0;
      if (wv.lpNorm<Eigen::Infinity>() == 0.0) continue;
      config_->tasks[z(g.task)]->accumulateHessian(tick.ctx, *tick.td[z(g.task)], wv, H_);
    }
  }

  double identityDiagonal(size_t k) const override {
    (void)k;
    const double dt2 = params_.dt * params_.dt;
    return params_.eps_dt2 * dt2 + params_.newton_identity_weight;
  }

  int factorLevel(size_t k, NewtonLevel& a, Eigen::MatrixXd& R) override {
    LEXDYN_ALWAYS_ASSERT(pending_level_ != nullptr && pending_tick_ != nullptr && pending_k_ == k,
                         "LexDynAH: factorLevel without the level's prepareLevel");
    buildHessian(a, *pending_level_, *pending_tick_, pending_have_lambda_);
    pending_level_ = nullptr;
    pending_tick_ = nullptr;
    const double dt2 = params_.dt * params_.dt;
    // eq. 91: Higham's nearest PSD matrix plus (eps + alpha) I* on the occupied dofs.
    return higham_.regularizeAndFactor(H_, a.occupied, params_.eps_dt2 * dt2 + params_.newton_identity_weight, R, occ_list_);
  }

 private:
  Eigen::MatrixXd H_;
  std::vector<int> occ_list_;
  size_t pending_k_ = 0;
  const SolverLevel* pending_level_ = nullptr;
  const MethodTick* pending_tick_ = nullptr;
  bool pending_have_lambda_ = false;
  hessian::HighamRegularizer higham_;
};

}  // namespace

MethodInfo lexDynAhMethod() {
  return {"ah", "LexDynAH: velocity domain, Newton rows from the analytic Hessian (sec. VI-B)", false, &makeMethodOf<LexDynAh>};
}

}  // namespace lexdyn::control::methods
