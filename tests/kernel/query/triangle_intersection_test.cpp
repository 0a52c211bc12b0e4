// Triangle-triangle intersection against an independent oracle built from exact orientation signs:
//  * non-coplanar pairs intersect iff an edge of one meets the other triangle (closed segment-triangle
//    test: endpoints on closed opposite sides of the plane, then the three orient3d signs of the
//    segment against the triangle's edges not strictly mixed; a segment lying in the plane is tested
//    in 2D);
//  * coplanar pairs are tested in 2D on an exact coordinate-dropping projection: some pair of edges
//    meets, or a vertex of one lies in the other.
// Constructed configurations use small dyadic coordinates so that "exactly touching" is exact in
// double, also after translating by 5e4 mm.
#include "kernel/predicates/exact_predicates.h"
#include "kernel/query/triangle_distance.h"
#include "kernel/query/triangle_intersection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>

namespace gk {
namespace {

using Rng = std::mt19937_64;
using exact::orient2d;
using exact::orient3d;

// ---------------------------------------------------------------------------------------------
// Oracle.

struct P2 {
  double x, y;
};

int o2(const P2& a, const P2& b, const P2& c) { return orient2d(a.x, a.y, b.x, b.y, c.x, c.y); }

P2 drop_axis(const Vec3& v, int axis) {
  switch (axis) {
    case 0: return {v.y(), v.z()};
    case 1: return {v.x(), v.z()};
    default: return {v.x(), v.y()};
  }
}

// An axis whose dropping keeps the (non-degenerate) triangle non-degenerate: exact, by orient2d.
int projection_axis(const Triangle& t) {
  for (int axis = 0; axis < 3; ++axis) {
    if (o2(drop_axis(t[0], axis), drop_axis(t[1], axis), drop_axis(t[2], axis)) != 0) return axis;
  }
  ADD_FAILURE() << "degenerate triangle given to the oracle";
  return 2;
}

// p collinear with a, b: is it on the closed segment?
bool within_box(const P2& a, const P2& b, const P2& p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

bool segments_meet_2d(const P2& a, const P2& b, const P2& c, const P2& d) {
  const int d1 = o2(a, b, c), d2 = o2(a, b, d), d3 = o2(c, d, a), d4 = o2(c, d, b);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && within_box(a, b, c)) || (d2 == 0 && within_box(a, b, d)) || (d3 == 0 && within_box(c, d, a)) ||
         (d4 == 0 && within_box(c, d, b));
}

bool not_strictly_mixed(int s0, int s1, int s2) {
  const bool pos = s0 > 0 || s1 > 0 || s2 > 0;
  const bool neg = s0 < 0 || s1 < 0 || s2 < 0;
  return !(pos && neg);
}

bool point_in_triangle_2d(const P2& p, const P2& a, const P2& b, const P2& c) {
  return not_strictly_mixed(o2(a, b, p), o2(b, c, p), o2(c, a, p));
}

bool triangles_meet_2d(const std::array<P2, 3>& p, const std::array<P2, 3>& q) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segments_meet_2d(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3])) return true;
  return point_in_triangle_2d(p[0], q[0], q[1], q[2]) || point_in_triangle_2d(q[0], p[0], p[1], p[2]);
}

bool segment_meets_triangle(const Vec3& s0, const Vec3& s1, const Triangle& t) {
  const int o0 = orient3d(t[0], t[1], t[2], s0), o1 = orient3d(t[0], t[1], t[2], s1);
  if (o0 == 0 && o1 == 0) {  // the segment lies in the triangle's plane
    const int axis = projection_axis(t);
    const P2 a = drop_axis(s0, axis), b = drop_axis(s1, axis);
    const std::array<P2, 3> tt = {drop_axis(t[0], axis), drop_axis(t[1], axis), drop_axis(t[2], axis)};
    for (int j = 0; j < 3; ++j)
      if (segments_meet_2d(a, b, tt[j], tt[(j + 1) % 3])) return true;
    return point_in_triangle_2d(a, tt[0], tt[1], tt[2]);
  }
  if (o0 * o1 > 0) return false;
  return not_strictly_mixed(orient3d(s0, s1, t[0], t[1]), orient3d(s0, s1, t[1], t[2]), orient3d(s0, s1, t[2], t[0]));
}

bool oracle_coplanar(const Triangle& p, const Triangle& q) {
  return orient3d(q[0], q[1], q[2], p[0]) == 0 && orient3d(q[0], q[1], q[2], p[1]) == 0 &&
         orient3d(q[0], q[1], q[2], p[2]) == 0;
}

bool oracle_intersect(const Triangle& p, const Triangle& q) {
  if (oracle_coplanar(p, q)) {
    const int axis = projection_axis(p);
    return triangles_meet_2d({drop_axis(p[0], axis), drop_axis(p[1], axis), drop_axis(p[2], axis)},
                             {drop_axis(q[0], axis), drop_axis(q[1], axis), drop_axis(q[2], axis)});
  }
  for (int i = 0; i < 3; ++i) {
    if (segment_meets_triangle(p[i], p[(i + 1) % 3], q)) return true;
    if (segment_meets_triangle(q[i], q[(i + 1) % 3], p)) return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// Checks.

std::string describe(const Triangle& t) {
  std::ostringstream s;
  s.precision(17);
  for (const Vec3& v : t) s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ") ";
  return s.str();
}

Triangle translated(const Triangle& t, const Vec3& offset) { return {t[0] + offset, t[1] + offset, t[2] + offset}; }

// The six vertex orders of a triangle: three cyclic shifts, each with either winding.
Triangle variant(const Triangle& t, int k) {
  const int shift = k % 3;
  Triangle out = {t[shift], t[(shift + 1) % 3], t[(shift + 2) % 3]};
  if (k >= 3) std::swap(out[1], out[2]);
  return out;
}

double magnitude(const Triangle& p, const Triangle& q) {
  double m = 1.0;
  for (const Triangle* t : {&p, &q})
    for (const Vec3& v : *t) m = std::max(m, v.cwiseAbs().maxCoeff());
  return m;
}

double distance_to_segment(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - x).norm();
}

double distance_to_boundaries(const Vec3& x, const Triangle& p, const Triangle& q) {
  double best = std::numeric_limits<double>::infinity();
  for (const Triangle* t : {&p, &q})
    for (int i = 0; i < 3; ++i) best = std::min(best, distance_to_segment(x, (*t)[i], (*t)[(i + 1) % 3]));
  return best;
}

// The intersection segment of an intersecting pair lies in both triangles: each endpoint is within
// 1e-9 * max(1, largest |coordinate|) mm of both (tolerance: the segment is constructed in floating
// point; exact coordinates of a few units give errors near 1e-15 relative). The intersection is
// convex, so its extreme points lie on the boundary of p or of q: each endpoint is within the same
// tolerance of an edge of p or of q (a shrunken segment would not be).
void expect_segment_on_both(const TriangleIntersection& hit, const Triangle& p, const Triangle& q) {
  const double tolerance = 1e-9 * magnitude(p, q);
  for (const Vec3* end : {&hit.segment_start, &hit.segment_end}) {
    ASSERT_TRUE(end->allFinite()) << describe(p) << "| " << describe(q);
    EXPECT_LE((closest_point_on_triangle(*end, p) - *end).norm(), tolerance)
        << "endpoint (" << end->transpose() << ") off p\np: " << describe(p) << "\nq: " << describe(q);
    EXPECT_LE((closest_point_on_triangle(*end, q) - *end).norm(), tolerance)
        << "endpoint (" << end->transpose() << ") off q\np: " << describe(p) << "\nq: " << describe(q);
    EXPECT_LE(distance_to_boundaries(*end, p, q), tolerance)
        << "endpoint (" << end->transpose() << ") inside both\np: " << describe(p) << "\nq: " << describe(q);
  }
}

// One pair: the kernel agrees with the expectation in both argument orders and for the given vertex
// orders; intersect_triangles agrees with triangles_intersect and gives a segment on both triangles.
void check_pair(const Triangle& p, const Triangle& q, bool expected, int variants = 36) {
  const bool coplanar = oracle_coplanar(p, q);
  for (int k = 0; k < variants; ++k) {
    const int index = (k * 7) % 36;  // a stride coprime with 36: few variants still vary both triangles
    const Triangle pv = variant(p, index / 6), qv = variant(q, index % 6);
    ASSERT_EQ(triangles_intersect(pv, qv), expected) << "variant " << k << "\np: " << describe(pv) << "\nq: "
                                                     << describe(qv);
    ASSERT_EQ(triangles_intersect(qv, pv), expected) << "swapped, variant " << k << "\np: " << describe(pv)
                                                     << "\nq: " << describe(qv);
  }
  for (const bool swapped : {false, true}) {
    const Triangle& a = swapped ? q : p;
    const Triangle& b = swapped ? p : q;
    const TriangleIntersection hit = intersect_triangles(a, b);
    ASSERT_EQ(hit.intersects, expected) << "intersect_triangles\np: " << describe(a) << "\nq: " << describe(b);
    if (expected) {
      EXPECT_EQ(hit.coplanar, coplanar) << "p: " << describe(a) << "\nq: " << describe(b);
      expect_segment_on_both(hit, a, b);
    }
  }
}

// The oracle decides, and the configuration translated by 5e4 mm (exact for the dyadic inputs
// used) must give the same answer.
void check_against_oracle(const Triangle& p, const Triangle& q, int variants = 36) {
  const bool expected = oracle_intersect(p, q);
  check_pair(p, q, expected, variants);
  const Vec3 offset(5.0e4, -5.0e4, 5.0e4);
  const Triangle pt = translated(p, offset), qt = translated(q, offset);
  ASSERT_EQ(oracle_intersect(pt, qt), expected) << "the oracle is not translation invariant here";
  check_pair(pt, qt, expected, variants);
}

bool degenerate(const Triangle& t) { return exact::collinear(t[0], t[1], t[2]); }

// ---------------------------------------------------------------------------------------------
// The oracle on known cases first: it must be right before it judges anything.

TEST(TriangleIntersectionOracle, KnownCases) {
  const Triangle p = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  EXPECT_TRUE(oracle_intersect(p, {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(2, 3, 1)}));       // pierces
  EXPECT_FALSE(oracle_intersect(p, {Vec3(1, 1, 0.5), Vec3(1, 2, 1), Vec3(2, 1, 1)}));     // above
  EXPECT_TRUE(oracle_intersect(p, {Vec3(1, 1, 0), Vec3(1, 2, 1), Vec3(2, 1, 1)}));        // vertex on face
  EXPECT_FALSE(oracle_intersect(p, {Vec3(3, 3, 0), Vec3(3, 4, 1), Vec3(4, 3, 1)}));       // vertex on plane, outside
  EXPECT_TRUE(oracle_intersect(p, {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 2, 0)}));        // coplanar, inside
  EXPECT_FALSE(oracle_intersect(p, {Vec3(3, 3, 0), Vec3(5, 3, 0), Vec3(3, 5, 0)}));       // coplanar, apart
  EXPECT_TRUE(oracle_intersect(p, {Vec3(-1, -1, 0), Vec3(9, -1, 0), Vec3(-1, 9, 0)}));    // coplanar, contains
  EXPECT_TRUE(oracle_intersect(p, {Vec3(2, 2, 0), Vec3(4, 4, 0), Vec3(2, 4, 0)}));        // coplanar, vertex on edge
  EXPECT_FALSE(oracle_intersect(p, {Vec3(-1, 5, 0), Vec3(5, -1, 1), Vec3(5, 5, 0)}));     // over the hypotenuse
}

// ---------------------------------------------------------------------------------------------
// Named configurations.

const Triangle kBase = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};  // in z = 0

void check_named(const Triangle& q, bool expected) {
  ASSERT_EQ(oracle_intersect(kBase, q), expected) << "oracle disagrees with the construction";
  check_against_oracle(kBase, q);
}

TEST(TriangleIntersection, VertexExactlyOnFace) {
  const Triangle q = {Vec3(1.25, 0.5, 0), Vec3(2, 2, 3), Vec3(0.5, 3, 1)};
  check_named(q, true);
  const TriangleIntersection hit = intersect_triangles(kBase, q);
  // A single touching point: both ends at the vertex (tolerance 1e-12 mm: construction in doubles).
  EXPECT_LE((hit.segment_start - q[0]).norm(), 1e-12);
  EXPECT_LE((hit.segment_end - q[0]).norm(), 1e-12);
  // Lifted by 2^-30 mm: clear; lowered by 2^-30 mm: crossing.
  check_named({Vec3(1.25, 0.5, 0x1p-30), q[1], q[2]}, false);
  check_named({Vec3(1.25, 0.5, -0x1p-30), q[1], q[2]}, true);
}

// A zero-area triangle (collinear corners: a needle) is its edges. Through the face, ending on
// it, lying in its plane across it, and beside it by 2^-30 mm; both orders. (It was never
// decided: the canonical tests need a plane on each side, and a needle through a plate passed.)
TEST(TriangleIntersection, ANeedleIsItsEdges) {
  const auto both = [](const Triangle& needle, bool expected, const char* what) {
    EXPECT_EQ(triangles_intersect(kBase, needle), expected) << what;
    EXPECT_EQ(triangles_intersect(needle, kBase), expected) << what << " (needle first)";
  };
  both({Vec3(1, 1, -5), Vec3(1, 1, 2), Vec3(1, 1, 7)}, true, "through the face");
  both({Vec3(1, 1, 0), Vec3(1, 1, 2), Vec3(1, 1, 7)}, true, "ending on the face");
  both({Vec3(1, 1, 0x1p-30), Vec3(1, 1, 2), Vec3(1, 1, 7)}, false, "ending just above it");
  both({Vec3(-1, 1, 0), Vec3(1, 1, 0), Vec3(3, 1, 0)}, true, "in its plane, across it");
  both({Vec3(-1, -0x1p-30, 0), Vec3(1, -0x1p-30, 0), Vec3(3, -0x1p-30, 0)}, false, "in its plane, beside it");
  both({Vec3(-3, 1, -5), Vec3(-3, 1, 2), Vec3(-3, 1, 7)}, false, "beside it, through its plane");
  both({Vec3(1, 1, -5), Vec3(1, 1, -5), Vec3(1, 1, 7)}, true, "a repeated corner");
  const TriangleIntersection hit = intersect_triangles(kBase, {Vec3(1, 1, -5), Vec3(1, 1, 2), Vec3(1, 1, 7)});
  EXPECT_LE((hit.segment_start - Vec3(1, 1, 0)).norm(), 1e-12);
}

TEST(TriangleIntersection, VertexExactlyOnEdgeAndOnVertex) {
  check_named({Vec3(2.5, 0, 0), Vec3(2, 2, 3), Vec3(3, -2, 1)}, true);       // on edge y = 0
  check_named({Vec3(2.5, -0x1p-30, 0), Vec3(2, 2, 3), Vec3(3, -2, 1)}, false);
  check_named({Vec3(1.5, 2.5, 0), Vec3(2, 2, 3), Vec3(3, 3, 1)}, true);      // on the hypotenuse
  check_named({Vec3(1.5, 2.5 + 0x1p-30, 0), Vec3(2, 2, 3), Vec3(3, 3, 1)}, false);
  check_named({Vec3(4, 0, 0), Vec3(5, 1, 3), Vec3(6, -1, 1)}, true);         // on a vertex
  check_named({Vec3(4 + 0x1p-30, 0, 0), Vec3(5, 1, 3), Vec3(6, -1, 1)}, false);
}

TEST(TriangleIntersection, EdgeCrossingEdgeInThePlane) {
  // q is vertical (plane x - y = 4); its edge in z = 0 touches p only at p's vertex (4, 0, 0).
  check_named({Vec3(5, 1, 0), Vec3(3, -1, 0), Vec3(4, 0, 3)}, true);
  check_named({Vec3(5 + 0x1p-30, 1, 0), Vec3(3 + 0x1p-30, -1, 0), Vec3(4 + 0x1p-30, 0, 3)}, false);
  // q's edge in z = 0 crosses p's edge y = 0 at (1, 0, 0) and runs into p.
  check_named({Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(1, 0, 2)}, true);
  // q's edge in z = 0 ends exactly on p's edge y = 0, from outside.
  check_named({Vec3(1, -1, 0), Vec3(1, 0, 0), Vec3(1, -0.5, 2)}, true);
  check_named({Vec3(1, -1, 0), Vec3(1, -0x1p-30, 0), Vec3(1, -0.5, 2)}, false);
  // q's edge lies along p's edge (collinear overlap), q standing up.
  check_named({Vec3(1, 0, 0), Vec3(6, 0, 0), Vec3(3, 0, 2)}, true);
  check_named({Vec3(4, 0, 0), Vec3(6, 0, 0), Vec3(5, 0, 2)}, true);   // touching end to end
  check_named({Vec3(4.25, 0, 0), Vec3(6, 0, 0), Vec3(5, 0, 2)}, false);
}

TEST(TriangleIntersection, SkewEdgesTouchingAtOnePoint) {
  // q lies in the plane x = 2 and meets z = 0 in the segment from (2, -2, 0) to (2, 0, 0), which
  // touches p's edge y = 0 at (2, 0, 0) only.
  const Triangle q = {Vec3(2, -1, 1), Vec3(2, 1, -1), Vec3(2, -3, -1)};
  check_named(q, true);
  const TriangleIntersection hit = intersect_triangles(kBase, q);
  // Tolerance 1e-12 mm: the touching point is constructed in doubles from exact inputs.
  EXPECT_LE((hit.segment_start - Vec3(2, 0, 0)).norm(), 1e-12);
  EXPECT_LE((hit.segment_end - Vec3(2, 0, 0)).norm(), 1e-12);
  check_named(translated(q, Vec3(0, -0x1p-30, 0)), false);
  check_named(translated(q, Vec3(0, 0x1p-30, 0)), true);
}

TEST(TriangleIntersection, CrossingPairsGiveTheIntersectionSegment) {
  // q pierces p along x = 1 from y = 0.5 to y = 2 (q's edge ends inside p).
  const Triangle q = {Vec3(1, 0.5, -1), Vec3(1, 0.5, 1), Vec3(1, 3.5, 1)};
  check_named(q, true);
  const TriangleIntersection hit = intersect_triangles(kBase, q);
  // Tolerance 1e-12 mm: construction in doubles.
  const Vec3 lo(1, 0.5, 0), hi(1, 2, 0);
  const bool forward = (hit.segment_start - lo).norm() < (hit.segment_start - hi).norm();
  EXPECT_LE((hit.segment_start - (forward ? lo : hi)).norm(), 1e-12);
  EXPECT_LE((hit.segment_end - (forward ? hi : lo)).norm(), 1e-12);
}

TEST(TriangleIntersection, CoplanarConfigurations) {
  check_named({Vec3(1, 1, 0), Vec3(5, 1, 0), Vec3(1, 5, 0)}, true);                 // overlapping
  check_named({Vec3(0.5, 0.5, 0), Vec3(1, 0.5, 0), Vec3(0.5, 1, 0)}, true);         // nested
  check_named({Vec3(-1, -1, 0), Vec3(9, -1, 0), Vec3(-1, 9, 0)}, true);             // containing
  check_named({Vec3(2, 2, 0), Vec3(5, 2, 0), Vec3(2, 5, 0)}, true);                 // vertex on the hypotenuse
  check_named({Vec3(2 + 0x1p-30, 2, 0), Vec3(5, 2, 0), Vec3(2, 5, 0)}, false);      // ... just beyond it
  check_named({Vec3(4, 4, 0), Vec3(0, 4, 0), Vec3(4, 0, 0)}, true);                 // shared hypotenuse
  check_named({Vec3(4, 0, 0), Vec3(6, 0, 0), Vec3(5, 1, 0)}, true);                 // vertex to vertex
  check_named({Vec3(4.5, 0, 0), Vec3(6, 0, 0), Vec3(5, 1, 0)}, false);              // apart along x
  check_named({Vec3(1, -1, 0), Vec3(3, -1, 0), Vec3(2, -0x1p-30, 0)}, false);       // apart, tiny gap
  check_named({Vec3(1, -1, 0), Vec3(3, -1, 0), Vec3(2, 0, 0)}, true);               // vertex on edge
  check_named({Vec3(1, -1, 0), Vec3(3, -1, 0), Vec3(2, 1, 0)}, true);               // crossing edges
  check_named({Vec3(-1, 1, 0), Vec3(5, 1, 0), Vec3(2, 0.5, 0)}, true);              // a vertex inside, edges crossing
  // A star of David: no vertex of either inside the other.
  const Triangle up = {Vec3(0, 0, 0), Vec3(6, 0, 0), Vec3(3, 6, 0)};
  const Triangle down = {Vec3(0, 4, 0), Vec3(3, -2, 0), Vec3(6, 4, 0)};
  ASSERT_TRUE(oracle_intersect(up, down));
  check_against_oracle(up, down);
}

TEST(TriangleIntersection, SharedVertexAndSharedEdge) {
  check_named({Vec3(0, 0, 0), Vec3(-1, 2, 3), Vec3(-2, -1, 1)}, true);  // shared vertex, q outside otherwise
  check_named({Vec3(4, 0, 0), Vec3(0, 0, 0), Vec3(2, -1, 3)}, true);    // shared edge, folded
  check_named({Vec3(4, 0, 0), Vec3(0, 0, 0), Vec3(2, 1, 3)}, true);     // shared edge, over p
  check_named({Vec3(4, 0, 0), Vec3(0, 0, 0), Vec3(2, -3, 0)}, true);    // shared edge, coplanar, adjacent
  // A vertex 2^-30 mm from p's vertex, across the corner: clear.
  check_named({Vec3(-0x1p-30, 0, 0), Vec3(-1, 2, 3), Vec3(-2, -1, 1)}, false);
}

TEST(TriangleIntersection, SameConfigurationsFarFromOrigin) {
  // Built at 5e4 mm directly (check_against_oracle also translates every named case).
  const Vec3 o(5.0e4, 5.0e4, 5.0e4);
  const Triangle p = translated(kBase, o);
  check_pair(p, translated({Vec3(1.25, 0.5, 0), Vec3(2, 2, 3), Vec3(0.5, 3, 1)}, o), true);
  check_pair(p, translated({Vec3(1.25, 0.5, 0x1p-30), Vec3(2, 2, 3), Vec3(0.5, 3, 1)}, o), false);
  check_pair(p, translated({Vec3(2, -1, 1), Vec3(2, 1, -1), Vec3(2, -3, -1)}, o), true);
  check_pair(p, translated({Vec3(2, -1 - 0x1p-30, 1), Vec3(2, 1 - 0x1p-30, -1), Vec3(2, -3, -1)}, o), false);
  check_pair(p, translated({Vec3(2, 2, 0), Vec3(5, 2, 0), Vec3(2, 5, 0)}, o), true);
  check_pair(p, translated({Vec3(2, 2 + 0x1p-30, 0), Vec3(5, 2, 0), Vec3(2, 5, 0)}, o), false);
}

// ---------------------------------------------------------------------------------------------
// Random cases.

TEST(TriangleIntersection, RandomTrianglesInASmallBox) {
  Rng rng(11);
  std::uniform_real_distribution<double> coord(0.0, 1.0);
  int hits = 0, total = 0;
  for (int n = 0; n < 3000; ++n) {
    Triangle p, q;
    for (Vec3& v : p) v = Vec3(coord(rng), coord(rng), coord(rng));
    for (Vec3& v : q) v = Vec3(coord(rng), coord(rng), coord(rng));
    if (degenerate(p) || degenerate(q)) continue;
    const bool expected = oracle_intersect(p, q);
    hits += expected;
    ++total;
    check_pair(p, q, expected, n % 10 == 0 ? 36 : 2);
    if (::testing::Test::HasFatalFailure()) return;
  }
  EXPECT_GT(hits, total / 5);
  EXPECT_LT(hits, total * 4 / 5);
}

// Random dyadic points (multiples of 1/16 in [-3, 3]) on the plane x[dep] = s1 x[a1] + s2 x[a2] + c,
// exact in double for every slope used.
struct DyadicPlane {
  int dep, a1, a2;
  double s1, s2, c;
  Vec3 point(double u, double v, double off = 0.0) const {
    Vec3 out;
    out[a1] = u;
    out[a2] = v;
    out[dep] = s1 * u + s2 * v + c + off;
    return out;
  }
};

double dyadic(Rng& rng, int limit_sixteenths) {
  return static_cast<double>(std::uniform_int_distribution<int>(-limit_sixteenths, limit_sixteenths)(rng)) / 16.0;
}

DyadicPlane random_plane(Rng& rng) {
  static constexpr double kSlopes[] = {0.0, 0.5, -0.5, 1.0, -1.0, 2.0, -0.25};
  std::uniform_int_distribution<int> axis(0, 2), slope(0, 6);
  DyadicPlane plane;
  plane.dep = axis(rng);
  plane.a1 = (plane.dep + 1) % 3;
  plane.a2 = (plane.dep + 2) % 3;
  plane.s1 = kSlopes[slope(rng)];
  plane.s2 = kSlopes[slope(rng)];
  plane.c = dyadic(rng, 16);
  return plane;
}

TEST(TriangleIntersection, RandomExactlyTouchingAndCoplanarConfigurations) {
  // p on a dyadic plane; q has 1, 2 or 3 vertices exactly on that plane (random dyadic points: inside,
  // on the boundary of, or outside p) and the others off it, on one side or on both. Many pairs
  // touch exactly at a point or along a segment; the oracle decides each.
  Rng rng(22);
  std::uniform_int_distribution<int> on_plane_count(0, 3), side(0, 2);
  int hits = 0, total = 0, coplanar_hits = 0, coplanar_misses = 0;
  for (int n = 0; n < 700; ++n) {
    const DyadicPlane plane = random_plane(rng);
    Triangle p, q;
    for (Vec3& v : p) v = plane.point(dyadic(rng, 32), dyadic(rng, 32));
    const int on = 1 + on_plane_count(rng) % 3;
    const int mode = side(rng);  // 0: all off-plane vertices above, 1: below, 2: either
    for (int k = 0; k < 3; ++k) {
      double off = 0.0;
      if (k >= on) {
        off = std::fabs(dyadic(rng, 24)) + 0.0625;
        if (mode == 1 || (mode == 2 && side(rng) == 0)) off = -off;
      }
      q[k] = plane.point(dyadic(rng, 32), dyadic(rng, 32), off);
    }
    if (n % 4 == 0) q[0] = p[static_cast<std::size_t>(side(rng))];                        // shared vertex
    if (n % 8 == 1) { q[0] = p[0]; q[1] = p[1]; }                                          // shared edge
    if (n % 8 == 3) q[0] = 0.5 * (p[0] + p[1]);                                            // vertex mid-edge
    if (degenerate(p) || degenerate(q)) continue;
    const bool expected = oracle_intersect(p, q);
    hits += expected;
    ++total;
    if (oracle_coplanar(p, q)) (expected ? coplanar_hits : coplanar_misses) += 1;
    check_against_oracle(p, q, n % 25 == 0 ? 36 : 2);
    if (::testing::Test::HasFatalFailure()) return;
  }
  EXPECT_GT(hits, total / 5);
  EXPECT_LT(hits, total * 4 / 5);
  EXPECT_GT(coplanar_hits, 30);
  EXPECT_GT(coplanar_misses, 10);
}

TEST(TriangleIntersection, RandomCoplanarTrianglesOnASmallGrid) {
  // Vertices on a 5 x 5 grid of a dyadic plane: nearly every pair shares vertices, has a vertex on an
  // edge or collinear edges, which is where the 2D boundary cases of the coplanar test live.
  Rng rng(33);
  std::uniform_int_distribution<int> grid(0, 4);
  int hits = 0, total = 0;
  for (int n = 0; n < 500; ++n) {
    const DyadicPlane plane = random_plane(rng);
    auto grid_point = [&]() { return plane.point(0.5 * grid(rng), 0.5 * grid(rng)); };
    const Triangle p = {grid_point(), grid_point(), grid_point()};
    const Triangle q = {grid_point(), grid_point(), grid_point()};
    if (degenerate(p) || degenerate(q)) continue;
    const bool expected = oracle_intersect(p, q);
    hits += expected;
    ++total;
    check_pair(p, q, expected, n % 25 == 0 ? 36 : 3);
    if (::testing::Test::HasFatalFailure()) return;
  }
  EXPECT_GT(hits, total / 5);
  EXPECT_LT(hits, total * 19 / 20);
}

}  // namespace
}  // namespace gk
