// Poses of B near A for benchmarks: a random orientation and direction, then B moved along the
// witness direction so that the gap is uniform in [-1, 3] mm (negative: interpenetrating).
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/rigid_transform.h"

#include <vector>

namespace gk::testing {

std::vector<RigidTransform> near_contact_poses(const MeshBvh& a, const MeshBvh& b, unsigned seed, int count);

}  // namespace gk::testing
