// A bounding-volume hierarchy over a mesh's triangles, built by OCCT's SAH binned builder into an
// OCCT BVH_Tree<double,3>. Queries read the tree's node arrays directly (a tight loop, no virtual
// calls); refit after the vertices move uses BVH::UpdateBounds, keeping the topology.
#pragma once

#include "kernel/core/aabb.h"
#include "kernel/core/geometry_types.h"
#include "kernel/core/status.h"
#include "kernel/mesh/oriented_box.h"
#include "kernel/mesh/triangle_mesh.h"

#include <NCollection_Vec3.hxx>
#include <NCollection_Vec4.hxx>

#include <memory>
#include <mutex>
#include <vector>

namespace gk {

struct BvhBuildOptions {
  // Triangles per leaf. 4 since 2026-11-26: against 1, random-pose distances 1.3-1.6x faster,
  // collide 1.1-1.5x, builds twice as fast and trees take about 40 % less memory; near-contact
  // distance on the smallest pair (env/rob) about 6 % slower (docs/PERFORMANCE.md, kernel_fcl_table).
  int leaf_size = 4;
  // SAH bins are a compile-time parameter of OCCT's builder: 8 for meshes of up to 512
  // triangles, 32 above.
};

// A mesh ready for queries: the mesh, its tree, and its triangles' corners in tree order.
class MeshBvh {
 public:
  // The node arrays as OCCT lays them out (see BVH_Tree.hxx).
  struct NodeView {
    const NCollection_Vec3<double>* min_point;
    const NCollection_Vec3<double>* max_point;
    const NCollection_Vec4<int>* info;  // x: leaf flag, y/z: children or primitive range
  };

  static Result<std::shared_ptr<MeshBvh>> build(std::shared_ptr<const TriangleMesh> mesh,
                                                const BvhBuildOptions& options = {});
  ~MeshBvh();
  MeshBvh(const MeshBvh&) = delete;
  MeshBvh& operator=(const MeshBvh&) = delete;

  // The tree as bytes (node arrays, depth, triangle order), and back onto the same mesh without
  // the SAH build. Loading checks every index, so damaged bytes are an error, never a bad tree.
  std::string serialize() const;
  static Result<std::shared_ptr<MeshBvh>> deserialize(std::shared_ptr<const TriangleMesh> mesh, const std::string& bytes);

  // Recomputes every box bottom-up from the mesh's current vertices (same topology).
  void refit(std::shared_ptr<const TriangleMesh> moved_mesh);

  const TriangleMesh& mesh() const { return *mesh_; }
  // Each node's box as centre and half extents, derived from the tree's min/max arrays after every
  // build or refit: the form the separating-axis and distance-bound tests consume.
  const Vec3& node_center(int n) const { return node_center_[n]; }
  const Vec3& node_half_extent(int n) const { return node_half_[n]; }
  NodeView nodes() const;
  int node_count() const;
  int depth() const;
  Aabb root_bounds() const;
  // The mesh's principal-axes box (OrientedBox::fit of its vertices), fitted on first use and kept
  // until a refit: a scene's objects share it per mesh instead of fitting it for every move.
  OrientedBox oriented_box() const;

  // Tree-ordered triangle k: its corners and its index in the mesh.
  const Triangle& ordered_triangle(int k) const { return ordered_corners_[k]; }
  std::uint32_t mesh_triangle_index(int k) const { return ordered_to_mesh_[k]; }
  bool ordered_is_degenerate(int k) const { return mesh_->is_degenerate(ordered_to_mesh_[k]); }

  struct Impl;

 private:
  MeshBvh() = default;
  void reload_corners();
  void reload_node_boxes();

  std::shared_ptr<const TriangleMesh> mesh_;
  std::unique_ptr<Impl> impl_;
  std::vector<Triangle> ordered_corners_;
  std::vector<Vec3> node_center_;
  std::vector<Vec3> node_half_;
  std::vector<std::uint32_t> ordered_to_mesh_;
  int depth_ = 0;
  mutable std::mutex oriented_box_mutex_;
  mutable bool oriented_box_fitted_ = false;
  mutable OrientedBox oriented_box_;
};

}  // namespace gk
