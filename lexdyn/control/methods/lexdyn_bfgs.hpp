// LexDynBFGS (paper sec. VI-A, VII, VIII-A; docs/controller.md, "Newton augmentation"): the
// velocity-domain hierarchy whose augmented levels get Newton rows R u(k+1) = 0 (eq. 35) or
// R u(k) (eq. 62), R^T R a per-level quasi-Newton approximation of the level's Lagrangian
// Hessian: initialised by eq. 89, updated every tick by eq. 87-88 from the step actually taken,
// never re-initialised on occupancy changes (sec. VII), with the sign-change guard (sec. VIII-A);
// SR1 instead of BFGS with ControllerParams::sr1.
#pragma once

#include "lexdyn/control/method.hpp"

namespace lexdyn::control::methods {

/// Registry entry "bfgs".
MethodInfo lexDynBfgsMethod();

}  // namespace lexdyn::control::methods
