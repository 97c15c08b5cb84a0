// WLS, the paper's LSSOL baseline (docs/controller.md, "Levels"): acceleration-domain variables
// [udot(k+1); gamma], exactly two configured levels: the hard constraints and the weighted
// objective, whose task rows are scaled by sqrt(weight). The command integrates eq. 57. A
// violation of the hard level above ControllerParams::wls_infeasibility_tolerance (relative to
// its finite bounds) is a controller failure (TickStatus::Infeasible): LSSOL fails where the
// hierarchical solver would relax. With ControllerParams::damping = mu > 0 the objective level
// carries the rows mu udot = 0 (eq. 50).
#pragma once

#include "lexdyn/control/method.hpp"

namespace lexdyn::control::methods {

/// Registry entry "wls".
MethodInfo wlsMethod();

}  // namespace lexdyn::control::methods
