// Checks on the lexdyn controller's health and cost (docs/cases.md, "Checks"):
//   controller_status   ticks whose status is not among the allowed ones
//   active_set_peak     largest solver.iterations of a tick
//   factorization_peak  largest solver.factorizations of a tick (deterministic)
//   augmented_fraction  fraction of rows with a level augmented with Newton rows
//   tick_time           a percentile of a per-tick wall time (machine-dependent)
#pragma once

#include "harness/checks/check_registry.hpp"

#include <string>
#include <vector>

namespace lexdyn::checks {

struct ControllerStatusParams {
  std::vector<std::string> allowed = {"ok", "solver_stopped_early"};  ///< of controllerStatusNames()
};

struct AugmentedFractionParams {
  std::string level;
};

struct TickTimeParams {
  std::string timer;          ///< model | tasks | hessian | solver | tick
  double percentile = 100.0;  ///< nearest rank
};

CheckType controllerStatusCheck();
CheckType activeSetPeakCheck();      ///< no params
CheckType factorizationPeakCheck();  ///< no params
CheckType augmentedFractionCheck();
CheckType tickTimeCheck();

}  // namespace lexdyn::checks
