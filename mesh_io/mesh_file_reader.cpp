#include "mesh_io/mesh_file_reader.h"

#include "kernel/core/content_hash.h"

#include "mesh_io/format_readers.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <unordered_map>

namespace gk::mesh_io {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// The formats read by our own readers, coordinates exactly as written (format_readers.h).
Result<RawMesh> (*own_reader(const std::string& format))(std::string_view) {
  if (format == "obj") return read_obj;
  if (format == "off") return read_off;
  if (format == "ply") return read_ply;
  if (format == "stl") return read_stl;
  if (format == "gltf" || format == "glb") return read_gltf;
  return nullptr;
}

// Exactly equal corners become one vertex (an STL is a soup of triangles); nothing moves.
void merge_identical(RawMesh& mesh) {
  struct Hash {
    std::size_t operator()(const Vec3& v) const {
      const double c[3] = {v[0] == 0.0 ? 0.0 : v[0], v[1] == 0.0 ? 0.0 : v[1], v[2] == 0.0 ? 0.0 : v[2]};  // -0 and +0 are one point
      return static_cast<std::size_t>(hash_bytes64(c, sizeof c));
    }
  };
  std::unordered_map<Vec3, std::uint32_t, Hash> index;
  std::vector<Vec3> merged;
  std::vector<std::uint32_t> remap(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto [it, added] = index.emplace(mesh.vertices[i], static_cast<std::uint32_t>(merged.size()));
    if (added) merged.push_back(mesh.vertices[i]);
    remap[i] = it->second;
  }
  for (TriangleMesh::Face& f : mesh.faces)
    for (std::uint32_t& v : f) v = remap[v];
  mesh.vertices = std::move(merged);
}

Result<TriangleMesh> read_own(std::string_view bytes, const std::string& format, const std::string& source,
                              const ReadOptions& options) {
  auto raw = own_reader(format)(bytes);
  if (!raw.ok()) return invalid_argument(source + ": " + raw.error().field, raw.error().message);
  RawMesh& mesh = raw.value();
  if (mesh.faces.empty()) return invalid_argument(source, "file holds no triangles");
  if (options.merge_identical_vertices) merge_identical(mesh);
  auto built = TriangleMesh::create(std::move(mesh.vertices), std::move(mesh.faces), options.build);
  if (!built.ok()) return invalid_argument(source + ": " + built.error().field, built.error().message);
  return built;
}

}  // namespace

Result<TriangleMesh> read_mesh_file(const std::string& path, const ReadOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return invalid_argument(path, "no such file");
  const std::string format = lower(std::filesystem::path(path).extension().string().substr(std::min<std::size_t>(
      1, std::filesystem::path(path).extension().string().size())));
  if (!own_reader(format)) return invalid_argument(path, "unknown mesh format '" + format + "'");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) return invalid_argument(path, "cannot read the file");
  if (bytes.str().empty()) return invalid_argument(path, "empty file");
  return read_own(bytes.str(), format, path, options);
}

Result<TriangleMesh> read_mesh_bytes(const std::string& bytes, const std::string& format_hint,
                                     const ReadOptions& options) {
  if (bytes.empty()) return invalid_argument("bytes", "empty mesh payload");
  if (!own_reader(lower(format_hint))) return invalid_argument("format", "unknown mesh format '" + format_hint + "'");
  return read_own(bytes, lower(format_hint), "bytes (" + format_hint + ")", options);
}

}  // namespace gk::mesh_io
