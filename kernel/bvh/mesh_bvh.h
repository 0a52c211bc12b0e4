// A bounding-volume hierarchy over a mesh's triangles in a compact layout of our own: 32-byte nodes
// with float boxes rounded outward (kernel/bvh/bvh_node.h), built by a binned SAH in float
// (kernel/bvh/binned_sah_builder.h), and the triangles in tree order as indices into a tree-ordered
// copy of the vertices, so a leaf's corners sit together in memory. Queries read the node array
// directly (a tight loop, no virtual calls); refit after the vertices move keeps the topology.
#pragma once

#include "kernel/bvh/bvh_node.h"
#include "kernel/bvh/node_slabs.h"
#include "kernel/core/aabb.h"
#include "kernel/core/geometry_types.h"
#include "kernel/core/status.h"
#include "kernel/mesh/oriented_box.h"
#include "kernel/mesh/triangle_mesh.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace gk {

struct BvhBuildOptions {
  // Triangles per leaf. 4 since 2026-11-26: against 1, random-pose distances 1.3-1.6x faster,
  // collide 1.1-1.5x, builds twice as fast and trees take about 40 % less memory; near-contact
  // distance on the smallest pair (env/rob) about 6 % slower (docs/PERFORMANCE.md, kernel_fcl_table).
  int leaf_size = 4;
  // One key per mesh triangle, or none: triangles of different keys part in the nodes of at most
  // key_split_at triangles (BuildKeys), so that those nodes each hold one key.
  const std::vector<std::int32_t>* keys = nullptr;
  std::size_t key_split_at = 1024;
  // Node slabs (node_slabs) for a mesh of any size, not only from kMinTrianglesForSlabs triangles:
  // for small meshes queried at contact distances many times over (a fixture's elements, each
  // frame), where curved surfaces a fraction of a millimetre apart (a pin in its hole) have leaf
  // boxes that overlap all round and slabs that do not.
  bool slabs_at_any_size = false;
};

// A mesh ready for queries: the mesh, its tree, and its triangles in tree order.
class MeshBvh {
 public:
  static Result<std::shared_ptr<MeshBvh>> build(std::shared_ptr<const TriangleMesh> mesh,
                                                const BvhBuildOptions& options = {});
  ~MeshBvh();
  MeshBvh(const MeshBvh&) = delete;
  MeshBvh& operator=(const MeshBvh&) = delete;

  // The tree as bytes (nodes, depth, triangle order), and back onto the same mesh without the
  // build. Loading checks every index, so damaged bytes are an error, never a bad tree.
  std::string serialize() const;
  // The same bytes appended to out (one resize and two block copies: how a pack is written).
  void append_serialized(std::string& out) const;
  static Result<std::shared_ptr<MeshBvh>> deserialize(std::shared_ptr<const TriangleMesh> mesh, std::string_view bytes);

  // The same tree on a copy of the mesh renumbered in tree order (TriangleMesh::in_face_order):
  // its tree-ordered corners are the mesh's own arrays, not a second copy. How packs store a mesh
  // (kernel/bvh/mesh_pack), so reading one needs no reordering.
  std::shared_ptr<MeshBvh> in_tree_order() const;

  // Recomputes every box bottom-up from the mesh's current vertices (same topology).
  void refit(std::shared_ptr<const TriangleMesh> moved_mesh);

  const TriangleMesh& mesh() const { return *mesh_; }
  const std::shared_ptr<const TriangleMesh>& shared_mesh() const { return mesh_; }
  // The nodes in pre-order, the root first.
  const BvhNode* nodes() const { return nodes_.data(); }
  const BvhNode& node(int n) const { return nodes_[static_cast<std::size_t>(n)]; }
  int node_count() const { return static_cast<int>(nodes_.size()); }
  int depth() const { return depth_; }
  // The mesh's exact bounds (the root's float box holds them).
  Aabb root_bounds() const { return mesh_->bounds(); }
  // The mesh's principal-axes box (OrientedBox::fit of its vertices), fitted on first use and kept
  // until a refit: a scene's objects share it per mesh instead of fitting it for every move.
  OrientedBox oriented_box() const;

  // One slab per node (kernel/bvh/node_slabs.h), fitted on first use and kept until a refit:
  // distance queries read them, collision tests do not, so a mesh only ever collided with never
  // pays their 20 bytes a node. None (nullptr) for a mesh of fewer than kMinTrianglesForSlabs
  // unless built with BvhBuildOptions::slabs_at_any_size.
  static constexpr std::size_t kMinTrianglesForSlabs = 4096;
  const NodeSlab* node_slabs() const;
  // The most bytes the slabs of a mesh of this many triangles can take (a tree has fewer than two
  // nodes per triangle): what a memory budget must allow for a mesh that may be distance-queried.
  static std::size_t slab_bytes_at_most(std::size_t triangles) {
    return triangles < kMinTrianglesForSlabs ? 0 : 2 * triangles * sizeof(NodeSlab);
  }

  // Tree-ordered triangle k: its corners and its index in the mesh.
  Triangle ordered_triangle(int k) const {
    const TriangleMesh::Face& f = faces_in_order_[k];
    return {vertices_in_order_[f[0]], vertices_in_order_[f[1]], vertices_in_order_[f[2]]};
  }
  std::uint32_t mesh_triangle_index(int k) const { return ordered_to_mesh_[k]; }
  bool ordered_is_degenerate(int k) const { return mesh_->is_degenerate(ordered_to_mesh_[k]); }

 private:
  MeshBvh() = default;
  // The tree-ordered faces and vertex copy from ordered_to_mesh_ (after a build or a load), or
  // none when the mesh is in tree order already (then the mesh's arrays are used).
  void order_triangles();
  // The vertex copy again from the mesh's current vertices (after a refit).
  void reload_vertices();

  std::shared_ptr<const TriangleMesh> mesh_;
  std::vector<BvhNode> nodes_;
  std::vector<TriangleMesh::Face> ordered_faces_;  // into ordered_vertices_
  std::vector<Vec3> ordered_vertices_;             // the mesh's vertices in order of first use by the tree
  std::vector<std::uint32_t> ordered_to_mesh_;
  // What ordered_triangle reads: the two vectors above, or the mesh's own arrays.
  const TriangleMesh::Face* faces_in_order_ = nullptr;
  const Vec3* vertices_in_order_ = nullptr;
  int depth_ = 0;
  bool slabs_at_any_size_ = false;
  mutable std::mutex slabs_mutex_;
  mutable std::vector<NodeSlab> slabs_;
  mutable std::atomic<bool> slabs_fitted_{false};
  mutable std::mutex oriented_box_mutex_;
  mutable bool oriented_box_fitted_ = false;
  mutable OrientedBox oriented_box_;
};

}  // namespace gk
