// Checks on joint channels of the lexdyn controller's runs (docs/cases.md, "Checks"):
//   torque_limits                    max over rows and joints of |tau| / URDF effort limit
//   joint_acceleration_sign_changes  sign changes per second of the joints' accelerations
//   joint_velocity_hf_energy         mean energy of the joint velocities above a cut-off
#pragma once

#include "harness/checks/check_registry.hpp"

#include <string>
#include <vector>

namespace lexdyn::checks {

struct TorqueLimitsParams {
  std::string source = "both";  ///< applied (tau.<J>) | commanded (cmd.tau.<J>) | both
  std::vector<std::string> joints;
  std::vector<double> joint_limits;  ///< the effort limit of each joint of `joints`
};

struct JointSignChangesParams {
  std::string source = "measured";  ///< measured (qd.<J>) | commanded (cmd.qd.<J>)
  std::vector<std::string> joints;
  double dead_band = 0.0;  ///< rad/s^2: |acceleration| <= dead_band carries no sign
};

struct JointHfEnergyParams {
  std::string source = "measured";  ///< measured | commanded
  std::vector<std::string> joints;
  double cutoff_hz = 0.0;
};

CheckType torqueLimitsCheck();
CheckType jointAccelerationSignChangesCheck();
CheckType jointVelocityHfEnergyCheck();

}  // namespace lexdyn::checks
