// When a level gets Newton rows (paper eq. 95; docs/controller.md, "Newton augmentation").
#pragma once

namespace lexdyn::control {

/// The level's state at the previous tick's solve.
struct LevelOutcome {
  double violation_norm = 0.0;  ///< ||w_ctrl|| of the level's task rows
  int held_rows = 0;            ///< task rows the solver held (active); read by rank switching only
  int rank = 0;                 ///< rank of the level after projection; read by rank switching only
};

/// Switching rule: the level is augmented at this tick when
/// omega = 1/2 ||w_optim||^2 >= nu, with w_optim = dt w_ctrl (eq. 37) and nu = nu_dt2 dt^2
/// (eq. 95); with `rank_switching` (beyond the paper) also when its held rows have lost rank
/// after projection (rank < held_rows).
bool switchToNewton(const LevelOutcome& level, double dt, double nu_dt2, bool rank_switching);

}  // namespace lexdyn::control
