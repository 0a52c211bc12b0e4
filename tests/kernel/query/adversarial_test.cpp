// Configurations that break inexact kernels: coplanar overlap, edge-on-edge and vertex-on-face
// touching, 0.003 mm gaps 50 m from the origin in every orientation, slivers and degenerate input.
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gk {
namespace {

using testing::Rng;

std::shared_ptr<MeshBvh> single_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  return MeshBvh::build(testing::share(TriangleMesh::create({a, b, c}, {{0, 1, 2}}).value())).value();
}

bool touches(const MeshBvh& a, const MeshBvh& b, const RigidTransform& pose_b = {}) {
  return collide(a, RigidTransform{}, b, pose_b).value().colliding;
}

double gap(const MeshBvh& a, const MeshBvh& b, const RigidTransform& pose_b = {}) {
  return distance(a, RigidTransform{}, b, pose_b).value().distance_mm;
}

// Offsets that are exactly representable keep dyadic coordinates exact after translation.
const double kFar = 50000.0;

TEST(Adversarial, CoplanarOverlappingTrianglesCollideAndReportCoplanar) {
  for (double offset : {0.0, kFar}) {
    const Vec3 o(offset, offset, offset);
    auto a = single_triangle(o + Vec3(0, 0, 0), o + Vec3(4, 0, 0), o + Vec3(0, 4, 0));
    auto b = single_triangle(o + Vec3(1, 1, 0), o + Vec3(5, 1, 0), o + Vec3(1, 5, 0));
    const auto c = collide(*a, {}, *b, {}).value();
    ASSERT_TRUE(c.colliding) << offset;
    EXPECT_TRUE(c.contacts[0].coplanar);
    // Coplanar but disjoint: a 2^-20 mm gap inside the plane.
    auto d = single_triangle(o + Vec3(4 + std::ldexp(1.0, -20), 0, 0), o + Vec3(8, 0, 0), o + Vec3(8, 4, 0));
    EXPECT_FALSE(touches(*a, *d)) << offset;
    EXPECT_NEAR(gap(*a, *d), std::ldexp(1.0, -20), 1e-12);  // tolerance: rounding at 5e4 mm, ~1e-11
  }
}

TEST(Adversarial, EdgeOnEdgeTouchingIsContactAndAnyGapIsNot) {
  for (double offset : {0.0, kFar}) {
    const Vec3 o(offset, -offset, offset);
    // A in z = 0 below the x axis; B in x = 1 above it; their edges cross at (1, 0, 0).
    auto a = single_triangle(o + Vec3(0, 0, 0), o + Vec3(2, 0, 0), o + Vec3(1, -1, 0));
    auto b = single_triangle(o + Vec3(1, 0, -1), o + Vec3(1, 0, 1), o + Vec3(1, 1, 0));
    EXPECT_TRUE(touches(*a, *b)) << offset;
    EXPECT_EQ(gap(*a, *b), 0.0);
    for (double g : {0.003, 1e-6, std::ldexp(1.0, -30)}) {
      const RigidTransform shifted = RigidTransform::from_translation(Vec3(0, g, 0));
      EXPECT_FALSE(touches(*a, *b, shifted)) << "gap " << g << " offset " << offset;
      // The gap survives the trip through a 5e4 mm translation to about 1e-11 mm.
      EXPECT_NEAR(gap(*a, *b, shifted), g, 1e-11) << "gap " << g;
    }
  }
}

TEST(Adversarial, VertexOnFaceTouchesAndAVertexJustAboveDoesNot) {
  for (double offset : {0.0, -kFar}) {
    const Vec3 o(offset, offset, 0.5 * offset);
    auto a = single_triangle(o + Vec3(0, 0, 0), o + Vec3(4, 0, 0), o + Vec3(0, 4, 0));
    auto b = single_triangle(o + Vec3(1, 1, 0), o + Vec3(1, 2, 3), o + Vec3(2, 1, 3));
    EXPECT_TRUE(touches(*a, *b));
    auto above = single_triangle(o + Vec3(1, 1, std::ldexp(1.0, -24)), o + Vec3(1, 2, 3), o + Vec3(2, 1, 3));
    EXPECT_FALSE(touches(*a, *above));
    EXPECT_NEAR(gap(*a, *above), std::ldexp(1.0, -24), 1e-12);  // exact coordinates, ~1 ulp
  }
}

TEST(Adversarial, ThreeMicronGapsAndOverlapsFiftyMetresOutInEveryOrientation) {
  Rng rng(3);
  const auto cube_a = MeshBvh::build(testing::share(testing::box_mesh(Vec3(-50, -50, -50), Vec3(50, 50, 50)))).value();
  const auto cube_b = MeshBvh::build(testing::share(testing::box_mesh(Vec3(-20, -20, -20), Vec3(20, 20, 20)))).value();
  int decided = 0;
  for (int trial = 0; trial < 300; ++trial) {
    // Pose A anywhere 10^4..5*10^4 mm out, in any orientation; B beside one of A's faces, itself
    // turned about the face normal, separated by +-0.003 mm.
    RigidTransform pose_a = testing::random_pose(rng, 5e4);
    pose_a.translation += Vec3(1e4, 1e4, 1e4).cwiseProduct(pose_a.translation.cwiseSign());
    const int axis = trial % 3;
    const double side = (trial / 3) % 2 == 0 ? 1.0 : -1.0;
    for (double separation : {0.003, -0.003}) {
      Vec3 offset = Vec3::Zero();
      offset[axis] = side * (50.0 + 20.0 + separation);
      const double turn = std::uniform_real_distribution<double>(0.0, 6.283)(rng);
      Vec3 normal = Vec3::Zero();
      normal[axis] = 1.0;
      const RigidTransform local = RigidTransform::from_axis_angle(normal, turn, offset);
      const RigidTransform pose_b = pose_a * local;
      const auto verdict = assess(*cube_a, pose_a, *cube_b, pose_b).value();
      if (separation > 0) {
        EXPECT_EQ(verdict.verdict, Verdict::kClear) << "trial " << trial;
        // Tolerance: the relative transform carries ~1e-11 mm of rounding at 5e4 mm.
        EXPECT_NEAR(verdict.distance_mm, 0.003, 1e-9) << "trial " << trial;
      } else {
        EXPECT_EQ(verdict.verdict, Verdict::kCollision) << "trial " << trial;
      }
      ++decided;
    }
  }
  EXPECT_EQ(decided, 600);
}

TEST(Adversarial, MeshesStoredFiftyMetresOutAtThreeMicrons) {
  // The vertices themselves are at factory coordinates; poses are identity.
  const Vec3 base(kFar, -kFar, 0.7 * kFar);
  const auto a = MeshBvh::build(testing::share(testing::box_mesh(base, base + Vec3(100, 100, 100)))).value();
  const Vec3 b_min = base + Vec3(100.003, 10, 10);
  const auto b = MeshBvh::build(testing::share(testing::box_mesh(b_min, b_min + Vec3(40, 40, 40)))).value();
  const auto v = assess(*a, {}, *b, {}).value();
  EXPECT_EQ(v.verdict, Verdict::kClear);
  EXPECT_NEAR(v.distance_mm, 0.003, 1e-9);  // input rounding at 5e4 mm is ~7e-12 mm
}

TEST(Adversarial, SliversAreDecidedExactly) {
  // A needle-thin triangle (width 2^-40 mm) through a big one, and the same needle moved 2^-40 mm
  // past the big triangle's edge.
  auto big = single_triangle(Vec3(0, 0, 0), Vec3(8, 0, 0), Vec3(0, 8, 0));
  const double w = std::ldexp(1.0, -40);
  auto through = single_triangle(Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(1 + w, 1, 1));
  EXPECT_TRUE(touches(*big, *through));
  auto beside = single_triangle(Vec3(-w, 1, -1), Vec3(-w, 1, 1), Vec3(-2 * w, 1, 1));
  EXPECT_FALSE(touches(*big, *beside));
  EXPECT_NEAR(gap(*big, *beside), w, 1e-20);  // exact dyadic geometry
  auto on_edge = single_triangle(Vec3(0, 1, -1), Vec3(0, 1, 1), Vec3(-w, 1, 1));
  EXPECT_TRUE(touches(*big, *on_edge));
}

TEST(Adversarial, DegenerateTrianglesAreReportedAndNeverCrashQueries) {
  // One collinear triangle among good ones.
  std::vector<Vec3> v = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  auto mesh = TriangleMesh::create(v, {{0, 1, 2}, {0, 1, 3}, {0, 3, 4}});
  ASSERT_TRUE(mesh.ok());
  ASSERT_EQ(mesh.value().report().zero_area_triangles.size(), 1u);
  EXPECT_TRUE(mesh.value().is_degenerate(0));
  auto bvh = MeshBvh::build(testing::share(mesh.value())).value();
  // A triangle crossed by the degenerate one only.
  auto wall = single_triangle(Vec3(1.5, -1, -1), Vec3(1.5, 1, -1), Vec3(1.5, 0, 1));
  const auto verdict = assess(*bvh, {}, *wall, {}).value();
  EXPECT_EQ(verdict.verdict, Verdict::kInconclusive) << verdict.reason;
  // Asked to drop zero-area triangles, the mesh keeps this one: it reaches past the others'
  // edges (x from 1 to 2 is its own), and that is what crosses the wall.
  auto asked_to_drop = TriangleMesh::create(v, {{0, 1, 2}, {0, 1, 3}, {0, 3, 4}}, {true});
  ASSERT_TRUE(asked_to_drop.ok());
  EXPECT_EQ(asked_to_drop.value().triangle_count(), 3u);
  const auto kept = MeshBvh::build(testing::share(asked_to_drop.value())).value();
  EXPECT_EQ(assess(*kept, {}, *wall, {}).value().verdict, Verdict::kInconclusive);
}

}  // namespace
}  // namespace gk
