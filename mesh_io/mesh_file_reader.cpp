#include "mesh_io/mesh_file_reader.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <filesystem>

namespace gk::mesh_io {
namespace {

unsigned int import_flags(const ReadOptions& options) {
  // Normals would keep STL corners apart when joining vertices: drop them, we do not use them.
  unsigned int flags = aiProcess_Triangulate | aiProcess_DropNormals | aiProcess_PreTransformVertices;
  if (options.merge_identical_vertices) flags |= aiProcess_JoinIdenticalVertices;
  return flags;
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
  const aiScene* scene = importer.ReadFile(path, import_flags(options));
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    return invalid_argument(path, std::string("cannot read mesh file: ") + importer.GetErrorString());
  return convert(scene, path, options);
}

Result<TriangleMesh> read_mesh_bytes(const std::string& bytes, const std::string& format_hint,
                                     const ReadOptions& options) {
  if (bytes.empty()) return invalid_argument("bytes", "empty mesh payload");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), import_flags(options), format_hint.c_str());
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    return invalid_argument("bytes", std::string("cannot read ") + format_hint + " mesh: " + importer.GetErrorString());
  return convert(scene, "bytes", options);
}

}  // namespace gk::mesh_io
