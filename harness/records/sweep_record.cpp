#include "harness/records/sweep_record.hpp"

#include "harness/records/json_numbers.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>

namespace lexdyn::records {

using nlohmann::json;

namespace {

// "" when j[key] is there and of the kind `is` tests, else what is wrong with it.
template <class Is>
std::string need(const json& j, const char* key, Is is, const char* kind) {
  if (!j.contains(key)) return std::string("no ") + key;
  if (!is(j[key])) return std::string(key) + ": not " + kind;
  return "";
}
bool isString(const json& v) { return v.is_string(); }
bool isObject(const json& v) { return v.is_object(); }
bool isArray(const json& v) { return v.is_array(); }
bool isInteger(const json& v) { return v.is_number_integer(); }
bool isNumberOrNull(const json& v) { return v.is_number() || v.is_null(); }
bool isStrings(const json& v) {
  if (!v.is_array()) return false;
  for (const auto& x : v) {
    if (!x.is_string()) return false;
  }
  return true;
}
bool isStringValues(const json& v) {
  if (!v.is_object()) return false;
  for (const auto& x : v) {
    if (!x.is_string()) return false;
  }
  return true;
}

// "" when `j` has the format `format`; else why not (`what`: "a point record").
std::string formatProblem(const json& j, const char* format, const char* what) {
  if (!j.is_object()) return "not a JSON object";
  const std::string f = j.contains("format") && j["format"].is_string() ? j["format"].get<std::string>() : "";
  if (f == format) return "";
  return (f.empty() ? std::string(what) + " of no format (written by an older build)" : std::string(what) + " of format '" + f + "'") +
         ", this build reads '" + format + "'";
}

std::map<std::string, std::string> stringMap(const json& v) {
  std::map<std::string, std::string> out;
  for (auto it = v.begin(); it != v.end(); ++it) out[it.key()] = it.value().get<std::string>();
  return out;
}

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
                      {"value", finiteOrNull(c.value)},
                      {"limit", finiteOrNull(c.limit)},
                      {"margin", finiteOrNull(c.margin)},
                      {"unit", c.unit},
                      {"detail", c.detail}});
  }
  json st = json::object(), fe = json::object();
  for (const auto& [k, v] : r.statistics) st[k] = finiteOrNull(v);
  for (const auto& [k, v] : r.final_errors) fe[k] = finiteOrNull(v);
  return {{"format", kSweepRunFormat}, {"status", toString(r.status)},        {"message", r.message}, {"exit_code", r.exit_code},
          {"wall_s", r.wall_s},        {"simulated_s", r.simulated_s},        {"checks", checks},     {"statistics", st},
          {"final_errors", fe},        {"peak_iterations", r.peak_iterations}};
}

std::optional<SweepRunRecord> sweepRunFromJson(const json& j, std::string& why) {
  if (!j.is_object()) {
    why = "not a JSON object";
    return std::nullopt;
  }
  why = formatProblem(j, kSweepRunFormat, "a run record");
  if (!why.empty()) return std::nullopt;
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
    o.value = numberOrNaN(c.value("value", json()));
    o.limit = numberOrNaN(c.value("limit", json()));
    o.margin = numberOrNaN(c.value("margin", json()));
    o.unit = c.value("unit", "");
    o.detail = c.value("detail", "");
    r.checks.push_back(std::move(o));
  }
  for (auto it = j["statistics"].begin(); it != j["statistics"].end(); ++it) r.statistics[it.key()] = numberOrNaN(it.value());
  for (auto it = j["final_errors"].begin(); it != j["final_errors"].end(); ++it) r.final_errors[it.key()] = numberOrNaN(it.value());
  return r;
}

std::string SweepPointRecord::value(const std::string& parameter, const std::string& otherwise) const {
  const auto it = values.find(parameter);
  return it == values.end() ? otherwise : it->second;
}

json toJson(const SweepPointRecord& r) {
  json overrides = json::array();
  for (const auto& [path, value] : r.overrides) overrides.push_back({{"path", path}, {"value", value}});
  json runs = json::object();
  for (const auto& [m, pr] : r.runs) {
    json jr = toJson(pr.run);
    jr["reproduce"] = pr.reproduce;
    jr["rerun"] = pr.rerun;
    runs[m] = jr;
  }
  json comps = json::array();
  for (const auto& c : r.comparisons) {
    comps.push_back({{"name", c.name},
                     {"better", c.better},
                     {"worse", c.worse},
                     {"value", finiteOrNull(c.value)},
                     {"limit", finiteOrNull(c.limit)},
                     {"margin", finiteOrNull(c.margin)},
                     {"better_wins", c.better_wins},
                     {"stopped_early", c.stopped_early}});
  }
  return {{"format", kSweepPointFormat}, {"point", r.point},      {"values", r.values}, {"overrides", overrides}, {"runs", runs},
          {"comparisons", comps},        {"failures", r.failures}};
}

std::optional<SweepPointRecord> sweepPointFromJson(const json& j, std::string& why) {
  why = formatProblem(j, kSweepPointFormat, "a point record");
  if (why.empty()) why = need(j, "point", isInteger, "an integer");
  if (why.empty()) why = need(j, "values", isStringValues, "an object of strings");
  if (why.empty()) why = need(j, "overrides", isArray, "a list");
  if (why.empty()) why = need(j, "runs", isObject, "an object");
  if (why.empty()) why = need(j, "comparisons", isArray, "a list");
  if (why.empty()) why = need(j, "failures", isStrings, "a list of strings");
  if (!why.empty()) return std::nullopt;
  SweepPointRecord r;
  r.point = j["point"].get<long>();
  r.values = stringMap(j["values"]);
  r.failures = j["failures"].get<std::vector<std::string>>();
  for (const auto& o : j["overrides"]) {
    if (!o.is_object() || need(o, "path", isString, "").size() || need(o, "value", isString, "").size()) {
      why = "overrides: an entry without its path and value";
      return std::nullopt;
    }
    r.overrides.emplace_back(o["path"].get<std::string>(), o["value"].get<std::string>());
  }
  for (auto it = j["runs"].begin(); it != j["runs"].end(); ++it) {
    std::string run_why;
    std::optional<SweepRunRecord> run = sweepRunFromJson(it.value(), run_why);
    if (!run) {
      why = "the run of " + it.key() + ": " + run_why;
      return std::nullopt;
    }
    SweepPointRun& pr = r.runs[it.key()];
    pr.run = std::move(*run);
    pr.reproduce = it.value().value("reproduce", "");
    pr.rerun = it.value().value("rerun", "");
  }
  for (const auto& c : j["comparisons"]) {
    std::string bad = c.is_object() ? "" : "not an object";
    for (const char* key : {"name", "better", "worse"}) {
      if (bad.empty()) bad = need(c, key, isString, "a string");
    }
    for (const char* key : {"value", "limit", "margin"}) {
      if (bad.empty()) bad = need(c, key, isNumberOrNull, "a number");
    }
    if (bad.empty() && !(c.contains("better_wins") && c["better_wins"].is_boolean())) bad = "better_wins: not true or false";
    if (bad.empty()) bad = need(c, "stopped_early", isStrings, "a list of strings");
    if (!bad.empty()) {
      why = "comparisons: " + bad;
      return std::nullopt;
    }
    SweepComparisonRecord o;
    o.name = c["name"].get<std::string>();
    o.better = c["better"].get<std::string>();
    o.worse = c["worse"].get<std::string>();
    o.value = numberOrNaN(c["value"]);
    o.limit = numberOrNaN(c["limit"]);
    o.margin = numberOrNaN(c["margin"]);
    o.better_wins = c["better_wins"].get<bool>();
    o.stopped_early = c["stopped_early"].get<std::vector<std::string>>();
    r.comparisons.push_back(std::move(o));
  }
  return r;
}

json toJson(const SweepFailureEntry& e) {
  return {{"format", kSweepFailureFormat},           {"sweep", e.sweep}, {"method", e.method}, {"check", e.check}, {"values", e.values},
          {"duration_s", finiteOrNull(e.duration_s)}};
}

std::optional<SweepFailureEntry> sweepFailureFromJson(const json& j, std::string& why) {
  why = "";
  if (!j.is_object()) why = "not a JSON object";
  // A line without a format was written before the key existed: the same fields.
  if (why.empty() && j.contains("format")) why = formatProblem(j, kSweepFailureFormat, "a failure entry");
  for (const char* key : {"sweep", "method", "check"}) {
    if (why.empty()) why = need(j, key, isString, "a string");
  }
  if (why.empty()) why = need(j, "values", isStringValues, "an object of strings");
  if (why.empty() && j.contains("duration_s") && !isNumberOrNull(j["duration_s"])) why = "duration_s: not a number";
  if (!why.empty()) return std::nullopt;
  SweepFailureEntry e;
  e.sweep = j["sweep"].get<std::string>();
  e.method = j["method"].get<std::string>();
  e.check = j["check"].get<std::string>();
  e.values = stringMap(j["values"]);
  e.duration_s = numberOrNaN(j.value("duration_s", json()));
  if (!std::isfinite(e.duration_s)) e.duration_s = 0.0;
  return e;
}

json toJson(const SweepReplayRecord& r) {
  json j = toJson(r.entry);
  j["format"] = kSweepReplayFormat;
  j["status"] = toString(r.status);
  j["still_fails"] = r.still_fails;
  j["value"] = finiteOrNull(r.value);
  j["limit"] = finiteOrNull(r.limit);
  return j;
}

}  // namespace lexdyn::records
