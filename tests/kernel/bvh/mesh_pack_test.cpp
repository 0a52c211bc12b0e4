// A packed mesh (kernel/bvh/mesh_pack) reads back as the same triangles with a tree that answers
// like the original's (checked against brute force over every triangle pair of the original: the
// proper triangles' contacts and the distance), and
// damaged, truncated or foreign bytes are an error, never a mesh.
#include "kernel/bvh/mesh_pack.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "tests/support/brute_force.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

namespace gk {
namespace {

using testing::Rng;

// The triangles as sorted lists of corner coordinates: equal whatever the numbering.
std::vector<std::array<double, 9>> triangle_set(const TriangleMesh& mesh) {
  std::vector<std::array<double, 9>> out;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Triangle tri = mesh.triangle(t);
    std::array<double, 9> c{};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) c[static_cast<std::size_t>(3 * k + a)] = tri[static_cast<std::size_t>(k)][a];
    out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::shared_ptr<const MeshBvh>> sample_meshes() {
  Rng rng(11);
  std::vector<TriangleMesh> meshes;
  meshes.push_back(testing::random_closed_blob(rng, 4, 50.0, 0.4, Vec3(5e6, -3e6, 1e3)));  // factory coordinates
  meshes.push_back(testing::random_soup(rng, 400, 100.0, 30.0));                         // open, many bodies
  std::vector<Vec3> v = testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)).vertices();
  std::vector<TriangleMesh::Face> f = testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)).faces();
  v.push_back(Vec3(20, 0, 0));
  v.push_back(Vec3(30, 0, 0));
  v.push_back(Vec3(40, 0, 0));  // a zero-area triangle beside a closed box
  f.push_back({8, 9, 10});
  meshes.push_back(TriangleMesh::create(v, f).value());
  std::vector<std::shared_ptr<const MeshBvh>> out;
  for (TriangleMesh& m : meshes) out.push_back(MeshBvh::build(testing::share(std::move(m))).value());
  return out;
}

TEST(MeshPack, AnUnpackedMeshHasTheSameTrianglesAndAnswersAsBruteForceOnTheOriginal) {
  Rng rng(12);
  const auto other = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 3, 40.0, 0.5, Vec3::Zero()))).value();
  for (const auto& original : sample_meshes()) {
    const std::string bytes = pack_mesh_bvh(*original);
    auto unpacked = unpack_mesh_bvh(bytes);
    ASSERT_TRUE(unpacked.ok()) << unpacked.error().to_string();
    const MeshBvh& u = *unpacked.value();
    const TriangleMesh& m = original->mesh();
    EXPECT_EQ(triangle_set(u.mesh()), triangle_set(m));
    EXPECT_EQ(u.mesh().is_closed_oriented(), m.is_closed_oriented());
    EXPECT_EQ(u.mesh().report().boundary_edges, m.report().boundary_edges);
    EXPECT_EQ(u.mesh().body_seeds().size(), m.body_seeds().size());
    EXPECT_EQ(u.mesh().has_degenerate_triangles(), m.has_degenerate_triangles());
    EXPECT_EQ(u.root_bounds().min, original->root_bounds().min);
    EXPECT_EQ(u.root_bounds().max, original->root_bounds().max);
    // In tree order: the tree reads the mesh's own arrays; every leaf box holds its triangles.
    for (int n = 0; n < u.node_count(); ++n) {
      const BvhNode& node = u.node(n);
      if (!node.is_leaf()) continue;
      for (int k = node.first_triangle(); k <= node.last_triangle(); ++k) {
        EXPECT_EQ(u.mesh_triangle_index(k), static_cast<std::uint32_t>(k));
        EXPECT_EQ(u.ordered_triangle(k), u.mesh().triangle(static_cast<std::size_t>(k)));
        for (const Vec3& p : u.ordered_triangle(k))
          for (int a = 0; a < 3; ++a) {
            EXPECT_LE(double{node.lo[a]}, p[a]);
            EXPECT_GE(double{node.hi[a]}, p[a]);
          }
      }
    }
    // Queries on the unpacked tree against brute force on the original mesh.
    const Vec3 centre = original->root_bounds().center();
    for (int i = 0; i < 12; ++i) {
      const RigidTransform pa = RigidTransform::identity();
      RigidTransform pb = testing::random_pose(rng, 30.0);
      pb.translation += centre;
      const auto expected_contacts = testing::brute_force_contacts(m, pa, other->mesh(), pb);
      CollisionRequest all;
      all.all_contacts = true;
      const auto c = collide(u, pa, *other, pb, all);
      ASSERT_TRUE(c.ok());
      // Pairs with a zero-area triangle are reported conservatively by the triangle test and may
      // be proven apart by the boxes first: compared on proper triangles only.
      std::size_t expected_proper = 0, got_proper = 0;
      for (const auto& pair : expected_contacts) expected_proper += m.is_degenerate(pair.first) ? 0 : 1;
      for (const Contact& x : c.value().contacts) got_proper += x.involves_degenerate ? 0 : 1;
      EXPECT_EQ(got_proper, expected_proper) << "pose " << i;
      const auto d = distance(u, pa, *other, pb);
      ASSERT_TRUE(d.ok());
      if (expected_contacts.empty()) {
        EXPECT_EQ(d.value().distance_mm, testing::brute_force_distance(m, pa, other->mesh(), pb)) << "pose " << i;
      }
    }
  }
}

TEST(MeshPack, DamagedTruncatedOrForeignBytesAreAnErrorNeverAMesh) {
  Rng rng(13);
  for (const auto& original : sample_meshes()) {
    const std::string bytes = pack_mesh_bvh(*original);
    ASSERT_TRUE(unpack_mesh_bvh(bytes).ok());
    std::uniform_int_distribution<std::size_t> at(0, bytes.size() - 1);
    for (int i = 0; i < 400; ++i) {  // one bit anywhere: header, arrays, tree or checksum
      std::string damaged = bytes;
      damaged[at(rng)] ^= static_cast<char>(1 << (i % 8));
      EXPECT_FALSE(unpack_mesh_bvh(damaged).ok());
    }
    for (std::size_t cut : {std::size_t{0}, std::size_t{7}, std::size_t{24}, bytes.size() / 2, bytes.size() - 1})
      EXPECT_FALSE(unpack_mesh_bvh(bytes.substr(0, cut)).ok()) << "cut at " << cut;
    EXPECT_FALSE(unpack_mesh_bvh(bytes + '\0').ok());
    std::string other_version = bytes;
    other_version[7] = '0';
    EXPECT_FALSE(unpack_mesh_bvh(other_version).ok());
    EXPECT_FALSE(unpack_mesh_bvh(original->serialize()).ok());  // a bare tree is not a pack
  }
}

}  // namespace
}  // namespace gk
