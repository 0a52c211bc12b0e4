// Minimum distance between two triangles, with the closest points on each.
#pragma once

#include "kernel/core/geometry_types.h"

#include <limits>

namespace gk {

struct TriangleDistance {
  double distance = 0.0;  // [mm]; 0 when the triangles intersect or touch (exact decision)
  Vec3 on_p = Vec3::Zero();
  Vec3 on_q = Vec3::Zero();
  bool bounded_only = false;  // stopped at the lower bound; on_p/on_q are not set
};

// Exact intersection decision first (a touching or crossing pair is at distance 0, with a point of
// the intersection as both witnesses); otherwise the minimum over the six vertex-triangle and the
// nine edge-edge closest pairs, which is where the minimum of two disjoint triangles lies.
// With a finite stop_at, a pair whose cheap lower bound (box gap, plane separation) already reaches
// stop_at is not measured: the result has bounded_only set and distance holds that lower bound.
TriangleDistance triangle_distance(const Triangle& p, const Triangle& q,
                                   double stop_at = std::numeric_limits<double>::infinity());

// A cheap lower bound of the distance: the larger of the two boxes' gap and the separation of each
// triangle from the other's plane. Never exceeds the true distance (up to rounding).
double triangle_distance_lower_bound(const Triangle& p, const Triangle& q);

// Closest point on triangle t to point x (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_point_on_triangle(const Vec3& x, const Triangle& t);

// Closest points between segments [p0,p1] and [q0,q1] (Ericson 5.1.9); degenerate segments allowed.
void closest_points_on_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, Vec3& on_p, Vec3& on_q);

}  // namespace gk
