// A mesh and its tree as one block of bytes that reads back without analysing the mesh or
// building the tree: what an out-of-core audit keeps on disk for each object and reads when a tile
// needs it (engine/parts/packed_mesh_file).
//
// Layout: "GKPACK01", the mesh's byte count, the mesh renumbered in tree order
// (MeshBvh::in_tree_order, TriangleMesh::append_bytes), the tree (MeshBvh::serialize), then the
// XXH3-128 of everything before it. The unpacked mesh is that renumbered copy: the same triangles
// and coordinates, other indices. Reading checks the checksum
// first, then every count and index, and the tree as MeshBvh::deserialize does (each box holds
// what it claims, compared in double): a damaged or foreign block is an error, never a mesh.
#pragma once

#include "kernel/bvh/mesh_bvh.h"

#include <memory>
#include <string>
#include <string_view>

namespace gk {

std::string pack_mesh_bvh(const MeshBvh& bvh);
Result<std::shared_ptr<MeshBvh>> unpack_mesh_bvh(std::string_view bytes);

}  // namespace gk
