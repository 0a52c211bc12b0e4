// Oriented bounding boxes and the separating-axis overlap test (Gottschalk 1996; seed 004 §5.2:
// the cheap face-axis separations are tried first, the nine edge-edge axes only if they all fail).
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/rigid_transform.h"

#include <cmath>
#include <vector>

namespace gk {

struct OrientedBox {
  Vec3 center = Vec3::Zero();
  Mat3 axes = Mat3::Identity();  // columns: the box's unit axes in the parent frame
  Vec3 half_extent = Vec3::Zero();

  // Fitted by principal axes of the points; contains every point.
  static OrientedBox fit(const std::vector<Vec3>& points);
  bool contains(const Vec3& p, double slack = 0.0) const {
    const Vec3 local = axes.transpose() * (p - center);
    return (local.cwiseAbs().array() <= half_extent.array() + slack).all();
  }
  std::array<Vec3, 8> corners() const;
};

// Overlap of box A (axis-aligned in its own frame: centre ca, half extents ea) with box B given in
// A's frame by its centre cb, rotation r (B's axes as columns) and half extents eb. abs_r must be
// |r| plus a small epsilon, so that near-parallel edge axes never separate boxes that touch.
// slack widens every interval: a positive slack never reports separated boxes that touch.
inline bool boxes_overlap(const Vec3& ca, const Vec3& ea, const Vec3& cb, const Mat3& r, const Mat3& abs_r,
                          const Vec3& eb, double slack) {
  const Vec3 d = cb - ca;
  // A's face axes.
  for (int i = 0; i < 3; ++i) {
    if (std::fabs(d[i]) > ea[i] + abs_r.row(i).dot(eb) + slack) return false;
  }
  // B's face axes.
  for (int j = 0; j < 3; ++j) {
    if (std::fabs(r.col(j).dot(d)) > abs_r.col(j).dot(ea) + eb[j] + slack) return false;
  }
  // Edge-edge axes A_i x B_j.
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double dist = std::fabs(d[i2] * r(i1, j) - d[i1] * r(i2, j));
      const double ra = ea[i1] * abs_r(i2, j) + ea[i2] * abs_r(i1, j);
      const double rb = eb[j1] * abs_r(i, j2) + eb[j2] * abs_r(i, j1);
      if (dist > ra + rb + slack) return false;
    }
  }
  return true;
}

// Absolute rotation with the epsilon the separating-axis test needs for parallel edges.
inline Mat3 abs_with_epsilon(const Mat3& r) { return (r.cwiseAbs().array() + 1e-12).matrix(); }

bool overlap(const OrientedBox& a, const OrientedBox& b, double slack = 0.0);

}  // namespace gk
