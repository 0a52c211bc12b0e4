// One object's mesh and tree on disk (kernel/bvh/mesh_pack), named by the mesh's content hash:
// what an out-of-core audit reads when a tile needs the object, and releases after. What the
// broad phase needs (bounds, triangle count, size) is known without reading the file.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/aabb.h"
#include "kernel/core/content_hash.h"
#include "kernel/core/status.h"

#include <cstdint>
#include <memory>
#include <string>

namespace gk::engine {

struct PackedMeshFile {
  std::string path;
  Aabb bounds;                 // the mesh's exact bounds in its own frame
  std::size_t triangles = 0;
  std::uint64_t bytes = 0;     // the file's size
  Hash128 checksum;            // the pack's own (kernel/bvh/mesh_pack): this file and no other valid pack
};

// Writes the pack as `<directory>/<content hash>.pack` (whole, then renamed into place, so a
// reader never sees half of one); a file already there under that name is kept when it ends with
// the same checksum, else written again. The directory is created if needed.
Result<PackedMeshFile> write_packed_mesh(const MeshBvh& bvh, const std::string& directory);

// Reads and checks the file (kernel/bvh/mesh_pack), and that it is the pack described: a regular
// file of the same size ending with the same checksum (another valid pack put in its place is
// refused), with the same triangle count and bounds (the broad phase was run on them). An error
// names the file; nothing blocks on a file that is not a regular one.
Result<std::shared_ptr<const MeshBvh>> read_packed_mesh(const PackedMeshFile& file);

}  // namespace gk::engine
