#include "lexdyn/control/methods/lexdyn_ah.hpp"

#include <cmath>

#include "lexdyn/control/methods/detail/velocity_domain.hpp"
#include "lexdyn/hessian/higham.hpp"

namespace lexdyn::control::methods {

namespace {

class LexDynAh final : public VelocityDomainMethod {
 public:
  explicit LexDynAh(const ControllerParams& p) : VelocityDomainMethod(p) {}

  bool needsKinematicHessians() const override { return true; }
  // The Hessian of a tick reads that tick's Jacobians and witness points only.
  bool readsPreviousJacobians() const override { return false; }

  void setup(const MethodSetup& s) override {
    VelocityDomainMethod::setup(s);
    H_.setZero(nv_, nv_);
    occ_list_.reserve(z(nv_));
    higham_.setup(nv_);
  }

 protected:
  bool newtonRows() const override { return true; }

  // eq. 21 for the level, built only when it switches to Newton at this tick (most do not).
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

  int factorLevel(size_t k, NewtonLevel& a, const SolverLevel& L, const MethodTick& tick, bool have_lambda, Eigen::MatrixXd& R) override {
    buildHessian(a, L, tick, have_lambda);
    // eq. 91: Higham's nearest PSD matrix plus (eps + alpha) I* on the occupied dofs, as rows
    // sqrt(max(lambda, 0) + eps + alpha) v^T of its eigendecomposition (R^T R is that matrix).
    return higham_.regularizedRows(H_, a.occupied, identityDiagonal(k), R, occ_list_);
  }

 private:
  Eigen::MatrixXd H_;
  std::vector<int> occ_list_;
  hessian::HighamRegularizer higham_;
};

}  // namespace

MethodInfo lexDynAhMethod() {
  return {"ah", "LexDynAH: velocity domain, Newton rows from the analytic Hessian (sec. VI-B)", false, &makeMethodOf<LexDynAh>};
}

}  // namespace lexdyn::control::methods
