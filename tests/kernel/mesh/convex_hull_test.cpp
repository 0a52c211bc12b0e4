// Quickhull: every input point lies inside or on every hull face (exact), the hull is a closed,
// outward-wound mesh whose corners are input points, and known hulls have their known volume.
#include "kernel/mesh/convex_hull.h"
#include "kernel/predicates/exact_predicates.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <random>

namespace gk {
namespace {

void expect_hull_of(const TriangleMesh& hull, const std::vector<Vec3>& points) {
  EXPECT_TRUE(hull.is_closed_oriented());
  EXPECT_GT(hull.signed_volume(), 0.0);  // outward winding
  for (const auto& f : hull.faces()) {
    const Vec3 &a = hull.vertices()[f[0]], &b = hull.vertices()[f[1]], &c = hull.vertices()[f[2]];
    for (const Vec3& p : points) ASSERT_LE(exact::orient3d(a, b, c, p), 0) << "a point lies outside a hull face";
  }
  for (const Vec3& v : hull.vertices()) EXPECT_NE(std::find(points.begin(), points.end(), v), points.end());
}

TEST(ConvexHull, RandomCloudsAreEnclosedExactly) {
  testing::Rng rng(8);
  std::normal_distribution<double> g(0.0, 10.0);
  for (int round = 0; round < 30; ++round) {
    std::vector<Vec3> pts;
    const int n = 10 + 20 * round;
    for (int i = 0; i < n; ++i) pts.emplace_back(g(rng), g(rng), g(rng));
    if (round % 3 == 0)
      for (Vec3& p : pts) p += Vec3(5e4, -5e4, 5e4);  // far from the origin
    auto hull = convex_hull(pts);
    ASSERT_TRUE(hull.ok()) << hull.error().to_string();
    expect_hull_of(hull.value(), pts);
  }
}

TEST(ConvexHull, CubeWithInteriorAndFacePointsHasTheCubesVolume) {
  std::vector<Vec3> pts;
  for (int k = 0; k < 8; ++k) pts.emplace_back((k & 1) ? 2.0 : 0.0, (k & 2) ? 2.0 : 0.0, (k & 4) ? 2.0 : 0.0);
  // Interior points, points in the middle of faces and edges (coplanar with hull faces).
  pts.emplace_back(1, 1, 1);
  pts.emplace_back(1, 1, 0);
  pts.emplace_back(2, 1, 1);
  pts.emplace_back(1, 0, 0);
  pts.emplace_back(0.5, 1.5, 2);
  auto hull = convex_hull(pts);
  ASSERT_TRUE(hull.ok());
  expect_hull_of(hull.value(), pts);
  EXPECT_NEAR(hull.value().signed_volume(), 8.0, 1e-12);  // exact corners, rounding only
}

TEST(ConvexHull, PointsOnASphereAllBecomeCorners) {
  testing::Rng rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> pts;
  for (int i = 0; i < 200; ++i) pts.push_back(Vec3(g(rng), g(rng), g(rng)).normalized() * 50.0);
  auto hull = convex_hull(pts);
  ASSERT_TRUE(hull.ok());
  expect_hull_of(hull.value(), pts);
  EXPECT_EQ(hull.value().vertices().size(), 200u);
}

TEST(ConvexHull, DegenerateInputIsAnError) {
  EXPECT_FALSE(convex_hull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}).ok());
  EXPECT_FALSE(convex_hull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0), Vec3(3, 2, 0)}).ok());
  EXPECT_FALSE(convex_hull({Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2), Vec3(3, 3, 3)}).ok());
  auto nan = convex_hull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, std::nan(""))});
  ASSERT_FALSE(nan.ok());
  EXPECT_EQ(nan.error().field, "points[3]");
}

}  // namespace
}  // namespace gk
