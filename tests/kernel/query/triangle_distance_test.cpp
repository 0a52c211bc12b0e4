// Triangle-triangle distance and closest points, against analytic cases and a dense sampling
// oracle: the true distance is at most the smallest sampled distance and at least that minus the
// sampling resolution (every point of a triangle sampled on an N x N barycentric grid is within
// longest edge / N of a sample).
#include "kernel/query/triangle_distance.h"
#include "kernel/query/triangle_intersection.h"

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace gk {
namespace {

using Rng = std::mt19937_64;

std::string describe(const Triangle& t) {
  std::ostringstream s;
  s.precision(17);
  for (const Vec3& v : t) s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ") ";
  return s.str();
}

double magnitude(const Triangle& p, const Triangle& q) {
  double m = 1.0;
  for (const Triangle* t : {&p, &q})
    for (const Vec3& v : *t) m = std::max(m, v.cwiseAbs().maxCoeff());
  return m;
}

double longest_edge(const Triangle& t) {
  return std::max({(t[1] - t[0]).norm(), (t[2] - t[1]).norm(), (t[0] - t[2]).norm()});
}

Triangle transformed(const Triangle& t, const Mat3& r, const Vec3& offset) {
  return {r * t[0] + offset, r * t[1] + offset, r * t[2] + offset};
}

Mat3 random_rotation(Rng& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return q.toRotationMatrix();
}

Vec3 random_vector(Rng& rng, double half) {
  std::uniform_real_distribution<double> u(-half, half);
  const double x = u(rng), y = u(rng), z = u(rng);  // sequenced: the same values on every compiler
  return Vec3(x, y, z);
}

// Independent point-segment distance (projection, clamped).
Vec3 project_on_segment(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 == 0.0) return a;
  return a + std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) * ab;
}

// Samples of a triangle, stored coordinate by coordinate (a plain loop stays fast under the
// sanitizers): the barycentric grid with n steps per edge, plus m points along each edge.
struct Samples {
  std::vector<double> x, y, z;
  void add(const Vec3& v) {
    x.push_back(v.x());
    y.push_back(v.y());
    z.push_back(v.z());
  }
};

Samples samples(const Triangle& t, int n, int m) {
  Samples out;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j)
      out.add(t[0] + (static_cast<double>(i) / n) * (t[1] - t[0]) + (static_cast<double>(j) / n) * (t[2] - t[0]));
  for (int e = 0; e < 3; ++e)
    for (int k = 0; k < m; ++k) out.add(t[e] + (static_cast<double>(k) / m) * (t[(e + 1) % 3] - t[e]));
  return out;
}

double min_sampled_distance(const Samples& a, const Samples& b) {
  double best = std::numeric_limits<double>::infinity();
  const std::size_t nb = b.x.size();
  const double* bx = b.x.data();
  const double* by = b.y.data();
  const double* bz = b.z.data();
  for (std::size_t i = 0; i < a.x.size(); ++i) {
    const double ax = a.x[i], ay = a.y[i], az = a.z[i];
    for (std::size_t j = 0; j < nb; ++j) {
      const double dx = ax - bx[j], dy = ay - by[j], dz = az - bz[j];
      best = std::min(best, dx * dx + dy * dy + dz * dz);
    }
  }
  return std::sqrt(best);
}

// The invariants of every answer: the points lie on their triangles (1e-9 relative to the
// coordinate magnitude: they are constructed in floating point) and their distance is the reported
// distance (1e-12 relative: the same subtraction and norm).
void expect_consistent(const TriangleDistance& d, const Triangle& p, const Triangle& q) {
  const double mag = magnitude(p, q);
  EXPECT_GE(d.distance, 0.0);
  EXPECT_LE((closest_point_on_triangle(d.on_p, p) - d.on_p).norm(), 1e-9 * mag)
      << "on_p off p\np: " << describe(p) << "\nq: " << describe(q);
  EXPECT_LE((closest_point_on_triangle(d.on_q, q) - d.on_q).norm(), 1e-9 * mag)
      << "on_q off q\np: " << describe(p) << "\nq: " << describe(q);
  EXPECT_NEAR((d.on_p - d.on_q).norm(), d.distance, 1e-12 * std::max(d.distance, 1e-300))
      << "p: " << describe(p) << "\nq: " << describe(q);
}

// ---------------------------------------------------------------------------------------------

TEST(TriangleDistance, RandomPairsAgainstDenseSampling) {
  Rng rng(1);
  constexpr int kGrid = 40, kEdgeSamples = 200;
  int separated = 0, touching = 0;
  for (int n = 0; n < 30; ++n) {
    Triangle p, q;
    for (Vec3& v : p) v = random_vector(rng, 1.0);
    if (n % 3 == 0) {
      // q's first edge runs through p's centroid along p's normal (give or take 0.1 mm): crossing.
      const Vec3 c = (p[0] + p[1] + p[2]) / 3.0;
      const Vec3 normal = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
      q = {c + 0.5 * normal + random_vector(rng, 0.05), c - 0.5 * normal + random_vector(rng, 0.05),
           c + random_vector(rng, 1.0)};
    } else {
      const double reach = n % 3 == 1 ? 0.5 : 3.0;  // overlapping region or apart
      const Vec3 shift =
          random_vector(rng, 1.0).normalized() * std::uniform_real_distribution<double>(0.0, reach)(rng);
      for (Vec3& v : q) v = random_vector(rng, 1.0) + shift;
    }
    if (n % 4 == 0) {  // the same pair far from the origin
      const Vec3 far(5.0e4, -5.0e4, 5.0e4);
      for (Vec3& v : p) v += far;
      for (Vec3& v : q) v += far;
    }
    const TriangleDistance d = triangle_distance(p, q);
    expect_consistent(d, p, q);
    const bool intersecting = triangles_intersect(p, q);
    EXPECT_EQ(d.distance == 0.0, intersecting) << "p: " << describe(p) << "\nq: " << describe(q);
    (intersecting ? touching : separated) += 1;
    const double sampled = min_sampled_distance(samples(p, kGrid, kEdgeSamples), samples(q, kGrid, kEdgeSamples));
    const double resolution = (longest_edge(p) + longest_edge(q)) / kGrid;
    // Upper bound: a sampled pair is a pair of points on the triangles (slack 1e-12 relative to the
    // coordinate magnitude for the rounding of the samples). Lower bound: sampled minus resolution.
    EXPECT_LE(d.distance, sampled + 1e-12 * magnitude(p, q)) << "p: " << describe(p) << "\nq: " << describe(q);
    EXPECT_GE(d.distance, sampled - resolution) << "p: " << describe(p) << "\nq: " << describe(q);
    // Symmetric in its arguments (1e-12 relative to the magnitude: different rounding order).
    const TriangleDistance back = triangle_distance(q, p);
    EXPECT_NEAR(back.distance, d.distance, 1e-12 * magnitude(p, q));
  }
  EXPECT_GT(separated, 10);
  EXPECT_GT(touching, 8);
}

TEST(TriangleDistance, SmallSeparatedPairsWithinTightSamplingBounds) {
  // Small, well separated triangles: the sampling bound is tight (resolution below 2% of the
  // distance), so a wrong feature pair would show.
  Rng rng(2);
  constexpr int kGrid = 40, kEdgeSamples = 300;
  for (int n = 0; n < 10; ++n) {
    Triangle p, q;
    for (Vec3& v : p) v = random_vector(rng, 0.05);
    const Vec3 shift = random_vector(rng, 1.0).normalized();
    for (Vec3& v : q) v = random_vector(rng, 0.05) + shift;
    const Mat3 r = random_rotation(rng);
    p = transformed(p, r, Vec3::Zero());
    q = transformed(q, r, Vec3::Zero());
    const TriangleDistance d = triangle_distance(p, q);
    expect_consistent(d, p, q);
    const double sampled = min_sampled_distance(samples(p, kGrid, kEdgeSamples), samples(q, kGrid, kEdgeSamples));
    const double resolution = (longest_edge(p) + longest_edge(q)) / kGrid;
    ASSERT_LT(resolution, 0.02 * sampled);
    EXPECT_LE(d.distance, sampled + 1e-12);  // absolute 1e-12 mm: coordinates about 1 mm
    EXPECT_GE(d.distance, sampled - resolution);
  }
}

TEST(TriangleDistance, InvariantUnderVertexOrder) {
  Rng rng(3);
  for (int n = 0; n < 50; ++n) {
    Triangle p, q;
    for (Vec3& v : p) v = random_vector(rng, 1.0);
    for (Vec3& v : q) v = random_vector(rng, 1.0) + Vec3(1.5, 0, 0);
    const double reference = triangle_distance(p, q).distance;
    const Triangle p_reversed = {p[0], p[2], p[1]}, q_shifted = {q[1], q[2], q[0]};
    // 1e-12 relative (plus 1e-15 mm): another vertex order only changes the rounding.
    EXPECT_NEAR(triangle_distance(p_reversed, q_shifted).distance, reference, 1e-12 * reference + 1e-15);
    EXPECT_NEAR(triangle_distance(q_shifted, p_reversed).distance, reference, 1e-12 * reference + 1e-15);
  }
}

// ---------------------------------------------------------------------------------------------
// Analytic cases.

const Triangle kBase = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};

TEST(TriangleDistance, ParallelTrianglesAtOffset) {
  for (double h : {1.0, 3.0e-3, 1.0e-6, 0.5}) {
    const Triangle q = {Vec3(1, 1, h), Vec3(3, 1, h), Vec3(1, 2.5, h)};
    const TriangleDistance d = triangle_distance(kBase, q);
    expect_consistent(d, kBase, q);
    EXPECT_NEAR(d.distance, h, 1e-12 * h) << "h " << h;  // 1e-12 relative
    EXPECT_NEAR(d.on_q.z() - d.on_p.z(), h, 1e-12 * h);  // straight across
    // Far from the origin the stored offset is the rounded difference of the coordinates; the
    // constructed points carry errors of a few ulps of 5e4 (1e-15 * 5e4 = 5e-11 mm allowed).
    const Vec3 far(5.0e4, 5.0e4, 5.0e4);
    const Triangle pf = {kBase[0] + far, kBase[1] + far, kBase[2] + far};
    const Triangle qf = {q[0] + far, q[1] + far, q[2] + far};
    const double stored_h = qf[0].z() - pf[0].z();
    const TriangleDistance df = triangle_distance(pf, qf);
    expect_consistent(df, pf, qf);
    EXPECT_NEAR(df.distance, stored_h, 1e-12 * h + 1e-15 * 5.0e4) << "h " << h;
  }
}

TEST(TriangleDistance, SkewEdgesAtKnownDistance) {
  // p lies in z <= 0 and touches z = 0 only along its edge on the x axis; q lies in z >= h and
  // touches z = h only along an edge through (0, 0, h) at angle theta: the closest points are
  // (0, 0, 0) and (0, 0, h), at distance h, whatever rigid motion is applied to both.
  Rng rng(4);
  for (int n = 0; n < 40; ++n) {
    const double h = std::uniform_real_distribution<double>(1e-4, 2.0)(rng);
    const double theta = std::uniform_real_distribution<double>(0.2, 2.9)(rng);
    const Vec3 dir(std::cos(theta), std::sin(theta), 0.0);
    const Triangle p = {Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0.3, -1, -1)};
    const Triangle q = {Vec3(0, 0, h) - dir, Vec3(0, 0, h) + 2 * dir, Vec3(0.2, 0.1, h + 1)};
    const Mat3 r = n == 0 ? Mat3::Identity() : random_rotation(rng);
    const Vec3 t = n == 0 ? Vec3::Zero() : random_vector(rng, 10.0);
    const Triangle pr = transformed(p, r, t), qr = transformed(q, r, t);
    const TriangleDistance d = triangle_distance(pr, qr);
    expect_consistent(d, pr, qr);
    // Tolerances 1e-12 mm on the distance and 1e-9 mm on the points: coordinates below 20 mm, the
    // points are found on a well-conditioned crossing (theta away from 0 and pi).
    EXPECT_NEAR(d.distance, h, 1e-12) << "case " << n;
    EXPECT_LE((d.on_p - t).norm(), 1e-9) << "case " << n;
    EXPECT_LE((d.on_q - (r * Vec3(0, 0, h) + t)).norm(), 1e-9) << "case " << n;
  }
}

TEST(TriangleDistance, NearlyParallelCrossingEdgesAtKnownDistance) {
  // As above with the crossing angle theta small: p's edge on the x axis, q's edge through (0, 0, h)
  // at angle theta, both edges' endpoints with z exactly 0 and exactly h. The stored coordinates
  // still have their edges cross in projection, so the distance is exactly h. Tolerance 1e-12 mm
  // (a thousandth of kPointContactMm) plus 1e-9 relative: the problem is well conditioned in
  // distance, coordinates are below 1 mm.
  for (double theta : {1e-3, 1e-5, 1e-8}) {
    for (double h : {1e-6, 1e-9}) {
      const Vec3 dir(std::cos(theta), std::sin(theta), 0.0);
      const Triangle p = {Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0.3, -1, -1)};
      const Triangle q = {Vec3(0, 0, h) - 0.6 * dir, Vec3(0, 0, h) + 0.9 * dir, Vec3(0.2, 0.1, h + 1)};
      const TriangleDistance d = triangle_distance(p, q);
      expect_consistent(d, p, q);
      EXPECT_NEAR(d.distance, h, 1e-12 + 1e-9 * h)
          << "theta " << theta << " h " << h << ": on_p " << d.on_p.transpose() << " on_q " << d.on_q.transpose();
    }
  }
}

// Nearly parallel edges in general position (not axis-aligned as above), long and far from the
// origin, whose closest points lie inside both: the interior parameters computed each on their
// own pulled the two points apart across the edges, by 1e-8 mm where the edges are 7e-10 apart
// (found by an adversarial review). The expected values are the exact minimum of the two
// triangles, computed by the reviewer in rational arithmetic (GMP) from these same doubles; the
// tolerance is 1e-15 of the coordinates' magnitude (rounding).
TEST(TriangleDistance, NearlyParallelEdgesInGeneralPositionAreNotOverestimated) {
  struct Case {
    Triangle p, q;
    double exact, magnitude;
  };
  const Vec3 p0(0x1.9506881593523p+9, 0x1.923bde3b0d508p+7, -0x1.64710e0fa48f5p+5);
  const Vec3 p1(0x1.909f2e47a1caep+9, 0x1.9e92e7147b6e1p+7, -0x1.ada094dd92b84p+5);
  const Vec3 q0(0x1.91a20765a2d83p+9, 0x1.9bbd909920022p+7, -0x1.9cd2c3f79d14cp+5);
  const Vec3 q1(0x1.8d4ff1da05fb5p+9, 0x1.a7d901b888ebap+7, -0x1.e4a0dc37c909dp+5);
  const Case cases[] = {
      // Edges about 16 mm long at about 800 mm, 2.1e-8 rad apart.
      {{p0, p1, Vec3(p0.x() + 3, p0.y() - 7, p0.z() + 11)}, {q0, q1, Vec3(q0.x() - 3, q0.y() + 7, q0.z() - 11)},
       6.874160914216704e-10, 810.0},
      // Edges about 8.9 m long, 2.2e-8 rad apart.
      {{Vec3(0x1.d98d0faa5aa49p+3, -0x1.36550a4a33cb5p+6, 0x1.203ba603a7a72p+5),
        Vec3(-0x1.e7eeb880836b1p+11, 0x1.d902cff3b10c2p+11, 0x1.0b916740a5cd9p+12),
        Vec3(-0x1.14b9e4ad88505p+13, -0x1.72dd14ee447e9p+12, -0x1.e5eae2b4b26p+12)},
       {Vec3(-0x1.9f60fab1c0589p+8, 0x1.5a61b25d7ec44p+8, 0x1.f615c9be11053p+8),
        Vec3(-0x1.c8a1821ebc41p+11, 0x1.ba29527a90332p+11, 0x1.f53941ba8d48fp+11),
        Vec3(-0x1.870387c9d8425p+12, 0x1.9e4aed087aa9cp+11, 0x1.19763a4741bffp+13)},
       8.4897269906714854e-08, 9000.0},
  };
  for (const Case& c : cases) {
    const TriangleDistance d = triangle_distance(c.p, c.q);
    expect_consistent(d, c.p, c.q);
    EXPECT_NEAR(d.distance, c.exact, 1e-15 * c.magnitude);
    const TriangleDistance swapped = triangle_distance(c.q, c.p);
    EXPECT_NEAR(swapped.distance, c.exact, 1e-15 * c.magnitude);
  }
}

TEST(TriangleDistance, VertexAboveFaceAndVertexBesideEdge) {
  for (double h : {2.0, 1.0e-3, 1.0e-7}) {
    // q's lowest point is its vertex above p's interior.
    const Triangle q = {Vec3(1.5, 0.75, h), Vec3(1, 2, h + 2), Vec3(3, -1, h + 1)};
    const TriangleDistance d = triangle_distance(kBase, q);
    expect_consistent(d, kBase, q);
    // 1e-12 relative on the distance; 1e-12 mm on the points (coordinates of a few mm).
    EXPECT_NEAR(d.distance, h, 1e-12 * h);
    EXPECT_LE((d.on_p - Vec3(1.5, 0.75, 0)).norm(), 1e-12);
    EXPECT_LE((d.on_q - q[0]).norm(), 1e-12);
    // The same with the arguments swapped: the face is now the second triangle.
    const TriangleDistance swapped = triangle_distance(q, kBase);
    EXPECT_NEAR(swapped.distance, h, 1e-12 * h);
    EXPECT_LE((swapped.on_q - Vec3(1.5, 0.75, 0)).norm(), 1e-12);
    // q lies in y <= -h and reaches y = -h only at its vertex beside p's edge y = 0.
    const Triangle beside = {Vec3(2, -h, 0), Vec3(2, -h - 1, 1), Vec3(3, -h - 2, -1)};
    const TriangleDistance e = triangle_distance(kBase, beside);
    expect_consistent(e, kBase, beside);
    EXPECT_NEAR(e.distance, h, 1e-12 * h);
    EXPECT_LE((e.on_p - Vec3(2, 0, 0)).norm(), 1e-12);
    // Beside p's vertex (4, 0, 0), diagonally (q lies in x >= 4 + h, y <= -h): distance
    // hypot(stored 4 + h - 4, h), about h sqrt(2).
    const Triangle corner = {Vec3(4 + h, -h, 0), Vec3(5 + h, -h - 1, 1), Vec3(5 + h, -h - 1, -1)};
    const TriangleDistance c = triangle_distance(kBase, corner);
    expect_consistent(c, kBase, corner);
    EXPECT_NEAR(c.distance, std::hypot(corner[0].x() - 4.0, h), 1e-12 * h);
    EXPECT_LE((c.on_p - Vec3(4, 0, 0)).norm(), 1e-12);
  }
}

TEST(TriangleDistance, IntersectingAndTouchingPairsAreAtZero) {
  const std::vector<Triangle> others = {
      {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(2, 1.5, 1)},           // pierces
      {Vec3(1.25, 0.5, 0), Vec3(2, 2, 3), Vec3(0.5, 3, 1)},       // vertex on the face
      {Vec3(2.5, 0, 0), Vec3(2, 2, 3), Vec3(3, -2, 1)},           // vertex on an edge
      {Vec3(4, 0, 0), Vec3(5, 1, 3), Vec3(6, -1, 1)},             // vertex on a vertex
      {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 2, 0)},              // coplanar, nested
      {Vec3(4, 0, 0), Vec3(0, 0, 0), Vec3(2, -1, 3)},             // shared edge
  };
  for (const Triangle& q : others) {
    const TriangleDistance d = triangle_distance(kBase, q);
    EXPECT_EQ(d.distance, 0.0) << describe(q);
    EXPECT_EQ(d.on_p, d.on_q) << describe(q);
    // The witness lies on both triangles (1e-12 mm: coordinates of a few mm, constructed point).
    EXPECT_LE((closest_point_on_triangle(d.on_p, kBase) - d.on_p).norm(), 1e-12) << describe(q);
    EXPECT_LE((closest_point_on_triangle(d.on_p, q) - d.on_p).norm(), 1e-12) << describe(q);
  }
  // Lifted by 2^-30 mm, the vertex-on-face pair is clear at exactly that distance (1e-12 relative).
  const Triangle lifted = {Vec3(1.25, 0.5, 0x1p-30), Vec3(2, 2, 3), Vec3(0.5, 3, 1)};
  EXPECT_NEAR(triangle_distance(kBase, lifted).distance, 0x1p-30, 1e-12 * 0x1p-30);
}

TEST(TriangleDistance, ClosestPointOnTriangleRegions) {
  // One query point in each Voronoi region of the triangle (0,0,0), (4,0,0), (0,4,0), 2 mm above.
  struct Case {
    Vec3 x, expected;
  };
  const Case cases[] = {
      {Vec3(1, 1, 2), Vec3(1, 1, 0)},      // face
      {Vec3(-1, -1, 2), Vec3(0, 0, 0)},    // vertex a
      {Vec3(5, -1, 2), Vec3(4, 0, 0)},     // vertex b
      {Vec3(-1, 5, 2), Vec3(0, 4, 0)},     // vertex c
      {Vec3(2, -3, 2), Vec3(2, 0, 0)},     // edge ab
      {Vec3(-3, 2, 2), Vec3(0, 2, 0)},     // edge ac
      {Vec3(3, 3, 2), Vec3(2, 2, 0)},      // edge bc
      {Vec3(2, 0, 0), Vec3(2, 0, 0)},      // on the boundary
  };
  for (const Case& c : cases) {
    // 1e-12 mm: coordinates of a few mm.
    EXPECT_LE((closest_point_on_triangle(c.x, kBase) - c.expected).norm(), 1e-12) << c.x.transpose();
    const Triangle reversed = {kBase[0], kBase[2], kBase[1]};
    EXPECT_LE((closest_point_on_triangle(c.x, reversed) - c.expected).norm(), 1e-12) << c.x.transpose();
  }
}

// The exact squared distance from x to triangle t: Ericson's region walk on exact rationals (the
// doubles' own values), the oracle for slivers, where the walk on doubles cancels.
mpq_class exact_squared_distance(const Vec3& x, const Triangle& t) {
  using Q = std::array<mpq_class, 3>;
  const auto q = [](const Vec3& v) { return Q{mpq_class(v.x()), mpq_class(v.y()), mpq_class(v.z())}; };
  const auto sub = [](const Q& u, const Q& v) { return Q{u[0] - v[0], u[1] - v[1], u[2] - v[2]}; };
  const auto dot = [](const Q& u, const Q& v) { return mpq_class(u[0] * v[0] + u[1] * v[1] + u[2] * v[2]); };
  const Q a = q(t[0]), b = q(t[1]), c = q(t[2]), p = q(x);
  const auto dist_sq_to = [&](const Q& y) { const Q d = sub(p, y); return dot(d, d); };
  const auto along = [](const Q& from, const Q& dir, const mpq_class& s) { return Q{from[0] + s * dir[0], from[1] + s * dir[1], from[2] + s * dir[2]}; };
  const Q ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const mpq_class d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return dist_sq_to(a);
  const Q bp = sub(p, b);
  const mpq_class d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dist_sq_to(b);
  const mpq_class vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return dist_sq_to(along(a, ab, mpq_class(d1 / (d1 - d3))));
  const Q cp = sub(p, c);
  const mpq_class d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dist_sq_to(c);
  const mpq_class vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return dist_sq_to(along(a, ac, mpq_class(d2 / (d2 - d6))));
  const mpq_class va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return dist_sq_to(along(b, sub(c, b), mpq_class((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  const mpq_class sum = va + vb + vc, v = vb / sum, w = vc / sum;
  const Q on = {a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w};
  return dist_sq_to(on);
}

// Slivers a thousandth to a billionth as wide as they are long (0.1 mm to 5 m), at the origin and
// at factory coordinates, points just above their faces, beside their edges and off their ends:
// the closest point's distance must equal the exact one to 1e-9 mm plus 1e-12 of the coordinates.
// Ericson's products on doubles missed by up to millimetres here (a review measured 2.7 mm on a
// 1 m sliver 0.1 um wide) and the mesh queries' bounds pruned real contacts with it.
TEST(TriangleDistance, ClosestPointOnSliversEqualsTheExactRationalOne) {
  Rng rng(2027);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double length = std::pow(10.0, -1.0 + 4.7 * unit(rng));
    const double aspect = std::pow(10.0, -3.0 - 6.0 * unit(rng));
    const Vec3 origin = trial % 2 ? Vec3(9.9e6 * unit(rng), -4.0e6 * unit(rng), 1.0e6 * unit(rng)) : Vec3::Zero();
    const Vec3 e = Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
    Vec3 u = Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    u = (u - u.dot(e) * e).normalized();
    const Vec3 n = e.cross(u);
    const Triangle t = {origin, origin + length * e, origin + (length * unit(rng)) * e + (aspect * length) * u};
    // Above the face (within its width), beside it, or off an end, 0 to 1e-3 mm from the plane.
    const double s = length * (-0.1 + 1.2 * unit(rng));
    const double across = aspect * length * (-1.0 + 3.0 * unit(rng));
    const Vec3 x = origin + s * e + across * u + (1e-3 * unit(rng)) * n;
    const double got = (closest_point_on_triangle(x, t) - x).norm();
    const double truth = std::sqrt(exact_squared_distance(x, t).get_d());
    const double allowed = 1e-9 + 1e-12 * origin.norm();
    ASSERT_LE(std::abs(got - truth), allowed) << "trial " << trial << " length " << length << " aspect " << aspect << " got " << got
                                              << " truth " << truth;
    worst = std::max(worst, std::abs(got - truth));
  }
  std::printf("worst error on slivers: %.3g mm\n", worst);
}

// ---------------------------------------------------------------------------------------------
// Segment-segment closest points.

void expect_segment_pair(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, const Vec3& want_p,
                         const Vec3& want_q) {
  Vec3 on_p, on_q;
  closest_points_on_segments(p0, p1, q0, q1, on_p, on_q);
  // 1e-12 mm: coordinates of a few mm.
  EXPECT_LE((on_p - want_p).norm(), 1e-12) << "on_p " << on_p.transpose() << " want " << want_p.transpose();
  EXPECT_LE((on_q - want_q).norm(), 1e-12) << "on_q " << on_q.transpose() << " want " << want_q.transpose();
}

TEST(ClosestPointsOnSegments, DegenerateSegments) {
  const Vec3 a(1, 2, 3), b(-1, 0, 2);
  expect_segment_pair(a, a, b, b, a, b);                                                   // two points
  expect_segment_pair(Vec3(0.5, 1, 0), Vec3(0.5, 1, 0), Vec3(0, 0, 0), Vec3(2, 0, 0),      // point, segment
                      Vec3(0.5, 1, 0), Vec3(0.5, 0, 0));
  expect_segment_pair(Vec3(3, 1, 0), Vec3(3, 1, 0), Vec3(0, 0, 0), Vec3(2, 0, 0),          // beyond the end
                      Vec3(3, 1, 0), Vec3(2, 0, 0));
  expect_segment_pair(Vec3(-3, 1, 0), Vec3(-3, 1, 0), Vec3(0, 0, 0), Vec3(2, 0, 0),        // before the start
                      Vec3(-3, 1, 0), Vec3(0, 0, 0));
  expect_segment_pair(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1.5, -1, 1), Vec3(1.5, -1, 1),    // segment, point
                      Vec3(1.5, 0, 0), Vec3(1.5, -1, 1));
  expect_segment_pair(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(7, 1, 1), Vec3(7, 1, 1), Vec3(2, 0, 0), Vec3(7, 1, 1));
}

TEST(ClosestPointsOnSegments, ParallelAndCollinearSegments) {
  Vec3 on_p, on_q;
  // Parallel, overlapping in x over [1, 2]: any pair straight across, distance 1.
  for (const bool reversed : {false, true}) {
    const Vec3 q0 = reversed ? Vec3(3, 1, 0) : Vec3(1, 1, 0), q1 = reversed ? Vec3(1, 1, 0) : Vec3(3, 1, 0);
    closest_points_on_segments(Vec3(0, 0, 0), Vec3(2, 0, 0), q0, q1, on_p, on_q);
    // 1e-12 mm: coordinates of a few mm.
    EXPECT_NEAR((on_p - on_q).norm(), 1.0, 1e-12);
    EXPECT_NEAR(on_p.y(), 0.0, 1e-12);
    EXPECT_NEAR(on_q.y(), 1.0, 1e-12);
    EXPECT_NEAR(on_p.x(), on_q.x(), 1e-12);
    EXPECT_GE(on_p.x(), 1.0 - 1e-12);
    EXPECT_LE(on_p.x(), 2.0 + 1e-12);
  }
  // Parallel, apart along x: end to end.
  expect_segment_pair(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 1, 0), Vec3(3, 1, 0), Vec3(1, 0, 0), Vec3(2, 1, 0));
  expect_segment_pair(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(3, 1, 0), Vec3(2, 1, 0), Vec3(1, 0, 0), Vec3(2, 1, 0));
  expect_segment_pair(Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(-3, 1, 0), Vec3(-2, 1, 0), Vec3(0, 0, 0), Vec3(-2, 1, 0));
  // Collinear and overlapping: distance 0.
  closest_points_on_segments(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, 0, 0), Vec3(5, 0, 0), on_p, on_q);
  EXPECT_NEAR((on_p - on_q).norm(), 0.0, 1e-12);
  // Skew and perpendicular: (0, 0, 0) and (0, 0, 0.5).
  expect_segment_pair(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, 0.5), Vec3(0, 1, 0.5), Vec3(0, 0, 0),
                      Vec3(0, 0, 0.5));
}

// Oracle: the distance from P(s) to the segment q is |d_p|-Lipschitz in s, so minimising the exact
// point-to-segment distance over 1001 samples of s (and the same from q to p) is within
// min(|d_p|, |d_q|) / 2000 of the true minimum, and never below it.
double sampled_segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  constexpr int kSamples = 1000;
  double sampled = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= kSamples; ++k) {
    const double s = static_cast<double>(k) / kSamples;
    const Vec3 x = p0 + s * (p1 - p0), y = q0 + s * (q1 - q0);
    sampled = std::min(
        {sampled, (project_on_segment(x, q0, q1) - x).norm(), (project_on_segment(y, p0, p1) - y).norm()});
  }
  return sampled;
}

double sampling_resolution(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  return std::min((p1 - p0).norm(), (q1 - q0).norm()) / 2000.0;
}

std::string describe_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, const Vec3& on_p,
                              const Vec3& on_q) {
  std::ostringstream what;
  what.precision(17);
  what << "p0 " << p0.transpose() << " p1 " << p1.transpose() << " q0 " << q0.transpose() << " q1 "
       << q1.transpose() << " -> on_p " << on_p.transpose() << " on_q " << on_q.transpose();
  return what.str();
}

// The points lie on their segments (1e-12 mm: coordinates below 3 mm).
void expect_on_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, const Vec3& on_p,
                        const Vec3& on_q) {
  EXPECT_LE((project_on_segment(on_p, p0, p1) - on_p).norm(), 1e-12) << describe_segments(p0, p1, q0, q1, on_p, on_q);
  EXPECT_LE((project_on_segment(on_q, q0, q1) - on_q).norm(), 1e-12) << describe_segments(p0, p1, q0, q1, on_p, on_q);
}

TEST(ClosestPointsOnSegments, RandomPairsAgainstSampling) {
  Rng rng(5);
  for (int n = 0; n < 200; ++n) {
    // Dyadic coordinates (multiples of 1/64 in [-1, 1]) so that parallel directions are exact.
    auto point = [&rng]() {
      std::uniform_int_distribution<int> k(-64, 64);
      const double x = k(rng) / 64.0, y = k(rng) / 64.0, z = k(rng) / 64.0;
      return Vec3(x, y, z);
    };
    const Vec3 p0 = point(), p1 = point(), q0 = point();
    Vec3 q1 = point();
    if (n % 3 == 1) q1 = q0 + (p1 - p0) * 0.75;   // exactly parallel
    if (n % 3 == 2) q1 = q0 - (p1 - p0) * 1.25;   // exactly anti-parallel
    Vec3 on_p, on_q;
    closest_points_on_segments(p0, p1, q0, q1, on_p, on_q);
    expect_on_segments(p0, p1, q0, q1, on_p, on_q);
    const double d = (on_p - on_q).norm();
    const double sampled = sampled_segment_distance(p0, p1, q0, q1);
    // Upper bound with 1e-12 mm of rounding slack (coordinates below 3 mm round at 1e-16); lower
    // bound by the sampling resolution.
    EXPECT_LE(d, sampled + 1e-12) << "case " << n << ": " << describe_segments(p0, p1, q0, q1, on_p, on_q);
    EXPECT_GE(d, sampled - sampling_resolution(p0, p1, q0, q1)) << "case " << n;
  }
}

TEST(ClosestPointsOnSegments, NearlyParallelSegmentsAgainstSampling) {
  // Directions a tiny angle apart (about 1e-10 to 1e-6 rad): the closest distance is still well
  // conditioned, and any sampled pair closer than the answer proves the answer is not the closest.
  // Tolerance as above: 1e-12 mm. The worst case is reported.
  Rng rng(6);
  double worst = -std::numeric_limits<double>::infinity();
  std::string worst_case;
  for (int n = 0; n < 200; ++n) {
    const Vec3 p0 = random_vector(rng, 1.0), p1 = random_vector(rng, 1.0), q0 = random_vector(rng, 1.0);
    const double noise = std::pow(10.0, -6.0 - (n % 5));
    const Vec3 q1 = q0 + (p1 - p0) * 0.7 + random_vector(rng, noise);
    Vec3 on_p, on_q;
    closest_points_on_segments(p0, p1, q0, q1, on_p, on_q);
    expect_on_segments(p0, p1, q0, q1, on_p, on_q);
    const double d = (on_p - on_q).norm();
    const double sampled = sampled_segment_distance(p0, p1, q0, q1);
    EXPECT_GE(d, sampled - sampling_resolution(p0, p1, q0, q1)) << "case " << n;
    if (d - sampled > worst) {
      worst = d - sampled;
      std::ostringstream what;
      what.precision(17);
      what << "case " << n << ": " << describe_segments(p0, p1, q0, q1, on_p, on_q) << "\ndistance " << d
           << ", a sampled pair is at " << sampled;
      worst_case = what.str();
    }
  }
  EXPECT_LE(worst, 1e-12) << worst_case;
}

}  // namespace
}  // namespace gk

namespace gk {
namespace {

// Found by an adversarial review: a needle (nearly collinear, not exactly degenerate) triangle
// whose long edge pierces a small triangle. The plane bound took the needle's normal (a cross
// product of nearly parallel edges: rounding) at face value, claimed a gap of 0.02-0.29 mm, and the
// exact intersection test was skipped: the pair was at 0.005 mm instead of 0, and pairs_within
// missed it. Now the bound takes off its rounding error, so it never exceeds the true distance.
TEST(TriangleDistance, ANeedlePiercingATriangleIsAtZeroAndItsBoundNeverExceedsTheDistance) {
  const Triangle needle = {Vec3(0.11741428103451812, 0.94930120289264419, 0.75438530415285798),
                           Vec3(1.6683458660739485, 1.0905727660964311, 1.6462984808653345),
                           Vec3(1.2023123095088359, 1.0481226092510534, 1.3782908692465179)};
  const Triangle small = {Vec3(0.89197294704258456, 1.0298957555779527, 1.2003418925090963),
                          Vec3(0.88902775645403198, 1.0145653840706703, 1.2078914330147035),
                          Vec3(0.89763951716608348, 1.0153498138349899, 1.1927923520034891)};
  ASSERT_TRUE(intersect_triangles(needle, small).intersects);  // the exact test
  EXPECT_EQ(triangle_distance_lower_bound(needle, small), 0.0);
  EXPECT_EQ(triangle_distance(needle, small).distance, 0.0);
  EXPECT_EQ(triangle_distance(small, needle).distance, 0.0);
  // Random needles through random small triangles: every lower bound at most the distance, which
  // is 0 whenever the exact test says they meet.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int meeting = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p0(u(rng), u(rng), u(rng)), p1 = p0 + Vec3(10 * u(rng) + 1, u(rng), u(rng));
    const Vec3 p2 = p0 + (p1 - p0) * (0.2 + 0.6 * u(rng));
    const Vec3 e = p1 - p0, m = p0 + (0.3 + 0.4 * u(rng)) * e + 1e-3 * (u(rng) - 0.5) * e.unitOrthogonal();
    const Vec3 a = e.unitOrthogonal(), b = e.normalized().cross(a);
    const double r = 1e-2;
    const Triangle t = {m + r * a, m + r * (-0.5 * a + 0.87 * b), m + r * (-0.5 * a - 0.87 * b)};
    const Triangle n = {p0, p1, p2};
    const double d = triangle_distance(n, t).distance;
    EXPECT_LE(triangle_distance_lower_bound(n, t), d) << i;
    if (intersect_triangles(n, t).intersects) {
      ++meeting;
      EXPECT_EQ(d, 0.0) << i;
    }
  }
  EXPECT_GT(meeting, 1000);
}

// Also from the review: a triangle tiny beside the query point (1e-16 relative) made
// closest_point_on_triangle divide 0 by 0, and the NaN turned a traversal's bound into +inf.
TEST(TriangleDistance, ClosestPointOnATinyFarTriangleIsFinite) {
  const Triangle tiny = {Vec3(1.88, 0, 0), Vec3(1.88 + 4e-13, 0, 0), Vec3(1.88, 4e-13, 0)};
  for (const Vec3& x : {Vec3(2.2e5, 0, 0), Vec3(-2.2e5, 1e-3, 0), Vec3(1.88, 2.2e5, 0), Vec3(0, 0, 2.2e5)}) {
    const Vec3 c = closest_point_on_triangle(x, tiny);
    EXPECT_TRUE(c.allFinite()) << x.transpose();
    EXPECT_NEAR((c - tiny[0]).norm(), 0.0, 1e-12);
  }
}

}  // namespace
}  // namespace gk
