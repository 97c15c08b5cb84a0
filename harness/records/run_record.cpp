#include "harness/records/run_record.hpp"

#include "lexdyn/common/error.hpp"

#include "harness/records/json_numbers.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace lexdyn::records {

using nlohmann::json;

namespace {

// Reads fields of one JSON object, collecting every problem ("field: what") instead of stopping at
// the first, so that one error names all of them.
class FieldReader {
 public:
  FieldReader(const json& j, std::string path, std::vector<std::string>& problems) : j_(j), path_(std::move(path)), problems_(problems) {
    if (!j_.is_object()) problem("", "not an object");
  }
  bool has(const char* key) const { return j_.is_object() && j_.contains(key) && !j_[key].is_null(); }
  const json* field(const char* key, bool required) {
    if (!j_.is_object()) return nullptr;
    if (!j_.contains(key)) {
      if (required) problem(key, "missing");
      return nullptr;
    }
    return &j_[key];
  }
  std::string string(const char* key, bool required = true) {
    const json* v = field(key, required);
    if (!v) return "";
    if (!v->is_string()) return problem(key, "not a string"), "";
    return v->get<std::string>();
  }
  /// A number; null reads as NaN (how NaN is written).
  double number(const char* key, bool required = true) {
    const json* v = field(key, required);
    if (!v || v->is_null()) return std::numeric_limits<double>::quiet_NaN();
    if (!v->is_number()) return problem(key, "not a number"), std::numeric_limits<double>::quiet_NaN();
    return v->get<double>();
  }
  long integer(const char* key, bool required = true) {
    const json* v = field(key, required);
    if (!v) return 0;
    if (!v->is_number_integer()) return problem(key, "not an integer"), 0;
    return v->get<long>();
  }
  bool boolean(const char* key, bool required = true) {
    const json* v = field(key, required);
    if (!v) return false;
    if (!v->is_boolean()) return problem(key, "not true or false"), false;
    return v->get<bool>();
  }
  const json* array(const char* key, bool required = true) {
    const json* v = field(key, required);
    if (v && !v->is_array()) return problem(key, "not a list"), nullptr;
    return v;
  }
  const json* object(const char* key, bool required = true) {
    const json* v = field(key, required);
    if (v && !v->is_object()) return problem(key, "not an object"), nullptr;
    return v;
  }
  std::vector<std::string> strings(const char* key, bool required = true) {
    std::vector<std::string> out;
    const json* v = array(key, required);
    if (!v) return out;
    for (size_t i = 0; i < v->size(); ++i) {
      if (!(*v)[i].is_string()) {
        problem(key + ("[" + std::to_string(i) + "]"), "not a string");
        continue;
      }
      out.push_back((*v)[i].get<std::string>());
    }
    return out;
  }
  std::string path(const std::string& key) const { return path_.empty() ? key : key.empty() ? path_ : path_ + "." + key; }
  void problem(const std::string& key, const std::string& what) { problems_.push_back(path(key) + ": " + what); }

 private:
  const json& j_;
  std::string path_;
  std::vector<std::string>& problems_;
};

RunStatus readStatus(FieldReader& r, const char* key) {
  const std::string text = r.string(key);
  if (text.empty() && !r.has(key)) return RunStatus::Completed;  // missing: reported
  const std::optional<RunStatus> s = parseRunStatus(text);
  if (!s || !isRunsOwn(*s)) {
    r.problem(key, "'" + text + "' is no run status (" + spellings(runsOwnStatuses()) + ")");
    return RunStatus::Completed;
  }
  return *s;
}

template <typename Fn>
void eachMember(FieldReader& parent, const char* key, bool required, Fn fn) {
  const json* o = parent.object(key, required);
  if (!o) return;
  for (auto it = o->begin(); it != o->end(); ++it) fn(it.key(), it.value(), parent.path(key) + "." + it.key());
}

}  // namespace

const CheckRecord* RunRecord::check(const std::string& name) const {
  for (const CheckRecord& c : checks) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

json toJson(const std::vector<CheckRecord>& records) {
  json checks = json::array();
  for (const CheckRecord& c : records) {
    checks.push_back({{"name", c.name},
                      {"type", c.type},
                      {"passed", c.passed},
                      {"value", finiteOrNull(c.value)},
                      {"limit", finiteOrNull(c.limit)},
                      {"margin", finiteOrNull(c.margin)},
                      {"unit", c.unit},
                      {"detail", c.detail}});
    // Wall-clock checks: reported, and a verdict only when asked for (docs/cases.md, "Checks").
    if (c.machine_dependent) {
      checks.back()["machine_dependent"] = true;
      checks.back()["decides"] = c.decides;
    }
    if (!c.partial_window.empty()) checks.back()["partial_window"] = c.partial_window;
  }
  return checks;
}

json toJson(const RunRecord& r) {
  json j;
  j["format"] = r.format;
  j["case"] = r.case_name;
  j["case_file"] = r.case_file;
  j["status"] = toString(r.status);
  j["message"] = r.message;
  if (!r.method.empty()) j["method"] = r.method;
  j["duration_s"] = r.duration_s;
  j["simulated_s"] = r.simulated_s;
  j["wall_s"] = r.wall_s;
  j["realtime_factor"] = finiteOrNull(r.realtime_factor);
  j["ticks"] = r.ticks;
  const IntegratorRecord& in = r.integrator;
  j["integrator"] = {{"steps", in.steps},
                     {"rhs_evals", in.rhs_evals},
                     {"jac_evals", in.jac_evals},
                     {"jac_rhs_evals", in.jac_rhs_evals},
                     {"nonlin_iters", in.nonlin_iters},
                     {"nonlin_conv_fails", in.nonlin_conv_fails},
                     {"err_test_fails", in.err_test_fails},
                     {"restarts", in.restarts}};
  j["checks"] = toJson(r.checks);
  if (!r.statistics.empty()) {
    json st = json::object();
    for (const auto& [name, s] : r.statistics) st[name] = {{"value", finiteOrNull(s.value)}, {"detail", s.detail}};
    j["statistics"] = st;
  }
  json overrides = json::array();
  for (const auto& [path, value] : r.overrides) overrides.push_back({{"path", path}, {"value", value}});
  j["overrides"] = overrides;
  j["effective_case"] = r.effective_case;
  json skipped = json::array();
  for (const auto& [name, reason] : r.skipped_checks) skipped.push_back({{"name", name}, {"reason", reason}});
  j["skipped_checks"] = skipped;
  if (r.scenario_duration_s) j["scenario_duration_s"] = *r.scenario_duration_s;
  j["robot_warnings"] = r.robot_warnings;
  j["start_warnings"] = r.start_warnings;
  j["all_checks_passed"] = r.all_checks_passed;
  if (r.expected_failure) {
    const ExpectedFailureRecord& x = *r.expected_failure;
    j["expected_failure"] = {{"status", toString(x.status)}, {"checks", x.checks},  {"reason", x.reason}, {"met", x.met},
                             {"mismatches", x.mismatches},   {"reached", x.reached}};
  }
  j["exit_code"] = r.exit_code;
  if (r.controller) {
    const ControllerRecord& cs = *r.controller;
    json tasks = json::object();
    for (const auto& [name, t] : cs.tasks)
      tasks[name] = {{"final_error", finiteOrNull(t.final_error)}, {"mean_error", finiteOrNull(t.mean_error)}};
    j["tasks"] = tasks;
    j["controller"] = {{"ticks", cs.ticks}, {"status_counts", cs.status_counts}, {"augmented_ticks", cs.augmented_ticks}};
    j["solver"] = {{"peak_iterations", cs.peak_iterations},
                   {"peak_iterations_at_s", cs.peak_iterations_at_s},
                   {"peak_factorizations", cs.peak_factorizations},
                   {"peak_factorizations_at_s", cs.peak_factorizations_at_s},
                   {"status_counts", cs.solver_status_counts}};
    json timing = json::object();
    for (const auto& [name, t] : cs.timing_us)
      timing[name] = {{"median", finiteOrNull(t.median)}, {"p99", finiteOrNull(t.p99)}, {"max", finiteOrNull(t.max)}};
    j["timing_us"] = timing;
  }
  j["trace"] = r.trace;
  json header = json::object();
  for (const auto& [key, value] : r.trace_header) header[key] = value;
  j["trace_header"] = header;
  return j;
}

RunRecord runRecordFromJson(const json& j, const std::string& where) {
  const std::string format = j.is_object() && j.contains("format") && j["format"].is_string() ? j["format"].get<std::string>() : "";
  if (format != kRunSummaryFormat) {
    throw InputError(
        where, "a run summary of " +
                   (format.empty() ? std::string("no format (no 'format' key: written by an older build)") : "format '" + format + "'") +
                   "; this build reads '" + kRunSummaryFormat + "'");
  }
  std::vector<std::string> problems;
  FieldReader f(j, "", problems);
  RunRecord r;
  r.format = format;
  r.case_name = f.string("case");
  r.case_file = f.string("case_file");
  r.status = readStatus(f, "status");
  r.message = f.string("message");
  r.method = f.string("method", false);
  r.duration_s = f.number("duration_s");
  r.simulated_s = f.number("simulated_s");
  r.wall_s = f.number("wall_s");
  r.realtime_factor = f.number("realtime_factor");
  r.ticks = f.integer("ticks");
  if (const json* in = f.object("integrator")) {
    FieldReader g(*in, "integrator", problems);
    IntegratorRecord& i = r.integrator;
    i.steps = g.integer("steps");
    i.rhs_evals = g.integer("rhs_evals");
    i.jac_evals = g.integer("jac_evals");
    i.jac_rhs_evals = g.integer("jac_rhs_evals");
    i.nonlin_iters = g.integer("nonlin_iters");
    i.nonlin_conv_fails = g.integer("nonlin_conv_fails");
    i.err_test_fails = g.integer("err_test_fails");
    i.restarts = g.integer("restarts");
  }
  if (const json* checks = f.array("checks")) {
    for (size_t k = 0; k < checks->size(); ++k) {
      FieldReader c((*checks)[k], "checks[" + std::to_string(k) + "]", problems);
      CheckRecord o;
      o.name = c.string("name");
      o.type = c.string("type");
      o.passed = c.boolean("passed");
      o.value = c.number("value");
      o.limit = c.number("limit");
      o.margin = c.number("margin");
      o.unit = c.string("unit");
      o.detail = c.string("detail");
      o.machine_dependent = c.has("machine_dependent") && c.boolean("machine_dependent");
      o.decides = !c.has("decides") || c.boolean("decides");
      o.partial_window = c.string("partial_window", false);
      r.checks.push_back(std::move(o));
    }
  }
  eachMember(f, "statistics", false, [&](const std::string& name, const json& v, const std::string& path) {
    FieldReader s(v, path, problems);
    r.statistics[name] = {s.number("value"), s.string("detail", false)};
  });
  if (const json* overrides = f.array("overrides")) {
    for (size_t k = 0; k < overrides->size(); ++k) {
      FieldReader o((*overrides)[k], "overrides[" + std::to_string(k) + "]", problems);
      r.overrides.emplace_back(o.string("path"), o.string("value"));
    }
  }
  r.effective_case = f.string("effective_case");
  if (const json* skipped = f.array("skipped_checks")) {
    for (size_t k = 0; k < skipped->size(); ++k) {
      FieldReader s((*skipped)[k], "skipped_checks[" + std::to_string(k) + "]", problems);
      r.skipped_checks.emplace_back(s.string("name"), s.string("reason"));
    }
  }
  if (f.has("scenario_duration_s")) r.scenario_duration_s = f.number("scenario_duration_s");
  r.robot_warnings = f.strings("robot_warnings");
  if (f.has("start_warnings")) r.start_warnings = f.strings("start_warnings");
  r.all_checks_passed = f.boolean("all_checks_passed");
  if (const json* x = f.object("expected_failure", false)) {
    FieldReader e(*x, "expected_failure", problems);
    ExpectedFailureRecord xr;
    xr.status = readStatus(e, "status");
    xr.checks = e.strings("checks");
    xr.reason = e.string("reason");
    xr.met = e.boolean("met");
    xr.mismatches = e.strings("mismatches");
    xr.reached = e.boolean("reached");
    r.expected_failure = std::move(xr);
  }
  r.exit_code = static_cast<int>(f.integer("exit_code"));
  if (f.has("controller") || f.has("solver") || f.has("tasks") || f.has("timing_us")) {
    ControllerRecord cs;
    auto counts = [&](const json& v, const std::string& path, std::map<std::string, long>& out) {
      if (!v.is_object()) return problems.push_back(path + ": not an object");
      for (auto it = v.begin(); it != v.end(); ++it) {
        if (!it.value().is_number_integer()) {
          problems.push_back(path + "." + it.key() + ": not an integer");
          continue;
        }
        out[it.key()] = it.value().get<long>();
      }
    };
    eachMember(f, "tasks", true, [&](const std::string& name, const json& v, const std::string& path) {
      FieldReader t(v, path, problems);
      cs.tasks[name] = {t.number("final_error"), t.number("mean_error")};
    });
    if (const json* c = f.object("controller")) {
      FieldReader g(*c, "controller", problems);
      cs.ticks = g.integer("ticks");
      if (const json* s = g.object("status_counts")) counts(*s, "controller.status_counts", cs.status_counts);
      if (const json* s = g.object("augmented_ticks")) counts(*s, "controller.augmented_ticks", cs.augmented_ticks);
    }
    if (const json* s = f.object("solver")) {
      FieldReader g(*s, "solver", problems);
      cs.peak_iterations = static_cast<int>(g.integer("peak_iterations"));
      cs.peak_iterations_at_s = g.number("peak_iterations_at_s");
      cs.peak_factorizations = static_cast<int>(g.integer("peak_factorizations"));
      cs.peak_factorizations_at_s = g.number("peak_factorizations_at_s");
      if (const json* c = g.object("status_counts")) counts(*c, "solver.status_counts", cs.solver_status_counts);
    }
    eachMember(f, "timing_us", true, [&](const std::string& name, const json& v, const std::string& path) {
      FieldReader t(v, path, problems);
      cs.timing_us[name] = {t.number("median"), t.number("p99"), t.number("max")};
    });
    r.controller = std::move(cs);
  }
  r.trace = f.string("trace");
  eachMember(f, "trace_header", true, [&](const std::string& key, const json& v, const std::string& path) {
    if (!v.is_string()) return problems.push_back(path + ": not a string");
    r.trace_header.emplace_back(key, v.get<std::string>());
  });
  if (!problems.empty()) {
    std::string what = "not a run summary this build can read: ";
    for (size_t k = 0; k < problems.size(); ++k) what += (k ? "; " : "") + problems[k];
    throw InputError(where, what);
  }
  return r;
}

RunRecord readRunRecord(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot be read");
  std::stringstream ss;
  ss << in.rdbuf();
  json j;
  const std::string text = ss.str();
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(path, "not a run summary: " + jsonSyntaxProblem(text, e.byte, e.what()));
  } catch (const json::exception& e) {  // a number beyond the double range
    throw InputError(path, std::string("not a run summary: ") + e.what());
  }
  return runRecordFromJson(j, path);
}

}  // namespace lexdyn::records
