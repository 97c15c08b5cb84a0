// Checks on the lexdyn controller's contact wrenches (wrench[_sensed].<C>.*, in the contact
// frame; rows with the contact inactive are skipped; docs/cases.md, "Checks"):
//   contact_unilateral    lowest normal force (bounds from below)
//   contact_friction      max |f_t| / (mu f_n), the circular cone
//   contact_cop           max signed distance of the CoP to the support polygon (< 0 inside)
//   contact_wrench_match  |computed - sensed| force or torque, rms or max
#pragma once

#include "harness/checks/check_registry.hpp"

#include <string>
#include <utility>
#include <vector>

namespace lexdyn::checks {

/// contact_unilateral, and the common part of contact_friction and contact_cop.
struct ContactParams {
  std::string contact;                                ///< a controller contact
  std::string source = "computed";                    ///< computed (wrench.<C>) | sensed (wrench_sensed.<C>)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< the contact normal in the contact frame
};

struct ContactFrictionParams : ContactParams {
  double friction = 0.0;      ///< mu
  double min_normal_N = 1.0;  ///< rows with a lower normal force are skipped
};

struct ContactCopParams : ContactParams {
  /// The convex support polygon (x, y) in the contact frame, counter-clockwise.
  std::vector<std::pair<double, double>> polygon;
  double min_normal_N = 1.0;  ///< rows with a lower normal force are skipped
};

struct WrenchMatchParams {
  std::string contact;              ///< a controller contact with a linked sensor
  std::string component = "force";  ///< force | torque
  std::string statistic = "rms";    ///< rms | max
};

CheckType contactUnilateralCheck();
CheckType contactFrictionCheck();
CheckType contactCopCheck();
CheckType contactWrenchMatchCheck();

}  // namespace lexdyn::checks
