#include "tests/support/box_oracle.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace gk::testing {

Mat3 random_rotation(Rng& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const double w = g(rng), x = g(rng), y = g(rng), z = g(rng);
  return Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
}

Vec3 random_vector(Rng& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  const double x = u(rng), y = u(rng), z = u(rng);
  return Vec3(x, y, z);
}

OrientedBox make_box(const Vec3& center, const Mat3& axes, const Vec3& half_extent) {
  OrientedBox box;
  box.center = center;
  box.axes = axes;
  box.half_extent = half_extent;
  return box;
}

// Corners computed here, not with OrientedBox::corners().
std::array<Vec3, 8> corners_of(const OrientedBox& b) {
  std::array<Vec3, 8> out;
  for (int k = 0; k < 8; ++k) {
    const double sx = (k & 1) ? 1.0 : -1.0, sy = (k & 2) ? 1.0 : -1.0, sz = (k & 4) ? 1.0 : -1.0;
    out[k] = b.center + sx * b.half_extent.x() * b.axes.col(0) + sy * b.half_extent.y() * b.axes.col(1) +
             sz * b.half_extent.z() * b.axes.col(2);
  }
  return out;
}

SatResult oracle_sat(const OrientedBox& a, const OrientedBox& b) {
  const std::array<Vec3, 8> ca = corners_of(a), cb = corners_of(b);
  std::vector<Vec3> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a.axes.col(i));
  for (int j = 0; j < 3; ++j) axes.push_back(b.axes.col(j));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vec3 c = a.axes.col(i).cross(b.axes.col(j));
      if (c.norm() > 1e-6) axes.push_back(c.normalized());
    }
  }
  SatResult out;
  for (std::size_t k = 0; k < axes.size(); ++k) {
    double amin = std::numeric_limits<double>::infinity(), amax = -amin, bmin = amin, bmax = -amin;
    for (const Vec3& p : ca) {
      amin = std::min(amin, p.dot(axes[k]));
      amax = std::max(amax, p.dot(axes[k]));
    }
    for (const Vec3& p : cb) {
      bmin = std::min(bmin, p.dot(axes[k]));
      bmax = std::max(bmax, p.dot(axes[k]));
    }
    const double gap = std::max(bmin - amax, amin - bmax);
    out.gap = std::max(out.gap, gap);
    if (k < 6 && gap > 0.0) out.face_axis_separates = true;
  }
  return out;
}

}  // namespace gk::testing
