// Which process of a distributed audit takes which tiles: longest processing time first (the
// costliest tile to the least loaded process), the same plan on every process from the same tile
// costs, so no message is needed to agree on it.
#pragma once

#include <cstddef>
#include <vector>

namespace gk::engine {

// costs: per tile (0: nothing to audit, assigned to nobody). Returns each process's tiles in the
// order it should take them (costliest first). processes >= 1.
std::vector<std::vector<std::size_t>> plan_tiles(const std::vector<double>& costs, int processes);

}  // namespace gk::engine
