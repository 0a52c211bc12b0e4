// A uniform grid of cubic cells over boxes, shared by the hash-grid broad phase, the layout
// session and contact-region grouping. Cells are keyed by their integer coordinates (never by a
// hash alone, so two cells are never merged); coordinates are clamped before conversion, so a
// tiny cell far from the origin cannot overflow.
#pragma once

#include "kernel/core/aabb.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace gk {

struct GridCell {
  std::int64_t x = 0, y = 0, z = 0;
  bool operator==(const GridCell& o) const { return x == o.x && y == o.y && z == o.z; }
};

struct GridCellHash {
  std::size_t operator()(const GridCell& c) const {
    // Unsigned arithmetic: wrapping is defined.
    return static_cast<std::size_t>(static_cast<std::uint64_t>(c.x) * 73856093ULL ^ static_cast<std::uint64_t>(c.y) * 19349663ULL ^
                                    static_cast<std::uint64_t>(c.z) * 83492791ULL);
  }
};

inline std::int64_t grid_coordinate(double x, double cell_mm) {
  constexpr double kLimit = 4.0e18;  // inside int64's range
  return static_cast<std::int64_t>(std::clamp(std::floor(x / cell_mm), -kLimit, kLimit));
}

inline GridCell grid_cell_of(const Vec3& p, double cell_mm) {
  return {grid_coordinate(p.x(), cell_mm), grid_coordinate(p.y(), cell_mm), grid_coordinate(p.z(), cell_mm)};
}

struct GridCellRange {
  GridCell lo, hi;
  bool operator==(const GridCellRange& o) const { return lo == o.lo && hi == o.hi; }
  double cells() const {
    return static_cast<double>(hi.x - lo.x + 1) * static_cast<double>(hi.y - lo.y + 1) * static_cast<double>(hi.z - lo.z + 1);
  }
};

inline GridCellRange grid_cell_range(const Aabb& box, double cell_mm) {
  return {grid_cell_of(box.min, cell_mm), grid_cell_of(box.max, cell_mm)};
}

// Boxes wider than this many cells on some axis are kept out of the grid (an oversized list).
inline constexpr double kGridMaxCellsPerAxis = 4.0;

class UniformGrid {
 public:
  // Every non-empty box except `skip` goes into the cells it meets, or into the oversized list.
  // The cell is twice the median diagonal of those boxes (at least min_cell_mm).
  UniformGrid(const std::vector<Aabb>& boxes, double min_cell_mm, std::size_t skip = static_cast<std::size_t>(-1)) {
    std::vector<double> diagonals;
    for (std::size_t i = 0; i < boxes.size(); ++i)
      if (i != skip && !boxes[i].empty()) diagonals.push_back(boxes[i].diagonal().norm());
    if (!diagonals.empty()) {
      const auto mid = diagonals.begin() + static_cast<std::ptrdiff_t>(diagonals.size() / 2);
      std::nth_element(diagonals.begin(), mid, diagonals.end());
      cell_mm_ = std::max(2.0 * *mid, min_cell_mm);
    } else {
      cell_mm_ = min_cell_mm;
    }
    for (std::uint32_t i = 0; i < boxes.size(); ++i) {
      if (i == skip || boxes[i].empty()) continue;
      if ((boxes[i].diagonal().array() > kGridMaxCellsPerAxis * cell_mm_).any()) {
        oversized_.push_back(i);
        continue;
      }
      for_each_cell(grid_cell_range(boxes[i], cell_mm_), [&](const GridCell& c) {
        cells_[c].push_back(i);
        ++entries_;
      });
    }
  }

  double cell_mm() const { return cell_mm_; }
  const std::vector<std::uint32_t>& oversized() const { return oversized_; }
  const std::unordered_map<GridCell, std::vector<std::uint32_t>, GridCellHash>& cells() const { return cells_; }
  std::size_t entries() const { return entries_; }

  // The members of the range's cells (an id once per cell it is in).
  template <typename Visit>
  void for_each_member(const GridCellRange& range, Visit&& visit) const {
    for_each_cell(range, [&](const GridCell& c) {
      auto it = cells_.find(c);
      if (it != cells_.end())
        for (std::uint32_t id : it->second) visit(id);
    });
  }

  template <typename Visit>
  static void for_each_cell(const GridCellRange& r, Visit&& visit) {
    for (std::int64_t x = r.lo.x; x <= r.hi.x; ++x)
      for (std::int64_t y = r.lo.y; y <= r.hi.y; ++y)
        for (std::int64_t z = r.lo.z; z <= r.hi.z; ++z) visit(GridCell{x, y, z});
  }

 private:
  double cell_mm_ = 1.0;
  std::unordered_map<GridCell, std::vector<std::uint32_t>, GridCellHash> cells_;
  std::vector<std::uint32_t> oversized_;
  std::size_t entries_ = 0;
};

}  // namespace gk
