#include "kernel/mesh/oriented_box.h"

#include <Eigen/Eigenvalues>

#include <limits>

namespace gk {

OrientedBox OrientedBox::fit(const std::vector<Vec3>& points) {
  OrientedBox box;
  if (points.empty()) return box;
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Mat3 covariance = Mat3::Zero();
  for (const Vec3& p : points) covariance += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> solver(covariance);
  Mat3 axes = solver.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  // Extents by projection, in the centred frame so far-away points lose no digits.
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (const Vec3& p : points) {
    const Vec3 local = axes.transpose() * (p - mean);
    lo = lo.cwiseMin(local);
    hi = hi.cwiseMax(local);
  }
  box.axes = axes;
  box.center = mean + axes * (0.5 * (lo + hi));
  box.half_extent = 0.5 * (hi - lo);
  return box;
}

std::array<Vec3, 8> OrientedBox::corners() const {
  std::array<Vec3, 8> out;
  for (int k = 0; k < 8; ++k) {
    const Vec3 sign((k & 1) ? 1.0 : -1.0, (k & 2) ? 1.0 : -1.0, (k & 4) ? 1.0 : -1.0);
    out[k] = center + axes * sign.cwiseProduct(half_extent);
  }
  return out;
}

bool overlap(const OrientedBox& a, const OrientedBox& b, double slack) {
  // Express B in A's frame, then A is axis-aligned.
  const Mat3 r = a.axes.transpose() * b.axes;
  const Vec3 cb = a.axes.transpose() * (b.center - a.center);
  return boxes_overlap(Vec3::Zero(), a.half_extent, cb, r, abs_with_epsilon(r), b.half_extent, slack);
}

}  // namespace gk
