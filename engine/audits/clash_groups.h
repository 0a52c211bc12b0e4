// An audit's clashes counted by object, by category pair and by 10 m floor cell, the largest
// group first: how a report says where the trouble is.
#pragma once

#include "engine/audits/audit_job.h"

#include <string>
#include <vector>

namespace gk::engine {

inline constexpr double kClashCellMm = 10000.0;  // the floor cells clashes are grouped by [mm]

struct ClashGroup {
  std::string key;  // an object id, "category / category", or the cell "i,j" (floor(x / 10 m), floor(y / 10 m))
  unsigned clashes = 0, collisions = 0;
};

struct ClashGroups {
  std::vector<ClashGroup> by_object, by_category, by_region;
};

ClashGroups group_clashes(const std::vector<ClashRecord>& clashes);

}  // namespace gk::engine
