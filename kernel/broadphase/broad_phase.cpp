#include "kernel/broadphase/broad_phase.h"

#include "kernel/broadphase/uniform_grid.h"
#include "kernel/core/tolerances.h"

#include <algorithm>
#include <cmath>

namespace gk {
namespace {

std::vector<Aabb> grown(const std::vector<Aabb>& boxes, double margin_mm) {
  std::vector<Aabb> out;
  out.reserve(boxes.size());
  for (const Aabb& b : boxes) out.push_back(b.empty() ? b : b.expanded(0.5 * margin_mm));
  return out;
}

int spread_axis(const std::vector<Aabb>& boxes) {
  Vec3 sum = Vec3::Zero(), sum_sq = Vec3::Zero();
  double n = 0.0;
  for (const Aabb& b : boxes) {
    if (b.empty()) continue;
    const Vec3 c = b.center();
    sum += c;
    sum_sq += c.cwiseProduct(c);
    n += 1.0;
  }
  if (n == 0.0) return 0;
  const Vec3 variance = sum_sq / n - (sum / n).cwiseProduct(sum / n);
  int axis = 0;
  variance.maxCoeff(&axis);
  return axis;
}

// Sweep over the listed boxes on `axis`; pairs with at least one member flagged in `wanted` (all
// when empty) are passed to emit.
template <typename Emit>
void sweep(const std::vector<Aabb>& g, std::vector<std::uint32_t> ids, int axis, Emit&& emit) {
  std::sort(ids.begin(), ids.end(), [&](std::uint32_t l, std::uint32_t r) {
    return g[l].min[axis] < g[r].min[axis] || (g[l].min[axis] == g[r].min[axis] && l < r);
  });
  std::vector<std::uint32_t> active;
  for (std::uint32_t id : ids) {
    const Aabb& box = g[id];
    std::size_t keep = 0;
    for (std::uint32_t other : active) {
      if (g[other].max[axis] < box.min[axis]) continue;  // ended before this one starts
      active[keep++] = other;
      if (box.overlaps(g[other])) emit(std::min(id, other), std::max(id, other));
    }
    active.resize(keep);
    active.push_back(id);
  }
}

}  // namespace

std::vector<IndexPair> sweep_and_prune(const std::vector<Aabb>& boxes, double margin_mm) {
  const std::vector<Aabb> g = grown(boxes, margin_mm);
  std::vector<std::uint32_t> ids;
  for (std::uint32_t i = 0; i < g.size(); ++i)
    if (!g[i].empty()) ids.push_back(i);
  std::vector<IndexPair> out;
  sweep(g, std::move(ids), spread_axis(g), [&](std::uint32_t a, std::uint32_t b) { out.emplace_back(a, b); });
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<IndexPair> hash_grid_pairs(const std::vector<Aabb>& boxes, double margin_mm, HashGridStats* stats) {
  const std::vector<Aabb> g = grown(boxes, margin_mm);
  const UniformGrid grid(g, tolerances::kGridMinCellMm);
  std::vector<IndexPair> out;
  for (const auto& [cell, members] : grid.cells())
    for (std::size_t i = 0; i < members.size(); ++i)
      for (std::size_t j = i + 1; j < members.size(); ++j) {
        const Aabb& a = g[members[i]];
        const Aabb& b = g[members[j]];
        if (!a.overlaps(b)) continue;
        // Only the cell holding the low corner of the intersection emits the pair.
        if (!(grid_cell_of(a.min.cwiseMax(b.min), grid.cell_mm()) == cell)) continue;
        out.emplace_back(std::min(members[i], members[j]), std::max(members[i], members[j]));
      }
  // Oversized boxes against everything: one sweep over all boxes, keeping pairs with an oversized member.
  std::vector<std::uint32_t> all;
  for (std::uint32_t i = 0; i < g.size(); ++i)
    if (!g[i].empty()) all.push_back(i);
  if (!grid.oversized().empty()) {
    std::vector<char> is_oversized(g.size(), 0);
    for (std::uint32_t i : grid.oversized()) is_oversized[i] = 1;
    sweep(g, all, spread_axis(g), [&](std::uint32_t a, std::uint32_t b) {
      if (is_oversized[a] || is_oversized[b]) out.emplace_back(a, b);
    });
  }
  std::sort(out.begin(), out.end());
  if (stats) *stats = {grid.cell_mm(), all.size() - grid.oversized().size(), grid.oversized().size(), grid.entries()};
  return out;
}

std::vector<IndexPair> all_overlapping_pairs(const std::vector<Aabb>& boxes, double margin_mm) {
  const std::vector<Aabb> g = grown(boxes, margin_mm);
  std::vector<IndexPair> out;
  for (std::uint32_t i = 0; i < g.size(); ++i)
    for (std::uint32_t j = i + 1; j < g.size(); ++j)
      if (!g[i].empty() && !g[j].empty() && g[i].overlaps(g[j])) out.emplace_back(i, j);
  return out;
}

std::vector<std::uint32_t> boxes_meeting(const std::vector<Aabb>& boxes, const Aabb& probe, double margin_mm) {
  const Aabb p = probe.expanded(0.5 * margin_mm);
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < boxes.size(); ++i)
    if (!boxes[i].empty() && boxes[i].expanded(0.5 * margin_mm).overlaps(p)) out.push_back(i);
  return out;
}

}  // namespace gk
