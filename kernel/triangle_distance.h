// Minimum distance between two triangles, with the closest points on each.
#pragma once

#include "kernel/geometry_types.h"

namespace gk {

struct TriangleDistance {
  double distance = 0.0;  // [mm]; 0 when the triangles intersect or touch (exact decision)
  Vec3 on_p = Vec3::Zero();
  Vec3 on_q = Vec3::Zero();
};

// Exact intersection decision first (a touching or crossing pair is at distance 0, with a point of
// the intersection as both witnesses); otherwise the minimum over the six vertex-triangle and the
// nine edge-edge closest pairs, which is where the minimum of two disjoint triangles lies.
TriangleDistance triangle_distance(const Triangle& p, const Triangle& q);

// Closest point on triangle t to point x (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_point_on_triangle(const Vec3& x, const Triangle& t);

// Closest points between segments [p0,p1] and [q0,q1] (Ericson 5.1.9); degenerate segments allowed.
void closest_points_on_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, Vec3& on_p, Vec3& on_q);

}  // namespace gk
