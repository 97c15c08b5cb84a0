#include "harness/checks/checks.hpp"
#include "harness/checks/check_base.hpp"

#include "lexdyn/common/format.hpp"
#include "lexdyn/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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

WindowCut cutWindow(const CheckSpec& spec, double run_end_s, double scenario_end_s) {
  WindowCut w;
  if (!(run_end_s < scenario_end_s - 1e-9)) return w;  // the whole scenario was run
  const double end = std::min(spec.to_s, scenario_end_s);
  auto window = [&] { return "[" + fmt(spec.from_s) + ", " + fmt(end) + "] s"; };
  if (spec.from_s > run_end_s + 1e-9) {
    w.skip = true;
    w.note = "its window " + window() + " starts after the run's end at " + fmt(run_end_s) + " s (stop_at_s, run --duration)";
  } else if (end > run_end_s + 1e-9) {
    w.note = "over [" + fmt(spec.from_s) + ", " + fmt(run_end_s) + "] s of its window " + window() + ": the run stopped at " +
             fmt(run_end_s) + " s (stop_at_s, run --duration)";
  }
  return w;
}

std::string taskChannel(const std::string& task, const char* what) { return "task." + task + "." + what; }
std::string levelChannel(const std::string& level, const char* what) { return "level." + level + "." + what; }
std::string wrenchChannel(const std::string& contact, bool sensed, const char* component) {
  return std::string(sensed ? "wrench_sensed." : "wrench.") + contact + "." + component;
}
std::string contactActiveChannel(const std::string& contact) { return "ctrl_contact." + contact + ".active"; }
std::string timerChannel(const std::string& timer) { return "time." + timer + "_us"; }

const std::vector<std::string>& controllerStatusNames() {
  static const std::vector<std::string> names = {"ok", "solver_stopped_early", "solver_iteration_limit", "infeasible", "non_finite"};
  return names;
}

const std::vector<std::string>& solverStatusNames() {
  static const std::vector<std::string> names = {"solved", "stopped_early", "iteration_limit", "non_finite_input", "non_finite_result"};
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
  // A run stopped early (stop_at_s) records the scenario's duration beside its own: windows are
  // cut as the run cut them (cutWindow).
  const std::string* run_end = findMetadata(trace.metadata, "duration_s");
  const std::string* scenario_end = findMetadata(trace.metadata, kScenarioDurationMetadata);
  const double run_end_s = run_end ? std::strtod(run_end->c_str(), nullptr) : kInf;
  const double scenario_end_s = scenario_end ? std::strtod(scenario_end->c_str(), nullptr) : run_end_s;
  std::vector<CheckResult> out;
  for (const auto& s : specs) {
    if (!appliesTo(s, method ? *method : std::string())) continue;
    const WindowCut cut = cutWindow(s, run_end_s, scenario_end_s);
    if (cut.skip) continue;
    CheckResult r = evaluate(s, schema, trace);
    if (!cut.note.empty() && !r.saw_rows) continue;
    r.partial_window = cut.note;
    applyWallClockPolicy(r, wall_clock_checks);
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace lexdyn::checks
