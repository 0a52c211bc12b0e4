// Groups of a mesh's triangles (the faces of one feature, say), labelled down its tree: a node
// carries a group when every triangle under it is in that group. A query given two trees' groups
// and the pairs of groups a caller has settled already (kernel/query/settled_pairs.h) skips whole
// subtrees of such pairs without visiting their triangles.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/status.h"

#include <cstdint>
#include <vector>

namespace gk {

class TriangleGroups {
 public:
  static constexpr std::int32_t kNone = -1;
  // The groups under a node: at most two (a feature and its collar share the leaves where they
  // meet), else kNone; `first` is kNone too when a triangle under it is in no group.
  struct NodeGroups {
    std::int32_t first = kNone;
    std::int32_t second = kNone;  // == first when there is one
  };

  // group_of: one entry per mesh triangle, a group (>= 0) or kNone.
  static Result<TriangleGroups> label(const MeshBvh& bvh, const std::vector<std::int32_t>& group_of);

  NodeGroups of_node(int n) const { return node_[static_cast<std::size_t>(n)]; }
  std::int32_t of_ordered_triangle(int k) const { return ordered_[static_cast<std::size_t>(k)]; }
  // Made for this tree (as many nodes and triangles): a tree rebuilt since needs new labels.
  bool labels(const MeshBvh& bvh) const {
    return node_.size() == static_cast<std::size_t>(bvh.node_count()) && ordered_.size() == bvh.mesh().triangle_count();
  }

 private:
  std::vector<NodeGroups> node_;       // per node in pre-order
  std::vector<std::int32_t> ordered_;  // per tree-ordered triangle
};

}  // namespace gk
