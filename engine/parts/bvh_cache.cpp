#include "engine/parts/bvh_cache.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace gk::engine {
Hash128 mesh_content_hash(const TriangleMesh& mesh) {
  ContentHash h;
  h.add(static_cast<std::uint64_t>(mesh.vertices().size())).add(static_cast<std::uint64_t>(mesh.faces().size()));
  h.add_bytes(mesh.vertices().data(), mesh.vertices().size() * sizeof(Vec3));
  h.add_bytes(mesh.faces().data(), mesh.faces().size() * sizeof(TriangleMesh::Face));
  return h.value();
}

BvhCache::BvhCache(std::string directory) : directory_(std::move(directory)) {
  std::error_code ec;
  std::filesystem::create_directories(directory_, ec);
}

Result<std::shared_ptr<MeshBvh>> BvhCache::get_or_build(std::shared_ptr<const TriangleMesh> mesh) {
  if (!mesh) return invalid_argument("mesh", "no mesh given");
  const std::string path = directory_ + "/" + mesh_content_hash(*mesh).hex() + ".bvh";
  {
    std::ifstream in(path, std::ios::binary);
    if (in) {
      std::ostringstream bytes;
      bytes << in.rdbuf();
      auto loaded = MeshBvh::deserialize(mesh, bytes.str());
      if (loaded.ok()) {
        ++loaded_;
        (void)loaded.value()->node_slabs();  // fitted with the part, not by its first query
        return loaded;
      }
      ++rejected_;
    }
  }
  auto built = MeshBvh::build(mesh);
  if (!built.ok()) return built;
  ++built_;
  (void)built.value()->node_slabs();  // fitted with the part, not by its first query
  // Whole file, then rename: a reader never sees half of one.
  std::ostringstream tmp_name;
  // Process and thread: ranks of an MPI audit share the cache directory.
  tmp_name << path << ".tmp." << ::getpid() << "." << std::this_thread::get_id();
  {
    std::ofstream out(tmp_name.str(), std::ios::binary | std::ios::trunc);
    const std::string bytes = built.value()->serialize();
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) ++write_failures_;
  }
  std::error_code ec;
  std::filesystem::rename(tmp_name.str(), path, ec);
  if (ec) {
    ++write_failures_;
    std::filesystem::remove(tmp_name.str(), ec);
  }
  return built;
}

}  // namespace gk::engine
