// The tree covers every triangle once, its float boxes bound their triangles' double coordinates
// (also at factory coordinates, where float spacing is millimetres' hundredths), and a refit after
// the vertices move gives the same answers as a rebuild.
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/tolerances.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "tests/support/brute_force.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <unistd.h>

namespace gk {
namespace {

using testing::Rng;

void expect_tree_bounds_triangles(const MeshBvh& bvh) {
  std::multiset<std::uint32_t> seen;
  for (int n = 0; n < bvh.node_count(); ++n) {
    const BvhNode& node = bvh.node(n);
    if (!node.is_leaf()) {
      // Children inside their parent, compared in double (tolerance 0).
      for (int child : {n + 1, node.second_child()})
        for (int a = 0; a < 3; ++a) {
          EXPECT_LE(double{node.lo[a]}, double{bvh.node(child).lo[a]});
          EXPECT_GE(double{node.hi[a]}, double{bvh.node(child).hi[a]});
        }
      continue;
    }
    for (int k = node.first_triangle(); k <= node.last_triangle(); ++k) {
      seen.insert(bvh.mesh_triangle_index(k));
      // The tree's copy of the corners is the mesh's triangle, bit for bit.
      EXPECT_EQ(bvh.ordered_triangle(k), bvh.mesh().triangle(bvh.mesh_triangle_index(k)));
      for (const Vec3& v : bvh.mesh().triangle(bvh.mesh_triangle_index(k)))
        for (int a = 0; a < 3; ++a) {
          // Float boxes rounded outward from the doubles: containment is exact (tolerance 0).
          EXPECT_LE(double{node.lo[a]}, v[a]);
          EXPECT_GE(double{node.hi[a]}, v[a]);
        }
    }
  }
  ASSERT_EQ(seen.size(), bvh.mesh().triangle_count());
  for (std::uint32_t t = 0; t < bvh.mesh().triangle_count(); ++t) EXPECT_EQ(seen.count(t), 1u) << "triangle " << t;
}

// How many triangles lie under node n (leaves' ranges are contiguous in pre-order).
std::size_t subtree_triangles(const MeshBvh& tree, int n) {
  int first = n, last = n;
  while (!tree.node(first).is_leaf()) first = first + 1;
  while (!tree.node(last).is_leaf()) last = tree.node(last).second_child();
  return static_cast<std::size_t>(tree.node(last).last_triangle() - tree.node(first).first_triangle() + 1);
}

TEST(MeshBvh, EveryTriangleInExactlyOneLeafInsideItsBox) {
  Rng rng(7);
  for (int leaf_size : {1, 4}) {
    auto bvh = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 3, 10.0, 0.3, Vec3::Zero())),
                              {leaf_size});
    ASSERT_TRUE(bvh.ok());
    expect_tree_bounds_triangles(*bvh.value());
    EXPECT_LE(bvh.value()->depth(), kMaxBvhDepth + 1);
  }
}

// Built with a key per triangle (a feature's group, say): every node of at most key_split_at
// triangles holds one key, the tree still holds every triangle once inside its boxes, many keys
// keep it shallow, and it answers as the tree built on space alone (brute force).
TEST(MeshBvh, KeyedTreesHoldOneKeyInEverySmallNode) {
  Rng rng(11);
  const auto blob = testing::share(testing::random_closed_blob(rng, 3, 10.0, 0.3, Vec3::Zero()));
  const auto other = testing::share(testing::random_closed_blob(rng, 2, 6.0, 0.3, Vec3::Zero()));
  for (const int key_count : {2, 5, 300}) {
    for (const std::size_t split_at : {std::size_t{16}, std::size_t{1024}, std::size_t{1} << 40}) {
      // Keys by place (a band of the blob) and by chance, and one key of every tenth triangle left out.
      std::vector<std::int32_t> keys(blob->triangle_count());
      for (std::size_t t = 0; t < keys.size(); ++t)
        keys[t] = t % 10 == 0 ? -1 : static_cast<std::int32_t>((static_cast<std::size_t>(std::floor(blob->triangle(t)[0].x() + 20.0)) * 7 + t % 3) % key_count);
      BvhBuildOptions options;
      options.keys = &keys;
      options.key_split_at = split_at;
      auto keyed = MeshBvh::build(blob, options);
      ASSERT_TRUE(keyed.ok());
      const MeshBvh& tree = *keyed.value();
      expect_tree_bounds_triangles(tree);
      EXPECT_LE(tree.depth(), kMaxBvhDepth + 1);
      EXPECT_LE(tree.depth(), 40) << key_count << " keys: parted half by half, not one by one";
      // The keys under each node (pre-order: children after their parent). A node of at most
      // split_at triangles and several keys parts them, no key on both sides, so that every node
      // below it holds one; above split_at space decides.
      std::vector<std::set<std::int32_t>> under(static_cast<std::size_t>(tree.node_count()));
      for (int n = tree.node_count() - 1; n >= 0; --n) {
        const BvhNode& node = tree.node(n);
        std::set<std::int32_t>& mine = under[static_cast<std::size_t>(n)];
        if (node.is_leaf()) {
          for (int k = node.first_triangle(); k <= node.last_triangle(); ++k) mine.insert(keys[tree.mesh_triangle_index(k)]);
          EXPECT_EQ(mine.size(), 1u) << "leaf " << n << " mixes keys";
          continue;
        }
        const std::set<std::int32_t>& left = under[static_cast<std::size_t>(n + 1)];
        const std::set<std::int32_t>& right = under[static_cast<std::size_t>(node.second_child())];
        mine = left;
        mine.insert(right.begin(), right.end());
        if (mine.size() > 1 && subtree_triangles(tree, n) <= split_at) {
          EXPECT_EQ(left.size() + right.size(), mine.size()) << "node " << n << " has a key on both sides";
        }
      }
      auto plain = MeshBvh::build(other).value();
      for (int i = 0; i < 8; ++i) {
        const RigidTransform pose = testing::random_pose(rng, 12.0);
        auto d = distance(tree, RigidTransform::identity(), *plain, pose);
        ASSERT_TRUE(d.ok());
        EXPECT_NEAR(d.value().distance_mm, testing::brute_force_distance(*blob, RigidTransform::identity(), *other, pose), 1e-9);
        CollisionRequest all;
        all.all_contacts = true;
        auto c = collide(tree, RigidTransform::identity(), *plain, pose, all);
        ASSERT_TRUE(c.ok());
        EXPECT_EQ(c.value().contacts.size(), testing::brute_force_contacts(*blob, RigidTransform::identity(), *other, pose).size());
      }
    }
  }
  std::vector<std::int32_t> short_keys(3, 0);
  BvhBuildOptions bad;
  bad.keys = &short_keys;
  auto refused = MeshBvh::build(blob, bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().field, "keys");
}

// Coordinates no float can hold: at 25,000 mm floats are 2 um apart, so a box rounded to nearest
// would cut off up to 1 um of a triangle. Jittered meshes at factory offsets, and corners placed
// just beside float values on both sides.
TEST(MeshBvh, FloatBoxesHoldDoubleCoordinatesAtFactoryOffsets) {
  Rng rng(11);
  for (double offset : {0.0, 25000.0, -25000.0, 1.0e6, 9.9e6}) {
    for (int leaf_size : {1, 4, 7}) {
      auto blob = testing::random_closed_blob(rng, 3, 10.0, 0.3, Vec3(offset, -offset / 3.0, offset / 7.0));
      auto bvh = MeshBvh::build(testing::share(blob), {leaf_size});
      ASSERT_TRUE(bvh.ok());
      expect_tree_bounds_triangles(*bvh.value());
    }
    std::vector<Vec3> vertices;
    std::vector<TriangleMesh::Face> faces;
    std::uniform_real_distribution<double> around(-50.0, 50.0);
    for (int i = 0; i < 300; ++i) {
      const float f = static_cast<float>(offset + around(rng));
      const double beside = std::nextafter(static_cast<double>(f), i % 2 ? 1e300 : -1e300);
      const auto base = static_cast<std::uint32_t>(vertices.size());
      vertices.push_back(Vec3(beside, static_cast<double>(f), -beside));
      vertices.push_back(Vec3(beside + 1e-9, static_cast<double>(f) + 1.0, -beside));
      vertices.push_back(Vec3(beside, static_cast<double>(f), -beside - 1e-9 * (i % 3)));
      faces.push_back({base, base + 1, base + 2});
    }
    auto mesh = TriangleMesh::create(vertices, faces);
    ASSERT_TRUE(mesh.ok());
    auto bvh = MeshBvh::build(testing::share(std::move(mesh).value()));
    ASSERT_TRUE(bvh.ok());
    expect_tree_bounds_triangles(*bvh.value());
  }
}

// Every corner of every triangle under a node lies within the node's slab, computed here in long
// double from the corner's own coordinates; the queries allow kBoxSlackRelative of the largest
// coordinate for their own rounding, so that is the only tolerance. Also after a refit, and not at
// all (no slabs) for a mesh below kMinTrianglesForSlabs.
void expect_slabs_hold_their_corners(const MeshBvh& bvh) {
  const NodeSlab* slabs = bvh.node_slabs();
  ASSERT_NE(slabs, nullptr);
  const Aabb bounds = bvh.root_bounds();
  const long double slack =
      tolerances::kBoxSlackRelative * std::max({bounds.min.cwiseAbs().maxCoeff(), bounds.max.cwiseAbs().maxCoeff(), 1.0});
  for (int n = 0; n < bvh.node_count(); ++n) {
    const NodeSlab& slab = slabs[n];
    EXPECT_LE(slab.direction().norm(), kSlabNormalMaxLength);
    EXPECT_LE(slab.lo, slab.hi);
    const BvhNode& node = bvh.node(n);
    const long double centre[3] = {0.5L * ((long double)node.lo[0] + node.hi[0]), 0.5L * ((long double)node.lo[1] + node.hi[1]),
                                   0.5L * ((long double)node.lo[2] + node.hi[2])};
    std::vector<int> stack{n};
    while (!stack.empty()) {
      const BvhNode& sub = bvh.node(stack.back());
      const int m = stack.back();
      stack.pop_back();
      if (!sub.is_leaf()) {
        stack.push_back(m + 1);
        stack.push_back(sub.second_child());
        continue;
      }
      for (int k = sub.first_triangle(); k <= sub.last_triangle(); ++k)
        for (const Vec3& v : bvh.mesh().triangle(bvh.mesh_triangle_index(k))) {
          long double s = 0.0L;
          for (int a = 0; a < 3; ++a) s += (long double)slab.normal[a] * ((long double)v[a] - centre[a]);
          EXPECT_GE(s, (long double)slab.lo - slack) << "node " << n;
          EXPECT_LE(s, (long double)slab.hi + slack) << "node " << n;
        }
    }
  }
}

TEST(MeshBvh, NodeSlabsHoldEveryCornerOfTheirTrianglesAtFactoryOffsets) {
  Rng rng(12);
  for (double offset : {0.0, 25000.0, -25000.0, 1.0e6, 9.9e6}) {
    // 8,192 triangles (five subdivisions): above kMinTrianglesForSlabs.
    auto blob = testing::random_closed_blob(rng, 5, 40.0, 0.3, Vec3(offset, -offset / 3.0, offset / 7.0));
    ASSERT_GE(blob.triangle_count(), MeshBvh::kMinTrianglesForSlabs);
    for (int leaf_size : {1, 4, 7}) {
      auto bvh = MeshBvh::build(testing::share(blob), {leaf_size}).value();
      expect_slabs_hold_their_corners(*bvh);
    }
  }
  // A flat sheet (every slab at its thinnest) and a soup of needles in all directions.
  std::vector<Vec3> vertices;
  std::vector<TriangleMesh::Face> faces;
  const int side = 50;
  for (int i = 0; i <= side; ++i)
    for (int j = 0; j <= side; ++j) vertices.push_back(Vec3(1.0e6 + 3.0 * i, 2.0 * j + 0.01 * i * j, 0.7 * i - 0.3 * j));
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const auto v = static_cast<std::uint32_t>(i * (side + 1) + j);
      faces.push_back({v, v + 1, v + side + 1});
      faces.push_back({v + 1, v + side + 2, v + side + 1});
    }
  expect_slabs_hold_their_corners(*MeshBvh::build(testing::share(TriangleMesh::create(vertices, faces).value())).value());
  expect_slabs_hold_their_corners(*MeshBvh::build(testing::share(testing::random_soup(rng, 5000, 300.0, 40.0))).value());
  // Below the size: none.
  EXPECT_EQ(MeshBvh::build(testing::share(testing::random_soup(rng, 4000, 300.0, 4.0))).value()->node_slabs(), nullptr);
}

TEST(MeshBvh, NodeSlabsAreFittedAgainAfterARefit) {
  Rng rng(13);
  auto original = testing::random_closed_blob(rng, 5, 40.0, 0.3, Vec3::Zero());
  auto bvh = MeshBvh::build(testing::share(original)).value();
  expect_slabs_hold_their_corners(*bvh);
  std::vector<Vec3> moved = original.vertices();
  std::normal_distribution<double> jitter(0.0, 4.0);
  for (Vec3& v : moved) v += Vec3(jitter(rng), jitter(rng), jitter(rng));
  auto mesh = original;
  ASSERT_TRUE(mesh.set_vertices(moved).ok());
  bvh->refit(testing::share(std::move(mesh)));
  expect_slabs_hold_their_corners(*bvh);
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
  auto mesh = testing::share(testing::random_closed_blob(rng, 5, 40.0, 0.3, Vec3::Zero()));
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
