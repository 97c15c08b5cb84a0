// Mesh files of a URDF (STL and the formats Debian's libassimp reads: DAE, OBJ, glTF, ...), read
// for their vertices: the support polygon of a foot, the picture of `robot check`, the replay.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace lexdyn::robot {

struct Mesh {
  std::vector<Eigen::Vector3f> vertices;   ///< metres, in the mesh file's frame, scale applied
  std::vector<Eigen::Vector3i> triangles;  ///< indices into vertices
};

/// Reads `path` (scaled by `scale`). Throws lexdyn::InputError naming the file when the mesh cannot
/// be read. A COLLADA file's unit is applied, its up axis is not (as ROS's tools read them).
Mesh readMesh(const std::string& path, const Eigen::Vector3d& scale = Eigen::Vector3d::Ones());

/// Writes a binary STL (for the replay's viewer). Throws lexdyn::InputError when it cannot.
void writeBinaryStl(const std::string& path, const Mesh& mesh);

}  // namespace lexdyn::robot
