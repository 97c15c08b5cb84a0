#include "lexdyn/control/switching.hpp"

namespace lexdyn::control {

bool switchToNewton(const LevelOutcome& level, double dt, double nu_dt2, bool rank_switching) {
  const double dt2 = dt * dt;
  const double wn = level.violation_norm;
  const double omega = 0.5 * dt2 * wn * wn;  // eq. 37: w_optim = dt w_ctrl
  bool augment = omega >= nu_dt2 * dt2;      // eq. 95
  if (rank_switching) augment = augment || level.rank < level.held_rows;
  return augment;
}

}  // namespace lexdyn::control
