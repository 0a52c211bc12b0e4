// One node of a mesh's bounding-volume hierarchy: a box in float, rounded outward from the double
// coordinates it bounds, and where its children or triangles are. 32 bytes; nodes are stored in
// pre-order, so an inner node's first child is the next node.
#pragma once

#include "kernel/core/geometry_types.h"

#include <cmath>
#include <cstdint>

namespace gk {

// Trees are never deeper than this (levels below the root); the builder makes a larger leaf
// instead. Traversal stacks are sized from it.
inline constexpr int kMaxBvhDepth = 60;

struct BvhNode {
  float lo[3];
  float hi[3];
  // Inner node: the second child (the first is the next node). Leaf: its first tree-ordered triangle.
  std::int32_t index;
  // Leaf: how many triangles (at least 1). Inner node: 0.
  std::int32_t count;

  bool is_leaf() const { return count > 0; }
  int second_child() const { return index; }
  int first_triangle() const { return index; }
  int last_triangle() const { return index + count - 1; }

  Vec3 lower() const { return Vec3(lo[0], lo[1], lo[2]); }
  Vec3 upper() const { return Vec3(hi[0], hi[1], hi[2]); }
  // In double: the rounding of these sums is covered by the queries' relative box slack.
  Vec3 center() const { return 0.5 * (lower() + upper()); }
  Vec3 half_extent() const { return 0.5 * (upper() - lower()); }
  // Size measure for choosing which node of a pair to open: the squared diagonal.
  float size() const {
    const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return x * x + y * y + z * z;
  }
};
static_assert(sizeof(BvhNode) == 32, "a node is 32 bytes");

// The nearest float at or below (above) a double: boxes rounded this way still hold every double
// coordinate they were made from.
inline float float_at_or_below(double v) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) > v) f = std::nextafter(f, -INFINITY);
  return f;
}
inline float float_at_or_above(double v) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) < v) f = std::nextafter(f, INFINITY);
  return f;
}

}  // namespace gk
