#include "harness/checks/checks.hpp"
#include "harness/checks/check_base.hpp"

#include "lexdyn/common/error.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

namespace lexdyn::checks {

std::string frameChannel(const std::string& frame, char axis) { return "frame." + frame + "." + axis; }
std::string contactForceChannel(const std::string& surface) { return "contact." + surface + ".fz"; }
std::string contactPointChannel(const std::string& surface, int point, char axis) {
  return "contact." + surface + ".p" + std::to_string(point) + "." + axis;
}

namespace {

using detail::CheckBase;
using detail::kNaN;
using detail::require;

class FrameDrift final : public CheckBase {
 public:
  explicit FrameDrift(const CheckSpec& s) : CheckBase(s, "m") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    for (int k = 0; k < 3; ++k) c_[k] = require(schema, frameChannel(spec_.frame, "xyz"[k]), spec_);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    if (!seen_) {
      for (int k = 0; k < 3; ++k) ref_[k] = row[c_[k]];
      seen_ = true;
    }
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (row[c_[k]] - ref_[k]) * (row[c_[k]] - ref_[k]);
    const double d = std::sqrt(d2);
    if (d > worst_ || std::isnan(d)) {
      worst_ = d;
      detail_ = "largest at t = " + std::to_string(row[t_]) + " s";
    }
  }

 private:
  int c_[3] = {0, 0, 0};
  double ref_[3] = {0, 0, 0};
};

class ForceBalance final : public CheckBase {
 public:
  explicit ForceBalance(const CheckSpec& s) : CheckBase(s, "relative") {}
  void bind(const TraceSchema& schema, const TraceMetadata& metadata) override {
    t_ = require(schema, kTimeChannel, spec_);
    for (const auto& s : spec_.surfaces) cols_.push_back(require(schema, contactForceChannel(s), spec_));
    const std::string* w = findMetadata(metadata, kWeightMetadata);
    if (!w) throw InputError(spec_.where, std::string("check '") + spec_.name + "' needs the trace metadata '" + kWeightMetadata + "'");
    weight_ = std::strtod(w->c_str(), nullptr);
    if (!(weight_ > 0.0)) throw InputError(spec_.where, "robot weight in the trace metadata must be > 0");
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    seen_ = true;
    double sum = 0.0;
    for (int c : cols_) sum += row[c];
    const double e = std::abs(sum - weight_) / weight_;
    if (e > worst_ || std::isnan(e)) {
      worst_ = e;
      detail_ = "largest at t = " + std::to_string(row[t_]) + " s: sum " + std::to_string(sum) + " N, weight " +
                std::to_string(weight_) + " N";
    }
  }

 private:
  std::vector<int> cols_;
  double weight_ = 0.0;
};

// Lowest height of a frame's origin; passes when it stays at or above the limit.
class FrameHeight final : public CheckBase {
 public:
  explicit FrameHeight(const CheckSpec& s) : CheckBase(s, "m") { worst_ = std::numeric_limits<double>::infinity(); }
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    z_ = require(schema, frameChannel(spec_.frame, 'z'), spec_);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    seen_ = true;
    const double z = row[z_];
    if (z < worst_ || std::isnan(z)) {
      worst_ = z;
      detail_ = "lowest at t = " + std::to_string(row[t_]) + " s";
    }
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (seen_) r.passed = worst_ >= spec_.limit;
    return r;
  }

 private:
  int z_ = 0;
};

class ContactSlip final : public CheckBase {
 public:
  explicit ContactSlip(const CheckSpec& s) : CheckBase(s, "m") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    for (const auto& s : spec_.surfaces) {
      int found = 0;
      for (int i = 0;; ++i) {
        const int cx = schema.find(contactPointChannel(s, i, 'x'));
        const int cy = schema.find(contactPointChannel(s, i, 'y'));
        if (cx < 0 || cy < 0) break;
        cols_.push_back({cx, cy});
        names_.push_back(s + ".p" + std::to_string(i));
        ++found;
      }
      if (found == 0) require(schema, contactPointChannel(s, 0, 'x'), spec_);
    }
    ref_.assign(cols_.size(), {0.0, 0.0});
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    if (!seen_) {
      for (size_t i = 0; i < cols_.size(); ++i) ref_[i] = {row[cols_[i].first], row[cols_[i].second]};
      seen_ = true;
    }
    for (size_t i = 0; i < cols_.size(); ++i) {
      const double dx = row[cols_[i].first] - ref_[i].first, dy = row[cols_[i].second] - ref_[i].second;
      const double d = std::sqrt(dx * dx + dy * dy);
      if (d > worst_ || std::isnan(d)) {
        worst_ = d;
        detail_ = "largest for " + names_[i] + " at t = " + std::to_string(row[t_]) + " s";
      }
    }
  }

 private:
  std::vector<std::pair<int, int>> cols_;
  std::vector<std::string> names_;
  std::vector<std::pair<double, double>> ref_;
};

}  // namespace

double margin(const CheckResult& r) {
  if (std::isnan(r.value) || !std::isfinite(r.limit)) return std::numeric_limits<double>::quiet_NaN();
  const bool lower_bound = r.type == "frame_height" || r.type == "contact_unilateral";
  return lower_bound ? r.value - r.limit : r.limit - r.value;
}

const std::vector<std::string>& checkTypes() {
  static const std::vector<std::string> types = [] {
    std::vector<std::string> v = {"frame_drift", "force_balance", "contact_slip", "frame_height"};
    for (const auto& t : detail::controllerCheckTypes()) v.push_back(t);
    return v;
  }();
  return types;
}

std::unique_ptr<Check> makeCheck(const CheckSpec& spec) {
  if (spec.type == "frame_drift") return std::make_unique<FrameDrift>(spec);
  if (spec.type == "force_balance") return std::make_unique<ForceBalance>(spec);
  if (spec.type == "contact_slip") return std::make_unique<ContactSlip>(spec);
  if (spec.type == "frame_height") return std::make_unique<FrameHeight>(spec);
  if (auto c = detail::makeControllerCheck(spec)) return c;
  throw InputError(spec.where, "unknown check type '" + spec.type + "'");
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

std::vector<CheckResult> runChecks(const std::vector<CheckSpec>& specs, const TraceTable& trace, bool wall_clock_checks) {
  TraceSchema schema;
  for (const auto& n : trace.names) schema.add(n);
  const std::string* method = findMetadata(trace.metadata, kMethodMetadata);
  std::vector<CheckResult> out;
  for (const auto& s : specs) {
    if (!appliesTo(s, method ? *method : std::string())) continue;
    auto c = makeCheck(s);
    c->bind(schema, trace.metadata);
    for (const auto& row : trace.rows) c->consume(row.data());
    out.push_back(c->result());
    applyWallClockPolicy(out.back(), wall_clock_checks);
  }
  return out;
}

}  // namespace lexdyn::checks
