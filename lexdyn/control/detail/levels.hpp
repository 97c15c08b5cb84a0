// Internal: how the controller's tasks map onto the solver's levels.
#pragma once

#include <vector>

namespace lexdyn::control {

/// A task's rows inside a solver level.
struct TaskSlot {
  int task = -1;
  int row = 0;         ///< first row in the solver level
  double scale = 1.0;  ///< sqrt(weight) on the WLS objective level
};

struct SolverLevel {
  int problem_level = -1;  ///< index in the solver problem
  int config_level = -1;   ///< configured level it comes from
  std::vector<TaskSlot> slots;
  int task_rows = 0;       ///< rows of the tasks
  int spare_row = -1;      ///< first of the nv rows reserved for Newton / damping rows, -1 if none
  bool augmentable = false;
  bool separate = false;   ///< the equation-of-motion level split off a configured level
};

}  // namespace lexdyn::control
