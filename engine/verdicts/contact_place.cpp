#include "engine/verdicts/contact_place.h"

namespace gk::engine {

ContactPlace place_of(const ContactRegion& r) {
  ContactPlace place;
  place.min_distance_mm = r.min_distance_mm;
  place.point_a = r.point_a;
  place.point_b = r.point_b;
  place.triangle_pairs = static_cast<std::uint32_t>(r.pairs.size());
  place.bounds = r.bounds;
  return place;
}

std::vector<ContactPlace> contact_places(const std::vector<ProximityPair>& pairs, double merge_mm) {
  std::vector<ContactPlace> out;
  for (const ContactRegion& r : group_into_regions(pairs, merge_mm)) out.push_back(place_of(r));
  return out;
}

}  // namespace gk::engine
