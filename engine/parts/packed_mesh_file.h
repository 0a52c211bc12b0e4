// One object's mesh and tree on disk (kernel/bvh/mesh_pack), named by the mesh's content hash:
// what an out-of-core audit reads when a tile needs the object, and releases after. What the
// broad phase needs (bounds, triangle count, size) is known without reading the file.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/aabb.h"
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
};

// Writes the pack as `<directory>/<content hash>.pack` (whole, then renamed into place, so a
// reader never sees half of one); a file already there under that name is checked by size and
// kept. The directory is created if needed.
Result<PackedMeshFile> write_packed_mesh(const MeshBvh& bvh, const std::string& directory);

// Reads and checks the file (kernel/bvh/mesh_pack), and that its mesh is the one described: the
// same size, triangle count and bounds (the broad phase was run on them). An error names the file.
Result<std::shared_ptr<const MeshBvh>> read_packed_mesh(const PackedMeshFile& file);

}  // namespace gk::engine
