#include "kernel/query/triangle_distance.h"

#include "kernel/query/triangle_intersection.h"
#include "kernel/core/tolerances.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gk {

namespace {

// The closest point to (px, py) on segment (a, b) in the 2-D frame of closest_point_on_sliver,
// if nearer than best_sq so far.
template <typename Real>
void closest_on_edge_2d(Real ax, Real ay, Real bx, Real by, Real px, Real py, Real& qx, Real& qy, Real& best_sq) {
  const Real dx = bx - ax, dy = by - ay, len_sq = dx * dx + dy * dy;
  Real u = len_sq > Real(0) ? ((px - ax) * dx + (py - ay) * dy) / len_sq : Real(0);
  u = std::clamp(u, Real(0), Real(1));
  const Real cx = ax + u * dx, cy = ay + u * dy;
  const Real d_sq = (px - cx) * (px - cx) + (py - cy) * (py - cy);
  if (d_sq < best_sq) {
    best_sq = d_sq;
    qx = cx;
    qy = cy;
  }
}

// The closest point on a sliver (a triangle far thinner than it is long). Ericson's products
// d1 d4 - d3 d2 cancel there (their error grows as eps (L / w)^2 L, millimetres on a metre-long
// sliver a micrometre wide), so the triangle is laid out exactly as it is in a frame of its
// longest edge instead: corners (0, 0), (L, 0), (s2, w), the point at (s, t). What remains is the
// frame's direction error, eps (L / w) L: in double down to widths of 1e-6 of the length, in long
// double below (kSliverLongDoubleAspect).
template <typename Real>
Vec3 closest_point_on_sliver(const Vec3& x, const Triangle& t, int longest) {
  using V = Eigen::Matrix<Real, 3, 1>;
  const V p0 = t[longest].cast<Real>(), p1 = t[(longest + 1) % 3].cast<Real>(), p2 = t[(longest + 2) % 3].cast<Real>();
  const V e = p1 - p0;
  const Real length = e.norm();
  const V along = e / length;
  const V to_p2 = p2 - p0;
  const Real s2 = to_p2.dot(along);
  const V across_raw = to_p2 - s2 * along;
  const Real width = across_raw.norm();
  if (!(width > Real(0))) {
    // Collinear corners: the nearest point of the longest edge covers the other two.
    const Real u = std::clamp((x.cast<Real>() - p0).dot(e) / (length * length), Real(0), Real(1));
    return (p0 + u * e).template cast<double>();
  }
  const V across = across_raw / width;
  const V rel = x.cast<Real>() - p0;
  const Real s = rel.dot(along), tt = rel.dot(across);
  // Inside the 2-D triangle (0,0), (length,0), (s2,width): above the first edge and on the inner
  // side of the other two (counter-clockwise, width > 0).
  const auto left_of = [](Real ax, Real ay, Real bx, Real by, Real px, Real py) { return (bx - ax) * (py - ay) - (by - ay) * (px - ax) >= Real(0); };
  Real qx = s, qy = tt;
  if (!(tt >= Real(0) && left_of(length, Real(0), s2, width, s, tt) && left_of(s2, width, Real(0), Real(0), s, tt))) {
    Real best_sq = std::numeric_limits<Real>::infinity();
    closest_on_edge_2d<Real>(Real(0), Real(0), length, Real(0), s, tt, qx, qy, best_sq);
    closest_on_edge_2d<Real>(length, Real(0), s2, width, s, tt, qx, qy, best_sq);
    closest_on_edge_2d<Real>(s2, width, Real(0), Real(0), s, tt, qx, qy, best_sq);
  }
  return (p0 + qx * along + qy * across).template cast<double>();
}

}  // namespace

Vec3 closest_point_on_triangle(const Vec3& x, const Triangle& t) {
  const Vec3 &a = t[0], &b = t[1], &c = t[2];
  const Vec3 ab = b - a, ac = c - a, ax = x - a;
  {
    // A sliver (twice its area below kSliverAspect times its longest edge squared) is measured
    // in its own frame; Ericson's products below are for the rest. Cheaply: (twice the area)^2 by
    // Lagrange's identity (its rounding, eps |ab|^2 |ac|^2, is far below the threshold), and the
    // longest edge squared at most 2 (|ab|^2 + |ac|^2), so a few more than the slivers go that way.
    const double l0 = ab.squaredNorm(), l2 = ac.squaredNorm(), abac = ab.dot(ac);
    const double twice_area_sq = l0 * l2 - abac * abac, sum = l0 + l2;
    if (sum > 0.0 && twice_area_sq < 4.0 * tolerances::kSliverAspect * tolerances::kSliverAspect * sum * sum) {
      const double l1 = (c - b).squaredNorm();
      const int longest = l0 >= l1 && l0 >= l2 ? 0 : (l1 >= l2 ? 1 : 2);
      const double longest_sq = std::max({l0, l1, l2});
      constexpr double k = tolerances::kSliverLongDoubleAspect;
      if (twice_area_sq < k * k * longest_sq * longest_sq) return closest_point_on_sliver<long double>(x, t, longest);
      return closest_point_on_sliver<double>(x, t, longest);
    }
  }
  const double d1 = ab.dot(ax), d2 = ac.dot(ax);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Vec3 bx = x - b;
  const double d3 = ab.dot(bx), d4 = ac.dot(bx);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    // d1 == d3 == 0 (a triangle tiny beside x: the products underflow): a is as good as any.
    if (!(d1 - d3 > 0.0)) return a;
    const double v = d1 / (d1 - d3);
    return a + v * ab;
  }
  const Vec3 cx = x - c;
  const double d5 = ab.dot(cx), d6 = ac.dot(cx);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    if (!(d2 - d6 > 0.0)) return a;
    const double w = d2 / (d2 - d6);
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    if (!((d4 - d3) + (d5 - d6) > 0.0)) return b;
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return b + w * (c - b);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0.0)) {
    // Degenerate (zero-area) triangle: the closest point lies on one of its edges.
    Vec3 best = a, on_edge, unused;
    double best_d = (x - a).squaredNorm();
    const Vec3* corners[3] = {&a, &b, &c};
    for (int e = 0; e < 3; ++e) {
      closest_points_on_segments(*corners[e], *corners[(e + 1) % 3], x, x, on_edge, unused);
      const double d = (x - on_edge).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = on_edge;
      }
    }
    return best;
  }
  const double v = vb / sum, w = vc / sum;
  return a + ab * v + ac * w;
}

namespace {

Vec3 closest_point_on_segment(const Vec3& a, const Vec3& b, const Vec3& x) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (!(len2 > 0.0)) return a;
  return a + std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) * ab;
}

}  // namespace

void closest_points_on_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, Vec3& on_p,
                                Vec3& on_q) {
  // The minimum is either between the two interiors (the lines' common perpendicular, when it
  // falls inside both segments) or has an endpoint on one side. The interior parameters come from
  // cross products (Goldman), which stay accurate for nearly parallel segments where the textbook
  // a*e - b*b denominator cancels.
  double best = std::numeric_limits<double>::infinity();
  auto consider = [&](const Vec3& a, const Vec3& b) {
    const double d = (a - b).squaredNorm();
    if (d < best) {
      best = d;
      on_p = a;
      on_q = b;
    }
  };
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = q0 - p0;
  const Vec3 n = d1.cross(d2);
  const double nn = n.squaredNorm();
  if (nn > 0.0) {
    const double s = r.cross(d2).dot(n) / nn;
    const double t = r.cross(d1).dot(n) / nn;
    if (s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0) {
      // s and t each come out accurate along the segments, but not together: their small errors
      // pull the two points apart across the segments, by far more than the distance when the
      // segments nearly meet at a small angle (1e-8 mm for edges 7e-10 mm apart at 2e-8 rad;
      // 3e-10 mm at 1e-3 rad). So only s is kept, and the pair is made mutually near by projection:
      // the point of q's segment nearest p(s), then the point of p's segment nearest that.
      const Vec3 nearest_q = closest_point_on_segment(q0, q1, p0 + s * d1);
      consider(closest_point_on_segment(p0, p1, nearest_q), nearest_q);
      // Clearly not parallel: the squared distance is then strictly convex in (s, t), so a minimum
      // inside both segments is the minimum; the endpoints below can only matter where the
      // parameters are ill-conditioned.
      if (nn > tolerances::kNearlyParallelSineSquared * d1.squaredNorm() * d2.squaredNorm()) return;
    }
  }
  consider(p0, closest_point_on_segment(q0, q1, p0));
  consider(p1, closest_point_on_segment(q0, q1, p1));
  consider(closest_point_on_segment(p0, p1, q0), q0);
  consider(closest_point_on_segment(p0, p1, q1), q1);
}

namespace {

// A lower bound of the distance from the plane of t to the nearest corner of other, when all of
// other's corners lie on one side; 0 when they straddle or touch the plane, or when rounding could
// put them there. The normal of a needle-like triangle is a cross product of nearly parallel edges,
// mostly rounding: its error (a few ulps of |e1| |e2| per component, times the corner's distance)
// is taken off, so the bound never exceeds the true distance.
double plane_separation(const Triangle& t, const Triangle& other) {
  const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
  const Vec3 n = e1.cross(e2);
  const double len_sq = n.squaredNorm();
  if (!(len_sq > 0.0)) return 0.0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, reach_sq = 0.0;
  for (const Vec3& v : other) {
    const Vec3 d = v - t[0];
    const double s = n.dot(d);
    lo = std::min(lo, s);
    hi = std::max(hi, s);
    reach_sq = std::max(reach_sq, d.squaredNorm());
  }
  // One square root for the error, one for the length, and only when a side is clear of zero.
  if (!(lo > 0.0) && !(hi < 0.0)) return 0.0;
  // Each normal component is a difference of two products of rounded edge components: off by at
  // most about 6 eps |e1| |e2|, so |n| by 11 eps |e1| |e2|; the dot product adds 3 eps |n| |d| and d
  // itself eps |d|. 32 eps covers the sum with room to spare.
  const double error = 32.0 * std::numeric_limits<double>::epsilon() * std::sqrt(e1.squaredNorm() * e2.squaredNorm() * reach_sq);
  if (lo > error) return (lo - error) / std::sqrt(len_sq);
  if (hi < -error) return (-hi - error) / std::sqrt(len_sq);
  return 0.0;
}

double box_gap(const Triangle& p, const Triangle& q) {
  const Vec3 pmin = p[0].cwiseMin(p[1]).cwiseMin(p[2]), pmax = p[0].cwiseMax(p[1]).cwiseMax(p[2]);
  const Vec3 qmin = q[0].cwiseMin(q[1]).cwiseMin(q[2]), qmax = q[0].cwiseMax(q[1]).cwiseMax(q[2]);
  return (qmin - pmax).cwiseMax(pmin - qmax).cwiseMax(Vec3::Zero()).norm();
}

}  // namespace

double triangle_distance_lower_bound(const Triangle& p, const Triangle& q) {
  return std::max({box_gap(p, q), plane_separation(p, q), plane_separation(q, p)});
}

TriangleDistance triangle_distance(const Triangle& p, const Triangle& q, double stop_at) {
  TriangleDistance best;
  // The same bound as triangle_distance_lower_bound, cheapest part first: most pairs a traversal
  // hands over are ruled out by their boxes alone.
  double bound = box_gap(p, q);
  if (bound < stop_at) bound = std::max(bound, plane_separation(p, q));
  if (bound < stop_at) bound = std::max(bound, plane_separation(q, p));
  if (bound >= stop_at) {
    best.distance = bound;
    best.bounded_only = true;
    return best;
  }
  // The exact intersection test is needed only when the floating bound cannot rule contact out
  // with a margin far above its rounding (1e-9 relative to the coordinates).
  const double magnitude = std::max({p[0].cwiseAbs().maxCoeff(), q[0].cwiseAbs().maxCoeff(), 1.0});
  if (!(bound > 1e-9 * magnitude)) {
    const TriangleIntersection hit = intersect_triangles(p, q);
    if (hit.intersects) {
      best.distance = 0.0;
      best.on_p = best.on_q = 0.5 * (hit.segment_start + hit.segment_end);
      return best;
    }
  }
  double best_sq = std::numeric_limits<double>::infinity();
  auto consider = [&](const Vec3& a, const Vec3& b) {
    const double d = (a - b).squaredNorm();
    if (d < best_sq) {
      best_sq = d;
      best.on_p = a;
      best.on_q = b;
    }
  };
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Vec3 a, b;
      closest_points_on_segments(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3], a, b);
      consider(a, b);
      // Early exit (as in PQP's TriDist): when the plane through a normal to b - a has all of p on
      // a's side and all of q on b's side, no pair of points can be closer than this one.
      const Vec3 v = b - a;
      if (v.squaredNorm() > 0.0 && (p[0] - a).dot(v) <= 0.0 && (p[1] - a).dot(v) <= 0.0 && (p[2] - a).dot(v) <= 0.0 &&
          (q[0] - b).dot(v) >= 0.0 && (q[1] - b).dot(v) >= 0.0 && (q[2] - b).dot(v) >= 0.0) {
        best.on_p = a;
        best.on_q = b;
        best.distance = v.norm();
        return best;
      }
    }
  }
  for (int i = 0; i < 3; ++i) {
    consider(p[i], closest_point_on_triangle(p[i], q));
    consider(closest_point_on_triangle(q[i], p), q[i]);
  }
  best.distance = std::sqrt(best_sq);
  return best;
}

}  // namespace gk
