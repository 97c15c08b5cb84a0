// PD control emulated in velocity (paper sec. V-B, docs/controller.md).
//
// For a task function f(q) with a constant target f_d, error e = f_d - f, edot = -J u:
//   eddot_ctrl = -kp e - kv edot                                         (eq. 55)
//   velocity domain:      J u(k+1) = J u - dt (eddot_ctrl + Jdot u)      (eq. 60-61)
//   acceleration domain:  J udot(k+1) = -eddot_ctrl - Jdot u             (eq. 54-55)
// kv defaults to 2 sqrt(kp): critical damping for a unit mass (sec. V-B, "kv = 2 sqrt(m kp)").
#pragma once

#include <cmath>
#include <optional>
#include <string>

#include "lexdyn/tasks/task.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

/// Gains of a PD task (parameters): kp in 1/s^2, kv in 1/s; kv absent = 2 sqrt(kp).
struct PdGains {
  double kp = 1.0;
  std::optional<double> kv;
};

/// Resolved gains.
struct Pd {
  double kp = 0.0, kv = 0.0;
};

/// Validates (kp, kv finite and >= 0; fields "kp", "kv" of the task) and resolves kv.
inline Pd resolvePd(const PdGains& g, const std::string& task) {
  requireNonNegative(g.kp, task, "kp");
  Pd pd;
  pd.kp = g.kp;
  if (g.kv) {
    requireNonNegative(*g.kv, task, "kv");
    pd.kv = *g.kv;
  } else {
    pd.kv = 2.0 * std::sqrt(g.kp);
  }
  return pd;
}

/// eddot_ctrl of eq. 55 for one row, with edot = -J u (Ju: the row's J u).
inline double pdAcceleration(const Pd& pd, double e, double Ju) { return -pd.kp * e + pd.kv * Ju; }

/// Right-hand side of one PD row (the row reads J x = rhs, x = u(k+1) or udot(k+1)):
/// velocity domain eq. 61, acceleration domain eq. 55. bias = the row's Jdot u.
inline double pdRowTarget(Domain domain, double dt, const Pd& pd, double e, double Ju, double bias) {
  const double eddot_ctrl = pdAcceleration(pd, e, Ju);                   // eq. 55
  if (domain == Domain::Velocity) return Ju - dt * (eddot_ctrl + bias);  // eq. 61
  return -eddot_ctrl - bias;
}

/// The N equality rows of a PD task with Jacobian d.J (N x nv, already computed), error e and
/// bias Jdot u: A = [J, 0], error = e, lower = upper = pdRowTarget per row (eq. 61 / 55).
/// Fixed-size vectors: allocation-free.
template <int N>
void writePdRows(const TickContext& ctx, const Pd& pd, const Eigen::Matrix<double, N, 1>& e, const Eigen::Matrix<double, N, 1>& bias,
                 int nv, TaskData& d) {
  Eigen::Matrix<double, N, 1> Ju;
  Ju.noalias() = d.J * (*ctx.u);
  d.A.leftCols(nv) = d.J;
  for (int i = 0; i < N; ++i) {
    d.error[i] = e[i];
    const double rhs = pdRowTarget(ctx.domain, ctx.dt, pd, e[i], Ju[i], bias[i]);
    d.lower[i] = rhs;
    d.upper[i] = rhs;
  }
}

}  // namespace lexdyn::tasks
