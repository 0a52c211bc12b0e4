// OCCT adapters on real files and shapes: import with clear errors, meshing with face ids, swept
// solids with their analytic volumes, and exact distance and common volume.
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/measure/interference_volume.h"
#include "kernel/query/mesh_distance.h"
#include "kernel/measure/exact_interference_volume.h"
#include "occt_adapters/brep_contact.h"
#include "occt_adapters/exact_measures.h"
#include "occt_adapters/shape_builders.h"
#include "occt_adapters/shape_impl.h"
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"
#include "tests/support/random_meshes.h"
#include "kernel/core/units.h"

#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <gp_Ax2.hxx>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>

namespace gk::occt {
namespace {


std::string write_temp(const std::string& name, const std::string& bytes) {
  const auto path = std::filesystem::temp_directory_path() / ("gk-occt-test-" + name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path.string();
}

TEST(ShapeImport, ReadsTheSharedStepBrepFiles) {
  struct Case {
    const char* file;
    int min_faces;
  };
  for (const Case& c : {Case{"step/occt/screw.step", 10}, Case{"step/occt/Pump_Nut.brep", 25},
                        Case{"step/occt/bottle.brep", 71}, Case{"step/occt/Pump_TopCover.brep", 8},
                        Case{"step/gmsh/as1-tu-203.stp", 10}}) {
    auto shape = read_shape_file(testing::shared_data(c.file));
    ASSERT_TRUE(shape.ok()) << c.file << ": " << shape.error().to_string();
    EXPECT_GE(shape.value().face_count(), c.min_faces) << c.file;
    EXPECT_FALSE(shape.value().bounds().empty()) << c.file;
  }
}

TEST(ShapeImport, BrokenFilesGiveClearErrors) {
  auto missing = read_shape_file("/nonexistent/part.step");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("no such file"), std::string::npos);
  const std::string garbage = write_temp("garbage.step", "ISO-10303-21;\nthis is not a STEP file\n");
  auto bad = read_shape_file(garbage);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().field, garbage);
  auto empty = read_shape_file(write_temp("empty.brep", ""));
  ASSERT_FALSE(empty.ok());
  auto bad_brep = read_shape_file(write_temp("bad.brep", "DBRep_DrawableShape\nCASCADE Topology V1\nnonsense"));
  ASSERT_FALSE(bad_brep.ok());
  auto bad_iges = read_shape_file(write_temp("bad.igs", std::string(200, 'x')));
  ASSERT_FALSE(bad_iges.ok());
  auto unknown = read_shape_file(write_temp("part.xyz", "x"));
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("unknown CAD format"), std::string::npos);
  // A truncated copy of a real STEP file.
  std::ifstream in(testing::shared_data("step/occt/screw.step"), std::ios::binary);
  std::string whole((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto truncated = read_shape_bytes(whole.substr(0, whole.size() / 3), "step");
  EXPECT_FALSE(truncated.ok() && truncated.value().face_count() >= 10) << "a third of a STEP file is not the whole part";
  auto from_bytes = read_shape_bytes(whole, "step");
  ASSERT_TRUE(from_bytes.ok());
  EXPECT_EQ(from_bytes.value().face_count(), read_shape_file(testing::shared_data("step/occt/screw.step")).value().face_count());
}

TEST(ShapeMesher, KeepsFaceIdsAndStaysWithinTheDeflection) {
  auto shape = read_shape_file(testing::shared_data("step/occt/Pump_Nut.brep")).value();
  for (double deflection : {0.5, 0.05}) {
    auto meshed = mesh_shape(shape, deflection);
    ASSERT_TRUE(meshed.ok()) << meshed.error().to_string();
    const MeshedShape& m = meshed.value();
    ASSERT_EQ(m.face_of_triangle.size(), m.mesh.triangle_count());
    // Faces share their edges' nodes: the solid's tessellation is closed.
    EXPECT_TRUE(m.mesh.is_closed_oriented()) << m.mesh.report().boundary_edges << " boundary edges";
    for (int id : m.face_of_triangle) {
      EXPECT_GE(id, 1);
      EXPECT_LE(id, shape.face_count());
    }
    // Every mesh vertex lies on the exact surface to within OCCT's tolerances (vertices are
    // sampled on the surface; the deflection bounds the triangles' interiors).
    for (std::size_t i = 0; i < m.mesh.vertices().size(); i += 97) {
      auto point = make_box(m.mesh.vertices()[i] - Vec3::Constant(1e-6), m.mesh.vertices()[i] + Vec3::Constant(1e-6));
      const double d = exact_distance(shape, point.value()).value().distance_mm;
      EXPECT_LE(d, 1e-3) << "vertex " << i;  // tolerance: OCCT edge/vertex tolerance, 1e-3 mm
    }
  }
  EXPECT_FALSE(mesh_shape(shape, 0.0).ok());
  EXPECT_FALSE(mesh_shape(Shape(), 0.1).ok());
}

// The deflection a tessellation reports bounds how far its triangles lie from the surface, where
// OCCT's own control does not hold the asked one. The oracle: each triangle's points on a grid of
// 66 against the analytic surface (a sphere at factory coordinates, a torus, a cylinder's side).
double farthest_from(const MeshedShape& m, const std::function<double(const Vec3&)>& from_surface) {
  double farthest = 0.0;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const Triangle tri = m.mesh.triangle(t);
    for (int i = 0; i <= 10; ++i)
      for (int j = 0; i + j <= 10; ++j) farthest = std::max(farthest, from_surface((i * tri[0] + j * tri[1] + (10 - i - j) * tri[2]) / 10.0));
  }
  return farthest;
}

TEST(ShapeMesher, TheReportedDeflectionBoundsTheTrianglesDistanceFromTheSurface) {
  for (const double radius : {5.0, 50.0, 500.0}) {
    const Vec3 centre(1e5, 0, 0);
    const MeshedShape m = mesh_shape(wrap(BRepPrimAPI_MakeSphere(gp_Pnt(centre.x(), 0, 0), radius).Shape()), 0.05).value();
    const double farthest = farthest_from(m, [&](const Vec3& p) { return std::abs((p - centre).norm() - radius); });
    EXPECT_GE(m.deflection_mm, farthest) << "R " << radius;
    EXPECT_LE(m.deflection_mm, 2.0 * std::max(0.05, farthest)) << "R " << radius << ": no wider than needed";
    if (radius == 50.0) {
      EXPECT_GT(farthest, 0.05) << "OCCT's own deflection on a sphere (if this fails, OCCT now holds it: the measure still bounds it)";
    }
  }
  const MeshedShape torus = mesh_shape(wrap(BRepPrimAPI_MakeTorus(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 40.0, 8.0).Shape()), 0.05).value();
  EXPECT_GE(torus.deflection_mm, farthest_from(torus, [](const Vec3& p) { return std::abs(std::hypot(std::hypot(p.x(), p.y()) - 40.0, p.z()) - 8.0); }));
  const MeshedShape cylinder = mesh_shape(wrap(BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 30.0, 10.0).Shape()), 0.05).value();
  // Its side only (the caps are planes, their triangles on them).
  EXPECT_GE(cylinder.deflection_mm, farthest_from(cylinder, [](const Vec3& p) {
    return p.z() > 1e-9 && p.z() < 10.0 - 1e-9 ? std::abs(std::hypot(p.x(), p.y()) - 30.0) : 0.0;
  }));
}

TEST(SweptSolids, RevolvedRectangleIsAQuarterCylinder) {
  auto face = make_rectangle(Vec3(0, 0, 0), Vec3(100, 0, 0), Vec3(0, 0, 50)).value();
  auto swept = revolve(face, Vec3::Zero(), Vec3::UnitX(), 90.0);
  ASSERT_TRUE(swept.ok()) << swept.error().to_string();
  EXPECT_NEAR(swept.value().volume(), 100.0 * kPi * 50.0 * 50.0 / 4.0, 1e-6 * 196349.54);  // 1e-6 relative
  // A 2 mm plate bent up 90 degrees about its top edge (a flange): swept through its boundary, the
  // sweep reaches y = hypot(40, 2) (the far bottom corner's arc) and z = 2 + 40 (the flange upright).
  auto plate = make_box(Vec3(0, 0, 0), Vec3(100, 40, 2)).value();
  auto bent = revolve(plate, Vec3(0, 0, 2), Vec3::UnitX(), 90.0);
  ASSERT_TRUE(bent.ok()) << bent.error().to_string();
  const Aabb box = bent.value().bounds();
  EXPECT_NEAR(box.max.y(), std::hypot(40.0, 2.0), 0.05);  // tolerance: OCCT's box enlargement
  EXPECT_NEAR(box.max.z(), 42.0, 0.05);
  EXPECT_NEAR(box.min.z(), 0.0, 0.05);
  EXPECT_NEAR(box.min.y(), 0.0, 0.05);
}

TEST(SweptSolids, AnglesAndAxesAreValidated) {
  auto face = make_rectangle(Vec3(0, 0, 0), Vec3(100, 0, 0), Vec3(0, 0, 50)).value();
  auto wrapped = revolve(face, Vec3::Zero(), Vec3::UnitX(), 540.0);
  ASSERT_FALSE(wrapped.ok());
  EXPECT_EQ(wrapped.error().field, "angle_deg");
  EXPECT_FALSE(revolve(face, Vec3::Zero(), Vec3::UnitX(), std::nan("")).ok());
  EXPECT_FALSE(revolve(face, Vec3::Zero(), Vec3::UnitX(), 0.0).ok());
  EXPECT_FALSE(revolve(face, Vec3::Zero(), Vec3::Zero(), 30.0).ok());
  auto box = make_box(Vec3(-1, -1, -1), Vec3(1, 1, 1)).value();
  auto through = revolve(box, Vec3::Zero(), Vec3::UnitZ(), 45.0);  // the axis crosses the interior
  if (through.ok()) {
    // Swept through its boundary: corners (1, -1) and (1, 1) reach x = y = sqrt 2 at 45 degrees.
    EXPECT_NEAR(through.value().bounds().max.x(), std::sqrt(2.0), 0.05);
    EXPECT_NEAR(through.value().bounds().max.y(), std::sqrt(2.0), 0.05);
  } else {
    EXPECT_EQ(through.error().field, "axis");
  }
}

TEST(SweptSolids, ExtrudedBoxHasItsVolume) {
  auto face = make_rectangle(Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 20, 0)).value();
  auto prism = extrude(face, Vec3(0, 0, 5));
  ASSERT_TRUE(prism.ok());
  EXPECT_NEAR(prism.value().volume(), 1000.0, 1e-9);
  EXPECT_FALSE(extrude(face, Vec3::Zero()).ok());
}

TEST(ExactMeasures, BoxDistanceAndCommonVolumeAreAnalytic) {
  auto a = make_box(Vec3(0, 0, 0), Vec3(10, 10, 10)).value();
  auto b = make_box(Vec3(13, 4, 4), Vec3(20, 6, 6)).value();
  auto d = exact_distance(a, b).value();
  EXPECT_NEAR(d.distance_mm, 3.0, 1e-9);
  EXPECT_NEAR(interference_volume(a, b).value(), 0.0, 1e-9);
  auto c = make_box(Vec3(8, 8, 8), Vec3(12, 13, 14)).value();
  EXPECT_NEAR(exact_distance(a, c).value().distance_mm, 0.0, 1e-12);
  EXPECT_NEAR(interference_volume(a, c).value(), 2.0 * 2.0 * 2.0, 1e-9);
}

TEST(ExactMeasures, RayCastMeshVolumeMatchesTheBooleanCommon) {
  // A box turned 30 degrees about z and tilted, cutting an axis-aligned one.
  auto a = make_box(Vec3(0, 0, 0), Vec3(10, 10, 10)).value();
  const RigidTransform turn = RigidTransform::from_axis_angle(Vec3(1, 2, 5), 0.5, Vec3(6, 4, 3));
  auto b = place(make_box(Vec3(0, 0, 0), Vec3(8, 6, 7)).value(), turn).value();
  const double exact = interference_volume(a, b).value();
  ASSERT_GT(exact, 10.0);
  const auto mesh_a = MeshBvh::build(testing::share(mesh_shape(a, 0.01).value().mesh)).value();
  const auto mesh_b = MeshBvh::build(testing::share(testing::box_mesh(Vec3(0, 0, 0), Vec3(8, 6, 7)))).value();
  const VolumeEstimate rays = gk::interference_volume(*mesh_a, {}, *mesh_b, turn, 512).value();
  // Midpoint rule on a 512 x 512 grid over the overlap: 0.5 % here.
  EXPECT_NEAR(rays.volume_mm3, exact, 0.005 * exact);
}

// Two independent exact methods on turned polyhedra: CGAL's corefinement of the meshes in
// rationals, OCCT's Boolean common of the same boxes as B-Rep solids.
TEST(ExactMeasures, ExactMeshVolumeMatchesTheBooleanCommonOnTurnedBoxes) {
  testing::Rng rng(41);
  std::uniform_real_distribution<double> size(2.0, 12.0);
  int overlapping = 0;
  for (int trial = 0; trial < 25; ++trial) {
    const Vec3 ha(size(rng), size(rng), size(rng)), hb(size(rng), size(rng), size(rng));
    RigidTransform pose = testing::random_pose(rng, 4.0);
    const Vec3 offset = trial % 2 == 0 ? Vec3::Zero() : Vec3(50000, -50000, 50000);  // factory coordinates
    pose.translation += offset;
    const RigidTransform at_offset = RigidTransform::from_translation(offset);
    const double boolean = shared_volume(make_box(-ha, ha).value(), at_offset, make_box(-hb, hb).value(), pose, offset)
                               .value()
                               .volume_mm3;
    auto exact = exact_interference_volume(testing::box_mesh(-ha, ha), at_offset, testing::box_mesh(-hb, hb), pose);
    ASSERT_TRUE(exact.ok()) << exact.error().to_string();
    SCOPED_TRACE("trial " + std::to_string(trial));
    EXPECT_NEAR(exact.value().volume_mm3, boolean, 1e-7 * std::max(1.0, boolean));
    overlapping += boolean > 1.0 ? 1 : 0;
  }
  EXPECT_GT(overlapping, 10);
}

// The solids of an assembly may overlap each other (a bolt modelled through its plate): the volume
// they share with another part counts their common region once.
TEST(ExactMeasures, SharedVolumeCountsAnAssemblysOverlappingSolidsOnce) {
  for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(50000, 50000, -50000)}) {
    const auto assembly = make_compound({make_box(Vec3(0, 0, 0), Vec3(10, 10, 10)).value(),
                                         make_box(Vec3(5, 0, 0), Vec3(15, 10, 10)).value()})
                              .value();
    const auto probe = make_box(Vec3(4, 2, 2), Vec3(12, 8, 8)).value();
    const RigidTransform at = RigidTransform::from_translation(offset);
    // B within the union [0, 15] x [0, 10]^2: 8 x 6 x 6 (solid by solid it would be 216 + 252).
    const SharedVolume v = shared_volume(assembly, at, probe, at, offset).value();
    EXPECT_NEAR(v.volume_mm3, 288.0, 1e-6);
    EXPECT_TRUE(v.crossing());
  }
}

TEST(ExactMeasures, KernelMeshDistanceMatchesBRepWithinTheDeflection) {
  auto nut = read_shape_file(testing::shared_data("step/occt/Pump_Nut.brep")).value();
  auto cover = read_shape_file(testing::shared_data("step/occt/Pump_TopCover.brep")).value();
  const double deflection = 0.01;
  const auto nut_mesh = mesh_shape(nut, deflection).value();
  const auto cover_mesh = mesh_shape(cover, deflection).value();
  const auto nut_bvh = MeshBvh::build(testing::share(nut_mesh.mesh)).value();
  const auto cover_bvh = MeshBvh::build(testing::share(cover_mesh.mesh)).value();
  testing::Rng rng(12);
  const Aabb nb = nut.bounds(), cb = cover.bounds();
  for (int trial = 0; trial < 5; ++trial) {
    RigidTransform pose = testing::random_pose(rng, 0.0);
    pose.translation = nb.center() - pose.rotation * cb.center() +
                       Vec3::Random().normalized() * (0.5 * (nb.diagonal().norm() + cb.diagonal().norm()) + 5.0);
    const auto placed = place(cover, pose).value();
    const double exact = exact_distance(nut, placed).value().distance_mm;
    const double meshed = distance(*nut_bvh, {}, *cover_bvh, pose).value().distance_mm;
    // Both tessellations are within the deflection of their surfaces.
    EXPECT_NEAR(meshed, exact, 2.0 * deflection + 1e-6) << "trial " << trial;
  }
}

}  // namespace
}  // namespace gk::occt
