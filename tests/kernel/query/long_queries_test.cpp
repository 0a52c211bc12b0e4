// Long queries end when their caller gives up, and grouping stays linear however densely contacts
// crowd (found by a hostile-client review: a 70k-triangle part against its own copy kept a
// clearance worker busy for about a minute after the client's 1 s deadline, most of it comparing
// 100,000 contact witnesses crowded into a few grid cells pair by pair).
#include "kernel/measure/contact_regions.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/measure/exact_interference_volume.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <random>

namespace gk {
namespace {

std::shared_ptr<const MeshBvh> blob(int subdivisions) {
  testing::Rng rng(7);
  return MeshBvh::build(testing::share(testing::random_closed_blob(rng, subdivisions, 50.0, 0.2, Vec3::Zero()))).value();
}

TEST(LongQueries, EveryTraversalStopsWhenItsCallerGivesUp) {
  auto a = blob(6);  // 32,768 triangles, against its own copy: every triangle touches its twin
  const StopToken gave_up([] { return true; });
  CollisionRequest all;
  all.all_contacts = true;
  all.stop = &gave_up;
  auto collided = collide(*a, {}, *a, {}, all);
  ASSERT_FALSE(collided.ok());
  EXPECT_EQ(collided.error().code, ErrorCode::kStopped);
  DistanceRequest nearest;
  nearest.stop = &gave_up;
  auto measured = distance(*a, {}, *a, RigidTransform::from_translation(Vec3(200, 0, 0)), nearest);
  ASSERT_FALSE(measured.ok());
  EXPECT_EQ(measured.error().code, ErrorCode::kStopped);
  auto near = pairs_within(*a, {}, *a, {}, 1.0, std::numeric_limits<std::size_t>::max(), gave_up);
  ASSERT_FALSE(near.ok());
  EXPECT_EQ(near.error().code, ErrorCode::kStopped);
  VerdictOptions options;
  options.stop = &gave_up;
  auto verdict = assess(*a, {}, *a, {}, options);
  ASSERT_FALSE(verdict.ok());
  EXPECT_EQ(verdict.error().code, ErrorCode::kStopped);
  // The exact corefinement too (CGAL's, stopped from its visitor): once from the first step, and not
  // at all when nobody asks.
  auto small = blob(3);
  const RigidTransform shifted = RigidTransform::from_translation(Vec3(30, 5, 2));
  auto exact = exact_interference_volume(small->mesh(), {}, small->mesh(), shifted, gave_up);
  ASSERT_FALSE(exact.ok());
  EXPECT_EQ(exact.error().code, ErrorCode::kStopped) << exact.error().to_string();
  auto answered = exact_interference_volume(small->mesh(), {}, small->mesh(), shifted);
  ASSERT_TRUE(answered.ok()) << answered.error().to_string();
  EXPECT_GT(answered.value().volume_mm3, 0.0);
  // Not asked to stop, the same queries answer.
  EXPECT_TRUE(collide(*a, {}, *a, {}, CollisionRequest{}).ok());
}

// 200,000 witnesses in a 1 mm cube, merged within 5 mm: one region, in linear time; and the
// grouping still equals single linkage on a sparse set (two clusters 5.0 and 5.0001 mm apart).
TEST(LongQueries, ContactRegionsOfCrowdedWitnessesAreGroupedInLinearTime) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<ProximityPair> crowded(200000);
  for (std::size_t i = 0; i < crowded.size(); ++i) {
    crowded[i].triangle_a = static_cast<std::uint32_t>(i);
    crowded[i].triangle_b = static_cast<std::uint32_t>(i);
    crowded[i].point_a = crowded[i].point_b = Vec3(unit(rng), unit(rng), unit(rng));
  }
  EXPECT_EQ(group_into_regions(crowded, 5.0).size(), 1u);
  for (double apart : {5.0, 5.0001}) {
    std::vector<ProximityPair> two(2);
    two[1].triangle_a = two[1].triangle_b = 1;
    two[1].point_a = Vec3(apart * 0.6, apart * 0.8, 0.0);
    EXPECT_EQ(group_into_regions(two, 5.0).size(), apart <= 5.0 ? 1u : 2u) << apart;
  }
}

}  // namespace
}  // namespace gk
