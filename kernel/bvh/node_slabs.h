// A slab per tree node: a unit direction (the node's area-weighted mean normal) and the interval
// its corners span along it, measured from the node box's centre. The box alone bounds a flat patch
// seen obliquely by most of its width; box and slab together bound it by its thickness, which is
// what the distance of two surfaces facing each other needs (the role of FCL's swept rectangles,
// at 20 bytes a node and without a fitted frame).
#pragma once

#include "kernel/bvh/bvh_node.h"
#include "kernel/core/geometry_types.h"
#include "kernel/core/tolerances.h"

#include <algorithm>
#include <functional>
#include <vector>

namespace gk {

using tolerances::kSlabNormalMaxLength;

struct NodeSlab {
  float normal[3];  // unit to float precision: |normal| <= kSlabNormalMaxLength
  float lo, hi;     // normal . (x - node centre) for every corner x, rounded outward [mm]

  Vec3 direction() const { return Vec3(normal[0], normal[1], normal[2]); }
};
static_assert(sizeof(NodeSlab) == 20, "a slab is 20 bytes");

// How far a node reaches along the axis u (in the node's frame) either way from its box's centre,
// bounded by its box (half extents e) and its slab together: u = alpha n + w, so u . x spans
// alpha [lo, hi] plus |w| . e (any alpha gives a bound; the projection on n makes w least), and
// never more than the box alone. What the queries and the fit of larger nodes both use.
struct SlabReach {
  double lo, hi;
};
inline SlabReach reach_along(const Vec3& u, const NodeSlab& slab, const Vec3& e) {
  const Vec3 n = slab.direction();
  const double alpha = u.dot(n);  // n is unit to float precision: close enough to the projection
  const double box = (u - alpha * n).cwiseAbs().dot(e);
  const double s0 = alpha * slab.lo, s1 = alpha * slab.hi;
  const double box_alone = u.cwiseAbs().dot(e);
  return {std::max(std::min(s0, s1) - box, -box_alone), std::min(std::max(s0, s1) + box, box_alone)};
}

// One slab per node of the pre-order tree `nodes`; triangle(k) gives tree-ordered triangle k.
std::vector<NodeSlab> fit_node_slabs(const std::vector<BvhNode>& nodes, const std::function<Triangle(int)>& triangle);

}  // namespace gk
