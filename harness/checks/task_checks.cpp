// Checks on the lexdyn controller's task channels: parsers and evaluators (docs/cases.md,
// "Checks"), and the method comparisons.
#include "harness/checks/task_checks.hpp"

#include "harness/checks/check_base.hpp"
#include "lexdyn/common/input_ranges.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lexdyn::checks {

namespace {

// ---------------------------------------------------------------------------------------------
// Parsers.

void readTaskError(CheckReader& r) {
  TaskErrorParams p;
  p.tasks = r.tasks("tasks");
  p.statistic = r.map.required("statistic").asEnum({"final", "mean", "max", "range"});
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("limit").asNonNegativeDouble();
}

void readTaskErrorRate(CheckReader& r) {
  TaskErrorRateParams p;
  p.task = r.task("task");
  p.dead_band = r.number("dead_band_per_s", 0.0, &yaml::Node::asNonNegativeDouble);
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("limit_per_s").asNonNegativeDouble();
}

// The gains default to the task's own (kv absent: 2 sqrt(kp), critical damping).
void readTaskClosedForm(CheckReader& r) {
  TaskClosedFormParams p;
  p.task = r.task("task");
  const CheckContext::Task& t = *r.context.findTask(p.task);
  auto kp = r.map.optional("kp");
  auto kv = r.map.optional("kv");
  if (!t.has_gains && !kp) r.map.required("task").fail("task '" + t.name + "' (" + t.type + ") has no PD gains; give kp (and kv)");
  p.kp = kp ? kp->asNonNegativeDouble() : t.kp;
  if (kv)
    p.kv = kv->asNonNegativeDouble();
  else if (!kp && t.kv)
    p.kv = *t.kv;
  else
    p.kv = 2.0 * std::sqrt(p.kp);
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("limit_rel").asNonNegativeDouble();
}

void readTaskOvershoot(CheckReader& r) {
  r.spec.params = TaskOvershootParams{r.task("task")};
  r.spec.limit = r.map.required("limit_rel").asNonNegativeDouble();
}

// ---------------------------------------------------------------------------------------------
// Convergence: a statistic of the sum of some tasks' error norms over the window.

class TaskErrorStat {
 public:
  void bind(const TraceSchema& schema, const CheckSpec& spec, const std::vector<std::string>& tasks) {
    cols_.clear();
    for (const auto& t : tasks) cols_.push_back(require(schema, taskChannel(t, "error"), spec));
  }
  void consume(double t, const double* row) {
    double s = 0.0;
    for (int c : cols_) s += row[c];
    if (n_ > 0)
      integral_ += 0.5 * (t - t_last_) * (s + last_);
    else
      t_first_ = t;
    if (n_ == 0 || s > max_ || std::isnan(s)) {
      max_ = s;
      t_max_ = t;
    }
    if (n_ == 0 || s < min_ || std::isnan(s)) {
      min_ = s;
      t_min_ = t;
    }
    sum_ += s;
    last_ = s;
    t_last_ = t;
    ++n_;
  }
  /// final | mean (time average, trapezoidal over the rows) | max | range (max - min: how much
  /// the error still moves within the window, a convergence measure)
  double value(const std::string& statistic) const {
    if (statistic == "final") return last_;
    if (statistic == "max") return max_;
    if (statistic == "range") return max_ - min_;
    if (t_last_ > t_first_) return integral_ / (t_last_ - t_first_);
    return sum_ / static_cast<double>(n_);
  }
  std::string describe(const std::string& statistic) const {
    if (statistic == "final") return "at t = " + fmt(t_last_) + " s";
    if (statistic == "max") return "largest at t = " + fmt(t_max_) + " s";
    if (statistic == "range") {
      return "largest " + fmt(max_) + " at t = " + fmt(t_max_) + " s, smallest " + fmt(min_) + " at t = " + fmt(t_min_) + " s";
    }
    return "time average over t = " + fmt(t_first_) + " .. " + fmt(t_last_) + " s";
  }

 private:
  std::vector<int> cols_;
  long n_ = 0;
  double sum_ = 0.0, integral_ = 0.0, last_ = 0.0, max_ = 0.0, t_max_ = 0.0, t_first_ = 0.0, t_last_ = 0.0;
  double min_ = 0.0, t_min_ = 0.0;
};

class TaskError final : public CheckOf<TaskErrorParams> {
 public:
  using CheckOf::CheckOf;
  void finish(CheckResult& r) const override {
    r.value = stat_.value(p_.statistic);
    r.passed = r.value <= spec_.limit;
    std::string names;
    for (const auto& t : p_.tasks) names += (names.empty() ? "" : " + ") + t;
    r.detail = p_.statistic + " of " + names + ", " + stat_.describe(p_.statistic);
  }

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override { stat_.bind(schema, spec_, p_.tasks); }
  void sample(const double* row, bool) override { stat_.consume(row[t_], row); }
  TaskErrorStat stat_;
};

// Sign changes per second of the rate of a task's error norm.
class TaskErrorRateSignChanges final : public CheckOf<TaskErrorRateParams> {
 public:
  using CheckOf::CheckOf;
  void finish(CheckResult& r) const override {
    const double span = t1_ - t0_;
    r.value = span > 0.0 ? static_cast<double>(counter_.changes) / span : 0.0;
    r.passed = r.value <= spec_.limit;
    r.detail = std::to_string(counter_.changes) + " sign changes of d/dt |e| of " + p_.task + " over " + fmt(span) + " s (dead band " +
               fmt(p_.dead_band) + ")";
  }

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override { col_ = channel(schema, taskChannel(p_.task, "error")); }
  void sample(const double* row, bool first) override {
    if (first) t0_ = row[t_];
    t1_ = row[t_];
    counter_.add(row[t_], row[col_], p_.dead_band);
  }
  int col_ = 0;
  SignChangeCounter counter_;
  double t0_ = 0.0, t1_ = 0.0;
};

// ---------------------------------------------------------------------------------------------
// PD convergence of one task against the closed form (the paper's sec. V-A, eq. 47-52).

/// Solution of x'' + kv x' + kp x = 0 with x(0) = 1, x'(0) = 0 (unit mass; eq. 48-49): critically
/// damped for kv = 2 sqrt(kp), x = (1 + w t) e^{-w t}, w = sqrt(kp); under- and over-damped
/// otherwise.
double pdClosedForm(double kp, double kv, double t) {
  const double delta = 0.5 * kv;
  const double disc = kp - delta * delta;
  if (std::abs(disc) <= 1e-12 * std::max(kp, delta * delta)) return (1.0 + delta * t) * std::exp(-delta * t);
  if (disc > 0.0) {
    const double wd = std::sqrt(disc);
    return std::exp(-delta * t) * (std::cos(wd * t) + delta / wd * std::sin(wd * t));
  }
  const double r = std::sqrt(-disc), r1 = -delta + r, r2 = -delta - r;
  return (r2 * std::exp(r1 * t) - r1 * std::exp(r2 * t)) / (r2 - r1);
}

// A check on one task's error norm e(t) relative to its value e0 at the window's first row (time
// t0): the response of a task started at that row. When e0 is not positive and finite there is
// no response to measure, and the check fails without a value.
class TaskResponseCheck : public CheckBase {
 public:
  TaskResponseCheck(const CheckSpec& s, const CheckType& t, const std::string& task) : CheckBase(s, t), task_(task) {}

 protected:
  /// One row of the window (only while e0 is usable).
  virtual void respond(double t, double e) = 0;
  bool validStart() const { return e0_ > 0.0 && std::isfinite(e0_); }
  /// The failed result of an unusable e0; `why` is appended to the detail.
  void invalidStart(CheckResult& r, const std::string& why) const {
    r.value = kNaN;
    r.passed = false;
    r.detail = "the error of " + task_ + " at the window's start (t = " + fmt(t0_) + " s) is " + fmt(e0_) + why;
  }
  /// " (e0 ... at t = ... s" shared by the details.
  std::string startDetail() const { return " (e0 " + fmt(e0_) + " at t = " + fmt(t0_) + " s"; }

  double t0_ = 0.0, e0_ = 0.0;

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override { col_ = channel(schema, taskChannel(task_, "error")); }
  void sample(const double* row, bool first) final {
    const double t = row[t_], e = row[col_];
    if (first) {
      t0_ = t;
      e0_ = e;
    }
    if (validStart()) respond(t, e);
  }
  std::string task_;
  int col_ = 0;
};

// Largest |e(t) - e0 |x(t - t0)|| / e0 over the window, x the closed form above: the error norm
// of a task started at rest against the continuous PD response (for a 1-D task; in more
// dimensions along a straight line).
class TaskErrorClosedForm final : public TaskResponseCheck {
 public:
  TaskErrorClosedForm(const CheckSpec& s, const CheckType& t)
      : TaskResponseCheck(s, t, s.paramsAs<TaskClosedFormParams>().task), p_(spec_.paramsAs<TaskClosedFormParams>()) {}
  void finish(CheckResult& r) const override {
    if (!validStart()) return invalidStart(r, ": no response to compare");
    const double zeta = p_.kp > 0.0 ? p_.kv / (2.0 * std::sqrt(p_.kp)) : kInf;
    r.detail = detail_ + startDetail() + "; kp " + fmt(p_.kp) + ", kv " + fmt(p_.kv) + ", damping ratio " + fmt(zeta) + ")";
  }

 private:
  void respond(double t, double e) override {
    const double ref = e0_ * std::abs(pdClosedForm(p_.kp, p_.kv, t - t0_));
    if (worse(std::abs(e - ref) / e0_)) detail_ = "largest at t = " + fmt(t) + " s: |e| " + fmt(e) + ", closed form " + fmt(ref);
  }
  const TaskClosedFormParams& p_;
};

// Overshoot of a task: the largest rise of its error norm above its running minimum, relative to
// the error at the window's first row. A task converging monotonically gives 0; a 1-D task that
// passes through its target (the norm goes to 0 and rises again) gives its largest excursion past
// the target.
class TaskOvershoot final : public TaskResponseCheck {
 public:
  TaskOvershoot(const CheckSpec& s, const CheckType& t) : TaskResponseCheck(s, t, s.paramsAs<TaskOvershootParams>().task) {}
  void finish(CheckResult& r) const override {
    if (!validStart()) return invalidStart(r, "");
    r.value = rise_ / e0_;
    r.passed = r.value <= spec_.limit;
    r.detail = (detail_.empty() ? std::string("the error never rises") : detail_) + startDetail() + ")";
  }

 private:
  void respond(double t, double e) override {
    if (!have_min_ || e < min_) {
      min_ = e;
      t_min_ = t;
      have_min_ = true;
    }
    const double rise = e - min_;
    if (rise > rise_ || std::isnan(rise)) {
      rise_ = rise;
      detail_ =
          "largest rise at t = " + fmt(t) + " s: |e| " + fmt(e) + " after a minimum of " + fmt(min_) + " at t = " + fmt(t_min_) + " s";
    }
  }
  bool have_min_ = false;
  double min_ = 0.0, t_min_ = 0.0, rise_ = 0.0;
};

}  // namespace

CheckType taskErrorCheck() {
  return {"task_error", "task error norm (m, rad)", kControllerChannels, readTaskError, makeEvaluator<TaskError>};
}
CheckType taskErrorRateSignChangesCheck() {
  return {"task_error_rate_sign_changes", "sign changes per second", kControllerChannels, readTaskErrorRate,
          makeEvaluator<TaskErrorRateSignChanges>};
}
CheckType taskErrorClosedFormCheck() {
  return {"task_error_closed_form", "fraction of the initial error", kControllerChannels, readTaskClosedForm,
          makeEvaluator<TaskErrorClosedForm>};
}
CheckType taskOvershootCheck() {
  return {"task_overshoot", "fraction of the initial error", kControllerChannels, readTaskOvershoot, makeEvaluator<TaskOvershoot>};
}

// ---------------------------------------------------------------------------------------------
// Method comparisons.

ComparisonSpec readComparison(const yaml::Node& node, const CheckContext& context) {
  yaml::StrictMap m(node);
  ComparisonSpec c;
  c.where = node.where();
  c.name = m.required("name").asString();
  c.type = m.required("type").asEnum({"method_comparison"});
  const yaml::Node tn = m.required("tasks");
  c.tasks = context.taskNames(tn);
  c.statistic = m.required("statistic").asEnum({"final", "mean", "max"});
  c.better = context.method(m.required("better"));
  c.worse = context.method(m.required("worse"));
  context.requireTasksInHierarchies(tn, c.tasks, {c.better, c.worse});
  if (auto v = m.optional("margin")) c.margin = v->asDouble();
  if (auto f = m.optional("from_s")) c.from_s = f->asDoubleIn(0.0, ranges::kMaxTime_s, "s");
  if (auto t = m.optional("to_s")) c.to_s = t->asNonNegativeDouble();
  if (auto x = m.optional("expected_to_fail")) c.expected_failure_reason = x->asString();  // the reason, non-empty
  m.finish();
  return c;
}

CheckSpec comparisonStatistic(const ComparisonSpec& spec) {
  CheckSpec cs;
  cs.name = spec.name;
  cs.type = "task_error";
  cs.where = spec.where;
  cs.from_s = spec.from_s;
  cs.to_s = spec.to_s;
  cs.params = TaskErrorParams{spec.tasks, spec.statistic};
  cs.limit = std::numeric_limits<double>::infinity();
  return cs;
}

CheckResult compareMethods(const ComparisonSpec& spec, const TraceTable& better, const TraceTable& worse) {
  const CheckSpec cs = comparisonStatistic(spec);
  auto statistic = [&](const TraceTable& t, const std::string& method) {
    const std::string* m = findMetadata(t.metadata, kMethodMetadata);
    if (!m || *m != method) {
      throw InputError(spec.where, "comparison '" + spec.name + "' needs a trace of method " + method + ", found " +
                                       (m ? *m : std::string("a trace without a method")));
    }
    return evaluate(cs, schemaOf(t), t);
  };
  const CheckResult b = statistic(better, spec.better), w = statistic(worse, spec.worse);
  CheckResult r;
  r.name = spec.name;
  r.type = spec.type;
  r.limit = spec.margin;
  r.unit = b.unit;
  if (std::isnan(b.value) || std::isnan(w.value)) {
    r.value = kNaN;
    r.passed = false;
    r.detail = "no rows in the window: " + spec.better + " " + b.detail + "; " + spec.worse + " " + w.detail;
    return r;
  }
  r.value = b.value - w.value;
  r.passed = r.value <= spec.margin;
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%s %s %.6g, %s %.6g", spec.statistic.c_str(), spec.better.c_str(), b.value, spec.worse.c_str(), w.value);
  r.detail = buf;
  return r;
}

}  // namespace lexdyn::checks
