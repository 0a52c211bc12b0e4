#include "kernel/query/mesh_collision.h"

#include "kernel/query/triangle_intersection.h"

#include <algorithm>
#include <array>
#include <limits>
#include <tuple>

namespace gk {
namespace {

struct NodePair {
  int a, b;
};

// Leaves up to this size get their triangles bounded one by one against the other leaf before
// their pairs are tested (the default leaf holds 4).
constexpr int kMaxLeafTrianglesBounded = 8;
// A triangle's bound against a leaf is asked only whether it is above zero: any part of it that is
// already above this settles it.
constexpr double kAnyGap = std::numeric_limits<double>::denorm_min();

// Tests the triangles of two overlapping leaves; returns false when the traversal should stop.
bool test_leaves(const MeshPairFrame& frame, int leaf_a, int leaf_b, const CollisionRequest& request,
                 CollisionResult& result) {
  const MeshBvh& a = frame.a();
  const MeshBvh& b = frame.b();
  // A triangle apart from the other leaf (box or slab) meets none of its triangles.
  std::array<bool, kMaxLeafTrianglesBounded> a_apart{};
  const int first_a = frame.begin_a(leaf_a), count_a = frame.end_a(leaf_a) - first_a + 1;
  const bool bound_a = count_a <= kMaxLeafTrianglesBounded;
  if (bound_a) {
    for (int i = 0; i < count_a; ++i)
      a_apart[static_cast<std::size_t>(i)] = frame.triangle_to_node_b_bound(frame.a_triangle_in_b(first_a + i), leaf_b, kAnyGap) > 0.0;
    result.stats.triangle_node_tests += count_a;
  }
  for (int kb = frame.begin_b(leaf_b); kb <= frame.end_b(leaf_b); ++kb) {
    const Triangle tb = frame.b_triangle_in_a(kb);
    ++result.stats.triangle_node_tests;
    if (frame.triangle_to_node_a_bound(tb, leaf_a, kAnyGap) > 0.0) continue;
    for (int ka = first_a; ka <= frame.end_a(leaf_a); ++ka) {
      if (bound_a && a_apart[static_cast<std::size_t>(ka - first_a)]) continue;
      if (request.settled && request.settled->skip_triangles(ka, kb, true)) continue;
      ++result.stats.triangle_pairs_tested;
      const Triangle ta = a.ordered_triangle(ka);
      const TriangleIntersection hit = intersect_triangles(ta, tb);
      if (!hit.intersects) continue;
      Contact c;
      c.triangle_a = a.mesh_triangle_index(ka);
      c.triangle_b = b.mesh_triangle_index(kb);
      c.segment_start = frame.to_world(hit.segment_start);
      c.segment_end = frame.to_world(hit.segment_end);
      c.point = 0.5 * (c.segment_start + c.segment_end);
      c.coplanar = hit.coplanar;
      c.involves_degenerate = a.ordered_is_degenerate(ka) || b.ordered_is_degenerate(kb);
      result.colliding = true;
      result.contacts.push_back(c);
      if (!request.all_contacts) return false;
      if (result.contacts.size() >= request.max_contacts) {
        result.truncated = true;
        return false;
      }
    }
  }
  return true;
}

}  // namespace

Result<CollisionResult> collide(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                const RigidTransform& pose_b, const CollisionRequest& request) {
  auto made = MeshPairFrame::make(a, pose_a, b, pose_b);
  if (!made.ok()) return made.error();
  MeshPairFrame& frame = made.value();
  frame.use_slabs();
  CollisionResult result;
  if (request.settled && !request.settled->labels(a, b)) return invalid_argument("settled", "labels made for other trees");

  // Depth-first over node pairs; the stack never holds more than depth(A) + depth(B) + 2 entries.
  std::array<NodePair, 2 * kMaxBvhDepth + 4> stack;
  int top = 0;
  stack[top++] = {0, 0};
  while (top > 0) {
    const NodePair p = stack[--top];
    if ((result.stats.node_pairs_tested++ & kStopCheckMask) == 0 && request.stop && request.stop->stop_requested())
      return stopped("the collision query");
    if (request.settled && request.settled->skip_nodes(p.a, p.b, true)) continue;
    if (!frame.nodes_overlap(p.a, p.b) || frame.slabs_separate(p.a, p.b)) continue;
    const bool leaf_a = frame.is_leaf_a(p.a), leaf_b = frame.is_leaf_b(p.b);
    if (leaf_a && leaf_b) {
      if (!test_leaves(frame, p.a, p.b, request, result)) break;
      continue;
    }
    if (leaf_a ? frame.leaf_a_misses_node_b(p.a, p.b) : leaf_b && frame.leaf_b_misses_node_a(p.b, p.a)) continue;
    const bool split_a = !leaf_a && (leaf_b || frame.size_a(p.a) >= frame.size_b(p.b));
    if (split_a) {
      stack[top++] = {frame.second_child_a(p.a), p.b};
      stack[top++] = {frame.first_child_a(p.a), p.b};
    } else {
      stack[top++] = {p.a, frame.second_child_b(p.b)};
      stack[top++] = {p.a, frame.first_child_b(p.b)};
    }
  }
  std::sort(result.contacts.begin(), result.contacts.end(), [](const Contact& x, const Contact& y) {
    return std::tie(x.triangle_a, x.triangle_b) < std::tie(y.triangle_a, y.triangle_b);
  });
  return result;
}

}  // namespace gk
