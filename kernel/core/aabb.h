// Axis-aligned bounding box in double precision.
#pragma once

#include "kernel/core/geometry_types.h"

#include <algorithm>
#include <limits>

namespace gk {

struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  bool empty() const { return (min.array() > max.array()).any(); }
  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void extend(const Aabb& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  Vec3 center() const { return 0.5 * (min + max); }
  Vec3 half_extent() const { return 0.5 * (max - min); }
  Vec3 diagonal() const { return max - min; }
  Aabb expanded(double margin) const { return {min.array() - margin, max.array() + margin}; }

  bool overlaps(const Aabb& b) const {
    return (min.array() <= b.max.array()).all() && (b.min.array() <= max.array()).all();
  }
  bool contains(const Aabb& b) const {
    return (min.array() <= b.min.array()).all() && (b.max.array() <= max.array()).all();
  }
  // Euclidean distance between the boxes, 0 when they overlap.
  double distance(const Aabb& b) const {
    const Vec3 gap = (b.min - max).cwiseMax(min - b.max).cwiseMax(Vec3::Zero());
    return gap.norm();
  }
};

}  // namespace gk
