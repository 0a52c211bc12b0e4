#include "kernel/bvh/node_slabs.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gk {
namespace {

// Nodes of up to this many triangles get the interval of their corners exactly; a larger node
// gets it from its children's slabs (looser, but such nodes are rarely flat, and measuring every
// corner at every level cost more than the tree's own build on the largest meshes).
constexpr int kExactUpTo = 64;

struct Interval {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double lo_value, double hi_value) {
    lo = std::min(lo, lo_value);
    hi = std::max(hi, hi_value);
  }
};

// The unit direction of a node's slab: its area-weighted normal, or, for a node with none worth
// the name (closed, strongly curved), the box's thinnest axis: any unit direction is a valid slab.
Vec3 slab_direction(const Vec3& area, const BvhNode& node) {
  const double length = area.norm();
  if (!(length > 0.0) || !std::isfinite(length)) {
    int thinnest = 0;
    node.half_extent().minCoeff(&thinnest);
    return Vec3::Unit(thinnest);
  }
  return area / length;
}

// The interval of u . (x - centre) over the corners of the triangles under node n.
Interval corners_along(const std::vector<BvhNode>& nodes, int n, const Vec3& u, const Vec3& centre,
                       const std::function<Triangle(int)>& triangle, std::vector<int>& stack) {
  Interval interval;
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
        const double s = u.dot(corner - centre);
        interval.add(s, s);
      }
    }
  }
  return interval;
}

}  // namespace

std::vector<NodeSlab> fit_node_slabs(const std::vector<BvhNode>& nodes, const std::function<Triangle(int)>& triangle) {
  const int count = static_cast<int>(nodes.size());
  std::vector<NodeSlab> slabs(nodes.size());
  // Area-weighted normals and triangle counts bottom-up: in pre-order both children come after
  // their parent.
  std::vector<Vec3> area(nodes.size(), Vec3::Zero());
  std::vector<int> triangles(nodes.size(), 0);
  for (int n = count - 1; n >= 0; --n) {
    const auto at = static_cast<std::size_t>(n);
    const BvhNode& node = nodes[at];
    if (node.is_leaf()) {
      for (int k = node.first_triangle(); k <= node.last_triangle(); ++k) {
        const Triangle t = triangle(k);
        area[at] += (t[1] - t[0]).cross(t[2] - t[0]);
      }
      triangles[at] = node.count;
    } else {
      const auto first = static_cast<std::size_t>(n + 1), second = static_cast<std::size_t>(node.second_child());
      area[at] = area[first] + area[second];
      triangles[at] = triangles[first] + triangles[second];
    }
  }
  std::vector<int> stack;
  stack.reserve(2 * kMaxBvhDepth + 4);
  // Children before parents: a large node's interval is made of its children's slabs.
  for (int n = count - 1; n >= 0; --n) {
    const auto at = static_cast<std::size_t>(n);
    const BvhNode& node = nodes[at];
    Vec3 direction = slab_direction(area[at], node);
    NodeSlab& slab = slabs[at];
    for (int c = 0; c < 3; ++c) slab.normal[c] = static_cast<float>(direction[c]);
    if (!(slab.direction().norm() <= kSlabNormalMaxLength)) {  // never seen; kept so the promise holds
      direction = Vec3::UnitX();
      slab.normal[0] = 1.0f;
      slab.normal[1] = slab.normal[2] = 0.0f;
    }
    // The interval is measured along the double direction, then widened by how far the stored
    // float direction can turn a point's projection: kSlabNormalTurn times its distance from the
    // centre, at most the box's half diagonal. (Measured along the float direction read back from
    // the slab, the -O3 build left corners 1e-8 mm outside their slab, as if the unrounded
    // direction had been used; the cause was not found, and this way does not depend on it.)
    const Vec3 centre = node.center();
    Interval interval;
    if (node.is_leaf() || triangles[at] <= kExactUpTo) {
      interval = corners_along(nodes, n, direction, centre, triangle, stack);
    } else {
      for (const int child : {n + 1, node.second_child()}) {
        const BvhNode& sub = nodes[static_cast<std::size_t>(child)];
        const double offset = direction.dot(sub.center() - centre);
        const SlabReach reach = reach_along(direction, slabs[static_cast<std::size_t>(child)], sub.half_extent());
        interval.add(offset + reach.lo, offset + reach.hi);
      }
    }
    const double turn = tolerances::kSlabNormalTurn * node.half_extent().norm() * 1.001;
    slab.lo = float_at_or_below(interval.lo - turn);
    slab.hi = float_at_or_above(interval.hi + turn);
  }
  return slabs;
}

}  // namespace gk
