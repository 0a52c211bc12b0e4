// Is a point inside a closed, consistently oriented mesh? The parity of the crossings of a segment
// from the point to beyond the mesh, found through the BVH (node boxes slightly grown so rounding
// cannot skip one) with every crossing decided by the exact orient3d predicate. A segment that
// grazes an edge or a vertex, or starts on the surface (some orientation exactly zero), is tried
// again along another direction. O(log n) per query instead of the winding number's O(n).
#pragma once

#include "kernel/bvh/mesh_bvh.h"

#include <optional>

namespace gk {

// nullopt when every direction tried was degenerate (the point lies on the surface, or the mesh
// is built to defeat it): the caller falls back to the winding number.
std::optional<bool> point_inside(const MeshBvh& mesh, const Vec3& point);

}  // namespace gk
