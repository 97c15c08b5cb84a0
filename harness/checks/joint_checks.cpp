// Checks on joint channels: parsers and evaluators (docs/cases.md, "Checks").
#include "harness/checks/joint_checks.hpp"

#include "harness/checks/check_base.hpp"

#include <cmath>

namespace lexdyn::checks {

namespace {

// ---------------------------------------------------------------------------------------------
// Parsers.

void readTorqueLimits(CheckReader& r) {
  TorqueLimitsParams p;
  if (auto src = r.map.optional("source")) p.source = src->asEnum({"applied", "commanded", "both"});
  p.joints = r.joints();
  for (const auto& j : p.joints) {
    double lim = 0.0;
    for (const CheckContext::Joint& cj : r.context.joints) {
      if (cj.name == j) lim = cj.effort_limit;
    }
    if (!(lim > 0.0)) r.map.node().fail("joint " + j + " has no effort limit in the URDF");
    p.joint_limits.push_back(lim);
  }
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("limit_fraction").asPositiveDouble();
}

/// `source` (measured | commanded) and `joints` of the oscillation checks.
template <class P>
P oscillationParams(CheckReader& r) {
  P p;
  if (auto src = r.map.optional("source")) p.source = src->asEnum({"measured", "commanded"});
  p.joints = r.joints();
  return p;
}

void readJointSignChanges(CheckReader& r) {
  JointSignChangesParams p = oscillationParams<JointSignChangesParams>(r);
  p.dead_band = r.number("dead_band_rad_per_s2", 0.0, &yaml::Node::asNonNegativeDouble);
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("limit_per_s").asNonNegativeDouble();
}

void readJointHfEnergy(CheckReader& r) {
  JointHfEnergyParams p = oscillationParams<JointHfEnergyParams>(r);
  const yaml::Node cutoff = r.map.required("cutoff_hz");
  p.cutoff_hz = cutoff.asPositiveDouble();
  if (p.cutoff_hz >= 0.5 / r.context.control_period_s) {
    cutoff.fail("must be below the Nyquist frequency of the control rate (" + std::to_string(0.5 / r.context.control_period_s) + " Hz)");
  }
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("limit_rad2_per_s2").asNonNegativeDouble();
}

// ---------------------------------------------------------------------------------------------
// Torque limits: max over joints and rows of |tau_j| / tau_max_j (applied and / or commanded).

// A torque exactly at its limit passes (the controller's torque-limit rows are active there, and
// the simulator saturates at the limit): the value may exceed limit_fraction by 1e-9 (round-off
// of the solver's torques, relative to the effort limit).
class TorqueLimits final : public CheckOf<TorqueLimitsParams> {
 public:
  TorqueLimits(const CheckSpec& s, const CheckType& t) : CheckOf(s, t) { tolerance_ = kBoundaryRelTolerance; }

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    if (p_.joints.size() != p_.joint_limits.size()) {
      throw InputError(spec_.where, "check '" + spec_.name + "': joints and joint limits differ in number");
    }
    for (size_t j = 0; j < p_.joints.size(); ++j) {
      if (p_.source == "applied" || p_.source == "both") cols_.push_back({channel(schema, "tau." + p_.joints[j]), j, "applied"});
      if (p_.source == "commanded" || p_.source == "both") cols_.push_back({channel(schema, "cmd.tau." + p_.joints[j]), j, "commanded"});
    }
  }
  void sample(const double* row, bool) override {
    for (const Col& c : cols_) {
      const double tau = row[c.col];
      const double ratio = std::abs(tau) / p_.joint_limits[c.joint];
      if (worse(ratio)) {
        detail_ = std::string(c.what) + " torque of " + p_.joints[c.joint] + " " + fmt(tau) + " N m (limit " +
                  fmt(p_.joint_limits[c.joint]) + ") at t = " + fmt(row[t_]) + " s; margin " + fmt(spec_.limit - ratio) +
                  " of the effort limit";
      }
    }
  }

  struct Col {
    int col;
    size_t joint;
    const char* what;
  };
  std::vector<Col> cols_;
};

// ---------------------------------------------------------------------------------------------
// Oscillation.

/// The velocity channels of `joints` (measured qd.<J> or commanded cmd.qd.<J>).
std::vector<int> velocityColumns(const TraceSchema& schema, const CheckSpec& spec, const std::string& source,
                                 const std::vector<std::string>& joints) {
  const std::string prefix = source == "commanded" ? "cmd.qd." : "qd.";
  std::vector<int> cols;
  for (const auto& j : joints) cols.push_back(require(schema, prefix + j, spec));
  return cols;
}

const char* sourceName(const std::string& source) { return source == "commanded" ? "commanded" : "measured"; }

// Sign changes per second of each joint's acceleration (the rate of its velocity between
// successive rows); value = the largest over the joints.
class JointAccelerationSignChanges final : public CheckOf<JointSignChangesParams> {
 public:
  using CheckOf::CheckOf;
  void finish(CheckResult& r) const override {
    const double span = t1_ - t0_;
    long best = -1;
    size_t best_j = 0;
    for (size_t j = 0; j < counters_.size(); ++j) {
      if (counters_[j].changes > best) {
        best = counters_[j].changes;
        best_j = j;
      }
    }
    if (best < 0) best = 0;
    r.value = span > 0.0 ? static_cast<double>(best) / span : 0.0;
    r.passed = r.value <= spec_.limit;
    r.detail = (cols_.empty() ? std::string("no joints") : p_.joints[best_j] + ": " + std::to_string(best)) + " sign changes of the " +
               sourceName(p_.source) + " acceleration over " + fmt(span) + " s (dead band " + fmt(p_.dead_band) + " rad/s^2)";
  }

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    cols_ = velocityColumns(schema, spec_, p_.source, p_.joints);
    counters_.assign(cols_.size(), SignChangeCounter{});
  }
  void sample(const double* row, bool first) override {
    const double t = row[t_];
    if (first) t0_ = t;
    t1_ = t;
    for (size_t j = 0; j < cols_.size(); ++j) counters_[j].add(t, row[cols_[j]], p_.dead_band);
  }
  std::vector<int> cols_;
  std::vector<SignChangeCounter> counters_;
  double t0_ = 0.0, t1_ = 0.0;
};

// Mean over the window of sum_j hp(qd_j)^2, hp a 2nd-order Butterworth high-pass (bilinear
// transform) at cutoff_hz; the sample period is the first row spacing, rows at another spacing
// (e.g. the last state of a run) are left out. The filters start at the first row of the trace
// at rest on its value (a constant gives 0).
class JointVelocityHfEnergy final : public CheckOf<JointHfEnergyParams> {
 public:
  using CheckOf::CheckOf;
  // Every row goes through the filters; the window's rows count.
  void consume(const double* row) override {
    const double t = row[t_];
    if (rows_ == 0) {
      t_prev_ = t;
      for (size_t j = 0; j < cols_.size(); ++j) state_[j].start(row[cols_[j]]);
      ++rows_;
      if (active(row)) {  // the first row has zero output
        seen_ = true;
        ++n_;
      }
      return;
    }
    const double h = t - t_prev_;
    if (rows_ == 1) {
      period_ = h;
      if (!(h > 0.0)) {
        invalid_ = "rows without time spacing";
      } else if (!(p_.cutoff_hz < 0.5 / h)) {
        invalid_ = "cutoff " + fmt(p_.cutoff_hz) + " Hz is not below the Nyquist frequency " + fmt(0.5 / h) + " Hz of the trace";
      } else {
        const double K = std::tan(M_PI * p_.cutoff_hz * h);
        const double Q = 1.0 / std::sqrt(2.0);
        const double norm = 1.0 / (1.0 + K / Q + K * K);
        b0_ = norm;
        a1_ = 2.0 * (K * K - 1.0) * norm;
        a2_ = (1.0 - K / Q + K * K) * norm;
      }
    } else if (std::abs(h - period_) > 1e-9 * period_) {
      ++skipped_;
      return;
    }
    ++rows_;
    t_prev_ = t;
    if (!invalid_.empty()) return;
    double e = 0.0;
    for (size_t j = 0; j < cols_.size(); ++j) {
      const double y = state_[j].step(row[cols_[j]], b0_, a1_, a2_);
      if (active(row)) energy_[j] += y * y;
      e += y * y;
    }
    if (active(row)) {
      seen_ = true;
      sum_ += e;
      ++n_;
    }
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!invalid_.empty()) {
      r.value = kNaN;
      r.passed = false;
      r.detail = invalid_;
      return r;
    }
    if (!seen_) return r;
    r.value = sum_ / static_cast<double>(n_);
    r.passed = r.value <= spec_.limit;
    size_t best = 0;
    for (size_t j = 1; j < energy_.size(); ++j) {
      if (energy_[j] > energy_[best]) best = j;
    }
    r.detail = "above " + fmt(p_.cutoff_hz) + " Hz, " + sourceName(p_.source) + " velocities, " + std::to_string(n_) + " rows";
    if (!energy_.empty()) r.detail += "; largest share " + p_.joints[best] + " " + fmt(energy_[best] / static_cast<double>(n_));
    if (skipped_ > 0) r.detail += "; " + std::to_string(skipped_) + " rows at another spacing left out";
    return r;
  }

 private:
  struct Biquad {
    double x1 = 0.0, x2 = 0.0, y1 = 0.0, y2 = 0.0;
    void start(double x) { x1 = x2 = x, y1 = y2 = 0.0; }
    // High-pass: b = b0 [1, -2, 1].
    double step(double x, double b0, double a1, double a2) {
      const double y = b0 * (x - 2.0 * x1 + x2) - a1 * y1 - a2 * y2;
      x2 = x1, x1 = x, y2 = y1, y1 = y;
      return y;
    }
  };
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    cols_ = velocityColumns(schema, spec_, p_.source, p_.joints);
    state_.assign(cols_.size(), Biquad{});
    energy_.assign(cols_.size(), 0.0);
  }
  std::vector<int> cols_;
  std::vector<Biquad> state_;
  std::vector<double> energy_;
  long rows_ = 0, n_ = 0, skipped_ = 0;
  double t_prev_ = 0.0, period_ = 0.0, b0_ = 0.0, a1_ = 0.0, a2_ = 0.0, sum_ = 0.0;
  std::string invalid_;
};

}  // namespace

CheckType torqueLimitsCheck() {
  return {"torque_limits", "fraction of the effort limit", kControllerChannels, readTorqueLimits, makeEvaluator<TorqueLimits>};
}
CheckType jointAccelerationSignChangesCheck() {
  return {"joint_acceleration_sign_changes", "sign changes per second", kControllerChannels, readJointSignChanges,
          makeEvaluator<JointAccelerationSignChanges>};
}
CheckType jointVelocityHfEnergyCheck() {
  return {"joint_velocity_hf_energy", "(rad/s)^2", kControllerChannels, readJointHfEnergy, makeEvaluator<JointVelocityHfEnergy>};
}

}  // namespace lexdyn::checks
