#include "engine/audits/clash_groups.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace gk::engine {
namespace {

std::vector<ClashGroup> sorted(const std::map<std::string, ClashGroup>& counts) {
  std::vector<ClashGroup> out;
  for (const auto& [key, group] : counts) out.push_back(group);
  std::stable_sort(out.begin(), out.end(), [](const ClashGroup& l, const ClashGroup& r) { return l.clashes > r.clashes; });
  return out;
}

void count(std::map<std::string, ClashGroup>& groups, const std::string& key, bool collision) {
  ClashGroup& g = groups[key];
  g.key = key;
  g.clashes += 1;
  g.collisions += collision ? 1u : 0u;
}

}  // namespace

ClashGroups group_clashes(const std::vector<ClashRecord>& clashes) {
  std::map<std::string, ClashGroup> by_object, by_category, by_region;
  for (const ClashRecord& r : clashes) {
    const bool collision = r.clash.verdict == Verdict::kCollision;
    count(by_object, r.a, collision);
    count(by_object, r.b, collision);
    count(by_category, std::min(r.category_a, r.category_b) + " / " + std::max(r.category_a, r.category_b), collision);
    const Vec3& p = r.clash.point_a;
    count(by_region,
          std::to_string(static_cast<long long>(std::floor(p.x() / kClashCellMm))) + "," +
              std::to_string(static_cast<long long>(std::floor(p.y() / kClashCellMm))),
          collision);
  }
  return {sorted(by_object), sorted(by_category), sorted(by_region)};
}

}  // namespace gk::engine
