// A mesh thinned for a report page: at most the asked triangles, every vertex within the
// original's box, and the shape still there (its box nearly the original's), on a real 70k-triangle
// robot base and on a small mesh that is left as it is.
#include "kernel/mesh/display_decimation.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

namespace gk {
namespace {

TEST(DisplayDecimation, AtMostTheAskedTrianglesWithinTheOriginalsBox) {
  const TriangleMesh base =
      mesh_io::read_mesh_file(testing::shared_data("meshes/robots/kuka_kr10r1420/visual/base_link.stl")).value();
  ASSERT_GT(base.triangle_count(), 50000u);
  const Aabb box = base.bounds();
  for (std::size_t budget : {200u, 2000u, 20000u}) {
    const DisplayMesh thin = decimate_for_display(base, budget);
    EXPECT_LE(thin.triangles.size(), budget);
    EXPECT_GT(thin.triangles.size(), budget / 10) << "thinned far more than asked";
    Aabb got;
    for (const Vec3& v : thin.vertices) {
      EXPECT_TRUE(box.contains(Aabb{v, v}));
      got.extend(v);
    }
    // Cell means pull the box in by at most a cell: a few percent of the size at these budgets.
    EXPECT_LT((got.max - box.max).norm() + (got.min - box.min).norm(), 0.2 * (box.max - box.min).norm()) << budget;
    for (const auto& t : thin.triangles)
      for (std::uint32_t i : t) EXPECT_LT(i, thin.vertices.size());
  }
  const TriangleMesh cube = testing::box_mesh(Vec3::Zero(), Vec3(1, 1, 1));
  const DisplayMesh same = decimate_for_display(cube, 100);
  EXPECT_EQ(same.triangles.size(), cube.triangle_count());
  EXPECT_EQ(same.vertices, cube.vertices());
}

}  // namespace
}  // namespace gk
