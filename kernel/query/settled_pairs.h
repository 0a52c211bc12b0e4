// Pairs of triangle groups of two meshes (kernel/bvh/triangle_groups.h) whose every triangle pair
// the caller has decided already - a pin's side and its hole's wall while their fit holds - so a
// query skips them: collide reports none of their contacts, pairs_within lists none of them but
// one witness that some are within its distance; and pairs the caller has proven out of reach.
#pragma once

#include "kernel/bvh/triangle_groups.h"

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace gk {

struct SettledPairs {
  using GroupPair = std::pair<std::int32_t, std::int32_t>;  // (a's group, b's group)
  const TriangleGroups* a = nullptr;  // labels of the first mesh's tree
  const TriangleGroups* b = nullptr;  // ... and of the second's
  std::vector<GroupPair> groups;      // decided by the caller wherever they meet; few
  // Proven farther apart than the query's reach (pairs_within's distance; any contact, collide's):
  // skipped outright, no witness looked for.
  std::vector<GroupPair> apart;
  // Where a settled pair within reach most likely is (world), when the caller knows: looked at
  // first (a pin pressed to one side of its hole meets it along one line).
  std::optional<Vec3> hint;

  // May the pairs under these two nodes (these two tree-ordered triangles) be skipped: each pair of
  // their groups proven apart, or settled once a settled pair within reach has been found (collide:
  // settled pairs are always skipped, their contacts not reported)?
  bool skip_nodes(int node_a, int node_b, bool settled_found) const {
    const TriangleGroups::NodeGroups x = a->of_node(node_a), y = b->of_node(node_b);
    return skip(x.first, y.first, settled_found) && skip(x.first, y.second, settled_found) && skip(x.second, y.first, settled_found) &&
           skip(x.second, y.second, settled_found);
  }
  bool skip_triangles(int ordered_a, int ordered_b, bool settled_found) const {
    return skip(a->of_ordered_triangle(ordered_a), b->of_ordered_triangle(ordered_b), settled_found);
  }
  // Could a settled pair lie under these two nodes (a node with a triangle in no group, or with
  // more than two groups, may hold any)?
  bool may_hold_settled(int node_a, int node_b) const {
    const TriangleGroups::NodeGroups x = a->of_node(node_a), y = b->of_node(node_b);
    if (x.first == TriangleGroups::kNone || y.first == TriangleGroups::kNone) return true;
    for (const std::int32_t ga : {x.first, x.second})
      for (const std::int32_t gb : {y.first, y.second})
        if (in(groups, ga, gb) && !in(apart, ga, gb)) return true;
    return false;
  }
  // Every pair of groups under the two nodes settled (apart ones not counted: a distance query
  // leaves the settled out, but what is only apart at one pose may come nearer at another).
  bool nodes_settled(int node_a, int node_b) const {
    const TriangleGroups::NodeGroups x = a->of_node(node_a), y = b->of_node(node_b);
    return in(groups, x.first, y.first) && in(groups, x.first, y.second) && in(groups, x.second, y.first) && in(groups, x.second, y.second);
  }
  bool triangles_settled(int ordered_a, int ordered_b) const {
    return in(groups, a->of_ordered_triangle(ordered_a), b->of_ordered_triangle(ordered_b));
  }
  // Labels for these two trees (a query refuses labels made for another tree).
  bool labels(const MeshBvh& tree_a, const MeshBvh& tree_b) const {
    return a && b && a->labels(tree_a) && b->labels(tree_b);
  }

 private:
  static bool in(const std::vector<GroupPair>& list, std::int32_t group_a, std::int32_t group_b) {
    if (group_a == TriangleGroups::kNone || group_b == TriangleGroups::kNone) return false;
    for (const auto& [x, y] : list)
      if (x == group_a && y == group_b) return true;
    return false;
  }
  bool skip(std::int32_t group_a, std::int32_t group_b, bool settled_found) const {
    return in(apart, group_a, group_b) || (settled_found && in(groups, group_a, group_b));
  }
};

}  // namespace gk
