// Internal: the common part of the check evaluators (sim_checks.cpp, task_checks.cpp, ...).
#pragma once

#include "harness/checks/check_registry.hpp"
#include "harness/checks/checks.hpp"
#include "lexdyn/common/error.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace lexdyn::checks {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// "%.6g" (the checks' details).
std::string fmt(double v);

/// The schema of a stored trace's channels.
TraceSchema schemaOf(const TraceTable& trace);
/// A check of a built-in type evaluated on a stored trace (every row).
CheckResult evaluate(const CheckSpec& spec, const TraceSchema& schema, const TraceTable& trace);

inline int require(const TraceSchema& schema, const std::string& channel, const CheckSpec& spec) {
  const int c = schema.find(channel);
  if (c < 0) throw InputError(spec.where, "check '" + spec.name + "' needs trace channel '" + channel + "', which is not recorded");
  return c;
}

/// A check over the rows of its window: bind() binds the time channel then the type's
/// (bindChannels), consume() passes each row of the window to sample(); the value is worst_ (the
/// largest, or the smallest for a type that bounds from below), compared with the limit; result()
/// as the type says (unit, direction, machine dependence).
class CheckBase : public Check {
 public:
  CheckBase(const CheckSpec& spec, const CheckType& type)
      : spec_(spec), unit_(type.unit), bounds_below_(type.boundsBelow()), machine_dependent_(type.machineDependent()) {
    if (bounds_below_) worst_ = kInf;
  }
  void bind(const TraceSchema& schema, const TraceMetadata& metadata) final {
    t_ = require(schema, kTimeChannel, spec_);
    bindChannels(schema, metadata);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    const bool first = !seen_;
    seen_ = true;
    sample(row, first);
  }
  CheckResult result() const override {
    CheckResult r;
    r.name = spec_.name;
    r.type = spec_.type;
    r.limit = spec_.limit;
    r.unit = unit_;
    r.bounds_below = bounds_below_;
    r.machine_dependent = machine_dependent_;
    if (!seen_) {
      r.value = kNaN;
      r.passed = false;
      r.saw_rows = false;
      r.detail = noRowDetail();
      return r;
    }
    r.value = worst_;
    r.passed = bounds_below_ ? worst_ >= spec_.limit - tolerance_ : worst_ <= spec_.limit + tolerance_;
    r.detail = detail_;
    finish(r);
    return r;
  }

 protected:
  /// Resolves the type's channels (the time channel is bound).
  virtual void bindChannels(const TraceSchema& schema, const TraceMetadata& metadata) = 0;
  /// One row of the window; `first`: the window's first row.
  virtual void sample(const double* row, bool first) {
    (void)row;
    (void)first;
  }
  /// Completes the result of a check that saw rows (value, passed and detail: from worst_).
  virtual void finish(CheckResult& r) const { (void)r; }
  /// The detail of a check that saw no row.
  virtual std::string noRowDetail() const {
    return "no trace row at t >= " + std::to_string(spec_.from_s) + " s" +
           (spec_.to_s < kInf ? " and <= " + std::to_string(spec_.to_s) + " s" : "");
  }
  bool active(const double* row) const { return row[t_] >= spec_.from_s - 1e-9 && row[t_] <= spec_.to_s + 1e-9; }
  /// The column of a channel the check needs (InputError naming the check when not recorded).
  int channel(const TraceSchema& schema, const std::string& name) const { return require(schema, name, spec_); }
  /// Keeps the row's value as the worst so far when it is worse (or NaN); true when it was.
  bool worse(double v) {
    const bool w = (bounds_below_ ? v < worst_ : v > worst_) || std::isnan(v);
    if (w) worst_ = v;
    return w;
  }
  const CheckSpec spec_;
  std::string unit_;
  const bool bounds_below_, machine_dependent_;
  int t_ = 0;
  bool seen_ = false;
  double worst_ = 0.0;
  std::string detail_;
  /// Boundary tolerance: the value may exceed the limit by this much (in the value's unit) and
  /// still pass, so that a quantity sitting exactly on a physical bound (a torque at its limit,
  /// a force on the friction cone) is not failed by round-off. 0 for limits chosen by the user.
  double tolerance_ = 0.0;
};

/// A check with the params struct P of its type (p_).
template <class P>
class CheckOf : public CheckBase {
 public:
  CheckOf(const CheckSpec& spec, const CheckType& type) : CheckBase(spec, type), p_(spec_.paramsAs<P>()) {}

 protected:
  const P& p_;
};

/// Relative round-off allowance of the checks whose limits are physical bounds (torque
/// limits, friction cone, support polygon, unilateral contact): docs/cases.md, "Checks".
constexpr double kBoundaryRelTolerance = 1e-9;

/// Counts sign changes of a rate computed from successive rows; |rate| <= dead_band carries no
/// sign (the last sign is kept).
struct SignChangeCounter {
  bool have_prev = false;
  double prev = 0.0, t_prev = 0.0;
  int last_sign = 0;
  long changes = 0;
  void add(double t, double value, double dead_band) {
    if (have_prev && t > t_prev) {
      const double rate = (value - prev) / (t - t_prev);
      const int sign = rate > dead_band ? 1 : (rate < -dead_band ? -1 : 0);
      if (sign != 0) {
        if (last_sign != 0 && sign != last_sign) ++changes;
        last_sign = sign;
      }
    }
    have_prev = true;
    prev = value;
    t_prev = t;
  }
};

}  // namespace lexdyn::checks
