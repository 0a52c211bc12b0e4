// A mesh and its tree as one block of bytes that reads back without analysing the mesh or
// building the tree: what an out-of-core audit keeps on disk for each object and reads when a tile
// needs it (engine/parts/packed_mesh_file).
//
// Layout: "GKPACK01", the mesh's byte count, the mesh renumbered in tree order
// (MeshBvh::in_tree_order, TriangleMesh::append_bytes), the tree (MeshBvh::serialize), then the
// XXH3-128 of everything before it. The unpacked mesh is that renumbered copy: the same triangles
// and coordinates, other indices. The checksum tells damage, not intent: a pack is trusted as
// written once it matches, so the mesh's analysis (closed, oriented, degenerate triangles) is not
// redone; whoever records where a pack is should record its checksum too (pack_checksum). Reading checks the checksum
// first, then every count and index, and the tree as MeshBvh::deserialize does (each box holds
// what it claims, compared in double): a damaged or foreign block is an error, never a mesh.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/content_hash.h"

#include <memory>
#include <string>
#include <string_view>

namespace gk {

std::string pack_mesh_bvh(const MeshBvh& bvh);
// The same into out, replacing what it held but keeping its capacity: a writer that packs many
// meshes reuses one buffer instead of asking the system for fresh pages for each pack.
void pack_mesh_bvh(const MeshBvh& bvh, std::string& out);
Result<std::shared_ptr<MeshBvh>> unpack_mesh_bvh(std::string_view bytes);
// The checksum a pack ends with (what names this pack among all others: a caller that recorded it
// when writing can tell its pack from another valid one put in its place). Zero for bytes too
// short to be a pack.
Hash128 pack_checksum(std::string_view bytes);

}  // namespace gk
