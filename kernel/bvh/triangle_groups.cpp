#include "kernel/bvh/triangle_groups.h"

namespace gk {

Result<TriangleGroups> TriangleGroups::label(const MeshBvh& bvh, const std::vector<std::int32_t>& group_of) {
  const std::size_t triangles = bvh.mesh().triangle_count();
  if (group_of.size() != triangles)
    return invalid_argument("group_of", "has " + std::to_string(group_of.size()) + " entries for a mesh of " + std::to_string(triangles));
  TriangleGroups out;
  out.ordered_.resize(triangles);
  for (std::size_t k = 0; k < triangles; ++k) {
    const std::int32_t g = group_of[bvh.mesh_triangle_index(static_cast<int>(k))];
    if (g < kNone) return invalid_argument("group_of", "a group is >= 0, or kNone");
    out.ordered_[k] = g;
  }
  // Pre-order puts a node's children after it: bottom-up is the reverse order.
  out.node_.assign(static_cast<std::size_t>(bvh.node_count()), NodeGroups{});
  const auto merge = [](NodeGroups& into, std::int32_t g) {  // false: more than two, or one is kNone
    if (g == kNone) return false;
    if (into.first == kNone) {
      into.first = into.second = g;
      return true;
    }
    if (g == into.first || g == into.second) return true;
    if (into.first != into.second) return false;
    into.second = g;
    return true;
  };
  for (int n = bvh.node_count() - 1; n >= 0; --n) {
    const BvhNode& node = bvh.node(n);
    NodeGroups groups;
    bool within_two = true;
    if (node.is_leaf()) {
      for (int k = node.first_triangle(); k <= node.last_triangle() && within_two; ++k)
        within_two = merge(groups, out.ordered_[static_cast<std::size_t>(k)]);
    } else {
      for (const int child : {n + 1, node.second_child()}) {
        const NodeGroups c = out.node_[static_cast<std::size_t>(child)];
        within_two = within_two && merge(groups, c.first) && merge(groups, c.second);
      }
    }
    out.node_[static_cast<std::size_t>(n)] = within_two ? groups : NodeGroups{};
  }
  return out;
}

}  // namespace gk
