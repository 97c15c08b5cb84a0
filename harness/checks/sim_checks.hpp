// Checks on the simulator's channels (docs/simulator.md, "Checks"): any controller.
//   frame_drift    max |p(t) - p(from_s)| of a frame's origin over t >= from_s           [m]
//   force_balance  max |sum of the surfaces' contact normal forces - robot weight| / weight
//   contact_slip   max horizontal displacement of any contact point of the given surfaces
//                  from its position at from_s, over t >= from_s                        [m]
//   frame_height   lowest height of a frame's origin over t >= from_s (bounds from below)
#pragma once

#include "harness/checks/check_registry.hpp"

#include <string>
#include <vector>

namespace lexdyn::checks {

/// frame_drift, frame_height.
struct FrameParams {
  std::string frame;
};

/// force_balance, contact_slip.
struct SurfacesParams {
  std::vector<std::string> surfaces;
};

CheckType frameDriftCheck();
CheckType forceBalanceCheck();
CheckType contactSlipCheck();
CheckType frameHeightCheck();

}  // namespace lexdyn::checks
