// Targets that move with time (docs/cases.md, "Events"): a recorded 3-D trajectory read from a
// CSV file and filtered by a causal moving average, and a parametric swing between two points.
// Both are evaluated at any time from the start of their event, exactly (no state carried from
// tick to tick), so that a run is deterministic and a target does not depend on how often it
// is sampled.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace lexdyn::cases {

/// A piecewise-linear path x(tau) through samples (t_i, x_i), tau the time since the event.
/// Before the first sample it holds x_0; after the last it holds the last sample, or with
/// `loop` it repeats with period t_last - t_0. The moving average of width W is causal:
///   x_f(tau) = (1 / W) * integral of x over [tau - W, tau]
/// (with the hold before t_0 the window starts filled with x_0), evaluated exactly from the
/// running integral of the piecewise-linear path.
class TargetTrajectory {
 public:
  TargetTrajectory() = default;
  /// Reads a CSV file: optional header line `t,x,y,z`, '#' comment lines, then one sample per
  /// line `t,x,y,z`; t >= 0 strictly increasing, at least 2 samples. Throws lexdyn::InputError
  /// naming the file and line.
  static TargetTrajectory fromCsv(const std::string& path, double moving_average_s, bool loop);
  /// From samples (t strictly increasing, at least 2); throws InputError naming `where`.
  TargetTrajectory(std::vector<double> t, std::vector<Eigen::Vector3d> x, double moving_average_s, bool loop, const std::string& where);

  /// The raw (unfiltered) path.
  Eigen::Vector3d raw(double tau) const;
  /// The filtered target (the raw path when the moving average is 0).
  Eigen::Vector3d at(double tau) const;

  double movingAverage() const { return window_; }
  bool loop() const { return loop_; }
  double duration() const { return t_.back() - t_.front(); }
  int samples() const { return static_cast<int>(t_.size()); }

 private:
  /// Integral of the raw path from t_0 to tau (negative for tau < t_0).
  Eigen::Vector3d integral(double tau) const;
  Eigen::Vector3d integralInside(double tau) const;  ///< t_0 <= tau <= t_last

  std::vector<double> t_;
  std::vector<Eigen::Vector3d> x_;
  std::vector<Eigen::Vector3d> cumulative_;  ///< integral from t_0 to t_i
  double window_ = 0.0;
  bool loop_ = false;
};

/// x(tau) = c + a sin(2 pi tau / period_s + phase_rad), c = (from + to) / 2, a = (to - from) / 2:
/// starts at the midpoint (phase 0) and moves towards `to` first.
struct Swing {
  Eigen::Vector3d from = Eigen::Vector3d::Zero(), to = Eigen::Vector3d::Zero();
  double period_s = 1.0;
  double phase_rad = 0.0;
  Eigen::Vector3d at(double tau) const;
};

}  // namespace lexdyn::cases
