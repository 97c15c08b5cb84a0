// Velocity damper (Kanoun et al.; method.md §7b; docs/controller.md) for a distance-like
// quantity d >= 0 with interaction distance d_i, safety distance d_s < d_i and gain xi (a
// velocity: m/s or rad/s):
//   d < d_i:  ddot >= -xi (d - d_s) / (d_i - d_s)      otherwise free.
// With ddot = J_d u(k+1) this is a row of the velocity domain. The acceleration domain bounds
// J_d udot(k+1) so that u(k+1) = u + dt udot satisfies the same bound:
//   J_d udot >= (-xi (d - d_s) / (d_i - d_s) - J_d u) / dt - Jdot_d u.
// At d = d_s the bound is 0 (no approach); below d_s it is positive (the distance is pushed back).
//
// Adaptive gain (default; our choice, the paper gives no gain): a fixed xi makes the bound jump to
// -xi when the damper engages; if the distance already shrinks faster than xi, the next velocity
// must change at once (an unbounded acceleration: a jolt of the whole robot for a CoM damper).
// With `adaptive`, the gain is set when the damper engages to
//   xi_eff = max(xi, -ddot (d_i - d_s) / (d - d_s)),
// so that the bound equals the current approach speed (continuous), and kept until the damper
// releases (d >= d_i); the bound then decreases linearly to 0 at d_s as in the fixed form.
#pragma once

#include <algorithm>
#include <limits>
#include <string>

#include <vector>

#include "lexdyn/tasks/task.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

struct DamperParams {
  double interaction = 0.1;  ///< d_i (m, rad, or a fraction of a range; per task)
  double safety = 0.01;      ///< d_s, 0 <= d_s < d_i
  double xi = 0.5;           ///< gain, velocity units, > 0
  bool adaptive = true;      ///< gain raised to the approach speed at engagement (see above)
};

/// Per-damper runtime state (lives in the task's data).
struct DamperState {
  bool engaged = false;
  double xi = 0.0;  ///< effective gain while engaged
};

/// Task data of the damper-based tasks: one state per damper (row and side).
struct DamperTaskData : TaskData {
  std::vector<DamperState> dampers;
  void resetDampers() {
    for (DamperState& s : dampers) s = DamperState{};
  }
};

/// Throws InputError naming the task and `<prefix>interaction`, `<prefix>safety`, `<prefix>xi`.
inline void validateDamper(const DamperParams& p, const std::string& task, const std::string& prefix = "") {
  requirePositive(p.interaction, task, prefix + "interaction");
  requireNonNegative(p.safety, task, prefix + "safety");
  if (!(p.safety < p.interaction)) {
    throwTaskInput(
        task, prefix + "safety",
        "must be smaller than " + prefix + "interaction (" + std::to_string(p.interaction) + "), found " + std::to_string(p.safety));
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

/// Velocity-domain bound with the adaptive gain; updates the state. ddot = current d rate.
inline double damperVelocityBound(double d, double ddot, const DamperParams& p, DamperState& st) {
  if (!damperEngaged(d, p.interaction)) {
    st.engaged = false;
    return -std::numeric_limits<double>::infinity();
  }
  if (!st.engaged) {
    st.engaged = true;
    st.xi = p.xi;
    if (p.adaptive && d > p.safety && ddot < 0.0) {
      st.xi = std::max(p.xi, -ddot * (p.interaction - p.safety) / (d - p.safety));
    }
  }
  return -st.xi * (d - p.safety) / (p.interaction - p.safety);
}

/// Acceleration-domain bound with the adaptive gain (bias = Jdot_d u).
inline double damperAccelerationBound(double d, double ddot, double bias, double dt, const DamperParams& p, DamperState& st) {
  const double v = damperVelocityBound(d, ddot, p, st);
  if (v == -std::numeric_limits<double>::infinity()) return v;
  return (v - ddot) / dt - bias;
}

/// Lower bound on J_d udot in the acceleration domain (ddot = J_d u now, bias = Jdot_d u).
inline double damperAccelerationBound(double d, double d_i, double d_s, double xi, double ddot, double bias, double dt) {
  if (!damperEngaged(d, d_i)) return -std::numeric_limits<double>::infinity();
  return (damperVelocityBound(d, d_i, d_s, xi) - ddot) / dt - bias;
}

}  // namespace lexdyn::tasks
