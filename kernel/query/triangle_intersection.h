// Triangle-triangle intersection: Moller's (1997) interval idea in the orientation-predicate form of
// Guigue and Devillers (2003), with every sign decided by the exact orient3d/orient2d predicates, so
// touching, edge-on and coplanar configurations are decided exactly on the given coordinates.
// The intersection segment is then constructed in floating point.
#pragma once

#include "kernel/core/geometry_types.h"

namespace gk {

struct TriangleIntersection {
  bool intersects = false;
  bool coplanar = false;
  // The intersection segment; for coplanar overlap, the two farthest corners of the overlap polygon.
  // Equal points for a single touching point.
  Vec3 segment_start = Vec3::Zero();
  Vec3 segment_end = Vec3::Zero();
};

// Exact boolean test (boundaries included). A zero-area triangle is taken as its edges (a needle
// through a face meets it); two zero-area triangles meet when their boxes do (undecided).
bool triangles_intersect(const Triangle& p, const Triangle& q);

// The same decision, plus the intersection geometry.
TriangleIntersection intersect_triangles(const Triangle& p, const Triangle& q);

// Exact coplanar overlap test of two triangles known to lie in one plane (with normal n of either).
bool coplanar_triangles_overlap(const Triangle& p, const Triangle& q, const Vec3& n);

}  // namespace gk
