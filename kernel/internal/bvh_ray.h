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
  const MeshBvh::NodeView nodes = mesh.nodes();
  int stack[128];  // OCCT trees are at most 32 levels deep (BVH_Constants_MaxTreeDepth)
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int n = stack[--top];
    const auto& lo = nodes.min_point[n];
    const auto& hi = nodes.max_point[n];
    const double los[3] = {lo.x() - slack, lo.y() - slack, lo.z() - slack};
    const double his[3] = {hi.x() + slack, hi.y() + slack, hi.z() + slack};
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
    if (nodes.info[n].x() == 0) {
      stack[top++] = nodes.info[n].y();
      stack[top++] = nodes.info[n].z();
      continue;
    }
    if (!visit(nodes.info[n].y(), nodes.info[n].z())) return;
  }
}

}  // namespace gk
