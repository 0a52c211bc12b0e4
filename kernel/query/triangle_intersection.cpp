#include "kernel/query/triangle_intersection.h"

#include "kernel/predicates/exact_predicates.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace gk {
namespace {

using exact::orient3d;

struct Vec2 {
  double x, y;
};

inline int orient(const Vec2& a, const Vec2& b, const Vec2& c) { return exact::orient2d(a.x, a.y, b.x, b.y, c.x, c.y); }

// Guigue-Devillers 2D tests; triangles counter-clockwise.
bool intersection_test_vertex(const Vec2& p1, const Vec2& q1, const Vec2& r1, const Vec2& p2, const Vec2& q2,
                              const Vec2& r2) {
  if (orient(r2, p2, q1) >= 0) {
    if (orient(r2, q2, q1) <= 0) {
      if (orient(p1, p2, q1) > 0) return orient(p1, q2, q1) <= 0;
      return orient(p1, p2, r1) >= 0 && orient(q1, r1, p2) >= 0;
    }
    return orient(p1, q2, q1) <= 0 && orient(r2, q2, r1) <= 0 && orient(q1, r1, q2) >= 0;
  }
  if (orient(r2, p2, r1) >= 0) {
    if (orient(q1, r1, r2) >= 0) return orient(p1, p2, r1) >= 0;
    return orient(q1, r1, q2) >= 0 && orient(r2, r1, q2) >= 0;
  }
  return false;
}

bool intersection_test_edge(const Vec2& p1, const Vec2& q1, const Vec2& r1, const Vec2& p2, const Vec2& r2) {
  if (orient(r2, p2, q1) >= 0) {
    if (orient(p1, p2, q1) >= 0) return orient(p1, q1, r2) >= 0;
    return orient(q1, r1, p2) >= 0 && orient(r1, p1, p2) >= 0;
  }
  if (orient(r2, p2, r1) >= 0) {
    return orient(p1, p2, r1) >= 0 && (orient(p1, r1, r2) >= 0 || orient(q1, r1, r2) >= 0);
  }
  return false;
}

bool ccw_triangles_intersect_2d(const Vec2& p1, const Vec2& q1, const Vec2& r1, const Vec2& p2, const Vec2& q2,
                                const Vec2& r2) {
  if (orient(p2, q2, p1) >= 0) {
    if (orient(q2, r2, p1) >= 0) {
      if (orient(r2, p2, p1) >= 0) return true;
      return intersection_test_edge(p1, q1, r1, p2, r2);
    }
    if (orient(r2, p2, p1) >= 0) return intersection_test_edge(p1, q1, r1, r2, q2);
    return intersection_test_vertex(p1, q1, r1, p2, q2, r2);
  }
  if (orient(q2, r2, p1) >= 0) {
    if (orient(r2, p2, p1) >= 0) return intersection_test_edge(p1, q1, r1, q2, p2);
    return intersection_test_vertex(p1, q1, r1, q2, r2, p2);
  }
  return intersection_test_vertex(p1, q1, r1, r2, p2, q2);
}

bool triangles_overlap_2d(const Vec2& p1, const Vec2& q1, const Vec2& r1, const Vec2& p2, const Vec2& q2,
                          const Vec2& r2) {
  const bool first_cw = orient(p1, q1, r1) < 0;
  const bool second_cw = orient(p2, q2, r2) < 0;
  if (first_cw) {
    return second_cw ? ccw_triangles_intersect_2d(p1, r1, q1, p2, r2, q2)
                     : ccw_triangles_intersect_2d(p1, r1, q1, p2, q2, r2);
  }
  return second_cw ? ccw_triangles_intersect_2d(p1, q1, r1, p2, r2, q2)
                   : ccw_triangles_intersect_2d(p1, q1, r1, p2, q2, r2);
}

// Drop the coordinate along which the plane's normal is largest: the projection keeps all
// incidences, and dropping a coordinate is exact.
int dropped_axis(const Vec3& n) {
  const Vec3 a = n.cwiseAbs();
  if (a.x() > a.z() && a.x() >= a.y()) return 0;
  if (a.y() > a.z() && a.y() >= a.x()) return 1;
  return 2;
}

Vec2 project(const Vec3& v, int drop) {
  switch (drop) {
    case 0: return {v.y(), v.z()};
    case 1: return {v.z(), v.x()};
    default: return {v.x(), v.y()};
  }
}

// The point where segment a->b crosses the plane through o with normal n (a and b on opposite
// closed sides). Clamped, so rounding can never move it off the segment.
Vec3 segment_plane_point(const Vec3& a, const Vec3& b, const Vec3& o, const Vec3& n) {
  const double da = (a - o).dot(n);
  const double db = (b - o).dot(n);
  const double denom = da - db;
  double alpha = denom != 0.0 ? da / denom : 0.0;
  alpha = std::clamp(alpha, 0.0, 1.0);
  return a + alpha * (b - a);
}

// Result of the canonical-form test: whether the intervals on the line of intersection overlap,
// and which edges bound the overlap (Guigue-Devillers' CONSTRUCT_INTERSECTION).
struct Canonical {
  const Vec3 *p1, *q1, *r1, *p2, *q2, *r2;
};

bool construct(const Canonical& c, const Vec3& n1, const Vec3& n2, bool want_segment, TriangleIntersection& out) {
  const Vec3 &p1 = *c.p1, &q1 = *c.q1, &r1 = *c.r1, &p2 = *c.p2, &q2 = *c.q2, &r2 = *c.r2;
  // Plane 1 passes through p1 (normal n1), plane 2 through p2 (normal n2).
  if (orient3d(p1, q1, r2, p2) > 0) {
    if (orient3d(p1, r1, r2, p2) > 0) return false;
    if (!want_segment) return true;
    if (orient3d(p1, r1, q2, p2) > 0) {
      out.segment_start = segment_plane_point(p1, r1, p2, n2);
      out.segment_end = segment_plane_point(p2, r2, p1, n1);
    } else {
      out.segment_start = segment_plane_point(p2, q2, p1, n1);
      out.segment_end = segment_plane_point(p2, r2, p1, n1);
    }
    return true;
  }
  if (orient3d(p1, q1, q2, p2) < 0) return false;
  if (!want_segment) return true;
  if (orient3d(p1, r1, q2, p2) >= 0) {
    out.segment_start = segment_plane_point(p1, r1, p2, n2);
    out.segment_end = segment_plane_point(p1, q1, p2, n2);
  } else {
    out.segment_start = segment_plane_point(p2, q2, p1, n1);
    out.segment_end = segment_plane_point(p1, q1, p2, n2);
  }
  return true;
}

// Coplanar overlap region: clip p by q's edges (floating point) for a representative segment.
void coplanar_overlap_segment(const Triangle& p, const Triangle& q, const Vec3& n, TriangleIntersection& out) {
  std::vector<Vec3> poly(p.begin(), p.end()), next;
  // q's winding relative to n decides which side of each edge is inside.
  const double q_sign = (q[1] - q[0]).cross(q[2] - q[0]).dot(n) >= 0.0 ? 1.0 : -1.0;
  for (int e = 0; e < 3 && !poly.empty(); ++e) {
    const Vec3& a = q[e];
    const Vec3& b = q[(e + 1) % 3];
    const Vec3 inward = q_sign * n.cross(b - a);
    next.clear();
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Vec3& s = poly[i];
      const Vec3& t = poly[(i + 1) % poly.size()];
      const double ds = (s - a).dot(inward), dt = (t - a).dot(inward);
      if (ds >= 0.0) next.push_back(s);
      if ((ds >= 0.0) != (dt >= 0.0)) next.push_back(s + (ds / (ds - dt)) * (t - s));
    }
    poly.swap(next);
  }
  if (poly.empty()) {
    // Touching along an edge or at a point that rounding clipped away: use the nearest corners.
    double best = std::numeric_limits<double>::infinity();
    for (const Vec3& a : p)
      for (const Vec3& b : q)
        if ((a - b).squaredNorm() < best) {
          best = (a - b).squaredNorm();
          out.segment_start = out.segment_end = 0.5 * (a + b);
        }
    return;
  }
  double best = -1.0;
  out.segment_start = out.segment_end = poly.front();
  for (std::size_t i = 0; i < poly.size(); ++i)
    for (std::size_t j = i + 1; j < poly.size(); ++j)
      if ((poly[i] - poly[j]).squaredNorm() > best) {
        best = (poly[i] - poly[j]).squaredNorm();
        out.segment_start = poly[i];
        out.segment_end = poly[j];
      }
}

// Canonical form of T2 given T1 with p1 alone on its side (Guigue-Devillers TRI_TRI_3D).
bool second_canonical(const Vec3& p1, const Vec3& q1, const Vec3& r1, const Vec3& p2, const Vec3& q2, const Vec3& r2,
                      int dp2, int dq2, int dr2, const Vec3& n1, const Vec3& n2, bool want, TriangleIntersection& out,
                      const Triangle& tp, const Triangle& tq) {
  auto go = [&](const Vec3& a1, const Vec3& b1, const Vec3& c1, const Vec3& a2, const Vec3& b2, const Vec3& c2) {
    return construct({&a1, &b1, &c1, &a2, &b2, &c2}, n1, n2, want, out);
  };
  if (dp2 > 0) {
    if (dq2 > 0) return go(p1, r1, q1, r2, p2, q2);
    if (dr2 > 0) return go(p1, r1, q1, q2, r2, p2);
    return go(p1, q1, r1, p2, q2, r2);
  }
  if (dp2 < 0) {
    if (dq2 < 0) return go(p1, q1, r1, r2, p2, q2);
    if (dr2 < 0) return go(p1, q1, r1, q2, r2, p2);
    return go(p1, r1, q1, p2, q2, r2);
  }
  if (dq2 < 0) {
    if (dr2 >= 0) return go(p1, r1, q1, q2, r2, p2);
    return go(p1, q1, r1, p2, q2, r2);
  }
  if (dq2 > 0) {
    if (dr2 > 0) return go(p1, r1, q1, p2, q2, r2);
    return go(p1, q1, r1, q2, r2, p2);
  }
  if (dr2 > 0) return go(p1, q1, r1, r2, p2, q2);
  if (dr2 < 0) return go(p1, r1, q1, r2, p2, q2);
  // T2 lies in T1's plane although T1 is not in T2's: only possible for degenerate input.
  out.coplanar = true;
  const bool hit = coplanar_triangles_overlap(tp, tq, n1);
  if (hit && want) coplanar_overlap_segment(tp, tq, n1, out);
  return hit;
}

// Exactly collinear corners (a zero-area triangle: a needle or a point): every projection to a
// coordinate plane is collinear too.
bool collinear(const Triangle& t) {
  for (int drop = 0; drop < 3; ++drop)
    if (orient(project(t[0], drop), project(t[1], drop), project(t[2], drop)) != 0) return false;
  return true;
}

// Does segment [a, b] meet triangle t (non-degenerate), boundaries included? Exact. `at` is a
// point of the meeting (rounded).
bool segment_meets_triangle(const Vec3& a, const Vec3& b, const Triangle& t, Vec3& at) {
  const int sa = orient3d(t[0], t[1], t[2], a), sb = orient3d(t[0], t[1], t[2], b);
  if (sa * sb > 0) return false;
  if (sa == 0 && sb == 0) {
    // In the triangle's plane: the 2-D projection that keeps it a triangle decides.
    const int drop = dropped_axis((t[1] - t[0]).cross(t[2] - t[0]));
    const Vec2 pa = project(a, drop), pb = project(b, drop);
    Vec2 v[3] = {project(t[0], drop), project(t[1], drop), project(t[2], drop)};
    if (orient(v[0], v[1], v[2]) < 0) std::swap(v[1], v[2]);
    const auto inside = [&](const Vec2& x) { return orient(v[0], v[1], x) >= 0 && orient(v[1], v[2], x) >= 0 && orient(v[2], v[0], x) >= 0; };
    if (inside(pa)) { at = a; return true; }
    if (inside(pb)) { at = b; return true; }
    for (int k = 0; k < 3; ++k) {
      const Vec2 &c = v[k], &d = v[(k + 1) % 3];
      const int o1 = orient(pa, pb, c), o2 = orient(pa, pb, d), o3 = orient(c, d, pa), o4 = orient(c, d, pb);
      if (o1 * o2 <= 0 && o3 * o4 <= 0 && !(o1 == 0 && o2 == 0)) {
        at = 0.5 * (a + b);
        return true;
      }
    }
    return false;
  }
  // Through the plane (or ending on it): through the triangle when the line a-b passes on the
  // same side of all three edges.
  const int e0 = orient3d(a, b, t[0], t[1]), e1 = orient3d(a, b, t[1], t[2]), e2 = orient3d(a, b, t[2], t[0]);
  if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) {
    at = segment_plane_point(a, b, t[0], (t[1] - t[0]).cross(t[2] - t[0]));
    return true;
  }
  return false;
}

// A zero-area triangle against a triangle: each of its edges against the other; two zero-area
// triangles (needles or points) are not decided and count as meeting when their boxes do (their
// contacts are reported as on zero-area triangles: INCONCLUSIVE, never CLEAR).
TriangleIntersection run_with_needle(const Triangle& needle, const Triangle& other) {
  TriangleIntersection out;
  if (collinear(other)) {
    out.intersects = true;
    out.segment_start = out.segment_end = needle[0];
    return out;
  }
  Vec3 at;
  for (int k = 0; k < 3; ++k)
    if (segment_meets_triangle(needle[k], needle[(k + 1) % 3], other, at)) {
      out.intersects = true;
      out.segment_start = out.segment_end = at;
      return out;
    }
  return out;
}

TriangleIntersection run(const Triangle& tp, const Triangle& tq, bool want_segment) {
  TriangleIntersection out;
  const Vec3 &p1 = tp[0], &q1 = tp[1], &r1 = tp[2];
  const Vec3 &p2 = tq[0], &q2 = tq[1], &r2 = tq[2];

  // Boxes apart on an axis: the triangles are apart. Exact (comparisons of the very coordinates
  // the predicates below would read) and much cheaper than six orientations; most triangle pairs
  // of two overlapping leaves end here.
  for (int k = 0; k < 3; ++k) {
    if (std::max({p1[k], q1[k], r1[k]}) < std::min({p2[k], q2[k], r2[k]})) return out;
    if (std::max({p2[k], q2[k], r2[k]}) < std::min({p1[k], q1[k], r1[k]})) return out;
  }

  const int dp1 = orient3d(p2, q2, r2, p1);
  const int dq1 = orient3d(p2, q2, r2, q1);
  const int dr1 = orient3d(p2, q2, r2, r1);
  if (dp1 * dq1 > 0 && dp1 * dr1 > 0) return out;

  const int dp2 = orient3d(p1, q1, r1, p2);
  const int dq2 = orient3d(p1, q1, r1, q2);
  const int dr2 = orient3d(p1, q1, r1, r2);
  if (dp2 * dq2 > 0 && dp2 * dr2 > 0) return out;

  // All of one triangle's corners on the other's "plane": coplanar, or that other has no plane (a
  // zero-area triangle, which the tests below cannot take: a needle through a face would pass).
  const bool p_needle = dp2 == 0 && dq2 == 0 && dr2 == 0 && collinear(tp);
  if (p_needle) return run_with_needle(tp, tq);
  if (dp1 == 0 && dq1 == 0 && dr1 == 0 && collinear(tq)) return run_with_needle(tq, tp);

  const Vec3 n1 = (q1 - p1).cross(r1 - p1);
  const Vec3 n2 = (q2 - p2).cross(r2 - p2);
  auto go = [&](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& x, const Vec3& y, const Vec3& z, int dx,
                int dy, int dz) {
    return second_canonical(a, b, c, x, y, z, dx, dy, dz, n1, n2, want_segment, out, tp, tq);
  };

  bool hit = false;
  if (dp1 > 0) {
    if (dq1 > 0) hit = go(r1, p1, q1, p2, r2, q2, dp2, dr2, dq2);
    else if (dr1 > 0) hit = go(q1, r1, p1, p2, r2, q2, dp2, dr2, dq2);
    else hit = go(p1, q1, r1, p2, q2, r2, dp2, dq2, dr2);
  } else if (dp1 < 0) {
    if (dq1 < 0) hit = go(r1, p1, q1, p2, q2, r2, dp2, dq2, dr2);
    else if (dr1 < 0) hit = go(q1, r1, p1, p2, q2, r2, dp2, dq2, dr2);
    else hit = go(p1, q1, r1, p2, r2, q2, dp2, dr2, dq2);
  } else if (dq1 < 0) {
    if (dr1 >= 0) hit = go(q1, r1, p1, p2, r2, q2, dp2, dr2, dq2);
    else hit = go(p1, q1, r1, p2, q2, r2, dp2, dq2, dr2);
  } else if (dq1 > 0) {
    if (dr1 > 0) hit = go(p1, q1, r1, p2, r2, q2, dp2, dr2, dq2);
    else hit = go(q1, r1, p1, p2, q2, r2, dp2, dq2, dr2);
  } else if (dr1 > 0) {
    hit = go(r1, p1, q1, p2, q2, r2, dp2, dq2, dr2);
  } else if (dr1 < 0) {
    hit = go(r1, p1, q1, p2, r2, q2, dp2, dr2, dq2);
  } else {
    out.coplanar = true;
    hit = coplanar_triangles_overlap(tp, tq, n1);
    if (hit && want_segment) coplanar_overlap_segment(tp, tq, n1, out);
  }
  out.intersects = hit;
  return out;
}

}  // namespace

bool coplanar_triangles_overlap(const Triangle& p, const Triangle& q, const Vec3& n) {
  const int drop = dropped_axis(n);
  return triangles_overlap_2d(project(p[0], drop), project(p[1], drop), project(p[2], drop), project(q[0], drop),
                              project(q[1], drop), project(q[2], drop));
}

bool triangles_intersect(const Triangle& p, const Triangle& q) { return run(p, q, false).intersects; }

TriangleIntersection intersect_triangles(const Triangle& p, const Triangle& q) { return run(p, q, true); }

}  // namespace gk
