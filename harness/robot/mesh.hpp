// Mesh files of a URDF (STL and the formats Debian's libassimp reads: DAE, OBJ, glTF, ...), read
// for their vertices: the support polygon of a foot, the picture of `robot check`, the replay.
#pragma once

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

namespace lexdyn::robot {

struct Mesh {
  std::vector<Eigen::Vector3f> vertices;   ///< metres, in the mesh file's frame, scale applied
  std::vector<Eigen::Vector3i> triangles;  ///< indices into vertices
  /// The up axis a COLLADA file declares (<up_axis>: 'X', 'Y' or 'Z'; 'Z' for every other format
  /// and when none is given). The vertices are as the file writes them either way.
  char up_axis = 'Z';
};

/// Reads `path` (scaled by `scale`). Throws lexdyn::InputError naming the file when the mesh cannot
/// be read. A COLLADA file's unit is applied; its up axis is recorded, not applied (ROS's tools,
/// RViz and MoveIt, take the coordinates as the file writes them; applyUpAxis turns them).
Mesh readMesh(const std::string& path, const Eigen::Vector3d& scale = Eigen::Vector3d::Ones());

/// The rotation that takes a mesh whose up axis is `up` to z up: Y_UP (x, y, z) -> (x, -z, y),
/// X_UP (x, y, z) -> (-z, y, x) (COLLADA's convention); the identity for 'Z'.
Eigen::Matrix3f upAxisRotation(char up);

/// The vertices turned to z up when `apply_up_axis` (upAxisRotation), then scaled by a URDF
/// <mesh scale> (which is in the link's coordinates).
Mesh placedMesh(Mesh mesh, const Eigen::Vector3d& scale, bool apply_up_axis);

/// Meshes read once per file, as the file writes them (robot init reads the same meshes twice).
struct MeshCache {
  std::map<std::string, Mesh> meshes;
  /// The mesh of `path`, read on first use. Throws as readMesh does.
  const Mesh& get(const std::string& path);
};

/// Writes a binary STL (for the replay's viewer). Throws lexdyn::InputError when it cannot.
void writeBinaryStl(const std::string& path, const Mesh& mesh);

}  // namespace lexdyn::robot
