// Settled group pairs (kernel/query/settled_pairs.h): a query skips the triangle pairs of groups a
// caller has decided, and nothing else. Checked against brute force over every triangle pair, on
// random soups and blobs with random groups: pairs_within lists exactly the pairs within reach
// that are not settled, and finds a witness exactly when a settled pair is within reach; collide
// reports exactly the crossing pairs that are not settled; a distance query leaving them out finds
// the nearest of the others. The tree labels equal their subtrees'.
#include "kernel/bvh/triangle_groups.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "kernel/query/settled_pairs.h"
#include "kernel/query/triangle_distance.h"
#include "kernel/query/triangle_intersection.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

namespace gk {
namespace {

// Random groups 0..groups-1 (or none), in spatial runs so that subtrees are often pure.
std::vector<std::int32_t> random_groups(const TriangleMesh& mesh, testing::Rng& rng, int groups) {
  std::vector<std::int32_t> out(mesh.triangle_count());
  std::uniform_int_distribution<int> pick(-1, groups - 1);
  const Vec3 axis = testing::random_pose(rng, 1.0).rotation.col(0);
  const Triangle t0 = mesh.triangle(0);
  const double step = 0.5 + 2.0 * std::uniform_real_distribution<double>(0, 1)(rng);
  std::vector<int> band_group(4096);
  for (int& g : band_group) g = pick(rng);
  for (std::uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const double along = axis.dot(mesh.triangle(t)[0] - t0[0]) / step;
    out[t] = band_group[static_cast<std::size_t>(std::abs(static_cast<long>(std::floor(along)))) % band_group.size()];
  }
  return out;
}

TEST(TriangleGroups, ANodesLabelIsWhatItsSubtreeHolds) {
  testing::Rng rng(11);
  for (int round = 0; round < 20; ++round) {
    auto mesh = testing::share(testing::random_closed_blob(rng, 4, 10.0, 0.3, Vec3::Zero()));
    auto tree = MeshBvh::build(mesh).value();
    const auto group_of = random_groups(*mesh, rng, 3);
    const TriangleGroups groups = TriangleGroups::label(*tree, group_of).value();
    ASSERT_TRUE(groups.labels(*tree));
    for (int n = 0; n < tree->node_count(); ++n) {
      // The subtree's triangles: pre-order, so the leaves from n up to its last descendant.
      std::set<std::int32_t> held;
      std::vector<int> stack = {n};
      while (!stack.empty()) {
        const int m = stack.back();
        stack.pop_back();
        const BvhNode& node = tree->node(m);
        if (node.is_leaf()) {
          for (int k = node.first_triangle(); k <= node.last_triangle(); ++k) {
            EXPECT_EQ(groups.of_ordered_triangle(k), group_of[tree->mesh_triangle_index(k)]);
            held.insert(group_of[tree->mesh_triangle_index(k)]);
          }
        } else {
          stack.push_back(m + 1);
          stack.push_back(node.second_child());
        }
      }
      const TriangleGroups::NodeGroups label = groups.of_node(n);
      if (held.count(TriangleGroups::kNone) || held.size() > 2) {
        EXPECT_EQ(label.first, TriangleGroups::kNone) << "node " << n;
      } else {
        EXPECT_EQ(std::set<std::int32_t>({label.first, label.second}), held) << "node " << n;
      }
    }
  }
  auto mesh = testing::share(testing::box_mesh(Vec3::Zero(), Vec3::Ones()));
  auto tree = MeshBvh::build(mesh).value();
  EXPECT_FALSE(TriangleGroups::label(*tree, std::vector<std::int32_t>(5, 0)).ok()) << "one entry per triangle";
  EXPECT_FALSE(TriangleGroups::label(*tree, std::vector<std::int32_t>(12, -2)).ok());
}

TEST(SettledPairs, QueriesSkipExactlyTheSettledPairs) {
  testing::Rng rng(23);
  int witnesses = 0, without = 0, skipped_contacts = 0;
  for (int round = 0; round < 60; ++round) {
    const bool soups = round % 2 == 0;
    auto mesh_a = testing::share(soups ? testing::random_soup(rng, 300, 6.0, 2.0) : testing::random_closed_blob(rng, 3, 6.0, 0.4, Vec3::Zero()));
    auto mesh_b = testing::share(soups ? testing::random_soup(rng, 300, 6.0, 2.0) : testing::random_closed_blob(rng, 3, 6.0, 0.4, Vec3::Zero()));
    auto tree_a = MeshBvh::build(mesh_a).value();
    auto tree_b = MeshBvh::build(mesh_b).value();
    const auto of_a = random_groups(*mesh_a, rng, 3), of_b = random_groups(*mesh_b, rng, 3);
    const TriangleGroups groups_a = TriangleGroups::label(*tree_a, of_a).value();
    const TriangleGroups groups_b = TriangleGroups::label(*tree_b, of_b).value();
    SettledPairs settled{&groups_a, &groups_b, {{0, 0}, {1, 2}, {2, 1}}, {}, std::nullopt};
    if (round % 3 == 0) settled.hint = Vec3(1, 2, 3);
    const auto is_settled = [&](std::uint32_t ta, std::uint32_t tb) {
      for (const auto& [x, y] : settled.groups)
        if (of_a[ta] == x && of_b[tb] == y) return true;
      return false;
    };
    const RigidTransform pose_a = testing::random_pose(rng, 3.0);
    RigidTransform pose_b = testing::random_pose(rng, 3.0);
    if (round % 4 == 1) pose_b.translation = pose_a.translation + Vec3(11.0, 0.0, 0.0);  // barely reaching each other
    const double delta = std::uniform_real_distribution<double>(0.0, 0.5)(rng);

    // Brute force over every pair, in world coordinates.
    std::set<std::pair<std::uint32_t, std::uint32_t>> near_open, crossing_open;
    bool settled_near = false;
    double nearest_open = std::numeric_limits<double>::infinity();
    // Also left out one by one (DistanceRequest::excluded_pair): pairs whose triangle ids sum to a
    // multiple of 3, judged on the ids alone.
    const auto left_out = [](std::uint32_t ta, std::uint32_t tb) { return (ta + tb) % 3 == 0; };
    double nearest_kept = std::numeric_limits<double>::infinity();
    for (std::uint32_t ta = 0; ta < mesh_a->triangle_count(); ++ta)
      for (std::uint32_t tb = 0; tb < mesh_b->triangle_count(); ++tb) {
        Triangle x = mesh_a->triangle(ta), y = mesh_b->triangle(tb);
        for (Vec3& p : x) p = pose_a.apply(p);
        for (Vec3& p : y) p = pose_b.apply(p);
        const double d = triangle_distance(x, y).distance;
        if (!is_settled(ta, tb)) nearest_open = std::min(nearest_open, d);
        if (!is_settled(ta, tb) && !left_out(ta, tb)) nearest_kept = std::min(nearest_kept, d);
        // Pairs within rounding of delta either way are left out of the comparison.
        if (std::abs(d - delta) < 1e-9) continue;
        if (is_settled(ta, tb)) {
          settled_near = settled_near || d < delta;
          continue;
        }
        if (d < delta) near_open.insert({ta, tb});
        if (intersect_triangles(x, y).intersects) crossing_open.insert({ta, tb});
      }

    auto near = pairs_within(*tree_a, pose_a, *tree_b, pose_b, delta, std::numeric_limits<std::size_t>::max(), {}, &settled).value();
    std::set<std::pair<std::uint32_t, std::uint32_t>> listed;
    for (const ProximityPair& p : near.pairs) {
      EXPECT_FALSE(is_settled(p.triangle_a, p.triangle_b)) << "a settled pair listed";
      listed.insert({p.triangle_a, p.triangle_b});
    }
    for (const auto& pair : near_open) EXPECT_TRUE(listed.count(pair)) << "round " << round << ": pair " << pair.first << "," << pair.second << " missed";
    EXPECT_EQ(near.settled_witness.has_value(), settled_near) << "round " << round;
    if (near.settled_witness) {
      EXPECT_TRUE(is_settled(near.settled_witness->triangle_a, near.settled_witness->triangle_b));
      EXPECT_LE(near.settled_witness->distance_mm, delta);
    }
    (settled_near ? witnesses : without)++;

    // A distance query leaving the settled pairs out: the nearest of the others.
    DistanceRequest excluding;
    excluding.excluded = &settled;
    const DistanceResult apart = distance(*tree_a, pose_a, *tree_b, pose_b, excluding).value();
    ASSERT_EQ(apart.found, std::isfinite(nearest_open));
    if (apart.found) {
      EXPECT_NEAR(apart.distance_mm, nearest_open, 1e-9) << "round " << round;
      EXPECT_FALSE(is_settled(apart.triangle_a, apart.triangle_b));
    }
    excluding.excluded_pair = [&](std::uint32_t ta, std::uint32_t tb, const Vec3&, const Vec3&, double) { return left_out(ta, tb); };
    const DistanceResult kept = distance(*tree_a, pose_a, *tree_b, pose_b, excluding).value();
    ASSERT_EQ(kept.found, std::isfinite(nearest_kept));
    if (kept.found) {
      EXPECT_NEAR(kept.distance_mm, nearest_kept, 1e-9) << "round " << round;
      EXPECT_FALSE(left_out(kept.triangle_a, kept.triangle_b));
    }

    CollisionRequest request;
    request.all_contacts = true;
    request.settled = &settled;
    auto met = collide(*tree_a, pose_a, *tree_b, pose_b, request).value();
    std::set<std::pair<std::uint32_t, std::uint32_t>> reported;
    for (const Contact& c : met.contacts) {
      EXPECT_FALSE(is_settled(c.triangle_a, c.triangle_b)) << "a settled contact reported";
      reported.insert({c.triangle_a, c.triangle_b});
    }
    EXPECT_EQ(reported, crossing_open) << "round " << round;
    request.settled = nullptr;
    skipped_contacts += static_cast<int>(collide(*tree_a, pose_a, *tree_b, pose_b, request).value().contacts.size() - met.contacts.size());
  }
  // Both outcomes were exercised, and settled contacts were there to skip.
  EXPECT_GT(witnesses, 5);
  EXPECT_GT(without, 5);
  EXPECT_GT(skipped_contacts, 10);
}

TEST(SettledPairs, LabelsMadeForAnotherTreeAreRefused) {
  testing::Rng rng(5);
  auto mesh = testing::share(testing::random_closed_blob(rng, 2, 5.0, 0.2, Vec3::Zero()));
  auto other = testing::share(testing::random_closed_blob(rng, 3, 5.0, 0.2, Vec3::Zero()));
  auto tree = MeshBvh::build(mesh).value();
  auto other_tree = MeshBvh::build(other).value();
  const TriangleGroups groups = TriangleGroups::label(*other_tree, std::vector<std::int32_t>(other->triangle_count(), 0)).value();
  SettledPairs settled{&groups, &groups, {{0, 0}}, {}, std::nullopt};
  EXPECT_FALSE(pairs_within(*tree, RigidTransform::identity(), *tree, RigidTransform::identity(), 0.1, 100, {}, &settled).ok());
  CollisionRequest request;
  request.settled = &settled;
  EXPECT_FALSE(collide(*tree, RigidTransform::identity(), *tree, RigidTransform::identity(), request).ok());
}

}  // namespace
}  // namespace gk
