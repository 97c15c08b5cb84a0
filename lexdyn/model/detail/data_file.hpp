// The data file side of loading a robot (internal; docs/model.md, "Data file format").
#pragma once

#include "lexdyn/common/problems.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/model/detail/urdf_reader.hpp"
#include "lexdyn/model/robot_description.hpp"

namespace lexdyn::model::detail {

/// What the URDF pass needs from the data file first: the base type and the mimic policy.
/// Throws InputError when `base` is missing or wrong (nothing can be built without it).
BaseType readBaseType(const yaml::Node& root);
MimicPolicy readMimicPolicy(const yaml::Node& root, ProblemList& problems);
/// The data file's `package_path` (folders for package:// URIs, relative to the data file).
std::vector<std::string> readPackagePaths(const yaml::Node& root, ProblemList& problems);

/// Reads the rest of the data file into d (whose URDF part is read), recording every problem.
void readDataFile(RobotDescription& d, const yaml::Node& root, ProblemList& problems);

}  // namespace lexdyn::model::detail
