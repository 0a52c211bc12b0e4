// TriangleMesh validation, degeneracy reporting, topology analysis, area and volume.
#include "kernel/mesh/triangle_mesh.h"

#include "kernel/core/tolerances.h"
#include "tests/support/random_meshes.h"
#include "kernel/core/units.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace gk {
namespace {

using Face = TriangleMesh::Face;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

const std::vector<Vec3> kTetraVertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
const std::vector<Face> kTetraFaces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};  // outward

// The error of a build that must fail, with its code checked.
Error build_error(std::vector<Vec3> vertices, std::vector<Face> faces) {
  const Result<TriangleMesh> result = TriangleMesh::create(std::move(vertices), std::move(faces));
  EXPECT_FALSE(result.ok());
  if (result.ok()) return {};
  EXPECT_EQ(result.error().code, ErrorCode::kInvalidArgument);
  EXPECT_FALSE(result.error().message.empty());
  return result.error();
}

std::vector<Vec3> with(std::vector<Vec3> vertices, std::size_t index, int axis, double value) {
  vertices[index][axis] = value;
  return vertices;
}

// The box mesh's vertices and faces, to edit (box_mesh itself returns a built mesh).
std::pair<std::vector<Vec3>, std::vector<Face>> box_parts(const Vec3& lo, const Vec3& hi) {
  const TriangleMesh box = testing::box_mesh(lo, hi);
  return {box.vertices(), box.faces()};
}

// ---------------------------------------------------------------------------------------------
// Errors.

TEST(TriangleMesh, ValidTetrahedronBuilds) {
  const Result<TriangleMesh> mesh = TriangleMesh::create(kTetraVertices, kTetraFaces);
  ASSERT_TRUE(mesh.ok()) << mesh.error().to_string();
  EXPECT_EQ(mesh.value().triangle_count(), 4u);
  EXPECT_EQ(mesh.value().vertices().size(), 4u);
  EXPECT_TRUE(mesh.value().is_closed_oriented());
  EXPECT_FALSE(mesh.value().has_degenerate_triangles());
  EXPECT_TRUE(mesh.value().report().zero_area_triangles.empty());
  // Volume 1/6, area 3/2 + sqrt(3)/2 (1e-15 relative: a handful of roundings).
  EXPECT_NEAR(mesh.value().signed_volume(), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(mesh.value().area(), 1.5 + std::sqrt(3.0) / 2.0, 1e-15 * 3.0);
}

TEST(TriangleMesh, EmptyInputsAreErrors) {
  EXPECT_EQ(build_error({}, kTetraFaces).field, "vertices");
  EXPECT_EQ(build_error(kTetraVertices, {}).field, "triangles");
}

TEST(TriangleMesh, NonFiniteCoordinatesNameTheElement) {
  EXPECT_EQ(build_error(with(kTetraVertices, 1, 1, kNaN), kTetraFaces).field, "vertices[1].y");
  EXPECT_EQ(build_error(with(kTetraVertices, 2, 2, kInf), kTetraFaces).field, "vertices[2].z");
  EXPECT_EQ(build_error(with(kTetraVertices, 0, 0, -kInf), kTetraFaces).field, "vertices[0].x");
  EXPECT_EQ(build_error(with(kTetraVertices, 3, 0, kNaN), kTetraFaces).field, "vertices[3].x");
}

TEST(TriangleMesh, CoordinatesBeyondTheRangeAreErrors) {
  const double limit = tolerances::kMaxCoordinateMm;
  const double beyond = std::nextafter(limit, kInf);
  EXPECT_EQ(build_error(with(kTetraVertices, 2, 1, beyond), kTetraFaces).field, "vertices[2].y");
  EXPECT_EQ(build_error(with(kTetraVertices, 3, 2, -beyond), kTetraFaces).field, "vertices[3].z");
  EXPECT_EQ(build_error(with(kTetraVertices, 1, 0, 2.0 * limit), kTetraFaces).field, "vertices[1].x");
  // The limit itself is accepted.
  std::vector<Vec3> far = kTetraVertices;
  for (Vec3& v : far) v.x() += limit - 1.0;
  const Result<TriangleMesh> at_limit = TriangleMesh::create(far, kTetraFaces);
  EXPECT_TRUE(at_limit.ok()) << at_limit.error().to_string();
}

TEST(TriangleMesh, IndexOutOfRangeNamesTheCorner) {
  std::vector<Face> faces = kTetraFaces;
  faces[0][2] = 4;  // one past the end
  EXPECT_EQ(build_error(kTetraVertices, faces).field, "triangles[0][2]");
  faces = kTetraFaces;
  faces[3][1] = 0xFFFFFFFFu;
  EXPECT_EQ(build_error(kTetraVertices, faces).field, "triangles[3][1]");
  faces = kTetraFaces;
  faces[2][0] = 3;  // the last valid index is fine
  EXPECT_TRUE(TriangleMesh::create(kTetraVertices, faces).ok());
}

// ---------------------------------------------------------------------------------------------
// Zero-area triangles.

TEST(TriangleMesh, ZeroAreaTrianglesAreReportedAndKept) {
  std::vector<Vec3> vertices = kTetraVertices;
  vertices.push_back(Vec3(0.5, 0.25, 0.125));   // 4
  vertices.push_back(Vec3(1.5, 0.75, 0.375));   // 5: exactly 3 x vertex 4
  vertices.push_back(Vec3(0.5, 0.25, 0.125 + 0x1p-40));  // 6: off the line by 2^-40 mm
  std::vector<Face> faces = kTetraFaces;
  faces.push_back({1, 1, 2});  // 4: repeated index
  faces.push_back({0, 4, 5});  // 5: exactly collinear corners
  faces.push_back({0, 6, 5});  // 6: nearly collinear, not degenerate
  const Result<TriangleMesh> built = TriangleMesh::create(vertices, faces);
  ASSERT_TRUE(built.ok()) << built.error().to_string();
  const TriangleMesh& mesh = built.value();
  EXPECT_EQ(mesh.report().zero_area_triangles, (std::vector<std::uint32_t>{4, 5}));
  EXPECT_EQ(mesh.report().dropped_triangles, 0u);
  EXPECT_EQ(mesh.triangle_count(), 7u);
  EXPECT_TRUE(mesh.has_degenerate_triangles());
  EXPECT_TRUE(mesh.is_degenerate(4));
  EXPECT_TRUE(mesh.is_degenerate(5));
  EXPECT_FALSE(mesh.is_degenerate(6));
  EXPECT_FALSE(mesh.is_degenerate(0));
}

// On request, a zero-area triangle whose edges are all edges of triangles with area (a repeated
// index on a tetrahedron's edge; a seam sliver A-M-B filling a T-junction, A-B on one side and
// A-M, M-B on the other) is dropped: its points are on those edges already. A needle with an edge
// of its own (corners off every triangle) is geometry - a wire through a plate - and is kept.
TEST(TriangleMesh, ZeroAreaTrianglesOnOtherTrianglesEdgesAreDroppedOnRequestNeedlesKept) {
  std::vector<Vec3> vertices = kTetraVertices;
  vertices.push_back(Vec3(0.5, 0.25, 0.125));  // 4
  vertices.push_back(Vec3(1.5, 0.75, 0.375));  // 5: on the line through 0 and 4
  std::vector<Face> faces = {{1, 1, 2}, kTetraFaces[0], {0, 4, 5}, kTetraFaces[1], kTetraFaces[2],
                             kTetraFaces[3]};
  const Result<TriangleMesh> built = TriangleMesh::create(vertices, faces, MeshBuildOptions{true});
  ASSERT_TRUE(built.ok()) << built.error().to_string();
  const TriangleMesh& mesh = built.value();
  EXPECT_EQ(mesh.report().zero_area_triangles, (std::vector<std::uint32_t>{0, 2}));  // input indices
  EXPECT_EQ(mesh.report().dropped_triangles, 1u);
  ASSERT_EQ(mesh.triangle_count(), 5u);
  EXPECT_TRUE(mesh.has_degenerate_triangles());
  EXPECT_TRUE(mesh.is_degenerate(1));  // the needle, kept in order
  EXPECT_EQ(mesh.faces()[1], (Face{0, 4, 5}));

  // A square split on one side into two triangles meeting at M (the middle of A-B) and whole on
  // the other, the gap at M filled by the sliver A-M-B: dropped.
  const std::vector<Vec3> seam = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(1, -1, 0)};
  const std::vector<Face> seam_faces = {{0, 2, 3}, {2, 1, 3}, {0, 4, 1}, {0, 2, 1}};
  const Result<TriangleMesh> seamed = TriangleMesh::create(seam, seam_faces, MeshBuildOptions{true});
  ASSERT_TRUE(seamed.ok()) << seamed.error().to_string();
  EXPECT_EQ(seamed.value().report().dropped_triangles, 1u);
  EXPECT_FALSE(seamed.value().has_degenerate_triangles());
}

// ---------------------------------------------------------------------------------------------
// Topology, area and volume.

TEST(TriangleMesh, BoxIsClosedOrientedWithExactVolumeAndArea) {
  const TriangleMesh box = testing::box_mesh(Vec3(-1, -2, -3), Vec3(1, 1.5, 2));  // 2 x 3.5 x 5
  EXPECT_TRUE(box.report().closed);
  EXPECT_TRUE(box.report().consistently_oriented);
  EXPECT_TRUE(box.is_closed_oriented());
  EXPECT_EQ(box.report().boundary_edges, 0u);
  EXPECT_EQ(box.report().non_manifold_edges, 0u);
  // Dyadic corners: every product is exact, so volume and area are exact up to 4 ulps.
  EXPECT_DOUBLE_EQ(box.signed_volume(), 35.0);
  EXPECT_DOUBLE_EQ(box.area(), 2.0 * (2.0 * 3.5 + 3.5 * 5.0 + 5.0 * 2.0));
  EXPECT_EQ(box.bounds().min, Vec3(-1, -2, -3));
  EXPECT_EQ(box.bounds().max, Vec3(1, 1.5, 2));
}

TEST(TriangleMesh, BoxFarFromTheOriginKeepsItsVolume) {
  for (const Vec3& offset : {Vec3(5.0e4, 5.0e4, 5.0e4), Vec3(-5.0e4, 3.0e4, 5.0e4), Vec3(0.0, 0.0, 9.0e6)}) {
    const Vec3 lo = offset + Vec3(0.1, 0.2, 0.3);
    const Vec3 hi = offset + Vec3(2.6, 3.3, 1.7);
    const TriangleMesh box = testing::box_mesh(lo, hi);
    const Vec3 size = hi - lo;  // the stored box's exact size (the subtraction is exact here)
    const double volume = size.x() * size.y() * size.z();
    const double area = 2.0 * (size.x() * size.y() + size.y() * size.z() + size.z() * size.x());
    EXPECT_TRUE(box.is_closed_oriented());
    EXPECT_NEAR(box.signed_volume(), volume, 1e-9 * volume) << offset.transpose();  // 1e-9 relative
    EXPECT_NEAR(box.area(), area, 1e-9 * area) << offset.transpose();               // 1e-9 relative
  }
}

TEST(TriangleMesh, InsideOutBoxHasNegativeVolume) {
  auto [vertices, faces] = box_parts(Vec3(0, 0, 0), Vec3(2, 3, 4));
  for (Face& f : faces) std::swap(f[1], f[2]);
  const Result<TriangleMesh> built = TriangleMesh::create(vertices, faces);
  ASSERT_TRUE(built.ok());
  EXPECT_TRUE(built.value().is_closed_oriented());
  EXPECT_DOUBLE_EQ(built.value().signed_volume(), -24.0);  // exact up to 4 ulps (dyadic corners)
}

TEST(TriangleMesh, RemovingAFaceOpensTheMesh) {
  auto [vertices, faces] = box_parts(Vec3(0, 0, 0), Vec3(1, 1, 1));
  faces.erase(faces.begin() + 5);
  const Result<TriangleMesh> built = TriangleMesh::create(vertices, faces);
  ASSERT_TRUE(built.ok());
  EXPECT_EQ(built.value().report().boundary_edges, 3u);
  EXPECT_EQ(built.value().report().non_manifold_edges, 0u);
  EXPECT_FALSE(built.value().report().closed);
  EXPECT_FALSE(built.value().is_closed_oriented());
}

TEST(TriangleMesh, FlippingOneFaceBreaksOrientationOnly) {
  auto [vertices, faces] = box_parts(Vec3(0, 0, 0), Vec3(1, 1, 1));
  std::swap(faces[7][0], faces[7][1]);
  const Result<TriangleMesh> built = TriangleMesh::create(vertices, faces);
  ASSERT_TRUE(built.ok());
  EXPECT_TRUE(built.value().report().closed);
  EXPECT_FALSE(built.value().report().consistently_oriented);
  EXPECT_EQ(built.value().report().boundary_edges, 0u);
  EXPECT_FALSE(built.value().is_closed_oriented());
}

TEST(TriangleMesh, ThreeTrianglesOnOneEdgeAreNonManifold) {
  // Three fins sharing the edge (0,0,0)-(0,0,1).
  const std::vector<Vec3> vertices = {Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(-1, -1, 0)};
  const std::vector<Face> faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const Result<TriangleMesh> built = TriangleMesh::create(vertices, faces);
  ASSERT_TRUE(built.ok());
  EXPECT_EQ(built.value().report().non_manifold_edges, 1u);
  EXPECT_EQ(built.value().report().boundary_edges, 6u);
  EXPECT_FALSE(built.value().report().closed);
  // A closed box with a fin glued to one of its edges: closed is false because of that edge.
  auto [box_vertices, box_faces] = box_parts(Vec3(0, 0, 0), Vec3(1, 1, 1));
  box_vertices.push_back(Vec3(-1, -1, 0.5));
  box_faces.push_back({0, 1, static_cast<std::uint32_t>(box_vertices.size() - 1)});  // edge 0-1 is a box edge
  const Result<TriangleMesh> finned = TriangleMesh::create(box_vertices, box_faces);
  ASSERT_TRUE(finned.ok());
  EXPECT_EQ(finned.value().report().non_manifold_edges, 1u);
  EXPECT_FALSE(finned.value().report().closed);
  EXPECT_FALSE(finned.value().is_closed_oriented());
}

TEST(TriangleMesh, RandomBlobIsClosedAndInsideItsBall) {
  testing::Rng rng(7);
  const double radius = 10.0;
  const TriangleMesh blob = testing::random_closed_blob(rng, 3, radius, 0.3, Vec3(5.0e4, 0, 0));
  EXPECT_TRUE(blob.is_closed_oriented());
  EXPECT_EQ(blob.triangle_count(), 8u * 64u);
  // Its vertices lie within the ball of radius r, so the polyhedron does: volume below the ball's.
  const double ball = 4.0 / 3.0 * kPi * radius * radius * radius;
  EXPECT_GT(blob.signed_volume(), 0.1 * ball);
  EXPECT_LT(blob.signed_volume(), ball);
  // A closed mesh's volume does not depend on the origin of the divergence theorem: summed here
  // about the blob's own centre, it agrees (1e-9 relative).
  const Vec3 centre(5.0e4, 0, 0);
  double six_volume = 0.0;
  for (std::size_t t = 0; t < blob.triangle_count(); ++t) {
    const Triangle tri = blob.triangle(t);
    six_volume += (tri[0] - centre).dot((tri[1] - centre).cross(tri[2] - centre));
  }
  EXPECT_NEAR(blob.signed_volume(), six_volume / 6.0, 1e-9 * ball);
}

TEST(TriangleMesh, SetVerticesKeepsTopologyAndChecksCount) {
  Result<TriangleMesh> built = TriangleMesh::create(kTetraVertices, kTetraFaces);
  ASSERT_TRUE(built.ok());
  TriangleMesh& mesh = built.value();
  // Wrong count: an error, and the mesh is unchanged.
  std::vector<Vec3> too_few(kTetraVertices.begin(), kTetraVertices.end() - 1);
  const Result<bool> fewer = mesh.set_vertices(too_few);
  ASSERT_FALSE(fewer.ok());
  EXPECT_EQ(fewer.error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(fewer.error().field, "vertices");
  std::vector<Vec3> too_many = kTetraVertices;
  too_many.push_back(Vec3(2, 2, 2));
  EXPECT_FALSE(mesh.set_vertices(too_many).ok());
  EXPECT_EQ(mesh.vertices(), kTetraVertices);
  // Non-finite coordinates are refused as well.
  EXPECT_FALSE(mesh.set_vertices(with(kTetraVertices, 2, 1, kNaN)).ok());
  EXPECT_EQ(mesh.vertices(), kTetraVertices);
  // Same count: moved, scaled by 2 (volume x 8, exact), bounds and degeneracy refreshed.
  std::vector<Vec3> scaled;
  for (const Vec3& v : kTetraVertices) scaled.push_back(2.0 * v + Vec3(1, 0, 0));
  ASSERT_TRUE(mesh.set_vertices(scaled).ok());
  EXPECT_DOUBLE_EQ(mesh.signed_volume(), 8.0 / 6.0);  // 4 ulps
  EXPECT_EQ(mesh.bounds().min, Vec3(1, 0, 0));
  EXPECT_EQ(mesh.bounds().max, Vec3(3, 2, 2));
  EXPECT_TRUE(mesh.is_closed_oriented());
  EXPECT_FALSE(mesh.has_degenerate_triangles());
  // Flatten vertex 3 onto the line through 0 and 1: faces 1 (0, 1, 3) is now exactly degenerate.
  std::vector<Vec3> flat = scaled;
  flat[3] = Vec3(2, 0, 0);
  ASSERT_TRUE(mesh.set_vertices(flat).ok());
  EXPECT_TRUE(mesh.has_degenerate_triangles());
  EXPECT_TRUE(mesh.is_degenerate(1));
  EXPECT_FALSE(mesh.is_degenerate(0));
}

}  // namespace
}  // namespace gk
