// Mesh-mesh collision: does any triangle of A intersect (or touch) any triangle of B?
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_pair_frame.h"
#include "kernel/query/settled_pairs.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "kernel/core/stop_token.h"

#include <cstdint>
#include <limits>
#include <vector>

namespace gk {

struct CollisionRequest {
  bool all_contacts = false;  // false: stop at the first intersecting pair
  std::size_t max_contacts = std::numeric_limits<std::size_t>::max();
  // Asked every few thousand node pairs: a caller that gave up ends the traversal (kStopped).
  const StopToken* stop = nullptr;
  // Pairs of triangle groups the caller has decided already: skipped, their contacts not reported.
  const SettledPairs* settled = nullptr;
};

// One intersecting triangle pair, in world coordinates.
struct Contact {
  std::uint32_t triangle_a = 0;  // index in mesh A
  std::uint32_t triangle_b = 0;  // index in mesh B
  Vec3 segment_start = Vec3::Zero();
  Vec3 segment_end = Vec3::Zero();
  Vec3 point = Vec3::Zero();      // representative point: the segment's midpoint
  bool coplanar = false;
  bool involves_degenerate = false;  // a zero-area triangle took part: the decision is conservative
};

struct CollisionResult {
  bool colliding = false;
  std::vector<Contact> contacts;  // the first one, or all of them (ordered by triangle ids)
  bool truncated = false;         // max_contacts was reached
  QueryStats stats;
};

Result<CollisionResult> collide(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                const RigidTransform& pose_b, const CollisionRequest& request = {});

}  // namespace gk
