#include "machine_models/p4/organ_geometry.h"

#include <algorithm>
#include <limits>

namespace gk::p4 {

TriangleMesh prism_mesh(const std::vector<Vec2>& profile, double x_min, double x_max) {
  const auto n = static_cast<std::uint32_t>(profile.size());
  std::vector<Vec3> v;
  for (const Vec2& p : profile) v.emplace_back(x_min, p.x(), p.y());
  for (const Vec2& p : profile) v.emplace_back(x_max, p.x(), p.y());
  std::vector<TriangleMesh::Face> f;
  // The profile is counter-clockwise seen from +X: the x_max cap keeps that order, x_min reverses it.
  for (std::uint32_t i = 1; i + 1 < n; ++i) {
    f.push_back({n, n + i, n + i + 1});
    f.push_back({0, i + 1, i});
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1) % n;
    f.push_back({i, j, n + j});
    f.push_back({i, n + j, n + i});
  }
  return TriangleMesh::create(std::move(v), std::move(f)).value();
}

double depth_inside_prism(const std::vector<Vec2>& profile, double x_min, double x_max, const Vec3& p) {
  double depth = std::min(p.x() - x_min, x_max - p.x());
  const Vec2 q(p.y(), p.z());
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const Vec2& a = profile[i];
    const Vec2& b = profile[(i + 1) % profile.size()];
    const Vec2 edge = b - a;
    // Inward normal of a counter-clockwise polygon edge is the edge turned left.
    const Vec2 inward = Vec2(-edge.y(), edge.x()).normalized();
    depth = std::min(depth, (q - a).dot(inward));
  }
  return depth;
}

}  // namespace gk::p4
