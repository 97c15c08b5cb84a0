// Checks on the lexdyn controller's health and cost: parsers and evaluators (docs/cases.md,
// "Checks").
#include "harness/checks/health_checks.hpp"

#include "harness/checks/check_base.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace lexdyn::checks {

namespace {

// ---------------------------------------------------------------------------------------------
// Parsers.

void readControllerStatus(CheckReader& r) {
  ControllerStatusParams p;
  if (auto v = r.map.optional("allowed")) {
    p.allowed.clear();
    for (const yaml::Node& a : v->elements()) p.allowed.push_back(a.asEnum(controllerStatusNames()));
  }
  r.spec.params = std::move(p);
  r.spec.limit = r.number("limit_count", 0.0, &yaml::Node::asNonNegativeDouble);
}

void readActiveSetPeak(CheckReader& r) { r.spec.limit = r.map.required("limit_iterations").asPositiveDouble(); }

void readFactorizationPeak(CheckReader& r) { r.spec.limit = r.map.required("limit_factorizations").asPositiveDouble(); }

void readAugmentedFraction(CheckReader& r) {
  const yaml::Node ln = r.map.required("level");
  AugmentedFractionParams p{ln.asString()};
  for (const std::string& method : r.methods) {
    const CheckContext::Method* m = r.context.findMethod(method);
    if (!m || std::find(m->levels.begin(), m->levels.end(), p.level) == m->levels.end()) {
      ln.fail("level '" + p.level + "' is not in the hierarchy of method " + method + "; restrict the check with methods: [...]");
    }
  }
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("max_fraction").asNonNegativeDouble();
}

void readTickTime(CheckReader& r) {
  TickTimeParams p;
  p.timer = r.map.required("timer").asEnum({"model", "tasks", "hessian", "solver", "tick"});
  if (auto v = r.map.optional("percentile")) {
    p.percentile = v->asDouble();
    if (!(p.percentile > 0.0 && p.percentile <= 100.0)) v->fail("expected a percentile in (0, 100]");
  }
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("limit_us").asPositiveDouble();
}

// ---------------------------------------------------------------------------------------------
// Evaluators.

// Number of rows whose controller status is not among the allowed ones.
class ControllerStatus final : public CheckOf<ControllerStatusParams> {
 public:
  using CheckOf::CheckOf;
  void finish(CheckResult& r) const override {
    std::string d;
    for (const auto& [name, n] : counts_) d += (d.empty() ? "" : ", ") + name + " " + std::to_string(n);
    r.detail = d + (first_bad_.empty() ? "" : "; " + first_bad_);
  }

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    col_ = channel(schema, kControllerStatusChannel);
    const auto& names = controllerStatusNames();
    allowed_.assign(names.size(), 0);
    for (const auto& a : p_.allowed) {
      const auto it = std::find(names.begin(), names.end(), a);
      if (it == names.end()) throw InputError(spec_.where, "unknown controller status '" + a + "'");
      allowed_[static_cast<size_t>(it - names.begin())] = 1;
    }
  }
  void sample(const double* row, bool) override {
    const double v = row[col_];
    const auto& names = controllerStatusNames();
    const int code = (v >= 0.0 && v < static_cast<double>(names.size()) && v == std::floor(v)) ? static_cast<int>(v) : -1;
    const std::string name = code >= 0 ? names[static_cast<size_t>(code)] : "invalid(" + fmt(v) + ")";
    ++counts_[name];
    if (code < 0 || !allowed_[static_cast<size_t>(code)]) {
      if (worst_ == 0.0) first_bad_ = "first at t = " + fmt(row[t_]) + " s (" + name + ")";
      worst_ += 1.0;
    }
  }
  int col_ = 0;
  std::vector<char> allowed_;
  std::map<std::string, long> counts_;
  std::string first_bad_;
};

// Largest value of a per-tick count (solver iterations or factorisations; deterministic, unlike
// tick_time).
class PeakCount : public CheckBase {
 public:
  PeakCount(const CheckSpec& s, const CheckType& t, const char* channel) : CheckBase(s, t), channel_(channel) {}

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override { col_ = channel(schema, channel_); }
  void sample(const double* row, bool first) override {
    const double v = row[col_];
    if (first || v > worst_ || std::isnan(v)) {
      worst_ = v;
      detail_ = "at t = " + fmt(row[t_]) + " s";
    }
  }
  const char* channel_;
  int col_ = 0;
};

// Largest number of active-set iterations of a tick.
class ActiveSetPeak final : public PeakCount {
 public:
  ActiveSetPeak(const CheckSpec& s, const CheckType& t) : PeakCount(s, t, kSolverIterationsChannel) {}
};

// Largest number of level stages the solver factorised in a tick: the deterministic proxy of a
// tick's solver time (the same on every machine and under any load, unlike tick_time).
class FactorizationPeak final : public PeakCount {
 public:
  FactorizationPeak(const CheckSpec& s, const CheckType& t) : PeakCount(s, t, kSolverFactorizationsChannel) {}
};

// Fraction of rows at which a level was augmented with Newton rows.
class AugmentedFraction final : public CheckOf<AugmentedFractionParams> {
 public:
  using CheckOf::CheckOf;

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    col_ = channel(schema, levelChannel(p_.level, "augmented"));
  }
  void sample(const double* row, bool) override {
    ++n_;
    if (row[col_] != 0.0) {
      if (augmented_ == 0) first_ = row[t_];
      ++augmented_;
    }
    worst_ = static_cast<double>(augmented_) / static_cast<double>(n_);
    detail_ =
        std::to_string(augmented_) + " of " + std::to_string(n_) + " rows" + (augmented_ > 0 ? ", first at t = " + fmt(first_) + " s" : "");
  }
  int col_ = 0;
  long n_ = 0, augmented_ = 0;
  double first_ = 0.0;
};

// A percentile (nearest rank) of a per-tick wall time, microseconds. Machine-dependent.
class TickTime final : public CheckOf<TickTimeParams> {
 public:
  using CheckOf::CheckOf;
  void finish(CheckResult& r) const override {
    std::vector<double> v = values_;
    std::sort(v.begin(), v.end());
    const double p = std::clamp(p_.percentile, 0.0, 100.0);
    size_t rank = static_cast<size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
    rank = std::clamp<size_t>(rank, 1, v.size());
    r.value = v[rank - 1];
    r.passed = r.value <= spec_.limit;
    r.detail = "p" + fmt(p) + " of " + p_.timer + " time over " + std::to_string(v.size()) + " ticks (max " + fmt(v.back()) +
               " us; wall-clock measurement, machine-dependent)";
  }

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override { col_ = channel(schema, timerChannel(p_.timer)); }
  void sample(const double* row, bool) override { values_.push_back(row[col_]); }
  int col_ = 0;
  std::vector<double> values_;
};

}  // namespace

CheckType controllerStatusCheck() {
  return {"controller_status", "ticks", kControllerChannels, readControllerStatus, makeEvaluator<ControllerStatus>};
}
CheckType activeSetPeakCheck() {
  return {"active_set_peak", "iterations", kControllerChannels, readActiveSetPeak, makeEvaluator<ActiveSetPeak>};
}
CheckType factorizationPeakCheck() {
  return {"factorization_peak", "level factorisations", kControllerChannels, readFactorizationPeak, makeEvaluator<FactorizationPeak>};
}
CheckType augmentedFractionCheck() {
  return {"augmented_fraction", "fraction of ticks", kControllerChannels, readAugmentedFraction, makeEvaluator<AugmentedFraction>};
}
CheckType tickTimeCheck() { return {"tick_time", "us", kControllerChannels | kMachineDependent, readTickTime, makeEvaluator<TickTime>}; }

}  // namespace lexdyn::checks
