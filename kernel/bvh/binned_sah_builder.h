// Builds a mesh's tree by binned surface-area heuristic on triangle centroids, in float: at each
// node the centroids are binned along the axis of their largest spread, the split with the least
// (left area x left count + right area x right count) is taken, and the triangles are partitioned
// in place. Node boxes are unions of the triangles' boxes rounded outward to float.
#pragma once

#include "kernel/bvh/bvh_node.h"
#include "kernel/mesh/triangle_mesh.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace gk {

struct BuiltTree {
  std::vector<BvhNode> nodes;        // pre-order, the root first
  std::vector<std::uint32_t> order;  // tree-ordered triangle k is mesh triangle order[k]
  int depth = 0;                     // levels, the root's being 1
};

// A key per mesh triangle (its group, say): a node of at most split_at triangles of several keys
// is split by key before space, one key's triangles from the rest, so that the nodes below hold
// one key each (a query can then skip a group's nodes whole, kernel/query/settled_pairs.h).
struct BuildKeys {
  const std::vector<std::int32_t>* of_triangle = nullptr;  // none: space only
  std::size_t split_at = 0;
};

// leaf_size: a node of at most this many triangles becomes a leaf. The mesh must have triangles.
BuiltTree build_binned_sah(const TriangleMesh& mesh, int leaf_size, const BuildKeys& keys = {});

// The box of one triangle rounded outward to float.
void triangle_float_box(const Triangle& t, float lo[3], float hi[3]);

// Recomputes every box bottom-up (leaves from their triangles, inner nodes from their children).
template <typename TriangleAt>
void refit_nodes(std::vector<BvhNode>& nodes, TriangleAt&& triangle_at) {
  for (std::size_t i = nodes.size(); i-- > 0;) {
    BvhNode& n = nodes[i];
    if (n.is_leaf()) {
      for (int a = 0; a < 3; ++a) {
        n.lo[a] = INFINITY;
        n.hi[a] = -INFINITY;
      }
      for (int k = n.first_triangle(); k <= n.last_triangle(); ++k) {
        float lo[3], hi[3];
        triangle_float_box(triangle_at(k), lo, hi);
        for (int a = 0; a < 3; ++a) {
          n.lo[a] = std::min(n.lo[a], lo[a]);
          n.hi[a] = std::max(n.hi[a], hi[a]);
        }
      }
    } else {
      const BvhNode& l = nodes[i + 1];
      const BvhNode& r = nodes[static_cast<std::size_t>(n.second_child())];
      for (int a = 0; a < 3; ++a) {
        n.lo[a] = std::min(l.lo[a], r.lo[a]);
        n.hi[a] = std::max(l.hi[a], r.hi[a]);
      }
    }
  }
}

}  // namespace gk
