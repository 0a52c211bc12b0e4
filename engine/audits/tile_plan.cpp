#include "engine/audits/tile_plan.h"

#include <algorithm>
#include <numeric>

namespace gk::engine {

std::vector<std::vector<std::size_t>> plan_tiles(const std::vector<double>& costs, int processes) {
  const auto n = static_cast<std::size_t>(std::max(1, processes));
  std::vector<std::vector<std::size_t>> plan(n);
  std::vector<std::size_t> tiles;
  for (std::size_t t = 0; t < costs.size(); ++t)
    if (costs[t] > 0.0) tiles.push_back(t);
  std::stable_sort(tiles.begin(), tiles.end(), [&](std::size_t a, std::size_t b) { return costs[a] > costs[b]; });
  std::vector<double> load(n, 0.0);
  for (std::size_t t : tiles) {
    const std::size_t least = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    plan[least].push_back(t);
    load[least] += costs[t];
  }
  return plan;
}

}  // namespace gk::engine
