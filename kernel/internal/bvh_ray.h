// Walking a mesh's BVH along a ray: every leaf whose box (grown by a slack) the ray meets for
// parameters t in [t_min, t_max] is handed to the visitor, as a range of tree-ordered triangles.
// Shared by the point-in-mesh parity test and the ray-cast interference volume.
#pragma once

#include "kernel/bvh/mesh_bvh.h"

#include <algorithm>
#include <limits>

namespace gk {

// visit(first, last) gets each leaf's inclusive triangle range; return false from it to stop.
template <typename Visit>
void for_each_leaf_along(const MeshBvh& mesh, const Vec3& origin, const Vec3& dir, double t_min, double t_max, double slack,
                         Visit&& visit) {
  const BvhNode* nodes = mesh.nodes();
  int stack[2 * kMaxBvhDepth + 4];  // at most one pending sibling per level
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int n = stack[--top];
    const BvhNode& node = nodes[n];
    const double los[3] = {node.lo[0] - slack, node.lo[1] - slack, node.lo[2] - slack};
    const double his[3] = {node.hi[0] + slack, node.hi[1] + slack, node.hi[2] + slack};
    double t0 = t_min, t1 = t_max;
    bool miss = false;
    for (int k = 0; k < 3 && !miss; ++k) {
      if (dir[k] == 0.0) {
        miss = origin[k] < los[k] || origin[k] > his[k];
        continue;
      }
      double a = (los[k] - origin[k]) / dir[k], b = (his[k] - origin[k]) / dir[k];
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
      miss = t0 > t1;
    }
    if (miss) continue;
    if (!node.is_leaf()) {
      stack[top++] = node.second_child();
      stack[top++] = n + 1;
      continue;
    }
    if (!visit(node.first_triangle(), node.last_triangle())) return;
  }
}

}  // namespace gk
