#include "kernel/query/mesh_distance.h"

#include "kernel/query/triangle_distance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

namespace gk {
namespace {

struct BoundedPair {
  int a, b;
  double lower_bound;
};

}  // namespace

Result<DistanceResult> distance(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                const RigidTransform& pose_b, const DistanceRequest& request) {
  if (std::isnan(request.upper_bound_mm) || request.upper_bound_mm < 0.0)
    return invalid_argument("upper_bound_mm", "must be a non-negative number or infinity");
  if (std::isnan(request.stop_below_mm)) return invalid_argument("stop_below_mm", "is NaN");
  auto made = MeshPairFrame::make(a, pose_a, b, pose_b);
  if (!made.ok()) return made.error();
  const MeshPairFrame& frame = made.value();

  DistanceResult result;
  double best = request.upper_bound_mm;
  int best_ka = -1, best_kb = -1;
  Vec3 best_pa = Vec3::Zero(), best_pb = Vec3::Zero();

  // Best-first: always expand the pair with the smallest lower bound, so the first leaves reached
  // are the likely nearest and the bound tightens before the rest is looked at. The queue is a
  // per-thread buffer reused across queries.
  thread_local std::vector<BoundedPair> queue;
  queue.clear();
  const auto farther = [](const BoundedPair& x, const BoundedPair& y) { return x.lower_bound > y.lower_bound; };
  queue.push_back({0, 0, frame.nodes_lower_bound(0, 0)});
  std::uint64_t popped = 0;
  ++result.stats.node_pairs_tested;
  while (!queue.empty()) {
    std::pop_heap(queue.begin(), queue.end(), farther);
    const BoundedPair p = queue.back();
    queue.pop_back();
    if ((popped++ & kStopCheckMask) == 0 && request.stop && request.stop->stop_requested()) return stopped("the distance query");
    if (p.lower_bound >= best) break;  // every pair left is at least this far: done
    const bool leaf_a = frame.is_leaf_a(p.a), leaf_b = frame.is_leaf_b(p.b);
    if (leaf_a && leaf_b) {
      for (int kb = frame.begin_b(p.b); kb <= frame.end_b(p.b); ++kb) {
        const Triangle tb = frame.b_triangle_in_a(kb);
        for (int ka = frame.begin_a(p.a); ka <= frame.end_a(p.a); ++ka) {
          ++result.stats.triangle_pairs_tested;
          const TriangleDistance d = triangle_distance(a.ordered_triangle(ka), tb, best);
          if (!d.bounded_only && d.distance < best) {
            best = d.distance;
            best_ka = ka;
            best_kb = kb;
            best_pa = d.on_p;
            best_pb = d.on_q;
          }
        }
      }
      if (best_ka >= 0 && best < request.stop_below_mm) {
        result.stopped_early = true;
        break;
      }
      continue;
    }
    // Split the larger node.
    BoundedPair first, second;
    const bool split_a = !leaf_a && (leaf_b || frame.size_a(p.a) >= frame.size_b(p.b));
    if (split_a) {
      first = {frame.first_child_a(p.a), p.b, 0.0};
      second = {frame.second_child_a(p.a), p.b, 0.0};
    } else {
      first = {p.a, frame.first_child_b(p.b), 0.0};
      second = {p.a, frame.second_child_b(p.b), 0.0};
    }
    first.lower_bound = frame.pair_lower_bound(first.a, first.b);
    second.lower_bound = frame.pair_lower_bound(second.a, second.b);
    result.stats.node_pairs_tested += 2;
    for (const BoundedPair& child : {first, second}) {
      if (child.lower_bound < best) {
        queue.push_back(child);
        std::push_heap(queue.begin(), queue.end(), farther);
      }
    }
  }

  if (best_ka >= 0) {
    result.found = true;
    result.distance_mm = best;
    result.triangle_a = a.mesh_triangle_index(best_ka);
    result.triangle_b = b.mesh_triangle_index(best_kb);
    result.point_a = frame.to_world(best_pa);
    result.point_b = frame.to_world(best_pb);
  }
  return result;
}

Result<ProximityResult> pairs_within(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                     const RigidTransform& pose_b, double delta_mm, std::size_t max_pairs,
                                     const StopToken& stop) {
  if (!(delta_mm >= 0.0) || !std::isfinite(delta_mm))
    return invalid_argument("delta_mm", "must be a finite, non-negative distance");
  auto made = MeshPairFrame::make(a, pose_a, b, pose_b);
  if (!made.ok()) return made.error();
  const MeshPairFrame& frame = made.value();
  ProximityResult result;

  std::array<std::pair<int, int>, 2 * kMaxBvhDepth + 4> stack;
  int top = 0;
  stack[top++] = {0, 0};
  while (top > 0 && !result.truncated) {
    const auto [na, nb] = stack[--top];
    if ((result.stats.node_pairs_tested++ & kStopCheckMask) == 0 && stop.stop_requested()) return stopped("the pairs within the gap");
    if (frame.pair_lower_bound(na, nb) > delta_mm) continue;
    const bool leaf_a = frame.is_leaf_a(na), leaf_b = frame.is_leaf_b(nb);
    if (leaf_a && leaf_b) {
      for (int kb = frame.begin_b(nb); kb <= frame.end_b(nb); ++kb) {
        const Triangle tb = frame.b_triangle_in_a(kb);
        for (int ka = frame.begin_a(na); ka <= frame.end_a(na); ++ka) {
          ++result.stats.triangle_pairs_tested;
          const TriangleDistance d = triangle_distance(a.ordered_triangle(ka), tb, std::nextafter(delta_mm, 1e300));
          if (!d.bounded_only && d.distance <= delta_mm) {
            if (result.pairs.size() >= max_pairs) {
              result.truncated = true;
              break;
            }
            result.pairs.push_back({a.mesh_triangle_index(ka), b.mesh_triangle_index(kb), d.distance,
                                    frame.to_world(d.on_p), frame.to_world(d.on_q)});
          }
        }
      }
      continue;
    }
    const bool split_a = !leaf_a && (leaf_b || frame.size_a(na) >= frame.size_b(nb));
    if (split_a) {
      stack[top++] = {frame.second_child_a(na), nb};
      stack[top++] = {frame.first_child_a(na), nb};
    } else {
      stack[top++] = {na, frame.second_child_b(nb)};
      stack[top++] = {na, frame.first_child_b(nb)};
    }
  }
  std::sort(result.pairs.begin(), result.pairs.end(), [](const ProximityPair& x, const ProximityPair& y) {
    return std::tie(x.triangle_a, x.triangle_b) < std::tie(y.triangle_a, y.triangle_b);
  });
  return result;
}

}  // namespace gk
