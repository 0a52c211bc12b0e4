// Convexity decided exactly (issue: geometry truth §6): a V-groove block and a U-channel have every
// vertex on their hull and were reported convex, so their penetration depth was flagged exact.
#include "kernel/mesh/convexity.h"
#include "kernel/mesh/convex_hull.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/measure/penetration_depth.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <array>

namespace gk {
namespace {

TriangleMesh v_groove_block() {
  // A groove from (4, 10) down to (5, 6) and up to (6, 10), ear-clipped into five triangles.
  const std::vector<Vec2> p = {{0, 0}, {10, 0}, {10, 10}, {6, 10}, {5, 6}, {4, 10}, {0, 10}};
  return testing::prism_mesh(p, {{0, 1, 4}, {1, 2, 3}, {1, 3, 4}, {0, 4, 5}, {0, 5, 6}}, 20.0);
}

TriangleMesh u_channel() { return testing::u_channel_mesh(); }

TEST(Convexity, GroovesAndChannelsAreNotConvexThoughEveryVertexIsOnTheHull) {
  const TriangleMesh groove = v_groove_block();
  const TriangleMesh channel = u_channel();
  ASSERT_TRUE(groove.is_closed_oriented());
  ASSERT_TRUE(channel.is_closed_oriented());
  EXPECT_GT(groove.signed_volume(), 0.0);
  EXPECT_GT(channel.signed_volume(), 0.0);
  EXPECT_FALSE(is_convex_solid(groove));
  EXPECT_FALSE(is_convex_solid(channel));
}

TEST(Convexity, ConvexSolidsAreRecognisedAndEverythingElseIsNot) {
  EXPECT_TRUE(is_convex_solid(testing::box_mesh(Vec3(5e4, 0, 0), Vec3(5e4 + 100, 1, 2))));
  EXPECT_TRUE(is_convex_solid(testing::cylinder_mesh(10.0, 30.0, 64)));
  testing::Rng rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 20; ++i) {
    std::vector<Vec3> points;
    for (int k = 0; k < 200; ++k) points.emplace_back(u(rng), u(rng), u(rng));
    EXPECT_TRUE(is_convex_solid(convex_hull(points).value()));
  }
  // Inward-wound, two bodies, open, and a star-shaped blob with dents.
  const TriangleMesh box = testing::box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
  std::vector<TriangleMesh::Face> inward = box.faces();
  for (auto& f : inward) std::swap(f[1], f[2]);
  EXPECT_FALSE(is_convex_solid(TriangleMesh::create(box.vertices(), inward).value()));
  std::vector<Vec3> two = box.vertices();
  std::vector<TriangleMesh::Face> two_faces = box.faces();
  for (const Vec3& p : box.vertices()) two.push_back(p + Vec3(5, 0, 0));
  for (const auto& f : box.faces()) two_faces.push_back({f[0] + 8, f[1] + 8, f[2] + 8});
  EXPECT_FALSE(is_convex_solid(TriangleMesh::create(two, two_faces).value()));
  std::vector<TriangleMesh::Face> open = box.faces();
  open.pop_back();
  EXPECT_FALSE(is_convex_solid(TriangleMesh::create(box.vertices(), open).value()));
  EXPECT_FALSE(is_convex_solid(testing::random_closed_blob(rng, 3, 10.0, 0.3, Vec3::Zero())));
}

TEST(Convexity, PenetrationDepthIsNotExactForAGroove) {
  auto groove = MeshBvh::build(testing::share(v_groove_block())).value();
  auto box = MeshBvh::build(testing::share(testing::box_mesh(Vec3(0, 0, 0), Vec3(3, 3, 3)))).value();
  // A small cube sunk into the groove's flank.
  const RigidTransform in_groove = RigidTransform::from_translation(Vec3(5.5, 7.5, 5.0));
  auto d = penetration_vector(*groove, {}, *box, in_groove, 162, 1e-4);
  ASSERT_TRUE(d.ok()) << d.error().to_string();
  EXPECT_GT(d.value().depth_mm, 0.0);
  EXPECT_FALSE(d.value().exact);
  auto convex = MeshBvh::build(testing::share(testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)))).value();
  auto c = penetration_vector(*convex, {}, *box, RigidTransform::from_translation(Vec3(8, 4, 4)), 162, 1e-4);
  ASSERT_TRUE(c.ok());
  EXPECT_TRUE(c.value().exact);
  EXPECT_NEAR(c.value().depth_mm, 2.0, 1e-3);  // x from 8 to 10 inside the block
}

}  // namespace
}  // namespace gk
