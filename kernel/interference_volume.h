// The volume two closed meshes share, by ray casting: vertical rays on a grid over the overlap of
// their boxes; along each ray the intervals inside A and inside B (from the sorted crossings of
// each closed surface) are intersected and their length summed. The midpoint rule's error shrinks
// with the grid; the result states its grid so a caller can tighten it. Exact B-Rep volumes come
// from occt_adapters (Boolean common).
#pragma once

#include "kernel/mesh_bvh.h"
#include "kernel/rigid_transform.h"
#include "kernel/status.h"

namespace gk {

struct VolumeEstimate {
  double volume_mm3 = 0.0;
  double cell_mm = 0.0;   // grid spacing used (the larger of the two cell sides)
  int rays = 0;
};

// Both meshes must be closed and consistently oriented; cells_per_axis in [4, 4096].
Result<VolumeEstimate> interference_volume(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                           const RigidTransform& pose_b, int cells_per_axis = 256);

}  // namespace gk
