// The OCCT-built tree covers every triangle once, its boxes bound their contents, and a refit after
// the vertices move gives the same answers as a rebuild.
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "tests/support/brute_force.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <unistd.h>

namespace gk {
namespace {

using testing::Rng;

void expect_tree_bounds_triangles(const MeshBvh& bvh) {
  const MeshBvh::NodeView nodes = bvh.nodes();
  std::multiset<std::uint32_t> seen;
  for (int n = 0; n < bvh.node_count(); ++n) {
    const auto& lo = nodes.min_point[n];
    const auto& hi = nodes.max_point[n];
    if (nodes.info[n].x() == 0) continue;
    for (int k = nodes.info[n].y(); k <= nodes.info[n].z(); ++k) {
      seen.insert(bvh.mesh_triangle_index(k));
      for (const Vec3& v : bvh.ordered_triangle(k)) {
        // Boxes are built from the same doubles: containment is exact (tolerance 0).
        EXPECT_LE(lo.x(), v.x());
        EXPECT_LE(lo.y(), v.y());
        EXPECT_LE(lo.z(), v.z());
        EXPECT_GE(hi.x(), v.x());
        EXPECT_GE(hi.y(), v.y());
        EXPECT_GE(hi.z(), v.z());
      }
    }
  }
  ASSERT_EQ(seen.size(), bvh.mesh().triangle_count());
  for (std::uint32_t t = 0; t < bvh.mesh().triangle_count(); ++t) EXPECT_EQ(seen.count(t), 1u) << "triangle " << t;
}

TEST(MeshBvh, EveryTriangleInExactlyOneLeafInsideItsBox) {
  Rng rng(7);
  for (int leaf_size : {1, 4}) {
    auto bvh = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 3, 10.0, 0.3, Vec3::Zero())),
                              {leaf_size});
    ASSERT_TRUE(bvh.ok());
    expect_tree_bounds_triangles(*bvh.value());
    EXPECT_LE(bvh.value()->depth(), 32);
  }
}

TEST(MeshBvh, InvalidOptionsAreErrors) {
  Rng rng(1);
  auto mesh = testing::share(testing::random_soup(rng, 10, 5.0, 1.0));
  auto bad = MeshBvh::build(mesh, {0});
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().field, "leaf_size");
  EXPECT_FALSE(MeshBvh::build(nullptr).ok());
}

TEST(MeshBvh, RefitAfterDeformationAnswersLikeARebuild) {
  Rng rng(11);
  const auto obstacle = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 2, 8.0, 0.4, Vec3::Zero()))).value();
  auto original = testing::random_closed_blob(rng, 2, 8.0, 0.4, Vec3::Zero());
  auto refitted = MeshBvh::build(testing::share(original)).value();
  std::normal_distribution<double> jitter(0.0, 1.5);
  for (int round = 0; round < 20; ++round) {
    std::vector<Vec3> moved = original.vertices();
    for (Vec3& v : moved) v += Vec3(jitter(rng), jitter(rng), jitter(rng));
    TriangleMesh deformed = original;
    ASSERT_TRUE(deformed.set_vertices(moved).ok());
    auto shared = testing::share(deformed);
    refitted->refit(shared);
    expect_tree_bounds_triangles(*refitted);
    const auto rebuilt = MeshBvh::build(shared).value();
    const RigidTransform pose = testing::random_pose(rng, 12.0);
    CollisionRequest all;
    all.all_contacts = true;
    const auto c1 = collide(*obstacle, RigidTransform{}, *refitted, pose, all).value();
    const auto c2 = collide(*obstacle, RigidTransform{}, *rebuilt, pose, all).value();
    ASSERT_EQ(c1.contacts.size(), c2.contacts.size());
    for (std::size_t i = 0; i < c1.contacts.size(); ++i) {
      EXPECT_EQ(c1.contacts[i].triangle_a, c2.contacts[i].triangle_a);
      EXPECT_EQ(c1.contacts[i].triangle_b, c2.contacts[i].triangle_b);
    }
    const auto d1 = distance(*obstacle, RigidTransform{}, *refitted, pose).value();
    const auto d2 = distance(*obstacle, RigidTransform{}, *rebuilt, pose).value();
    EXPECT_EQ(d1.distance_mm, d2.distance_mm);  // the same minimum pair: bit-identical
  }
}

}  // namespace
}  // namespace gk

namespace gk {
namespace {

TEST(MeshBvhSerialization, ARoundTripAnswersLikeTheBuiltTreeAndDamageIsRefused) {
  testing::Rng rng(21);
  auto mesh = testing::share(testing::random_closed_blob(rng, 4, 40.0, 0.3, Vec3::Zero()));
  const auto built = MeshBvh::build(mesh).value();
  const std::string bytes = built->serialize();
  const auto loaded = MeshBvh::deserialize(mesh, bytes).value();
  EXPECT_EQ(loaded->node_count(), built->node_count());
  EXPECT_EQ(loaded->depth(), built->depth());
  const auto other = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 3, 30.0, 0.3, Vec3::Zero()))).value();
  for (int i = 0; i < 50; ++i) {
    const RigidTransform pose = testing::random_pose(rng, 70.0);
    EXPECT_EQ(distance(*built, {}, *other, pose).value().distance_mm, distance(*loaded, {}, *other, pose).value().distance_mm);
    CollisionRequest all;
    all.all_contacts = true;
    EXPECT_EQ(collide(*built, {}, *other, pose, all).value().contacts.size(), collide(*loaded, {}, *other, pose, all).value().contacts.size());
  }
  // Truncated, foreign, or damaged bytes: an error, or (a damage that changes nothing a query
  // relies on) a tree that still bounds every triangle; never a crash.
  EXPECT_FALSE(MeshBvh::deserialize(mesh, bytes.substr(0, bytes.size() - 1)).ok());
  EXPECT_FALSE(MeshBvh::deserialize(mesh, "not a tree").ok());
  EXPECT_FALSE(MeshBvh::deserialize(other->mesh().triangle_count() == mesh->triangle_count() ? nullptr : testing::share(other->mesh()), bytes).ok());
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string damaged = bytes;
    const std::size_t at = 8 + std::uniform_int_distribution<std::size_t>(0, damaged.size() - 9)(rng);
    damaged[at] = static_cast<char>(damaged[at] ^ (1 << (trial % 8)));
    auto result = MeshBvh::deserialize(mesh, damaged);
    if (!result.ok()) {
      ++refused;
      continue;
    }
    const RigidTransform pose = testing::random_pose(rng, 70.0);
    EXPECT_EQ(distance(*result.value(), {}, *other, pose).value().distance_mm, distance(*built, {}, *other, pose).value().distance_mm);
  }
  EXPECT_GT(refused, 100);
}

}  // namespace
}  // namespace gk
