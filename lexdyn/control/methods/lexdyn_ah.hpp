// LexDynAH (paper sec. VI-B; docs/controller.md, "Newton augmentation"): the velocity-domain
// hierarchy whose augmented levels get Newton rows R u(k+1) = 0 (eq. 35) or R u(k) (eq. 62),
// R^T R = H~ + (eps + alpha) I* with H = sum_{i<=l} sum_d lambda_{i,l,d} H_{i,d} (eq. 21) from the
// analytic task Hessians (terms with |lambda| <= rho skipped), made positive semi-definite by
// Higham's method (eq. 91) on the occupied dofs.
#pragma once

#include "lexdyn/control/method.hpp"

namespace lexdyn::control::methods {

/// Registry entry "ah".
MethodInfo lexDynAhMethod();

}  // namespace lexdyn::control::methods
