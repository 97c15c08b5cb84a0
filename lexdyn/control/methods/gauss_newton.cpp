#include "lexdyn/control/methods/gauss_newton.hpp"

#include "lexdyn/control/methods/detail/velocity_domain.hpp"

namespace lexdyn::control::methods {

namespace {

/// Everything is the velocity domain's: no Newton rows (VelocityDomainMethod::newtonRows).
class GaussNewton final : public VelocityDomainMethod {
 public:
  explicit GaussNewton(const ControllerParams& p) : VelocityDomainMethod(p) {}
};

}  // namespace

MethodInfo gaussNewtonMethod() {
  return {"gn", "pure Gauss-Newton: velocity domain, no Newton rows (Fig. 14)", false, &makeMethodOf<GaussNewton>};
}

}  // namespace lexdyn::control::methods
