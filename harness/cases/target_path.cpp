#include "harness/cases/target_path.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/input_ranges.hpp"
#include "lexdyn/common/input_text.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace lexdyn::cases {

namespace {

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    std::string f = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const size_t a = f.find_first_not_of(" \t\r");
    const size_t b = f.find_last_not_of(" \t\r");
    out.push_back(a == std::string::npos ? std::string() : f.substr(a, b - a + 1));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

bool parseNumber(const std::string& s, double& v) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && errno != ERANGE && std::isfinite(v);
}

}  // namespace

TargetTrajectory TargetTrajectory::fromCsv(const std::string& path, double moving_average_s, bool loop) {
  std::istringstream in(readTextFile(path, "trajectory"));
  std::vector<double> t;
  std::vector<Eigen::Vector3d> x;
  std::string line;
  int lineno = 0;
  bool header_allowed = true;
  while (std::getline(in, line)) {
    ++lineno;
    const std::string where = path + ":" + std::to_string(lineno);
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<std::string> f = splitCsv(line);
    if (header_allowed && f.size() == 4 && f[0] == "t" && f[1] == "x" && f[2] == "y" && f[3] == "z") {
      header_allowed = false;
      continue;
    }
    header_allowed = false;
    if (f.size() != 4) throw InputError(where, "expected 4 values t,x,y,z, found " + std::to_string(f.size()));
    double v[4];
    for (int i = 0; i < 4; ++i) {
      if (!parseNumber(f[static_cast<size_t>(i)], v[i])) {
        throw InputError(where,
                         std::string("column ") + "txyz"[i] + ": expected a finite number, found '" + f[static_cast<size_t>(i)] + "'");
      }
    }
    if (v[0] < 0.0 || v[0] > ranges::kMaxTime_s) {
      throw InputError(where, "times must be >= 0 and at most 1e6 s (seconds since the event), found " + f[0]);
    }
    for (int i = 1; i < 4; ++i) {
      if (std::abs(v[i]) > ranges::kMaxPosition_m) {
        throw InputError(
            where, std::string("column ") + "txyz"[i] + ": expected a position in [-1000, 1000] m, found " + f[static_cast<size_t>(i)]);
      }
    }
    if (!t.empty() && !(v[0] > t.back()))
      throw InputError(where, "times must increase strictly, found " + f[0] + " after " + std::to_string(t.back()));
    t.push_back(v[0]);
    x.emplace_back(v[1], v[2], v[3]);
  }
  return TargetTrajectory(std::move(t), std::move(x), moving_average_s, loop, path);
}

TargetTrajectory::TargetTrajectory(std::vector<double> t, std::vector<Eigen::Vector3d> x, double moving_average_s, bool loop,
                                   const std::string& where)
    : t_(std::move(t)), x_(std::move(x)), window_(moving_average_s), loop_(loop) {
  if (t_.size() != x_.size()) throw InputError(where, "times and points differ in number");
  if (t_.size() < 2) throw InputError(where, "a trajectory needs at least 2 samples, found " + std::to_string(t_.size()));
  for (size_t i = 1; i < t_.size(); ++i) {
    if (!(t_[i] > t_[i - 1])) throw InputError(where, "times must increase strictly");
  }
  if (!(window_ >= 0.0) || !std::isfinite(window_)) throw InputError(where, "moving average must be >= 0 s");
  cumulative_.assign(t_.size(), Eigen::Vector3d::Zero());
  for (size_t i = 1; i < t_.size(); ++i) {
    cumulative_[i] = cumulative_[i - 1] + 0.5 * (t_[i] - t_[i - 1]) * (x_[i - 1] + x_[i]);
  }
}

Eigen::Vector3d TargetTrajectory::raw(double tau) const {
  if (tau <= t_.front()) return x_.front();
  if (tau >= t_.back()) {
    if (!loop_) return x_.back();
    const double T = duration();
    const double r = std::fmod(tau - t_.front(), T);
    tau = t_.front() + r;
  }
  const size_t i = static_cast<size_t>(std::upper_bound(t_.begin(), t_.end(), tau) - t_.begin()) - 1;
  if (i + 1 >= t_.size()) return x_.back();
  const double s = (tau - t_[i]) / (t_[i + 1] - t_[i]);
  return (1.0 - s) * x_[i] + s * x_[i + 1];
}

Eigen::Vector3d TargetTrajectory::integralInside(double tau) const {
  if (tau <= t_.front()) return Eigen::Vector3d::Zero();
  if (tau >= t_.back()) return cumulative_.back();
  const size_t i = static_cast<size_t>(std::upper_bound(t_.begin(), t_.end(), tau) - t_.begin()) - 1;
  const double s = (tau - t_[i]) / (t_[i + 1] - t_[i]);
  const Eigen::Vector3d xt = (1.0 - s) * x_[i] + s * x_[i + 1];
  return cumulative_[i] + 0.5 * (tau - t_[i]) * (x_[i] + xt);
}

Eigen::Vector3d TargetTrajectory::integral(double tau) const {
  if (tau <= t_.front()) return (tau - t_.front()) * x_.front();
  if (tau <= t_.back()) return integralInside(tau);
  if (!loop_) return cumulative_.back() + (tau - t_.back()) * x_.back();
  const double T = duration();
  const double n = std::floor((tau - t_.front()) / T);
  const double r = (tau - t_.front()) - n * T;
  return n * cumulative_.back() + integralInside(t_.front() + r);
}

Eigen::Vector3d TargetTrajectory::at(double tau) const {
  if (window_ <= 0.0) return raw(tau);
  return (integral(tau) - integral(tau - window_)) / window_;
}

Eigen::Vector3d Swing::at(double tau) const {
  const Eigen::Vector3d c = 0.5 * (from + to), a = 0.5 * (to - from);
  return c + a * std::sin(2.0 * M_PI * tau / period_s + phase_rad);
}

}  // namespace lexdyn::cases
