// The URDF side of loading a robot (internal; docs/model.md, "Loading and validation").
#pragma once

#include "lexdyn/common/problems.hpp"
#include "lexdyn/model/robot_description.hpp"

#include <map>
#include <string>

namespace lexdyn::model::detail {

/// What the data file says about the URDF's <mimic> joints, read before the tree is built.
struct MimicPolicy {
  MimicMode mode = MimicMode::Coupled;
  bool given = false;                           ///< the data file has a `mimic` section
  std::string where;                            ///< of that section, for messages
  std::string posture;                          ///< the posture whose master values lock them
  std::map<std::string, double> master_values;  ///< that posture's values (raw, by joint name)
};

/// Reads `text` (the URDF file `file`) into d: links (bodies after lumping), joints, frames of
/// every link, geometry, mimic joints. Records every problem in `problems` and throws (through
/// problems.throwIfErrors) when the tree cannot be built.
void readUrdf(const std::string& text, const std::string& file, BaseType base, const MimicPolicy& mimic, const LoadOptions& options,
              RobotDescription& d, ProblemList& problems);

/// Narrows each coupled mimic joint's master to where the coupled joint stays within its own
/// position and velocity limits (a warning for each), once the data file's joint_limits are in.
void narrowCoupledMasters(RobotDescription& d, ProblemList& problems);

/// Warnings (errors in strict mode) for the joints whose limits are still unspecified once the
/// data file's joint_limits are applied: unlimited effort, velocity or position range.
void noteUnspecifiedLimits(const RobotDescription& d, ProblemList& problems);

}  // namespace lexdyn::model::detail
