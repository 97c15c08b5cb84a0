// Velocity damper (Kanoun et al.; method.md §7b; docs/controller.md) for a distance-like
// quantity d >= 0 with interaction distance d_i, safety distance d_s < d_i and gain xi (a
// velocity: m/s or rad/s):
//   d < d_i:  ddot >= -xi (d - d_s) / (d_i - d_s)      otherwise free.
// With ddot = J_d u(k+1) this is a row of the velocity domain. The acceleration domain bounds
// J_d udot(k+1) so that u(k+1) = u + dt udot satisfies the same bound:
//   J_d udot >= (-xi (d - d_s) / (d_i - d_s) - J_d u) / dt - Jdot_d u.
// At d = d_s the bound is 0 (no approach); below d_s it is positive (the distance is pushed back).
#pragma once

#include <limits>
#include <string>

#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

struct DamperParams {
  double interaction = 0.1;  ///< d_i (m, rad, or a fraction of a range; per task)
  double safety = 0.01;      ///< d_s, 0 <= d_s < d_i
  double xi = 0.5;           ///< gain, velocity units, > 0
};

/// Throws InputError naming the task and `<prefix>interaction`, `<prefix>safety`, `<prefix>xi`.
inline void validateDamper(const DamperParams& p, const std::string& task, const std::string& prefix = "") {
  requirePositive(p.interaction, task, prefix + "interaction");
  requireNonNegative(p.safety, task, prefix + "safety");
  if (!(p.safety < p.interaction)) {
    throwTaskInput(task, prefix + "safety",
                   "must be smaller than " + prefix + "interaction (" + std::to_string(p.interaction) + "), found " +
                       std::to_string(p.safety));
  }
  requirePositive(p.xi, task, prefix + "xi");
}

/// True when the damper acts (d < d_i).
inline bool damperEngaged(double d, double d_i) { return d < d_i; }

/// Lower bound on ddot in the velocity domain, -inf when d >= d_i (or d = +inf).
inline double damperVelocityBound(double d, double d_i, double d_s, double xi) {
  if (!damperEngaged(d, d_i)) return -std::numeric_limits<double>::infinity();
  return -xi * (d - d_s) / (d_i - d_s);
}

/// Lower bound on J_d udot in the acceleration domain (ddot = J_d u now, bias = Jdot_d u).
inline double damperAccelerationBound(double d, double d_i, double d_s, double xi, double ddot, double bias,
                                      double dt) {
  if (!damperEngaged(d, d_i)) return -std::numeric_limits<double>::infinity();
  return (damperVelocityBound(d, d_i, d_s, xi) - ddot) / dt - bias;
}

}  // namespace lexdyn::tasks
