// Oriented boxes: fitting contains its points, and the overlap test agrees with an independent
// separating-axis oracle that projects all eight corners of both boxes onto the 15 candidate axes.
#include "kernel/mesh/oriented_box.h"

#include "kernel/core/tolerances.h"
#include "kernel/core/units.h"
#include "tests/support/box_oracle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace gk {
namespace {

using testing::corners_of;
using testing::make_box;
using testing::oracle_sat;
using testing::random_rotation;
using testing::random_vector;
using testing::Rng;
using testing::SatResult;

// ---------------------------------------------------------------------------------------------
// Fitting.

TEST(OrientedBox, FitContainsEveryPoint) {
  Rng rng(1);
  for (int n = 0; n < 40; ++n) {
    // An anisotropic, rotated cloud, sometimes far from the origin.
    const Mat3 r = random_rotation(rng);
    const Vec3 scale = random_vector(rng, 0.01, 20.0);
    const Vec3 offset = n % 2 == 0 ? random_vector(rng, -10.0, 10.0) : Vec3(5.0e4, -5.0e4, 5.0e4);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<Vec3> points;
    for (int k = 0; k < 200; ++k) {
      const double x = g(rng), y = g(rng), z = g(rng);
      points.push_back(offset + r * Vec3(x, y, z).cwiseProduct(scale));
    }
    const OrientedBox box = OrientedBox::fit(points);
    // Orthonormal, right-handed axes (1e-12: an eigen-decomposition of a 3x3 matrix).
    EXPECT_LE((box.axes.transpose() * box.axes - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_NEAR(box.axes.determinant(), 1.0, 1e-12);
    EXPECT_TRUE((box.half_extent.array() >= 0.0).all());
    // Containment with slack 1e-9 mm (the rounding of local coordinates at 5e4 mm is ~1e-11).
    for (const Vec3& p : points) ASSERT_TRUE(box.contains(p, 1e-9)) << "cloud " << n << " point " << p.transpose();
    // Fitted: along each of its axes, some point reaches each face (1e-9 mm).
    for (int axis = 0; axis < 3; ++axis) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (const Vec3& p : points) {
        const double local = box.axes.col(axis).dot(p - box.center);
        lo = std::min(lo, local);
        hi = std::max(hi, local);
      }
      EXPECT_NEAR(hi, box.half_extent[axis], 1e-9) << "cloud " << n << " axis " << axis;
      EXPECT_NEAR(lo, -box.half_extent[axis], 1e-9) << "cloud " << n << " axis " << axis;
    }
  }
}

TEST(OrientedBox, FitRecoversARotatedBoxFromItsCorners) {
  // The eight corners of a box with distinct extents: the principal axes are the box's axes, so the
  // fitted half extents are the box's (1e-9 relative: an eigen-decomposition).
  Rng rng(2);
  for (int n = 0; n < 20; ++n) {
    const Mat3 r = random_rotation(rng);
    const Vec3 half(1.0, 2.5, 7.0);
    const OrientedBox truth = make_box(random_vector(rng, -100.0, 100.0), r, half);
    const std::array<Vec3, 8> corners = corners_of(truth);
    const OrientedBox box = OrientedBox::fit(std::vector<Vec3>(corners.begin(), corners.end()));
    std::array<double, 3> got = {box.half_extent.x(), box.half_extent.y(), box.half_extent.z()};
    std::sort(got.begin(), got.end());
    EXPECT_NEAR(got[0], 1.0, 1e-9);
    EXPECT_NEAR(got[1], 2.5, 1e-9);
    EXPECT_NEAR(got[2], 7.0, 1e-9);
    EXPECT_LE((box.center - truth.center).norm(), 1e-9);
    for (const Vec3& c : corners) EXPECT_TRUE(box.contains(c, 1e-9));
  }
}

TEST(OrientedBox, FitDegenerateClouds) {
  // A single point: zero extents, containing the point.
  const OrientedBox single = OrientedBox::fit({Vec3(3, -4, 5)});
  EXPECT_TRUE(single.contains(Vec3(3, -4, 5), 1e-12));
  EXPECT_LE(single.half_extent.maxCoeff(), 1e-12);
  // Collinear and coplanar clouds: flat boxes that still contain every point (slack 1e-9 mm).
  Rng rng(3);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  std::vector<Vec3> line, plane;
  for (int k = 0; k < 50; ++k) {
    line.push_back(Vec3(1, 2, 3) + u(rng) * Vec3(1, -2, 0.5));
    const double a = u(rng), b = u(rng);
    plane.push_back(Vec3(-7, 0, 2) + a * Vec3(1, 1, 0) + b * Vec3(0, 1, 1));
  }
  for (const std::vector<Vec3>* cloud : {&line, &plane}) {
    const OrientedBox box = OrientedBox::fit(*cloud);
    for (const Vec3& p : *cloud) EXPECT_TRUE(box.contains(p, 1e-9)) << p.transpose();
    EXPECT_LE(box.half_extent.minCoeff(), 1e-9);  // flat along the missing direction
  }
}

TEST(OrientedBox, ContainsRespectsSlack) {
  const OrientedBox box = make_box(Vec3(1, 2, 3), Mat3::Identity(), Vec3(1, 2, 3));
  EXPECT_TRUE(box.contains(Vec3(2, 4, 6)));          // a corner, exactly
  EXPECT_FALSE(box.contains(Vec3(2.5, 2, 3)));
  EXPECT_TRUE(box.contains(Vec3(2.5, 2, 3), 0.5));
  EXPECT_FALSE(box.contains(Vec3(2.5, 2, 3), 0.25));
}

// ---------------------------------------------------------------------------------------------
// Overlap.

TEST(OrientedBox, OverlapAgreesWithSeparatingAxisOracle) {
  Rng rng(4);
  int overlapping = 0, separated = 0, only_edge_axes_separate = 0, ambiguous = 0;
  for (int n = 0; n < 4000; ++n) {
    const double scale = n % 5 == 0 ? 1e-3 : 1.0;  // also small boxes
    const Vec3 base = n % 7 == 0 ? Vec3(5.0e4, 5.0e4, -5.0e4) : Vec3::Zero();
    const OrientedBox a = make_box(base + scale * random_vector(rng, -1.0, 1.0), random_rotation(rng),
                                   scale * random_vector(rng, 0.05, 1.0));
    const OrientedBox b = make_box(base + scale * random_vector(rng, -1.3, 1.3), random_rotation(rng),
                                   scale * random_vector(rng, 0.05, 1.0));
    const SatResult sat = oracle_sat(a, b);
    // Boxes within 1e-9 of their size (plus 1e-12 of their distance from the origin, for the
    // rounding of the transform) of touching are left to the constructed cases: here the answer
    // must be unambiguous.
    if (std::fabs(sat.gap) <= 1e-9 * scale + 1e-12 * base.norm()) {
      ++ambiguous;
      continue;
    }
    const bool expected = sat.gap < 0.0;
    (expected ? overlapping : separated) += 1;
    if (!expected && !sat.face_axis_separates) ++only_edge_axes_separate;
    ASSERT_EQ(overlap(a, b), expected) << "case " << n << " gap " << sat.gap;
    ASSERT_EQ(overlap(b, a), expected) << "case " << n << " (swapped) gap " << sat.gap;
  }
  EXPECT_GT(overlapping, 1000);
  EXPECT_GT(separated, 1000);
  EXPECT_GT(only_edge_axes_separate, 20);  // the nine edge-edge axes were needed
  EXPECT_LT(ambiguous, 10);
}

TEST(OrientedBox, FaceTouchingBoxesOverlap) {
  // b's face lies exactly on a's face (b rotated about the shared face normal by a random angle and
  // shifted within the face so that the faces share area; a quarter of the cases without the turn, so
  // that b's edges are parallel to a's). Exact in the axis-aligned dyadic case;
  // otherwise the slack of the kernel's contract, kBoxSlackRelative times the coordinate magnitude,
  // absorbs the rounding. Pushed apart by 1e-6 of the box size, the boxes are separated.
  Rng rng(5);
  std::uniform_int_distribution<int> axis_pick(0, 2), sign_pick(0, 1);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * kPi), lateral(-0.4, 0.4);
  for (int n = 0; n < 500; ++n) {
    const bool aligned = n % 4 == 0;
    const Mat3 ra = aligned ? Mat3::Identity() : random_rotation(rng);
    const Vec3 ea = aligned ? Vec3(1.0, 0.5, 2.0) : random_vector(rng, 0.1, 2.0);
    const Vec3 eb = aligned ? Vec3(0.25, 1.5, 0.75) : random_vector(rng, 0.1, 2.0);
    const Vec3 far = n % 3 == 0 ? Vec3(5e4, 0, 0) : Vec3::Zero();
    const Vec3 ca = aligned ? Vec3(0.5, -1.0, 4.0) : random_vector(rng, -10.0, 10.0) + far;
    const int i = axis_pick(rng);                       // a's face normal axis
    const double sign = sign_pick(rng) == 0 ? 1.0 : -1.0;
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    // b's axes: a's, rotated about a's axis i (not in the aligned case), with b's axis i along it.
    // n % 4 == 1: b has a's axes exactly, so the edge-edge axes are degenerate (parallel edges).
    const double turn = angle(rng);
    const Mat3 spin =
        aligned || n % 4 == 1 ? Mat3::Identity() : Eigen::AngleAxisd(turn, Vec3::Unit(i)).toRotationMatrix();
    const Mat3 rb = ra * spin;
    const double u = aligned ? 0.25 : lateral(rng), v = aligned ? -0.125 : lateral(rng);
    const Vec3 offset_local = sign * (ea[i] + eb[i]) * Vec3::Unit(i) + u * ea[i1] * Vec3::Unit(i1) +
                              v * ea[i2] * Vec3::Unit(i2);
    const OrientedBox a = make_box(ca, ra, ea);
    const OrientedBox b = make_box(ca + ra * offset_local, rb, eb);
    const double slack = aligned ? 0.0 : tolerances::kBoxSlackRelative * (ca.norm() + ea.norm() + eb.norm());
    EXPECT_TRUE(overlap(a, b, slack)) << "case " << n;
    EXPECT_TRUE(overlap(b, a, slack)) << "case " << n;
    // The oracle agrees that the boxes touch: no gap beyond rounding (1e-9 relative).
    EXPECT_LE(oracle_sat(a, b).gap, 1e-9 * (1.0 + ca.norm())) << "case " << n;
    // Apart by 1e-6 of the size along the normal: separated, for the kernel and the oracle.
    const double apart = 1e-6 * (ea[i] + eb[i]);
    const OrientedBox b_apart = make_box(b.center + sign * apart * ra.col(i), rb, eb);
    EXPECT_FALSE(overlap(a, b_apart, slack)) << "case " << n;
    EXPECT_FALSE(overlap(b_apart, a, slack)) << "case " << n;
    EXPECT_GT(oracle_sat(a, b_apart).gap, 0.5 * apart) << "case " << n;
    // Pushed into a by the same amount: overlapping even with zero slack (degenerate or
    // near-parallel edge-edge axes must not separate them).
    const OrientedBox b_in = make_box(b.center - sign * apart * ra.col(i), rb, eb);
    EXPECT_TRUE(overlap(a, b_in)) << "case " << n;
    EXPECT_TRUE(overlap(b_in, a)) << "case " << n;
  }
}

TEST(OrientedBox, ClearlySeparatedBoxes) {
  Rng rng(6);
  for (int n = 0; n < 500; ++n) {
    const OrientedBox a = make_box(random_vector(rng, -1.0, 1.0), random_rotation(rng), random_vector(rng, 0.1, 1.0));
    // b's centre at least the two bounding-sphere radii (plus 0.1 mm) away from a's.
    const Vec3 eb = random_vector(rng, 0.1, 1.0);
    const Vec3 dir = random_vector(rng, -1.0, 1.0).normalized();
    const Vec3 cb = a.center + dir * (a.half_extent.norm() + eb.norm() + 0.1);
    const OrientedBox b = make_box(cb, random_rotation(rng), eb);
    ASSERT_GT(oracle_sat(a, b).gap, 0.0);
    EXPECT_FALSE(overlap(a, b)) << "case " << n;
    EXPECT_FALSE(overlap(b, a)) << "case " << n;
    // A slack of 1e-3 mm (far below the 0.1 mm gap) changes nothing.
    EXPECT_FALSE(overlap(a, b, 1e-3)) << "case " << n;
  }
}

TEST(OrientedBox, SlackWidensTheFaceAxisTest) {
  // Aligned boxes 2 mm apart along x: a slack above the gap reports overlap, below it does not.
  const OrientedBox a = make_box(Vec3(0, 0, 0), Mat3::Identity(), Vec3(1, 1, 1));
  const OrientedBox b = make_box(Vec3(4, 0.5, -0.5), Mat3::Identity(), Vec3(1, 1, 1));
  EXPECT_FALSE(overlap(a, b));
  EXPECT_FALSE(overlap(a, b, 1.5));
  EXPECT_TRUE(overlap(a, b, 2.5));
  EXPECT_TRUE(overlap(b, a, 2.5));
  // Containment and identity overlap.
  EXPECT_TRUE(overlap(a, a));
  EXPECT_TRUE(overlap(a, make_box(Vec3(0.1, 0.2, 0.3), Mat3::Identity(), Vec3(0.01, 0.01, 0.01))));
}

TEST(OrientedBox, EdgeToEdgeSeparation) {
  // Unit cubes (half extent 1): a turned 45 degrees about z, so its vertical edge reaches
  // (0, sqrt 2, z); b turned 45 degrees about x and centred at (0, 2 sqrt 2 +- 0.01, 0), so its edge
  // along x reaches down to y = sqrt 2 +- 0.01. The edges are perpendicular; only the axis
  // z cross x = y separates the boxes (by 0.01 mm); every face axis shows overlap.
  const Mat3 ra = Eigen::AngleAxisd(kPi / 4, Vec3::UnitZ()).toRotationMatrix();
  const Mat3 rb = Eigen::AngleAxisd(kPi / 4, Vec3::UnitX()).toRotationMatrix();
  const OrientedBox a = make_box(Vec3::Zero(), ra, Vec3(1, 1, 1));
  const double reach = 2.0 * std::sqrt(2.0);
  const OrientedBox apart = make_box(Vec3(0, reach + 0.01, 0), rb, Vec3(1, 1, 1));
  const OrientedBox crossing = make_box(Vec3(0, reach - 0.01, 0), rb, Vec3(1, 1, 1));
  const SatResult sat_apart = oracle_sat(a, apart);
  EXPECT_NEAR(sat_apart.gap, 0.01, 1e-12);  // 1e-12 mm: rounding of the corners
  EXPECT_FALSE(sat_apart.face_axis_separates);
  EXPECT_FALSE(overlap(a, apart));
  EXPECT_FALSE(overlap(apart, a));
  EXPECT_LT(oracle_sat(a, crossing).gap, 0.0);
  EXPECT_TRUE(overlap(a, crossing));
  EXPECT_TRUE(overlap(crossing, a));
}

}  // namespace
}  // namespace gk
