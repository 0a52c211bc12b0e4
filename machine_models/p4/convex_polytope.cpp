#include "machine_models/p4/convex_polytope.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gk::p4 {

ConvexPolytope ConvexPolytope::prism(const std::vector<Vec2>& profile, double x_min, double x_max) {
  ConvexPolytope p;
  for (const Vec2& q : profile) p.vertices.emplace_back(x_min, q.x(), q.y());
  for (const Vec2& q : profile) p.vertices.emplace_back(x_max, q.x(), q.y());
  p.face_normals.push_back(Vec3::UnitX());
  p.edge_directions.push_back(Vec3::UnitX());
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const Vec2 e = profile[(i + 1) % profile.size()] - profile[i];
    if (!(e.norm() > 0.0)) continue;
    const Vec2 u = e.normalized();
    p.edge_directions.emplace_back(0.0, u.x(), u.y());
    p.face_normals.emplace_back(0.0, u.y(), -u.x());  // outward for a counter-clockwise profile
  }
  return p;
}

ConvexPolytope ConvexPolytope::plate(const Plate& plate) {
  ConvexPolytope p;
  const auto corners = plate.corners();
  p.vertices.assign(corners.begin(), corners.end());
  p.face_normals.reserve(3);
  p.edge_directions.reserve(3);
  for (const Vec3& e : plate.edge) {
    if (!(e.norm() > 0.0)) continue;
    p.face_normals.push_back(e.normalized());
    p.edge_directions.push_back(e.normalized());
  }
  return p;
}

ConvexPolytope ConvexPolytope::transformed(const RigidTransform& pose) const {
  ConvexPolytope p;
  p.vertices.reserve(vertices.size());
  p.face_normals.reserve(face_normals.size());
  p.edge_directions.reserve(edge_directions.size());
  for (const Vec3& v : vertices) p.vertices.push_back(pose.apply(v));
  for (const Vec3& n : face_normals) p.face_normals.push_back(pose.apply_direction(n));
  for (const Vec3& e : edge_directions) p.edge_directions.push_back(pose.apply_direction(e));
  return p;
}

std::pair<double, double> projection(const std::vector<Vec3>& points, const Vec3& axis) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec3& v : points) {
    const double p = axis.dot(v);
    lo = std::min(lo, p);
    hi = std::max(hi, p);
  }
  return {lo, hi};
}

namespace {

// The signed overlap of the two projections on a unit axis: > 0 overlap, <= 0 a gap of -overlap.
double overlap_along(const ConvexPolytope& a, const ConvexPolytope& b, const Vec3& axis) {
  const auto [a_lo, a_hi] = projection(a.vertices, axis);
  const auto [b_lo, b_hi] = projection(b.vertices, axis);
  return std::min(a_hi - b_lo, b_hi - a_lo);
}

// The smallest overlap over every candidate axis (negative: the largest gap found), or the first
// one at or below `enough` (a caller that only needs to know that much stops there).
double smallest_overlap(const ConvexPolytope& a, const ConvexPolytope& b, double enough) {
  double smallest = std::numeric_limits<double>::infinity();
  auto try_axis = [&](const Vec3& axis) {
    smallest = std::min(smallest, overlap_along(a, b, axis));
    return smallest <= enough;
  };
  for (const Vec3& n : a.face_normals)
    if (try_axis(n)) return smallest;
  for (const Vec3& n : b.face_normals)
    if (try_axis(n)) return smallest;
  for (const Vec3& ea : a.edge_directions)
    for (const Vec3& eb : b.edge_directions) {
      const Vec3 c = ea.cross(eb);
      const double len = c.norm();
      if (len > 1e-9 && try_axis(c / len)) return smallest;
    }
  return smallest;
}

}  // namespace

double penetration_depth(const ConvexPolytope& a, const ConvexPolytope& b) {
  // Any axis without overlap proves depth 0: no need to look at the others.
  return std::max(0.0, smallest_overlap(a, b, 0.0));
}

double separation_lower_bound(const ConvexPolytope& a, const ConvexPolytope& b) {
  return std::max(0.0, -smallest_overlap(a, b, -std::numeric_limits<double>::infinity()));
}

}  // namespace gk::p4
