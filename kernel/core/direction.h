// A direction: a unit vector (a normal, a depth direction, an axis), kept apart from points and
// displacements in millimetres. Made only by of(), which normalises and refuses a zero or
// non-finite vector, so a Direction always has length 1 (to rounding).
#pragma once

#include "kernel/core/geometry_types.h"

#include <cmath>
#include <optional>

namespace gk {

class Direction {
 public:
  static std::optional<Direction> of(const Vec3& v) {
    const double n = v.norm();
    if (!std::isfinite(n) || !(n > 0.0)) return std::nullopt;
    return Direction(v / n);
  }
  // A direction kept earlier (a checkpoint, an archive) back bit for bit: accepted as it is when
  // its length is 1 to rounding, refused otherwise (never normalised again, which could move it).
  static std::optional<Direction> restored(const Vec3& unit) {
    const double n = unit.norm();
    if (!std::isfinite(n) || !(std::fabs(n - 1.0) <= 1e-12)) return std::nullopt;
    return Direction(unit);
  }
  const Vec3& vector() const { return unit_; }
  double x() const { return unit_.x(); }
  double y() const { return unit_.y(); }
  double z() const { return unit_.z(); }

 private:
  explicit Direction(const Vec3& unit) : unit_(unit) {}
  Vec3 unit_;
};

}  // namespace gk
