#include "kernel/bvh/node_slabs.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gk {

std::vector<NodeSlab> fit_node_slabs(const std::vector<BvhNode>& nodes, const std::function<Triangle(int)>& triangle) {
  const int count = static_cast<int>(nodes.size());
  std::vector<NodeSlab> slabs(nodes.size());
  // Area-weighted normals bottom-up: in pre-order both children come after their parent.
  std::vector<Vec3> area(nodes.size(), Vec3::Zero());
  for (int n = count - 1; n >= 0; --n) {
    const BvhNode& node = nodes[static_cast<std::size_t>(n)];
    if (node.is_leaf()) {
      for (int k = node.first_triangle(); k <= node.last_triangle(); ++k) {
        const Triangle t = triangle(k);
        area[static_cast<std::size_t>(n)] += (t[1] - t[0]).cross(t[2] - t[0]);
      }
    } else {
      area[static_cast<std::size_t>(n)] = area[static_cast<std::size_t>(n + 1)] + area[static_cast<std::size_t>(node.second_child())];
    }
  }
  std::vector<int> stack;
  stack.reserve(2 * kMaxBvhDepth + 4);
  for (int n = 0; n < count; ++n) {
    const BvhNode& node = nodes[static_cast<std::size_t>(n)];
    Vec3 direction = area[static_cast<std::size_t>(n)];
    const double length = direction.norm();
    // A closed or strongly curved node has no mean normal worth the name; any unit direction is
    // still a valid slab (as loose as the box), so take the box's thinnest axis.
    if (!(length > 0.0) || !std::isfinite(length)) {
      const Vec3 extent = node.half_extent();
      int thinnest = 0;
      extent.minCoeff(&thinnest);
      direction = Vec3::Unit(thinnest);
    } else {
      direction /= length;
    }
    NodeSlab& slab = slabs[static_cast<std::size_t>(n)];
    for (int c = 0; c < 3; ++c) slab.normal[c] = static_cast<float>(direction[c]);
    if (!(slab.direction().norm() <= kSlabNormalMaxLength)) {  // never seen; kept so the promise holds
      direction = Vec3::UnitX();
      slab.normal[0] = 1.0f;
      slab.normal[1] = slab.normal[2] = 0.0f;
    }
    // The interval is measured along the double direction, then widened by how far the stored
    // float direction can turn a corner's projection: each component is within 2^-24 of it
    // (relative), so the two differ by less than kFloatTurn, times the corner's distance from the
    // centre. (Measured along the float direction read back from the slab, the -O3 build left
    // corners 1e-8 mm outside their slab, as if the unrounded direction had been used; the cause
    // was not found, and this way does not depend on it.)
    constexpr double kFloatTurn = 1.0e-7;
    const Vec3 centre = node.center();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, reach_sq = 0.0;
    stack.clear();
    stack.push_back(n);
    while (!stack.empty()) {
      const int m = stack.back();
      stack.pop_back();
      const BvhNode& sub = nodes[static_cast<std::size_t>(m)];
      if (!sub.is_leaf()) {
        stack.push_back(sub.second_child());
        stack.push_back(m + 1);
        continue;
      }
      for (int k = sub.first_triangle(); k <= sub.last_triangle(); ++k) {
        const Triangle t = triangle(k);
        for (const Vec3& corner : t) {
          const Vec3 offset = corner - centre;
          const double s = direction.dot(offset);
          lo = std::min(lo, s);
          hi = std::max(hi, s);
          reach_sq = std::max(reach_sq, offset.squaredNorm());
        }
      }
    }
    const double turn = kFloatTurn * std::sqrt(reach_sq) * 1.001;
    lo -= turn;
    hi += turn;
    slab.lo = float_at_or_below(lo);
    slab.hi = float_at_or_above(hi);
  }
  return slabs;
}

}  // namespace gk
