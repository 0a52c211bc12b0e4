// Where two parts touch or come closer than asked: one group of triangle pairs
// (kernel/measure/contact_regions), the one form in which ClearanceQuery and audits report it.
#pragma once

#include "kernel/core/aabb.h"
#include "kernel/measure/contact_regions.h"

#include <cstdint>
#include <vector>

namespace gk::engine {

struct ContactPlace {
  double min_distance_mm = 0.0;         // its closest pair (0: in contact)
  Vec3 point_a = Vec3::Zero();          // that pair's witnesses, world coordinates
  Vec3 point_b = Vec3::Zero();
  std::uint32_t triangle_pairs = 0;
  Aabb bounds;                          // of the witnesses on A
  std::vector<int> faces_a, faces_b;    // CAD parts: the B-Rep faces (1-based) of its triangles
};

// One region of pairs as a place (faces empty: the caller knows whether a part has faces).
ContactPlace place_of(const ContactRegion& region);
// The pairs grouped (kernel's group_into_regions), closest first; faces stay empty.
std::vector<ContactPlace> contact_places(const std::vector<ProximityPair>& pairs, double merge_mm);

}  // namespace gk::engine
