// Internal: the common part of the check implementations (checks.cpp, controller_checks.cpp).
#pragma once

#include "harness/checks/checks.hpp"
#include "lexdyn/common/error.hpp"

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace lexdyn::checks::detail {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

inline int require(const TraceSchema& schema, const std::string& channel, const CheckSpec& spec) {
  const int c = schema.find(channel);
  if (c < 0) throw InputError(spec.where, "check '" + spec.name + "' needs trace channel '" + channel + "', which is not recorded");
  return c;
}

class CheckBase : public Check {
 public:
  explicit CheckBase(CheckSpec spec, std::string unit) : spec_(std::move(spec)), unit_(std::move(unit)) {}
  CheckResult result() const override {
    CheckResult r;
    r.name = spec_.name;
    r.type = spec_.type;
    r.limit = spec_.limit;
    r.unit = unit_;
    if (!seen_) {
      r.value = kNaN;
      r.passed = false;
      r.detail = "no trace row at t >= " + std::to_string(spec_.from_s) + " s" +
                 (spec_.to_s < std::numeric_limits<double>::infinity() ? " and <= " + std::to_string(spec_.to_s) + " s" : "");
      return r;
    }
    r.value = worst_;
    r.passed = worst_ <= spec_.limit + tolerance_;
    r.detail = detail_;
    return r;
  }

 protected:
  bool active(const double* row) const { return row[t_] >= spec_.from_s - 1e-9 && row[t_] <= spec_.to_s + 1e-9; }
  CheckSpec spec_;
  std::string unit_;
  int t_ = 0;
  bool seen_ = false;
  double worst_ = 0.0;
  std::string detail_;
  /// Boundary tolerance: the value may exceed the limit by this much (in the value's unit) and
  /// still pass, so that a quantity sitting exactly on a physical bound (a torque at its limit,
  /// a force on the friction cone) is not failed by round-off. 0 for limits chosen by the user.
  double tolerance_ = 0.0;
};

/// Relative round-off allowance of the checks whose limits are physical bounds (torque
/// limits, friction cone, support polygon, unilateral contact): docs/cases.md, "Checks".
constexpr double kBoundaryRelTolerance = 1e-9;

/// Builds a controller check (controller_checks.cpp); nullptr for an unknown type.
std::unique_ptr<Check> makeControllerCheck(const CheckSpec& spec);
/// The controller check types.
const std::vector<std::string>& controllerCheckTypes();

}  // namespace lexdyn::checks::detail
