#include "kernel/measure/contact_regions.h"

#include "kernel/broadphase/uniform_grid.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace gk {
namespace {

struct UnionFind {
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::size_t find(std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(std::size_t a, std::size_t b) { parent[find(a)] = find(b); }
};

}  // namespace

std::vector<ContactRegion> group_into_regions(const std::vector<ProximityPair>& pairs, double merge_mm) {
  UnionFind sets(pairs.size());
  // Shared triangles.
  std::unordered_map<std::uint32_t, std::size_t> first_with_a, first_with_b;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    auto [ia, new_a] = first_with_a.emplace(pairs[i].triangle_a, i);
    if (!new_a) sets.join(i, ia->second);
    auto [ib, new_b] = first_with_b.emplace(pairs[i].triangle_b, i);
    if (!new_b) sets.join(i, ib->second);
  }
  // Nearby witnesses, through a hash grid whose cells are small enough (diagonal just under
  // merge_mm) that all witnesses in one cell are joined at once; a cell is then joined to each
  // neighbour within reach (two cells each way) by the first pair of witnesses found close enough.
  // Linear in the pairs however densely they crowd (a part against its own copy puts 100,000
  // witnesses in a few cells: comparing each with its neighbours took a minute).
  if (merge_mm > 0.0 && std::isfinite(merge_mm)) {
    const double cell_mm = merge_mm / 1.7321;  // a little under merge_mm / sqrt(3)
    std::unordered_map<GridCell, std::vector<std::size_t>, GridCellHash> cells;
    for (std::size_t i = 0; i < pairs.size(); ++i) cells[grid_cell_of(pairs[i].point_a, cell_mm)].push_back(i);
    for (const auto& [c, members] : cells)
      for (std::size_t m = 1; m < members.size(); ++m) sets.join(members[m], members[0]);
    for (const auto& cell : cells) {
      const GridCell& c = cell.first;  // named, not bound: lambdas may not capture bindings in C++17
      const std::vector<std::size_t>& members = cell.second;
      UniformGrid::for_each_cell({{c.x - 2, c.y - 2, c.z - 2}, {c.x + 2, c.y + 2, c.z + 2}}, [&](const GridCell& near) {
        if (near == c) return;
        auto other = cells.find(near);
        if (other == cells.end() || sets.find(members[0]) == sets.find(other->second[0])) return;
        for (std::size_t i : members)
          for (std::size_t j : other->second)
            if ((pairs[j].point_a - pairs[i].point_a).norm() <= merge_mm) return sets.join(i, j);
      });
    }
  }
  std::unordered_map<std::size_t, std::size_t> region_of_root;
  std::vector<ContactRegion> regions;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::size_t root = sets.find(i);
    auto [it, fresh] = region_of_root.emplace(root, regions.size());
    if (fresh) {
      regions.emplace_back();
      regions.back().min_distance_mm = std::numeric_limits<double>::infinity();
    }
    ContactRegion& r = regions[it->second];
    r.pairs.push_back(pairs[i]);
    r.bounds.extend(pairs[i].point_a);
    if (pairs[i].distance_mm < r.min_distance_mm) {
      r.min_distance_mm = pairs[i].distance_mm;
      r.point_a = pairs[i].point_a;
      r.point_b = pairs[i].point_b;
    }
  }
  std::sort(regions.begin(), regions.end(),
            [](const ContactRegion& x, const ContactRegion& y) { return x.min_distance_mm < y.min_distance_mm; });
  return regions;
}

}  // namespace gk
