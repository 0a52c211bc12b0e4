// Triangle pairs closer than a gap, grouped into contact regions: what a person checking a
// clearance wants to see (a few places) instead of thousands of raw pairs.
#pragma once

#include "kernel/query/mesh_distance.h"

#include <vector>

namespace gk {

struct ContactRegion {
  std::vector<ProximityPair> pairs;  // the region's triangle pairs (world coordinates)
  double min_distance_mm = 0.0;      // its closest pair ...
  Vec3 point_a = Vec3::Zero();       // ... and that pair's witnesses
  Vec3 point_b = Vec3::Zero();
  Aabb bounds;                       // of the witnesses on A
};

// Two pairs belong to one region when they share a triangle of A or of B, or their witnesses on
// A lie within merge_mm of each other. Regions are ordered by their minimum distance.
std::vector<ContactRegion> group_into_regions(const std::vector<ProximityPair>& pairs, double merge_mm);

}  // namespace gk
