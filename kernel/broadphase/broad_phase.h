// Broad phase over many boxes: which pairs of boxes (grown by a margin) overlap. Two methods give
// the same set, so each can check the other and the caller can pick by measurement:
//  - sweep and prune: sort box intervals on the axis of largest spread, sweep, then filter the
//    other two axes (seed 000, Algorithm 1);
//  - a uniform hash grid with cells twice the median box diagonal. Boxes spanning more than a few
//    cells per axis (building columns, pipes across the hall) are kept out of the grid and swept
//    against everything instead, so huge objects do not blow the grid up. A pair met in several
//    cells is emitted only in the cell holding the low corner of the two boxes' intersection:
//    no deduplication set.
// Pairs come out as (lower index, higher index), sorted.
#pragma once

#include "kernel/core/aabb.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace gk {

using IndexPair = std::pair<std::uint32_t, std::uint32_t>;

// Boxes that overlap once each is grown by margin_mm / 2 on every side (so pairs closer than
// margin_mm are in). Empty boxes never pair.
std::vector<IndexPair> sweep_and_prune(const std::vector<Aabb>& boxes, double margin_mm);

struct HashGridStats {
  double cell_mm = 0.0;
  std::size_t gridded = 0, oversized = 0;  // boxes in the grid, boxes swept apart
  std::size_t cell_entries = 0;
};
std::vector<IndexPair> hash_grid_pairs(const std::vector<Aabb>& boxes, double margin_mm, HashGridStats* stats = nullptr);

// Every box against every other: the oracle.
std::vector<IndexPair> all_overlapping_pairs(const std::vector<Aabb>& boxes, double margin_mm);

// The boxes overlapping `probe` (grown by margin_mm / 2 on each, as above), ascending.
std::vector<std::uint32_t> boxes_meeting(const std::vector<Aabb>& boxes, const Aabb& probe, double margin_mm);

}  // namespace gk
