// CLEAR / TOUCHING / COLLISION / INCONCLUSIVE on closed and open meshes, and the invariant that
// moving one mesh along the witness direction by the distance minus or plus a little flips it.
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/point_containment.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace gk {
namespace {

using testing::Rng;

std::shared_ptr<MeshBvh> box(const Vec3& lo, const Vec3& hi) {
  return MeshBvh::build(testing::share(testing::box_mesh(lo, hi))).value();
}

Verdict verdict_of(const MeshBvh& a, const MeshBvh& b, const RigidTransform& pose_b = {}) {
  return assess(a, {}, b, pose_b).value().verdict;
}

TEST(ContactVerdict, BoxesStackedFaceToFaceTouch) {
  const auto a = box(Vec3(0, 0, 0), Vec3(10, 10, 10));
  const auto b = box(Vec3(2, 3, 10), Vec3(6, 7, 14));
  EXPECT_EQ(verdict_of(*a, *b), Verdict::kTouching);
  EXPECT_EQ(verdict_of(*b, *a), Verdict::kTouching);
}

// Equal boxes side by side: their faces meet flush and their side faces lie in common planes,
// meeting there only along an edge. Interiors apart: TOUCHING (it was a false COLLISION while
// coplanar faces with equal normals counted as overlapping whatever they shared). Pushed in by the
// least representable step, or by a micrometre, they collide.
TEST(ContactVerdict, EqualBoxesSideBySideWithFlushSideFacesTouch) {
  const auto a = box(Vec3(0, 0, 0), Vec3(100, 100, 100));
  for (const Vec3& offset : {Vec3(100, 0, 0), Vec3(100, 10, 0), Vec3(0, 0, 100), Vec3(100, 100, 0), Vec3(-100, 0, 0)}) {
    const auto b = box(Vec3(0, 0, 0), Vec3(100, 100, 100));
    EXPECT_EQ(verdict_of(*a, *b, RigidTransform::from_translation(offset)), Verdict::kTouching) << offset.transpose();
    EXPECT_EQ(verdict_of(*b, *a, RigidTransform::from_translation(-offset)), Verdict::kTouching) << offset.transpose();
  }
  const auto b = box(Vec3(0, 0, 0), Vec3(100, 100, 100));
  EXPECT_EQ(verdict_of(*a, *b, RigidTransform::from_translation(Vec3(std::nextafter(100.0, 0.0), 0, 0))), Verdict::kCollision);
  EXPECT_EQ(verdict_of(*a, *b, RigidTransform::from_translation(Vec3(99.999, 10, 0))), Verdict::kCollision);
  // Two equal boxes in the same place share every face with equal normals: a collision.
  EXPECT_EQ(verdict_of(*a, *b), Verdict::kCollision);
  // A smaller box on A with two side faces flush with A's (equal normals, meeting along an edge):
  // touching; sunk halfway in, its top face flush with A's: a collision.
  const auto small = box(Vec3(0, 0, 0), Vec3(50, 50, 50));
  EXPECT_EQ(verdict_of(*a, *small, RigidTransform::from_translation(Vec3(0, 0, 100))), Verdict::kTouching);
  EXPECT_EQ(verdict_of(*a, *small, RigidTransform::from_translation(Vec3(0, 0, 50))), Verdict::kCollision);
}

TEST(ContactVerdict, OverlapGapAndContactTolerance) {
  const auto a = box(Vec3(0, 0, 0), Vec3(10, 10, 10));
  const auto b = box(Vec3(2, 3, 0), Vec3(6, 7, 4));
  EXPECT_EQ(verdict_of(*a, *b, RigidTransform::from_translation(Vec3(0, 0, 10 - 0.003))), Verdict::kCollision);
  EXPECT_EQ(verdict_of(*a, *b, RigidTransform::from_translation(Vec3(0, 0, 10 + 0.003))), Verdict::kClear);
  const double inside_tolerance = 0.5 * tolerances::kContactMm;
  EXPECT_EQ(verdict_of(*a, *b, RigidTransform::from_translation(Vec3(0, 0, 10 + inside_tolerance))), Verdict::kTouching);
}

TEST(ContactVerdict, ContainedBoxIsACollisionWithoutAnySurfaceContact) {
  const auto outer = box(Vec3(0, 0, 0), Vec3(10, 10, 10));
  const auto inner = box(Vec3(4, 4, 4), Vec3(5, 5, 5));
  const auto v = assess(*outer, {}, *inner, {}).value();
  EXPECT_EQ(v.verdict, Verdict::kCollision);
  EXPECT_TRUE(v.contacts.empty());
  EXPECT_EQ(verdict_of(*inner, *outer), Verdict::kCollision);
}

// A part written at factory coordinates (its own vertices near 1e7 mm) with a smaller part inside
// it, 0.004 mm from its walls, both placed by one rotation written with 9 decimals (accepted, not
// orthonormal to the last bits). No surfaces meet, so only the containment test can see the
// collision; inverting the pose by its transpose put the inner part's probe 0.008 mm off, outside
// the walls, and the pair was CLEAR.
TEST(ContactVerdict, APartInsideAnotherAtFactoryCoordinatesUnderANineDecimalRotationIsContained) {
  Mat3 nine_decimals;
  nine_decimals << 0.866025404, -0.5, 0.0, 0.5, 0.866025404, 0.0, 0.0, 0.0, 1.0;
  const Vec3 stretch_axis = Vec3(1, 1, 1).normalized();
  const Vec3 lo(7e6, 2e6, 9.9e6);
  const auto outer = box(lo, lo + Vec3(1000, 1000, 1000));
  const auto inner = box(lo + Vec3(0.004, 0.004, 0.004), lo + Vec3(1000 - 0.004, 1000 - 0.004, 1000 - 0.004));
  for (double stretch : {0.0, 0.6e-9, -0.6e-9}) {
    const Mat3 r = nine_decimals * (Mat3::Identity() + (std::sqrt(1.0 + 3.0 * stretch) - 1.0) * stretch_axis * stretch_axis.transpose());
    const RigidTransform pose{r, -(r * lo)};  // the parts' world place near the origin
    ASSERT_TRUE(pose.is_rigid()) << "stretch " << stretch;
    // The inverse brings factory points back to within rounding of where they were.
    const Vec3 corner = lo + Vec3(1000, 1000, 1000);
    EXPECT_LT((pose.inverse().apply(pose.apply(corner)) - corner).norm(), 1e-6) << "stretch " << stretch;
    for (const bool outer_first : {true, false}) {
      const MeshBvh& a = outer_first ? *outer : *inner;
      const MeshBvh& b = outer_first ? *inner : *outer;
      const VerdictResult v = assess(a, pose, b, pose).value();
      EXPECT_EQ(v.verdict, Verdict::kCollision) << "stretch " << stretch << (outer_first ? ", outer first" : ", inner first");
      EXPECT_TRUE(v.contained) << "stretch " << stretch;
    }
  }
}

TEST(ContactVerdict, FlushInsideIsACollisionNotATouch) {
  // Shares the top face plane with equal normals: overlapping volume, coplanar faces.
  const auto outer = box(Vec3(0, 0, 0), Vec3(10, 10, 10));
  const auto inner = box(Vec3(2, 2, 6), Vec3(5, 5, 10));
  EXPECT_EQ(verdict_of(*outer, *inner), Verdict::kCollision);
}

TEST(ContactVerdict, EdgeRestingOnAFaceTouches) {
  const auto a = box(Vec3(-10, -10, -10), Vec3(10, 10, 0));
  const auto b = box(Vec3(-2, -2, -2), Vec3(2, 2, 2));
  // B turned 45 degrees about x so an edge points down; lifted so that edge lies on z = 0. The
  // rotation rounds the edge's height by ~1e-16 mm, far inside the contact tolerance.
  RigidTransform pose = RigidTransform::from_axis_angle(Vec3::UnitX(), 0.25 * 3.14159265358979323846);
  pose.translation = Vec3(0, 0, 2.0 * std::sqrt(2.0));
  EXPECT_EQ(verdict_of(*a, *b, pose), Verdict::kTouching);
  pose.translation.z() -= 0.01;
  EXPECT_EQ(verdict_of(*a, *b, pose), Verdict::kCollision);
}

TEST(ContactVerdict, OpenMeshesThatIntersectCollide) {
  Rng rng(4);
  const auto a = MeshBvh::build(testing::share(testing::random_soup(rng, 200, 5.0, 2.0))).value();
  const auto b = MeshBvh::build(testing::share(testing::random_soup(rng, 200, 5.0, 2.0))).value();
  const auto v = assess(*a, {}, *b, {}).value();
  ASSERT_FALSE(v.contacts.empty());
  EXPECT_EQ(v.verdict, Verdict::kCollision);
}

TEST(ContactVerdict, MovingByTheDistanceAlongTheWitnessFlipsTheVerdict) {
  Rng rng(77);
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const auto a = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 2, 10.0, 0.15, Vec3::Zero()))).value();
    const auto b = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 2, 8.0, 0.15, Vec3::Zero()))).value();
    const RigidTransform pose_a = testing::random_pose(rng, 1000.0);
    RigidTransform pose_b = testing::random_pose(rng, 1.0);
    const Vec3 dir = Vec3::Random().normalized();
    pose_b.translation = pose_a.translation + dir * 30.0;
    const auto start = assess(*a, pose_a, *b, pose_b).value();
    ASSERT_EQ(start.verdict, Verdict::kClear);
    const double d = start.distance_mm;
    const Vec3 u = (start.point_b - start.point_a) / d;
    const double eps = 0.01;  // [mm], 100x the contact tolerance
    RigidTransform nearer = pose_b, past = pose_b;
    nearer.translation -= (d - eps) * u;
    past.translation -= (d + eps) * u;
    const auto near_v = assess(*a, pose_a, *b, nearer).value();
    EXPECT_EQ(near_v.verdict, Verdict::kClear) << "trial " << trial;
    // After the move the old witnesses are eps apart, so the minimum is at most eps (1e-9 rounding).
    EXPECT_LE(near_v.distance_mm, eps + 1e-9);
    EXPECT_EQ(assess(*a, pose_a, *b, past).value().verdict, Verdict::kCollision) << "trial " << trial;
    ++checked;
  }
  EXPECT_EQ(checked, 60);
}

// With a distance bound the pair is measured first and the all-contacts search skipped when
// nothing lies within the contact tolerance: the verdict must be the one found without a bound
// (collide first, exact predicates), on every side of the tolerance. Blobs moved along their
// witness to gaps from a crossing of 1e-3 mm to 3x the tolerance, at the origin and at factory
// coordinates, for bounds below, at and above the tolerance.
TEST(ContactVerdict, ABoundedVerdictEqualsTheUnboundedOne) {
  Rng rng(2026);
  const double tol = tolerances::kContactMm;
  int touching = 0, clear = 0, colliding = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const auto a = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 2, 10.0, 0.15, Vec3::Zero()))).value();
    const auto b = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 2, 8.0, 0.15, Vec3::Zero()))).value();
    const double range = trial % 2 ? 9.0e6 : 100.0;
    const RigidTransform pose_a = testing::random_pose(rng, range);
    RigidTransform pose_b = testing::random_pose(rng, 1.0);
    pose_b.translation = pose_a.translation + Vec3::Random().normalized() * 30.0;
    const auto start = assess(*a, pose_a, *b, pose_b).value();
    ASSERT_EQ(start.verdict, Verdict::kClear);
    const Vec3 u = (start.point_b - start.point_a) / start.distance_mm;
    for (const double gap : {-1e-3, -1e-5, 0.0, 0.5 * tol, tol, 1.5 * tol, 2.0 * tol, 3.0 * tol}) {
      RigidTransform moved = pose_b;
      moved.translation -= (start.distance_mm - gap) * u;
      const VerdictResult unbounded = assess(*a, pose_a, *b, moved).value();
      for (const double bound : {0.0, tol, 1.5 * tol, 1.0}) {
        VerdictOptions options;
        options.distance_upper_bound_mm = bound;
        const VerdictResult bounded = assess(*a, pose_a, *b, moved, options).value();
        ASSERT_EQ(bounded.verdict, unbounded.verdict) << "trial " << trial << " gap " << gap << " bound " << bound;
        EXPECT_EQ(bounded.crossing_pairs, unbounded.crossing_pairs) << "trial " << trial << " gap " << gap;
        if (bounded.distance_is_lower_bound)
          EXPECT_LE(bounded.distance_mm, unbounded.distance_mm) << "trial " << trial << " gap " << gap << " bound " << bound;
        else
          EXPECT_EQ(bounded.distance_mm, unbounded.distance_mm) << "trial " << trial << " gap " << gap << " bound " << bound;
      }
      touching += unbounded.verdict == Verdict::kTouching;
      clear += unbounded.verdict == Verdict::kClear;
      colliding += unbounded.verdict == Verdict::kCollision;
    }
  }
  // Every side of the tolerance was reached.
  EXPECT_GT(touching, 10);
  EXPECT_GT(clear, 10);
  EXPECT_GT(colliding, 10);
}

// The same with the cases whose verdicts are known by construction, under a bound at the
// tolerance (what the fixture session asks): faces flush, within and beyond the tolerance,
// sunk in, a box inside another with no surface near, an edge resting on a face.
TEST(ContactVerdict, KnownCasesUnderABoundAtTheContactTolerance) {
  VerdictOptions options;
  options.distance_upper_bound_mm = tolerances::kContactMm;
  const auto a = box(Vec3(0, 0, 0), Vec3(10, 10, 10));
  const auto b = box(Vec3(2, 3, 0), Vec3(6, 7, 4));
  const auto at_height = [&](double z) { return assess(*a, {}, *b, RigidTransform::from_translation(Vec3(0, 0, z)), options).value(); };
  EXPECT_EQ(at_height(10.0).verdict, Verdict::kTouching);
  EXPECT_EQ(at_height(10.0 + 0.5 * tolerances::kContactMm).verdict, Verdict::kTouching);
  EXPECT_EQ(at_height(10.0 + 1.5 * tolerances::kContactMm).verdict, Verdict::kClear);
  const VerdictResult far = at_height(13.0);
  EXPECT_EQ(far.verdict, Verdict::kClear);
  EXPECT_TRUE(far.distance_is_lower_bound);
  EXPECT_GE(far.distance_mm, tolerances::kContactMm);
  EXPECT_LE(far.distance_mm, 3.0);
  EXPECT_EQ(at_height(10.0 - 1e-6).verdict, Verdict::kCollision);
  EXPECT_EQ(at_height(std::nextafter(10.0, 0.0)).verdict, Verdict::kCollision);
  const auto inner = box(Vec3(4, 4, 4), Vec3(5, 5, 5));
  const VerdictResult contained = assess(*a, {}, *inner, {}, options).value();
  EXPECT_EQ(contained.verdict, Verdict::kCollision);
  EXPECT_TRUE(contained.contained);
  const auto floor = box(Vec3(-10, -10, -10), Vec3(10, 10, 0));
  const auto cube = box(Vec3(-2, -2, -2), Vec3(2, 2, 2));
  RigidTransform edge_down = RigidTransform::from_axis_angle(Vec3::UnitX(), 0.25 * 3.14159265358979323846);
  edge_down.translation = Vec3(0, 0, 2.0 * std::sqrt(2.0));
  EXPECT_EQ(assess(*floor, {}, *cube, edge_down, options).value().verdict, Verdict::kTouching);
}

// A wire (an open mesh: one triangle and a needle, a zero-area triangle) run through a plate: its
// only contact is on the needle, which cannot be told touching from crossing: INCONCLUSIVE, never
// CLEAR, with or without a distance bound (it was CLEAR: the needle's crossing was not seen).
TEST(ContactVerdict, ANeedleThroughAPlateIsNeverClear) {
  const auto plate = box(Vec3(0, 0, 0), Vec3(100, 100, 10));
  const auto wire = MeshBvh::build(testing::share(TriangleMesh::create({Vec3(0, 0, -5), Vec3(0, 0, 10), Vec3(0, 0, 25), Vec3(1, 0, 25), Vec3(0, 1, 25)},
                                                                       {{0, 1, 2}, {2, 3, 4}}).value())).value();
  ASSERT_TRUE(wire->mesh().is_degenerate(0));
  for (const double z : {0.0, 3.0, 12.0})
    for (const double bound : {std::numeric_limits<double>::infinity(), tolerances::kContactMm, 1.0}) {
      VerdictOptions options;
      options.distance_upper_bound_mm = bound;
      const VerdictResult v = assess(*plate, {}, *wire, RigidTransform::from_translation(Vec3(30, 60, z)), options).value();
      EXPECT_EQ(v.verdict, Verdict::kInconclusive) << "z " << z << " bound " << bound;
      EXPECT_EQ(v.inconclusive_reason, InconclusiveReason::kDegenerateTriangles);
    }
  // Beside the plate: CLEAR.
  EXPECT_EQ(assess(*plate, {}, *wire, RigidTransform::from_translation(Vec3(130, 60, 0))).value().verdict, Verdict::kClear);
}

TEST(PointContainment, RayParityAgreesWithTheWindingNumber) {
  // Oracle: the winding number (O(n), no ray). Random points around rough blobs, and lattice
  // points on a box's faces, edges and corners, where rays graze edges and must be retried.
  testing::Rng rng(3);
  std::uniform_real_distribution<double> coord(-60.0, 60.0);
  for (int blob = 0; blob < 3; ++blob) {
    const auto mesh = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 4, 50.0, 0.4, Vec3(1, 2, 3)))).value();
    for (int i = 0; i < 2000; ++i) {
      const Vec3 p(coord(rng), coord(rng), coord(rng));
      const auto parity = point_inside(*mesh, p);
      ASSERT_TRUE(parity.has_value());
      EXPECT_EQ(*parity, std::fabs(winding_number(mesh->mesh(), p)) > 0.5) << p.transpose();
    }
  }
  const auto box = MeshBvh::build(testing::share(testing::box_mesh(Vec3(0, 0, 0), Vec3(4, 4, 4)))).value();
  for (int x = -1; x <= 5; ++x)
    for (int y = -1; y <= 5; ++y)
      for (int z = -1; z <= 5; ++z) {
        const Vec3 p(x, y, z);
        const auto parity = point_inside(*box, p);
        const bool on_surface = (p.minCoeff() >= 0 && p.maxCoeff() <= 4) && (p.minCoeff() == 0 || p.maxCoeff() == 4);
        if (on_surface) {
          EXPECT_FALSE(parity.has_value()) << p.transpose();  // on the surface: the caller decides
        } else {
          ASSERT_TRUE(parity.has_value()) << p.transpose();
          EXPECT_EQ(*parity, p.minCoeff() > 0 && p.maxCoeff() < 4) << p.transpose();
        }
      }
}

TEST(ContactVerdict, ToStringNamesEveryVerdict) {
  EXPECT_STREQ(to_string(Verdict::kClear), "CLEAR");
  EXPECT_STREQ(to_string(Verdict::kTouching), "TOUCHING");
  EXPECT_STREQ(to_string(Verdict::kCollision), "COLLISION");
  EXPECT_STREQ(to_string(Verdict::kInconclusive), "INCONCLUSIVE");
}

}  // namespace
}  // namespace gk
