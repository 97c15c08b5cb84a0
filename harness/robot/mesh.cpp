#include "harness/robot/mesh.hpp"

#include "lexdyn/common/error.hpp"

#include <Eigen/Geometry>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>

namespace lexdyn::robot {

namespace {

// Vertices of every mesh under `node`, transformed to the scene's root frame.
void collect(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent, Mesh& out) {
  const aiMatrix4x4 T = parent * node->mTransformation;
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    const aiMesh* m = scene->mMeshes[node->mMeshes[k]];
    const int base = static_cast<int>(out.vertices.size());
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const aiVector3D p = T * m->mVertices[v];
      out.vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace& face = m->mFaces[f];
      if (face.mNumIndices == 3) {
        out.triangles.emplace_back(base + static_cast<int>(face.mIndices[0]), base + static_cast<int>(face.mIndices[1]),
                                   base + static_cast<int>(face.mIndices[2]));
      }
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) collect(scene, node->mChildren[c], T, out);
}

// The <up_axis> of a COLLADA file ('X', 'Y' or 'Z'), from its <asset> near the top; 'Z' for
// other files and when none is given.
char declaredUpAxis(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(16384, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  if (head.find("<COLLADA") == std::string::npos) return 'Z';
  const size_t a = head.find("<up_axis>");
  if (a == std::string::npos) return 'Y';  // COLLADA's default
  size_t k = a + 9;
  while (k < head.size() && std::isspace(static_cast<unsigned char>(head[k]))) ++k;
  if (k < head.size() && (head[k] == 'X' || head[k] == 'Y' || head[k] == 'Z')) return head[k];
  return 'Z';
}

}  // namespace

Mesh readMesh(const std::string& path, const Eigen::Vector3d& scale) {
  Assimp::Importer importer;
  // Triangulated; no other processing (the vertices are what is used: a shared vertex appears
  // once per triangle, which costs less than joining them). COLLADA's <unit> is applied; its
  // <up_axis> is recorded, not applied (assimp would otherwise turn a Z_UP file into its own
  // Y-up convention).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_SortByPType);
  if (!scene || !scene->mRootNode) {
    throw InputError(path, std::string("cannot read the mesh: ") + importer.GetErrorString());
  }
  Mesh mesh;
  collect(scene, scene->mRootNode, aiMatrix4x4(), mesh);
  if (mesh.vertices.empty()) throw InputError(path, "the mesh has no vertices");
  mesh.up_axis = declaredUpAxis(path);
  for (auto& v : mesh.vertices) v = v.cwiseProduct(scale.cast<float>());
  return mesh;
}

Eigen::Matrix3f upAxisRotation(char up) {
  Eigen::Matrix3f R = Eigen::Matrix3f::Identity();
  if (up == 'Y') {
    R << 1, 0, 0, 0, 0, -1, 0, 1, 0;  // y up -> z up: (x, y, z) -> (x, -z, y)
  } else if (up == 'X') {
    R << 0, 0, -1, 0, 1, 0, 1, 0, 0;  // x up -> z up: (x, y, z) -> (-z, y, x)
  }
  return R;
}

Mesh placedMesh(Mesh mesh, const Eigen::Vector3d& scale, bool apply_up_axis) {
  const Eigen::Matrix3f R = apply_up_axis ? upAxisRotation(mesh.up_axis) : Eigen::Matrix3f::Identity();
  const Eigen::Vector3f s = scale.cast<float>();
  for (auto& v : mesh.vertices) v = (R * v).cwiseProduct(s);
  if (apply_up_axis) mesh.up_axis = 'Z';
  return mesh;
}

const Mesh& MeshCache::get(const std::string& path) {
  auto it = meshes.find(path);
  if (it == meshes.end()) it = meshes.emplace(path, readMesh(path)).first;
  return it->second;
}

void writeBinaryStl(const std::string& path, const Mesh& mesh) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError(path, "cannot open for writing");
  char header[80] = {0};
  std::strncpy(header, "lexdyn mesh", sizeof(header) - 1);
  out.write(header, 80);
  const std::uint32_t n = static_cast<std::uint32_t>(mesh.triangles.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f a = mesh.vertices[static_cast<size_t>(t[0])], b = mesh.vertices[static_cast<size_t>(t[1])],
                          c = mesh.vertices[static_cast<size_t>(t[2])];
    const Eigen::Vector3f ab = b - a, ac = c - a;
    Eigen::Vector3f nrm = ab.cross(ac);
    if (nrm.norm() > 0.0f) nrm.normalize();
    const float data[12] = {nrm.x(), nrm.y(), nrm.z(), a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), c.x(), c.y(), c.z()};
    out.write(reinterpret_cast<const char*>(data), sizeof(data));
    const std::uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), 2);
  }
  if (!out) throw InputError(path, "write error");
}

}  // namespace lexdyn::robot
