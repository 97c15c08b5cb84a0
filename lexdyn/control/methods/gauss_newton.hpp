// Pure Gauss-Newton (the paper's GN baseline, Fig. 14; docs/controller.md): the velocity-domain
// hierarchy of LexDynBFGS / LexDynAH without Newton rows. With ControllerParams::damping = mu > 0
// its geometric levels carry the constant Levenberg-Marquardt rows mu u(k+1) = 0 on their
// occupied dofs (eq. 81, the point-mass study of sec. V-A).
#pragma once

#include "lexdyn/control/method.hpp"

namespace lexdyn::control::methods {

/// Registry entry "gn".
MethodInfo gaussNewtonMethod();

}  // namespace lexdyn::control::methods
