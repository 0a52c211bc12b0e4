#include "mesh_io/mesh_file_reader.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>

namespace gk::mesh_io {
namespace {

// Normals would keep STL corners apart when joining vertices: drop them, we do not use them.
// Joining runs only after the coordinates were checked: Assimp would merge a NaN corner into a
// finite one and hide it.
constexpr unsigned int kImportFlags = aiProcess_Triangulate | aiProcess_DropNormals | aiProcess_PreTransformVertices;

// The first non-finite coordinate in the scene, as an error naming where it is.
std::optional<Error> find_non_finite(const aiScene* scene, const std::string& source) {
  for (unsigned int m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    for (unsigned int v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        return invalid_argument(source + ": meshes[" + std::to_string(m) + "].vertices[" + std::to_string(v) + "]",
                                "coordinate is not finite");
    }
  }
  return std::nullopt;
}

Result<const aiScene*> checked_scene(Assimp::Importer& importer, const aiScene* scene, const std::string& source,
                                     const ReadOptions& options) {
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    return invalid_argument(source, std::string("cannot read mesh file: ") + importer.GetErrorString());
  if (auto bad = find_non_finite(scene, source)) return *bad;
  if (options.merge_identical_vertices) {
    scene = importer.ApplyPostProcessing(aiProcess_JoinIdenticalVertices);
    if (scene == nullptr) return invalid_argument(source, std::string("cannot merge vertices: ") + importer.GetErrorString());
  }
  return scene;
}

Result<TriangleMesh> convert(const aiScene* scene, const std::string& source, const ReadOptions& options) {
  std::vector<Vec3> vertices;
  std::vector<TriangleMesh::Face> faces;
  for (unsigned int m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;  // points and lines carry no surface
    const auto base = static_cast<std::uint32_t>(vertices.size());
    for (unsigned int v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned int f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      faces.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (faces.empty()) return invalid_argument(source, "file holds no triangles");
  auto mesh = TriangleMesh::create(std::move(vertices), std::move(faces), options.build);
  if (!mesh.ok()) return invalid_argument(source + ": " + mesh.error().field, mesh.error().message);
  return mesh;
}

}  // namespace

Result<TriangleMesh> read_mesh_file(const std::string& path, const ReadOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return invalid_argument(path, "no such file");
  Assimp::Importer importer;
  auto scene = checked_scene(importer, importer.ReadFile(path, kImportFlags), path, options);
  if (!scene.ok()) return scene.error();
  return convert(scene.value(), path, options);
}

Result<TriangleMesh> read_mesh_bytes(const std::string& bytes, const std::string& format_hint,
                                     const ReadOptions& options) {
  if (bytes.empty()) return invalid_argument("bytes", "empty mesh payload");
  Assimp::Importer importer;
  const aiScene* raw = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kImportFlags, format_hint.c_str());
  auto scene = checked_scene(importer, raw, "bytes (" + format_hint + ")", options);
  if (!scene.ok()) return scene.error();
  return convert(scene.value(), "bytes", options);
}

}  // namespace gk::mesh_io
