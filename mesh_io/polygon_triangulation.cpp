#include "mesh_io/polygon_triangulation.h"

#include "kernel/predicates/exact_predicates.h"
#include "kernel/core/units.h"

#include <array>
#include <cmath>
#include <cstdint>

namespace gk::mesh_io {
namespace {


struct Point2 {
  double x, y;
};

bool same_point(const Point2& a, const Point2& b) { return a.x == b.x && a.y == b.y; }

// p inside or on the triangle (a, b, c) of orientation `sign` (exact).
bool inside_or_on(const Point2& p, const Point2& a, const Point2& b, const Point2& c, int sign) {
  return exact::orient2d(a.x, a.y, b.x, b.y, p.x, p.y) * sign >= 0 && exact::orient2d(b.x, b.y, c.x, c.y, p.x, p.y) * sign >= 0 &&
         exact::orient2d(c.x, c.y, a.x, a.y, p.x, p.y) * sign >= 0;
}

}  // namespace

Result<bool> append_polygon_triangles(const std::vector<Vec3>& vertices, const std::vector<std::uint32_t>& polygon,
                                      std::vector<TriangleMesh::Face>& out, TriangulationBudget& budget) {
  const std::size_t n = polygon.size();
  auto fan = [&] {
    for (std::size_t k = 1; k + 1 < n; ++k) out.push_back({polygon[0], polygon[k], polygon[k + 1]});
    return true;
  };
  if (n == 3) return fan();
  // Newell's normal picks the projection; its dominant component's sign is the polygon's
  // orientation there.
  Vec3 normal = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& p = vertices[polygon[i]];
    const Vec3& q = vertices[polygon[(i + 1) % n]];
    normal += Vec3((p.y() - q.y()) * (p.z() + q.z()), (p.z() - q.z()) * (p.x() + q.x()), (p.x() - q.x()) * (p.y() + q.y()));
  }
  int axis = 0;
  normal.cwiseAbs().maxCoeff(&axis);
  if (!(std::fabs(normal[axis]) > 0.0)) {
    // No area: on one line, its triangles are degenerate as written (the kernel knows them as
    // such); otherwise its lobes cancel, as in a bow tie.
    for (std::size_t i = 1; i + 1 < n; ++i)
      if (!exact::collinear(vertices[polygon[0]], vertices[polygon[i]], vertices[polygon[i + 1]]))
        return invalid_argument("", "a polygon that crosses itself");
    return fan();
  }
  const int sign = normal[axis] > 0.0 ? 1 : -1;
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  std::vector<Point2> p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = {vertices[polygon[i]][u], vertices[polygon[i]][v]};
  auto turn = [&](std::size_t a, std::size_t b, std::size_t c) { return exact::orient2d(p[a].x, p[a].y, p[b].x, p[b].y, p[c].x, p[c].y); };

  bool convex = true;
  double turning = 0.0;  // total turning angle: 2 pi for a polygon that winds once
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = (i + n - 1) % n, c = (i + 1) % n;
    if (turn(a, i, c) * sign < 0) convex = false;
    const double ex = p[i].x - p[a].x, ey = p[i].y - p[a].y, fx = p[c].x - p[i].x, fy = p[c].y - p[i].y;
    turning += std::atan2(ex * fy - ey * fx, ex * fx + ey * fy);
  }
  // A simple polygon turns once around (2 pi); a bow tie turns 0, a star twice.
  if (std::fabs(turning) < kPi || std::fabs(turning) > 3.0 * kPi)
    return invalid_argument("", "a polygon that crosses itself");
  if (convex) return fan();
  if (n > 100000) return invalid_argument("", "a concave polygon of more than 100,000 vertices");
  // Ear cutting: an ear is a convex corner whose triangle holds no other corner that is not convex
  // (for a simple polygon those are the only ones that can lie in it).
  std::vector<std::size_t> prev(n), next(n);
  for (std::size_t i = 0; i < n; ++i) {
    prev[i] = (i + n - 1) % n;
    next[i] = (i + 1) % n;
  }
  std::vector<std::array<std::size_t, 3>> ears;  // the triangles cut, as positions in the polygon
  ears.reserve(n - 2);
  std::size_t left = n, i = 0, since_last_ear = 0;
  while (left > 3) {
    if (since_last_ear > left) return invalid_argument("", "a polygon that crosses itself (no triangle can be cut from it)");
    const std::size_t a = prev[i], c = next[i];
    bool ear = turn(a, i, c) * sign > 0;
    for (std::size_t k = next[c]; ear && k != a; k = next[k]) {
      if (--budget.tests_left < 0) return invalid_argument("", "concave polygons too large to triangulate (more work than allowed)");
      if (turn(prev[k], k, next[k]) * sign > 0) continue;
      if (same_point(p[k], p[a]) || same_point(p[k], p[i]) || same_point(p[k], p[c])) continue;
      if (inside_or_on(p[k], p[a], p[i], p[c], sign)) ear = false;
    }
    if (ear) {
      out.push_back({polygon[a], polygon[i], polygon[c]});
      ears.push_back({a, i, c});
      next[a] = c;
      prev[c] = a;
      --left;
      since_last_ear = 0;
      i = c;
    } else {
      i = c;
      ++since_last_ear;
    }
  }
  if (turn(prev[i], i, next[i]) * sign < 0) return invalid_argument("", "a polygon that crosses itself");
  out.push_back({polygon[prev[i]], polygon[i], polygon[next[i]]});
  ears.push_back({prev[i], i, next[i]});
  // Triangles that cover the polygon once add up to its area; where it crosses itself some
  // overlap or stick out, and their areas add up to more (found by a review: a pentagon turning
  // once in all whose last ear faced the other way).
  double polygon_twice = 0.0, triangles_twice = 0.0;
  auto twice_area = [&](const Point2& a, const Point2& b, const Point2& c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  };
  for (std::size_t k = 1; k + 1 < n; ++k) polygon_twice += twice_area(p[0], p[k], p[k + 1]);
  for (const auto& [a, b, c] : ears) {
    triangles_twice += std::fabs(twice_area(p[a], p[b], p[c]));
  }
  if (triangles_twice - std::fabs(polygon_twice) > 1e-9 * triangles_twice) return invalid_argument("", "a polygon that crosses itself");
  return true;
}

}  // namespace gk::mesh_io
