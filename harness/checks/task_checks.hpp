// Checks on the lexdyn controller's task channels (task.<T>.error; docs/cases.md, "Checks"):
//   task_error                    a statistic of the sum of some tasks' error norms
//   task_error_rate_sign_changes  sign changes per second of d/dt of a task's error norm
//   task_error_closed_form        the error against the PD closed form (sec. V-A, eq. 49)
//   task_overshoot                the largest rise of the error above its running minimum
// and the method comparisons (a task_error statistic of two traces).
#pragma once

#include "harness/checks/check_registry.hpp"

#include <string>
#include <vector>

namespace lexdyn::checks {

struct TaskErrorParams {
  std::vector<std::string> tasks;  ///< the sum of their error norms
  std::string statistic;           ///< final | mean | max | range
};

struct TaskErrorRateParams {
  std::string task;
  double dead_band = 0.0;  ///< 1/s: |rate| <= dead_band carries no sign
};

struct TaskClosedFormParams {
  std::string task;
  double kp = 0.0, kv = 0.0;  ///< the PD gains (1/s^2, 1/s)
};

struct TaskOvershootParams {
  std::string task;
};

CheckType taskErrorCheck();
CheckType taskErrorRateSignChangesCheck();
CheckType taskErrorClosedFormCheck();
CheckType taskOvershootCheck();

}  // namespace lexdyn::checks
