// BVHs kept on disk by the content hash of their mesh: an audit or a restarted daemon that meets a
// mesh again loads its tree instead of building it. Files are written whole and renamed into
// place; a damaged or foreign file is ignored (and rebuilt over), never trusted.
#pragma once

#include "kernel/core/content_hash.h"
#include "kernel/bvh/mesh_bvh.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

namespace gk::engine {

// The content hash (kernel/core/content_hash.h) of the vertex coordinates and the face indices (and
// their counts): the cache file's name.
Hash128 mesh_content_hash(const TriangleMesh& mesh);

class BvhCache {
 public:
  // The directory is created if needed.
  explicit BvhCache(std::string directory);

  Result<std::shared_ptr<MeshBvh>> get_or_build(std::shared_ptr<const TriangleMesh> mesh);

  struct Stats {
    std::size_t loaded = 0, built = 0, rejected = 0, write_failures = 0;
  };
  Stats stats() const { return {loaded_, built_, rejected_, write_failures_}; }

 private:
  std::string directory_;
  std::atomic<std::size_t> loaded_{0}, built_{0}, rejected_{0}, write_failures_{0};
};

}  // namespace gk::engine
