// Checks on the lexdyn controller's trace channels (docs/cases.md, "Checks"). Like every check
// they read rows of named channels, so a stored trace gives the same result as the live run
// when it holds every row (trace.every_n_ticks: 1); rate-based checks use the rows' times.
#include "harness/checks/check_base.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace lexdyn::checks {

namespace detail {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

const char* const kWrenchComponents[6] = {"fx", "fy", "fz", "tx", "ty", "tz"};

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
    if (n_ > 0) integral_ += 0.5 * (t - t_last_) * (s + last_);
    else t_first_ = t;
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
  bool seen() const { return n_ > 0; }
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

class TaskError final : public CheckBase {
 public:
  explicit TaskError(const CheckSpec& s) : CheckBase(s, "task error norm (m, rad)") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    stat_.bind(schema, spec_, spec_.tasks);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    seen_ = true;
    stat_.consume(row[t_], row);
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) return r;
    r.value = stat_.value(spec_.statistic);
    r.passed = r.value <= spec_.limit;
    std::string names;
    for (const auto& t : spec_.tasks) names += (names.empty() ? "" : " + ") + t;
    r.detail = spec_.statistic + " of " + names + ", " + stat_.describe(spec_.statistic);
    return r;
  }

 private:
  TaskErrorStat stat_;
};

// ---------------------------------------------------------------------------------------------
// Torque limits: max over joints and rows of |tau_j| / tau_max_j (applied and / or commanded).

// A torque exactly at its limit passes (the controller's torque-limit rows are active there, and
// the simulator saturates at the limit): the value may exceed limit_fraction by 1e-9 (round-off
// of the solver's torques, relative to the effort limit).
class TorqueLimits final : public CheckBase {
 public:
  explicit TorqueLimits(const CheckSpec& s) : CheckBase(s, "fraction of the effort limit") { tolerance_ = kBoundaryRelTolerance; }
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    if (spec_.joints.size() != spec_.joint_limits.size()) {
      throw InputError(spec_.where, "check '" + spec_.name + "': joints and joint limits differ in number");
    }
    for (size_t j = 0; j < spec_.joints.size(); ++j) {
      if (spec_.source == "applied" || spec_.source == "both") cols_.push_back({require(schema, "tau." + spec_.joints[j], spec_), j, "applied"});
      if (spec_.source == "commanded" || spec_.source == "both") cols_.push_back({require(schema, "cmd.tau." + spec_.joints[j], spec_), j, "commanded"});
    }
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    seen_ = true;
    for (const Col& c : cols_) {
      const double tau = row[c.col];
      const double ratio = std::abs(tau) / spec_.joint_limits[c.joint];
      if (ratio > worst_ || std::isnan(ratio)) {
        worst_ = ratio;
        detail_ = std::string(c.what) + " torque of " + spec_.joints[c.joint] + " " + fmt(tau) + " N m (limit " +
                  fmt(spec_.joint_limits[c.joint]) + ") at t = " + fmt(row[t_]) + " s; margin " + fmt(spec_.limit - ratio) +
                  " of the effort limit";
      }
    }
  }


 private:
  struct Col {
    int col;
    size_t joint;
    const char* what;
  };
  std::vector<Col> cols_;
};

// ---------------------------------------------------------------------------------------------
// Contact wrenches (in the contact frame, about its origin; docs/cases.md). Rows where the
// controller's contact is inactive are skipped.

class ContactCheck : public CheckBase {
 public:
  ContactCheck(const CheckSpec& s, std::string unit) : CheckBase(s, std::move(unit)) {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    active_ = require(schema, contactActiveChannel(spec_.contact), spec_);
    const bool sensed = spec_.source == "sensed";
    for (int k = 0; k < 6; ++k) w_[k] = require(schema, wrenchChannel(spec_.contact, sensed, kWrenchComponents[k]), spec_);
  }

 protected:
  bool contactActive(const double* row) const { return active(row) && row[active_] != 0.0; }
  double normalForce(const double* row) const {
    return row[w_[0]] * spec_.normal[0] + row[w_[1]] * spec_.normal[1] + row[w_[2]] * spec_.normal[2];
  }
  double tangentialForce(const double* row) const {
    const double fn = normalForce(row);
    double s = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double ft = row[w_[k]] - fn * spec_.normal[k];
      s += ft * ft;
    }
    return std::sqrt(s);
  }
  const char* sourceName() const { return spec_.source == "sensed" ? "sensed" : "computed"; }
  int active_ = 0;
  int w_[6] = {0, 0, 0, 0, 0, 0};
};

// Lowest normal force while the contact is active; passes when every row has
// f_n >= min_N - 1e-9 |f| (round-off of the wrench's frame change, relative to the row's force).
class ContactUnilateral final : public ContactCheck {
 public:
  explicit ContactUnilateral(const CheckSpec& s) : ContactCheck(s, "N") { worst_ = kInf; }
  void consume(const double* row) override {
    if (!contactActive(row)) return;
    seen_ = true;
    const double fn = normalForce(row);
    const double fnorm = std::sqrt(row[w_[0]] * row[w_[0]] + row[w_[1]] * row[w_[1]] + row[w_[2]] * row[w_[2]]);
    if (!(fn >= spec_.limit - kBoundaryRelTolerance * fnorm)) {
      if (!below_) first_below_ = row[t_];
      below_ = true;
    }
    if (fn < worst_ || std::isnan(fn)) {
      worst_ = fn;
      detail_ = std::string("lowest ") + sourceName() + " normal force at t = " + fmt(row[t_]) + " s";
    }
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (seen_) {
      r.passed = !below_;
      if (below_) r.detail += "; first below " + fmt(spec_.limit) + " N at t = " + fmt(first_below_) + " s";
    } else {
      r.detail = "no row with contact '" + spec_.contact + "' active in the window";
    }
    return r;
  }

 private:
  bool below_ = false;
  double first_below_ = 0.0;
};

// max |f_t| / (mu f_n) over rows with f_n >= min_normal_N (the circular cone). The computed
// wrench lies exactly on the cone when a single generator of the friction pyramid carries it,
// so the ratio may exceed the limit by 1e-9 (round-off).
class ContactFriction final : public ContactCheck {
 public:
  explicit ContactFriction(const CheckSpec& s) : ContactCheck(s, "|f_t| / (mu f_n)") { tolerance_ = kBoundaryRelTolerance; }
  void consume(const double* row) override {
    if (!contactActive(row)) return;
    const double fn = normalForce(row);
    if (!(fn >= spec_.min_normal_N) || fn <= 0.0) {
      ++skipped_;
      return;
    }
    seen_ = true;
    const double ratio = tangentialForce(row) / (spec_.friction * fn);
    if (ratio > worst_ || std::isnan(ratio)) {
      worst_ = ratio;
      detail_ = std::string("largest ") + sourceName() + " ratio at t = " + fmt(row[t_]) + " s (f_n " + fmt(fn) + " N, mu " +
                fmt(spec_.friction) + ")";
    }
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) r.detail = "no row with contact '" + spec_.contact + "' active and f_n >= " + fmt(spec_.min_normal_N) + " N";
    else if (skipped_ > 0) r.detail += "; " + std::to_string(skipped_) + " rows with f_n below " + fmt(spec_.min_normal_N) + " N skipped";
    return r;
  }

 private:
  long skipped_ = 0;
};

// Signed distance (m) of the centre of pressure to the support polygon's boundary: negative
// inside, positive outside. Value = the largest over rows with f_n >= min_normal_N.
double signedDistanceToPolygon(const std::vector<std::pair<double, double>>& poly, double x, double y) {
  double dmin = kInf;
  bool inside = true;
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % n];
    const double ex = b.first - a.first, ey = b.second - a.second;
    const double px = x - a.first, py = y - a.second;
    if (ex * py - ey * px < 0.0) inside = false;  // right of a counter-clockwise edge
    const double len2 = ex * ex + ey * ey;
    const double s = len2 > 0.0 ? std::clamp((px * ex + py * ey) / len2, 0.0, 1.0) : 0.0;
    const double dx = px - s * ex, dy = py - s * ey;
    dmin = std::min(dmin, std::sqrt(dx * dx + dy * dy));
  }
  return inside ? -dmin : dmin;
}

// A CoP on the polygon's edge (all the force on one edge or corner) passes a limit of 0: the
// distance may exceed the limit by 1e-9 of the polygon's diameter (round-off).
class ContactCop final : public ContactCheck {
 public:
  explicit ContactCop(const CheckSpec& s) : ContactCheck(s, "m (signed distance to the sole's edge, < 0 inside)") {
    worst_ = -kInf;
    double diameter = 0.0;
    for (const auto& a : spec_.polygon) {
      for (const auto& b : spec_.polygon) diameter = std::max(diameter, std::hypot(a.first - b.first, a.second - b.second));
    }
    tolerance_ = kBoundaryRelTolerance * diameter;
  }
  void consume(const double* row) override {
    if (!contactActive(row)) return;
    const double fz = row[w_[2]];
    if (!(fz >= spec_.min_normal_N) || fz <= 0.0) {
      ++skipped_;
      return;
    }
    seen_ = true;
    // The contact frame's z is the normal; the CoP on the frame's z = 0 plane.
    const double x = 0.0 - row[w_[4]] / fz, y = row[w_[3]] / fz;  // 0.0 - : no "-0" in details
    const double d = signedDistanceToPolygon(spec_.polygon, x, y);
    if (d > worst_ || std::isnan(d)) {
      worst_ = d;
      detail_ = std::string(sourceName()) + " CoP (" + fmt(x) + ", " + fmt(y) + ") m in the contact frame at t = " + fmt(row[t_]) + " s";
    }
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) r.detail = "no row with contact '" + spec_.contact + "' active and f_n >= " + fmt(spec_.min_normal_N) + " N";
    else if (skipped_ > 0) r.detail += "; " + std::to_string(skipped_) + " rows with f_n below " + fmt(spec_.min_normal_N) + " N skipped";
    return r;
  }

 private:
  long skipped_ = 0;
};

// Computed (from gamma) against sensed wrench, force or torque part: rms or max of the norm of
// the difference over the rows with the contact active.
class ContactWrenchMatch final : public CheckBase {
 public:
  explicit ContactWrenchMatch(const CheckSpec& s) : CheckBase(s, s.component == "torque" ? "N m" : "N") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    active_ = require(schema, contactActiveChannel(spec_.contact), spec_);
    const int k0 = spec_.component == "torque" ? 3 : 0;
    for (int k = 0; k < 3; ++k) {
      c_[k] = require(schema, wrenchChannel(spec_.contact, false, kWrenchComponents[k0 + k]), spec_);
      s_[k] = require(schema, wrenchChannel(spec_.contact, true, kWrenchComponents[k0 + k]), spec_);
    }
  }
  void consume(const double* row) override {
    if (!active(row) || row[active_] == 0.0) return;
    seen_ = true;
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (row[c_[k]] - row[s_[k]]) * (row[c_[k]] - row[s_[k]]);
    const double d = std::sqrt(d2);
    sum2_ += d2;
    ++n_;
    if (d > max_ || std::isnan(d)) {
      max_ = d;
      t_max_ = row[t_];
    }
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) {
      r.detail = "no row with contact '" + spec_.contact + "' active in the window";
      return r;
    }
    r.value = spec_.statistic == "max" ? max_ : std::sqrt(sum2_ / static_cast<double>(n_));
    r.passed = r.value <= spec_.limit;
    r.detail = spec_.statistic + " of |computed - sensed| " + spec_.component + " over " + std::to_string(n_) +
               " rows; largest " + fmt(max_) + " at t = " + fmt(t_max_) + " s";
    return r;
  }

 private:
  int active_ = 0, c_[3] = {0, 0, 0}, s_[3] = {0, 0, 0};
  double sum2_ = 0.0, max_ = 0.0, t_max_ = 0.0;
  long n_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Oscillation.

// Counts sign changes of a rate computed from successive rows; |rate| <= dead_band carries no
// sign (the last sign is kept).
struct SignChangeCounter {
  bool have_prev = false;
  double prev = 0.0, t_prev = 0.0;
  int last_sign = 0;
  long changes = 0;
  void reset() { *this = SignChangeCounter{}; }
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

// Sign changes per second of each joint's acceleration (the rate of its velocity between
// successive rows); value = the largest over the joints.
class JointAccelerationSignChanges final : public CheckBase {
 public:
  explicit JointAccelerationSignChanges(const CheckSpec& s) : CheckBase(s, "sign changes per second") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    const std::string prefix = spec_.source == "commanded" ? "cmd.qd." : "qd.";
    for (const auto& j : spec_.joints) cols_.push_back(require(schema, prefix + j, spec_));
    counters_.assign(cols_.size(), SignChangeCounter{});
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    const double t = row[t_];
    if (!seen_) t0_ = t;
    seen_ = true;
    t1_ = t;
    for (size_t j = 0; j < cols_.size(); ++j) counters_[j].add(t, row[cols_[j]], spec_.dead_band);
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) return r;
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
    r.detail = (cols_.empty() ? std::string("no joints") : spec_.joints[best_j] + ": " + std::to_string(best)) +
               " sign changes of the " + (spec_.source == "commanded" ? "commanded" : "measured") +
               " acceleration over " + fmt(span) + " s (dead band " + fmt(spec_.dead_band) + " rad/s^2)";
    return r;
  }

 private:
  std::vector<int> cols_;
  std::vector<SignChangeCounter> counters_;
  double t0_ = 0.0, t1_ = 0.0;
};

// Mean over the window of sum_j hp(qd_j)^2, hp a 2nd-order Butterworth high-pass (bilinear
// transform) at cutoff_hz; the sample period is the first row spacing, rows at another spacing
// (e.g. the last state of a run) are left out. The filters start at the first row of the trace
// at rest on its value (a constant gives 0).
class JointVelocityHfEnergy final : public CheckBase {
 public:
  explicit JointVelocityHfEnergy(const CheckSpec& s) : CheckBase(s, "(rad/s)^2") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    const std::string prefix = spec_.source == "commanded" ? "cmd.qd." : "qd.";
    for (const auto& j : spec_.joints) cols_.push_back(require(schema, prefix + j, spec_));
    state_.assign(cols_.size(), Biquad{});
    energy_.assign(cols_.size(), 0.0);
  }
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
      } else if (!(spec_.cutoff_hz < 0.5 / h)) {
        invalid_ = "cutoff " + fmt(spec_.cutoff_hz) + " Hz is not below the Nyquist frequency " + fmt(0.5 / h) + " Hz of the trace";
      } else {
        const double K = std::tan(M_PI * spec_.cutoff_hz * h);
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
    r.detail = "above " + fmt(spec_.cutoff_hz) + " Hz, " + (spec_.source == "commanded" ? "commanded" : "measured") +
               " velocities, " + std::to_string(n_) + " rows";
    if (!energy_.empty()) r.detail += "; largest share " + spec_.joints[best] + " " + fmt(energy_[best] / static_cast<double>(n_));
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
  std::vector<int> cols_;
  std::vector<Biquad> state_;
  std::vector<double> energy_;
  long rows_ = 0, n_ = 0, skipped_ = 0;
  double t_prev_ = 0.0, period_ = 0.0, b0_ = 0.0, a1_ = 0.0, a2_ = 0.0, sum_ = 0.0;
  std::string invalid_;
};

// Sign changes per second of the rate of a task's error norm.
class TaskErrorRateSignChanges final : public CheckBase {
 public:
  explicit TaskErrorRateSignChanges(const CheckSpec& s) : CheckBase(s, "sign changes per second") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    if (spec_.tasks.size() != 1) throw InputError(spec_.where, "check '" + spec_.name + "' needs exactly one task");
    col_ = require(schema, taskChannel(spec_.tasks[0], "error"), spec_);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    if (!seen_) t0_ = row[t_];
    seen_ = true;
    t1_ = row[t_];
    counter_.add(row[t_], row[col_], spec_.dead_band);
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) return r;
    const double span = t1_ - t0_;
    r.value = span > 0.0 ? static_cast<double>(counter_.changes) / span : 0.0;
    r.passed = r.value <= spec_.limit;
    r.detail = std::to_string(counter_.changes) + " sign changes of d/dt |e| of " + spec_.tasks[0] + " over " + fmt(span) +
               " s (dead band " + fmt(spec_.dead_band) + ")";
    return r;
  }

 private:
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
  TaskResponseCheck(const CheckSpec& s, const char* unit) : CheckBase(s, unit) {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    if (spec_.tasks.size() != 1) throw InputError(spec_.where, "check '" + spec_.name + "' needs exactly one task");
    col_ = require(schema, taskChannel(spec_.tasks[0], "error"), spec_);
  }
  void consume(const double* row) final {
    if (!active(row)) return;
    const double t = row[t_], e = row[col_];
    if (!seen_) {
      t0_ = t;
      e0_ = e;
      seen_ = true;
    }
    if (validStart()) sample(t, e);
  }

 protected:
  /// One row of the window (only while e0 is usable).
  virtual void sample(double t, double e) = 0;
  bool validStart() const { return e0_ > 0.0 && std::isfinite(e0_); }
  /// The failed result of an unusable e0; `why` is appended to the detail.
  CheckResult invalidStart(CheckResult r, const std::string& why) const {
    r.value = kNaN;
    r.passed = false;
    r.detail = "the error of " + spec_.tasks[0] + " at the window's start (t = " + fmt(t0_) + " s) is " + fmt(e0_) + why;
    return r;
  }
  /// " (e0 ... at t = ... s" shared by the details.
  std::string startDetail() const { return " (e0 " + fmt(e0_) + " at t = " + fmt(t0_) + " s"; }

  double t0_ = 0.0, e0_ = 0.0;

 private:
  int col_ = 0;
};

// Largest |e(t) - e0 |x(t - t0)|| / e0 over the window, x the closed form above: the error norm
// of a task started at rest against the continuous PD response (for a 1-D task; in more
// dimensions along a straight line).
class TaskErrorClosedForm final : public TaskResponseCheck {
 public:
  explicit TaskErrorClosedForm(const CheckSpec& s) : TaskResponseCheck(s, "fraction of the initial error") {}
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) return r;
    if (!validStart()) return invalidStart(r, ": no response to compare");
    const double zeta = spec_.kp > 0.0 ? spec_.kv / (2.0 * std::sqrt(spec_.kp)) : kInf;
    r.detail = detail_ + startDetail() + "; kp " + fmt(spec_.kp) + ", kv " + fmt(spec_.kv) + ", damping ratio " + fmt(zeta) + ")";
    return r;
  }

 private:
  void sample(double t, double e) override {
    const double ref = e0_ * std::abs(pdClosedForm(spec_.kp, spec_.kv, t - t0_));
    const double d = std::abs(e - ref) / e0_;
    if (d > worst_ || std::isnan(d)) {
      worst_ = d;
      detail_ = "largest at t = " + fmt(t) + " s: |e| " + fmt(e) + ", closed form " + fmt(ref);
    }
  }
};

// Overshoot of a task: the largest rise of its error norm above its running minimum, relative to
// the error at the window's first row. A task converging monotonically gives 0; a 1-D task that
// passes through its target (the norm goes to 0 and rises again) gives its largest excursion past
// the target.
class TaskOvershoot final : public TaskResponseCheck {
 public:
  explicit TaskOvershoot(const CheckSpec& s) : TaskResponseCheck(s, "fraction of the initial error") {}
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) return r;
    if (!validStart()) return invalidStart(r, "");
    r.value = rise_ / e0_;
    r.passed = r.value <= spec_.limit;
    r.detail = (detail_.empty() ? std::string("the error never rises") : detail_) + startDetail() + ")";
    return r;
  }

 private:
  void sample(double t, double e) override {
    if (!have_min_ || e < min_) {
      min_ = e;
      t_min_ = t;
      have_min_ = true;
    }
    const double rise = e - min_;
    if (rise > rise_ || std::isnan(rise)) {
      rise_ = rise;
      detail_ = "largest rise at t = " + fmt(t) + " s: |e| " + fmt(e) + " after a minimum of " + fmt(min_) + " at t = " +
                fmt(t_min_) + " s";
    }
  }
  bool have_min_ = false;
  double min_ = 0.0, t_min_ = 0.0, rise_ = 0.0;
};

// ---------------------------------------------------------------------------------------------
// Controller health.

// Number of rows whose controller status is not among the allowed ones.
class ControllerStatus final : public CheckBase {
 public:
  explicit ControllerStatus(const CheckSpec& s) : CheckBase(s, "ticks") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    col_ = require(schema, kControllerStatusChannel, spec_);
    const auto& names = controllerStatusNames();
    allowed_.assign(names.size(), 0);
    for (const auto& a : spec_.allowed) {
      const auto it = std::find(names.begin(), names.end(), a);
      if (it == names.end()) throw InputError(spec_.where, "unknown controller status '" + a + "'");
      allowed_[static_cast<size_t>(it - names.begin())] = 1;
    }
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    seen_ = true;
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
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    if (!seen_) return r;
    std::string d;
    for (const auto& [name, n] : counts_) d += (d.empty() ? "" : ", ") + name + " " + std::to_string(n);
    r.detail = d + (first_bad_.empty() ? "" : "; " + first_bad_);
    return r;
  }

 private:
  int col_ = 0;
  std::vector<char> allowed_;
  std::map<std::string, long> counts_;
  std::string first_bad_;
};

// Largest number of active-set iterations of a tick.
class ActiveSetPeak final : public CheckBase {
 public:
  explicit ActiveSetPeak(const CheckSpec& s) : CheckBase(s, "iterations") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    col_ = require(schema, kSolverIterationsChannel, spec_);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    const double v = row[col_];
    if (!seen_ || v > worst_ || std::isnan(v)) {
      worst_ = v;
      detail_ = "at t = " + fmt(row[t_]) + " s";
    }
    seen_ = true;
  }

 private:
  int col_ = 0;
};

// Largest number of level stages the solver factorised in a tick: the deterministic proxy of a
// tick's solver time (the same on every machine and under any load, unlike tick_time).
class FactorizationPeak final : public CheckBase {
 public:
  explicit FactorizationPeak(const CheckSpec& s) : CheckBase(s, "level factorisations") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    col_ = require(schema, kSolverFactorizationsChannel, spec_);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    const double v = row[col_];
    if (!seen_ || v > worst_ || std::isnan(v)) {
      worst_ = v;
      detail_ = "at t = " + fmt(row[t_]) + " s";
    }
    seen_ = true;
  }

 private:
  int col_ = 0;
};

// Fraction of rows at which a level was augmented with Newton rows.
class AugmentedFraction final : public CheckBase {
 public:
  explicit AugmentedFraction(const CheckSpec& s) : CheckBase(s, "fraction of ticks") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    col_ = require(schema, levelChannel(spec_.level, "augmented"), spec_);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    seen_ = true;
    ++n_;
    if (row[col_] != 0.0) {
      if (augmented_ == 0) first_ = row[t_];
      ++augmented_;
    }
    worst_ = static_cast<double>(augmented_) / static_cast<double>(n_);
    detail_ = std::to_string(augmented_) + " of " + std::to_string(n_) + " rows" +
              (augmented_ > 0 ? ", first at t = " + fmt(first_) + " s" : "");
  }

 private:
  int col_ = 0;
  long n_ = 0, augmented_ = 0;
  double first_ = 0.0;
};

// A percentile (nearest rank) of a per-tick wall time, microseconds. Machine-dependent.
class TickTime final : public CheckBase {
 public:
  explicit TickTime(const CheckSpec& s) : CheckBase(s, "us") {}
  void bind(const TraceSchema& schema, const TraceMetadata&) override {
    t_ = require(schema, kTimeChannel, spec_);
    col_ = require(schema, timerChannel(spec_.timer), spec_);
  }
  void consume(const double* row) override {
    if (!active(row)) return;
    seen_ = true;
    values_.push_back(row[col_]);
  }
  CheckResult result() const override {
    CheckResult r = CheckBase::result();
    r.machine_dependent = true;
    if (!seen_) return r;
    std::vector<double> v = values_;
    std::sort(v.begin(), v.end());
    const double p = std::clamp(spec_.percentile, 0.0, 100.0);
    size_t rank = static_cast<size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
    rank = std::clamp<size_t>(rank, 1, v.size());
    r.value = v[rank - 1];
    r.passed = r.value <= spec_.limit;
    r.detail = "p" + fmt(p) + " of " + spec_.timer + " time over " + std::to_string(v.size()) + " ticks (max " + fmt(v.back()) +
               " us; wall-clock measurement, machine-dependent)";
    return r;
  }

 private:
  int col_ = 0;
  std::vector<double> values_;
};

}  // namespace

const std::vector<std::string>& controllerCheckTypes() {
  static const std::vector<std::string> types = {
      "task_error",        "torque_limits",       "contact_unilateral", "contact_friction",
      "contact_cop",       "contact_wrench_match", "joint_acceleration_sign_changes",
      "joint_velocity_hf_energy", "task_error_rate_sign_changes", "task_error_closed_form", "task_overshoot",
      "controller_status", "active_set_peak", "factorization_peak", "augmented_fraction", "tick_time"};
  return types;
}

std::unique_ptr<Check> makeControllerCheck(const CheckSpec& s) {
  if (s.type == "task_error") return std::make_unique<TaskError>(s);
  if (s.type == "torque_limits") return std::make_unique<TorqueLimits>(s);
  if (s.type == "contact_unilateral") return std::make_unique<ContactUnilateral>(s);
  if (s.type == "contact_friction") return std::make_unique<ContactFriction>(s);
  if (s.type == "contact_cop") return std::make_unique<ContactCop>(s);
  if (s.type == "contact_wrench_match") return std::make_unique<ContactWrenchMatch>(s);
  if (s.type == "joint_acceleration_sign_changes") return std::make_unique<JointAccelerationSignChanges>(s);
  if (s.type == "joint_velocity_hf_energy") return std::make_unique<JointVelocityHfEnergy>(s);
  if (s.type == "task_error_rate_sign_changes") return std::make_unique<TaskErrorRateSignChanges>(s);
  if (s.type == "task_error_closed_form") return std::make_unique<TaskErrorClosedForm>(s);
  if (s.type == "task_overshoot") return std::make_unique<TaskOvershoot>(s);
  if (s.type == "controller_status") return std::make_unique<ControllerStatus>(s);
  if (s.type == "active_set_peak") return std::make_unique<ActiveSetPeak>(s);
  if (s.type == "factorization_peak") return std::make_unique<FactorizationPeak>(s);
  if (s.type == "augmented_fraction") return std::make_unique<AugmentedFraction>(s);
  if (s.type == "tick_time") return std::make_unique<TickTime>(s);
  return nullptr;
}

}  // namespace detail

CheckSpec comparisonStatistic(const ComparisonSpec& spec) {
  CheckSpec cs;
  cs.name = spec.name;
  cs.type = "task_error";
  cs.where = spec.where;
  cs.from_s = spec.from_s;
  cs.to_s = spec.to_s;
  cs.tasks = spec.tasks;
  cs.statistic = spec.statistic;
  cs.limit = std::numeric_limits<double>::infinity();
  return cs;
}

CheckResult compareMethods(const ComparisonSpec& spec, const TraceTable& better, const TraceTable& worse) {
  const CheckSpec cs = comparisonStatistic(spec);
  auto evaluate = [&](const TraceTable& t, const std::string& method) {
    const std::string* m = findMetadata(t.metadata, kMethodMetadata);
    if (!m || *m != method) {
      throw InputError(spec.where, "comparison '" + spec.name + "' needs a trace of method " + method + ", found " +
                                       (m ? *m : std::string("a trace without a method")));
    }
    TraceSchema schema;
    for (const auto& n : t.names) schema.add(n);
    auto c = makeCheck(cs);
    c->bind(schema, t.metadata);
    for (const auto& row : t.rows) c->consume(row.data());
    return c->result();
  };
  const CheckResult b = evaluate(better, spec.better), w = evaluate(worse, spec.worse);
  CheckResult r;
  r.name = spec.name;
  r.type = spec.type;
  r.limit = spec.margin;
  r.unit = "task error norm (m, rad)";
  if (std::isnan(b.value) || std::isnan(w.value)) {
    r.value = std::numeric_limits<double>::quiet_NaN();
    r.passed = false;
    r.detail = "no rows in the window: " + spec.better + " " + b.detail + "; " + spec.worse + " " + w.detail;
    return r;
  }
  r.value = b.value - w.value;
  r.passed = r.value <= spec.margin;
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%s %s %.6g, %s %.6g", spec.statistic.c_str(), spec.better.c_str(), b.value,
                spec.worse.c_str(), w.value);
  r.detail = buf;
  return r;
}

}  // namespace lexdyn::checks
