#include "harness/records/sweep_record.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>

namespace lexdyn::records {

using nlohmann::json;

namespace {

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double num(const json& v) { return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN(); }

}  // namespace

std::vector<std::string> SweepRunRecord::failures() const {
  std::vector<std::string> out;
  if (status != RunStatus::Completed) out.push_back(kRunCompletedCheck);
  for (const auto& c : checks) {
    if (!c.passed) out.push_back(c.name);
  }
  return out;
}

const SweepCheckRecord* SweepRunRecord::check(const std::string& name) const {
  for (const auto& c : checks) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

json toJson(const SweepRunRecord& r) {
  json checks = json::array();
  for (const auto& c : r.checks) {
    checks.push_back({{"name", c.name},
                      {"passed", c.passed},
                      {"value", number(c.value)},
                      {"limit", number(c.limit)},
                      {"margin", number(c.margin)},
                      {"unit", c.unit},
                      {"detail", c.detail}});
  }
  json st = json::object(), fe = json::object();
  for (const auto& [k, v] : r.statistics) st[k] = number(v);
  for (const auto& [k, v] : r.final_errors) fe[k] = number(v);
  return {{"format", kSweepRunFormat}, {"status", toString(r.status)},        {"message", r.message}, {"exit_code", r.exit_code},
          {"wall_s", r.wall_s},        {"simulated_s", r.simulated_s},        {"checks", checks},     {"statistics", st},
          {"final_errors", fe},        {"peak_iterations", r.peak_iterations}};
}

std::optional<SweepRunRecord> sweepRunFromJson(const json& j, std::string& why) {
  if (!j.is_object()) {
    why = "not a JSON object";
    return std::nullopt;
  }
  const std::string format = j.contains("format") && j["format"].is_string() ? j["format"].get<std::string>() : "";
  if (format != kSweepRunFormat) {
    why = (format.empty() ? std::string("a run record of no format (written by an older build)")
                          : "a run record of format '" + format + "'") +
          ", this build reads '" + kSweepRunFormat + "'";
    return std::nullopt;
  }
  if (!j.contains("status") || !j["status"].is_string()) {
    why = "no status";
    return std::nullopt;
  }
  const std::string status = j["status"].get<std::string>();
  const std::optional<RunStatus> parsed = parseRunStatus(status);
  if (!parsed || !isRecordedBySweeps(*parsed)) {
    // interrupted, output_error, no_summary: runs killed or stopped from outside, which are never
    // results; the statuses of runs that ended on their own, and the driver's own verdicts on a
    // process, are (isRecordedBySweeps).
    why = "status '" + status + "' is not the end of a run";
    return std::nullopt;
  }
  for (const char* key : {"checks", "statistics", "final_errors"}) {
    if (!j.contains(key) || (std::string(key) == "checks" ? !j[key].is_array() : !j[key].is_object())) {
      why = std::string("no ") + key;
      return std::nullopt;
    }
  }
  for (const char* key : {"exit_code", "simulated_s", "peak_iterations"}) {
    if (!j.contains(key) || !j[key].is_number()) {
      why = std::string("no number ") + key;
      return std::nullopt;
    }
  }
  SweepRunRecord r;
  r.status = *parsed;
  r.message = j.value("message", "");
  r.exit_code = j.value("exit_code", 0);
  r.wall_s = j.value("wall_s", 0.0);
  r.simulated_s = j.value("simulated_s", 0.0);
  r.peak_iterations = j.value("peak_iterations", 0);
  for (const auto& c : j["checks"]) {
    if (!c.is_object() || !c.contains("name") || !c["name"].is_string() || !c.contains("passed") || !c["passed"].is_boolean()) {
      why = "a check without its name or verdict";
      return std::nullopt;
    }
    SweepCheckRecord o;
    o.name = c["name"].get<std::string>();
    o.passed = c["passed"].get<bool>();
    o.value = num(c.value("value", json()));
    o.limit = num(c.value("limit", json()));
    o.margin = num(c.value("margin", json()));
    o.unit = c.value("unit", "");
    o.detail = c.value("detail", "");
    r.checks.push_back(std::move(o));
  }
  for (auto it = j["statistics"].begin(); it != j["statistics"].end(); ++it) r.statistics[it.key()] = num(it.value());
  for (auto it = j["final_errors"].begin(); it != j["final_errors"].end(); ++it) r.final_errors[it.key()] = num(it.value());
  return r;
}

}  // namespace lexdyn::records
