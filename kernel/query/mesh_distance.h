// Mesh-mesh distance queries: the minimum distance with witnesses (dual-BVH traversal with pruning,
// seed 000 Algorithm 3), "is it closer than delta?" with early exit, and all pairs closer than delta.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_pair_frame.h"
#include "kernel/query/settled_pairs.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/spare_thread.h"
#include "kernel/core/status.h"
#include "kernel/core/stop_token.h"

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

namespace gk {

struct DistanceRequest {
  // Only distances below this matter: pairs whose lower bound reaches it are pruned. With a finite
  // bound and nothing closer, the result says so (found = false) and carries no witnesses. [mm]
  double upper_bound_mm = std::numeric_limits<double>::infinity();
  // Stop at the first pair found closer than this: answers "is it closer than delta?". [mm]
  double stop_below_mm = -1.0;
  // Asked every few thousand node pairs: a caller that gave up ends the traversal (kStopped).
  const StopToken* stop = nullptr;
  // A second thread to finish a large search on (not owned; without stop_below_mm only): the
  // node pairs queued once the search has opened kSplitFrontier of them are dealt out between
  // the two, which share the best distance found. The minimum is the same; of two witness pairs
  // at exactly that distance the one with the lower triangle ids is kept.
  SpareThread* spare = nullptr;
  // Pairs of these settled groups are left out (SettledPairs::groups; its `apart` list is not
  // used): the distance between everything else.
  const SettledPairs* excluded = nullptr;
  // And pairs the caller leaves out one by one, judged on their nearest points (mesh triangle
  // indices, world points; the distance is the pair's): asked only of a pair that would be the
  // nearest so far. The nodes' bounds do not know them, so a search among many such pairs costs
  // what it costs to look at them all.
  std::function<bool(std::uint32_t triangle_a, std::uint32_t triangle_b, const Vec3& point_a, const Vec3& point_b, double distance)>
      excluded_pair;
};

struct DistanceResult {
  bool found = false;  // a pair closer than upper_bound_mm was found
  double distance_mm = std::numeric_limits<double>::infinity();
  Vec3 point_a = Vec3::Zero();  // world coordinates, on mesh A
  Vec3 point_b = Vec3::Zero();  // world coordinates, on mesh B
  std::uint32_t triangle_a = 0;
  std::uint32_t triangle_b = 0;
  bool stopped_early = false;  // stop_below_mm triggered: distance_mm is an upper bound of the minimum
  QueryStats stats;
};

Result<DistanceResult> distance(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                const RigidTransform& pose_b, const DistanceRequest& request = {});

struct ProximityPair {
  std::uint32_t triangle_a = 0;
  std::uint32_t triangle_b = 0;
  double distance_mm = 0.0;
  Vec3 point_a = Vec3::Zero();
  Vec3 point_b = Vec3::Zero();
};

struct ProximityResult {
  std::vector<ProximityPair> pairs;  // ordered by triangle ids
  bool truncated = false;            // max_pairs was reached: the list is incomplete
  // With settled pairs: the first settled pair found within delta_mm, standing for all of them (the
  // others are skipped once one is found, and never listed in pairs).
  std::optional<ProximityPair> settled_witness;
  QueryStats stats;
};

// Every triangle pair at distance <= delta_mm (touching and intersecting pairs included), up to
// max_pairs of them; pairs of settled groups (optional) apart, as above. `enough` (optional) is
// asked of each pair as it is found: true ends the search there (truncated is then set; the
// list, sorted, holds the pairs found so far).
Result<ProximityResult> pairs_within(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                     const RigidTransform& pose_b, double delta_mm,
                                     std::size_t max_pairs = std::numeric_limits<std::size_t>::max(),
                                     const StopToken& stop = {}, const SettledPairs* settled = nullptr,
                                     const std::function<bool(const ProximityPair&)>& enough = {});

}  // namespace gk
