// Where a URDF's mesh URI points (docs/model.md, "Meshes and package:// URIs"): package://NAME/PATH
// through the package path (LoadOptions::package_paths, then $ROS_PACKAGE_PATH), file:///PATH,
// absolute paths, and paths relative to the URDF's folder.
#pragma once

#include <string>
#include <vector>

namespace lexdyn::model {

struct ResolvedResource {
  std::string path;            ///< the existing file; empty when not found
  std::string searched;        ///< where it was looked for (for the message when not found)
  bool package_found = false;  ///< a package:// URI whose package was found without the file
};

/// The folders a package:// URI is looked up in: `package_paths`, then (when `use_ros`) the
/// entries of $ROS_PACKAGE_PATH, in order.
std::vector<std::string> packageSearchPath(const std::vector<std::string>& package_paths, bool use_ros);

/// Resolves `uri` written in the URDF file `urdf_path`. A package NAME is the folder NAME directly
/// under a search folder, or the folder of a package.xml (searched 4 levels deep) whose <name> is
/// NAME; the URDF's own package (the nearest folder above it with a package.xml naming NAME, or
/// named NAME) is tried first.
ResolvedResource resolveResource(const std::string& uri, const std::string& urdf_path, const std::vector<std::string>& search);

}  // namespace lexdyn::model
