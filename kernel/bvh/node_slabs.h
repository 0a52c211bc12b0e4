// A slab per tree node: a unit direction (the node's area-weighted mean normal) and the interval
// its corners span along it, measured from the node box's centre. The box alone bounds a flat patch
// seen obliquely by most of its width; box and slab together bound it by its thickness, which is
// what the distance of two surfaces facing each other needs (the role of FCL's swept rectangles,
// at 20 bytes a node and without a fitted frame).
#pragma once

#include "kernel/bvh/bvh_node.h"
#include "kernel/core/geometry_types.h"
#include "kernel/core/tolerances.h"

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

// One slab per node of the pre-order tree `nodes`; triangle(k) gives tree-ordered triangle k.
std::vector<NodeSlab> fit_node_slabs(const std::vector<BvhNode>& nodes, const std::function<Triangle(int)>& triangle);

}  // namespace gk
