#include "harness/checks/checks.hpp"
#include "harness/checks/check_base.hpp"

#include "lexdyn/common/format.hpp"
#include "lexdyn/common/error.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

namespace lexdyn::checks {

std::string fmt(double v) { return formatNumber(v); }

void CheckSpec::paramsMismatch() const {
  const std::string msg = "check '" + name + "' of type " + type + " holds the params of another type (or none)";
  ::lexdyn::abortWithMessage(__FILE__, __LINE__, "params of the check's type", msg.c_str());
}

double margin(const CheckResult& r) {
  if (std::isnan(r.value) || !std::isfinite(r.limit)) return std::numeric_limits<double>::quiet_NaN();
  return r.bounds_below ? r.value - r.limit : r.limit - r.value;
}

bool appliesTo(const CheckSpec& spec, const std::string& method) {
  if (spec.methods.empty()) return true;
  for (const auto& m : spec.methods) {
    if (m == method) return true;
  }
  return false;
}

std::string taskChannel(const std::string& task, const char* what) { return "task." + task + "." + what; }
std::string levelChannel(const std::string& level, const char* what) { return "level." + level + "." + what; }
std::string wrenchChannel(const std::string& contact, bool sensed, const char* component) {
  return std::string(sensed ? "wrench_sensed." : "wrench.") + contact + "." + component;
}
std::string contactActiveChannel(const std::string& contact) { return "ctrl_contact." + contact + ".active"; }
std::string timerChannel(const std::string& timer) { return "time." + timer + "_us"; }

const std::vector<std::string>& controllerStatusNames() {
  static const std::vector<std::string> names = {"ok", "solver_stopped_early", "solver_iteration_limit", "infeasible",
                                                 "non_finite"};
  return names;
}

const std::vector<std::string>& solverStatusNames() {
  static const std::vector<std::string> names = {"solved", "stopped_early", "iteration_limit", "non_finite_input",
                                                 "non_finite_result"};
  return names;
}

void applyWallClockPolicy(CheckResult& r, bool wall_clock_checks) {
  if (r.machine_dependent) r.decides = wall_clock_checks;
}

bool allPassed(const std::vector<CheckResult>& results) {
  for (const auto& r : results) {
    if (r.decides && !r.passed) return false;
  }
  return true;
}

TraceSchema schemaOf(const TraceTable& trace) {
  TraceSchema schema;
  for (const auto& n : trace.names) schema.add(n);
  return schema;
}

CheckResult evaluate(const CheckSpec& spec, const TraceSchema& schema, const TraceTable& trace) {
  auto c = makeCheck(spec);
  c->bind(schema, trace.metadata);
  for (const auto& row : trace.rows) c->consume(row.data());
  return c->result();
}

std::vector<CheckResult> runChecks(const std::vector<CheckSpec>& specs, const TraceTable& trace, bool wall_clock_checks) {
  const TraceSchema schema = schemaOf(trace);
  const std::string* method = findMetadata(trace.metadata, kMethodMetadata);
  std::vector<CheckResult> out;
  for (const auto& s : specs) {
    if (!appliesTo(s, method ? *method : std::string())) continue;
    out.push_back(evaluate(s, schema, trace));
    applyWallClockPolicy(out.back(), wall_clock_checks);
  }
  return out;
}

}  // namespace lexdyn::checks
