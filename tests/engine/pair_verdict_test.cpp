// The CAD verdict decided on the exact faces (issue: geometry truth §2), against analytic solids:
// spheres, cylinders and boxes whose true distance is known in closed form, posed to overlap or
// part by less than the 0.05 mm tessellation — at the origin and at 5e4 mm, with the offset written
// into the file and with it in the pose. The shapes are built with OCCT's primitives, written to
// BREP bytes and read back through the project's reader, as an upload would be.
#include "engine/exact_depth.h"
#include "engine/pair_verdict.h"
#include "kernel/penetration_depth.h"
#include "kernel/tolerances.h"
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"

#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepTools.hxx>
#include <gp_Ax2.hxx>

#include <gtest/gtest.h>

#include <sstream>

namespace gk::engine {
namespace {

constexpr double kDeflectionMm = 0.05;

std::shared_ptr<PartGeometry> cad_part(const TopoDS_Shape& shape, double deflection_mm = kDeflectionMm) {
  std::ostringstream bytes;
  BRepTools::Write(shape, bytes);
  auto read = occt::read_shape_bytes(bytes.str(), "brep");
  EXPECT_TRUE(read.ok()) << read.error().to_string();
  auto meshed = occt::mesh_shape(read.value(), deflection_mm);
  EXPECT_TRUE(meshed.ok()) << meshed.error().to_string();
  auto part = std::make_shared<PartGeometry>();
  part->mesh = std::make_shared<const TriangleMesh>(std::move(meshed.value().mesh));
  part->bvh = MeshBvh::build(part->mesh).value();
  part->shape = read.value();
  part->face_of_triangle = std::move(meshed.value().face_of_triangle);
  part->deflection_mm = part->shape.is_polyhedral() ? 0.0 : deflection_mm;
  return part;
}

// A mesh part (no B-Rep): the tessellation of a shape taken as the part itself.
std::shared_ptr<PartGeometry> mesh_part(const TopoDS_Shape& shape) {
  auto p = cad_part(shape);
  auto out = std::make_shared<PartGeometry>();
  out->mesh = p->mesh;
  out->bvh = p->bvh;
  return out;
}

TopoDS_Shape sphere(const Vec3& c, double r) { return BRepPrimAPI_MakeSphere(gp_Pnt(c.x(), c.y(), c.z()), r).Shape(); }

std::string describe(const PairVerdict& v) {
  std::ostringstream s;
  s << to_string(v.result.verdict) << " d=" << v.result.distance_mm << " bound=" << v.error_bound_mm
    << " brep=" << v.decided_on_brep << " reason=" << v.result.reason << " (" << to_string(v.result.inconclusive_reason) << ")";
  return s.str();
}

// The truth for a signed gap: apart -> CLEAR at that distance; crossing -> COLLISION.
void expect_truth(const PairVerdict& v, double gap_mm, const std::string& where) {
  SCOPED_TRACE(where + ": " + describe(v));
  if (gap_mm > 0.0) {
    ASSERT_EQ(v.result.verdict, Verdict::kClear);
    EXPECT_GT(v.result.distance_mm, v.error_bound_mm);
    EXPECT_LE(std::fabs(v.result.distance_mm - gap_mm), v.error_bound_mm);
  } else if (gap_mm < 0.0) {
    EXPECT_EQ(v.result.verdict, Verdict::kCollision);
  } else {
    EXPECT_EQ(v.result.verdict, Verdict::kTouching);
  }
}

const double kGaps[] = {-0.03, -0.01, -0.003, -0.001, 0.0, 0.001, 0.003, 0.01, 0.03, 0.2};

TEST(CadPairVerdict, SpheresWithinTheTessellationAreDecidedOnTheExactFaces) {
  for (double base : {0.0, 5e4}) {
    const Vec3 c(base, base * 0.5, -base * 0.25);
    auto a = cad_part(sphere(c, 50.0));
    auto at_origin = cad_part(sphere(Vec3::Zero(), 50.0));
    for (double gap : kGaps) {
      const Vec3 offset(100.0 + gap, 0.0, 0.0);
      // In the file: B's sphere written at its place; in the pose: B at the origin, moved there.
      auto b_in_file = cad_part(sphere(c + offset, 50.0));
      auto in_file = decide_pair({a.get(), {}}, {b_in_file.get(), {}});
      ASSERT_TRUE(in_file.ok()) << in_file.error().to_string();
      expect_truth(in_file.value(), gap, "in file at " + std::to_string(base) + " gap " + std::to_string(gap));
      auto in_pose = decide_pair({at_origin.get(), RigidTransform::from_translation(c)},
                                 {at_origin.get(), RigidTransform::from_translation(c + offset)});
      ASSERT_TRUE(in_pose.ok()) << in_pose.error().to_string();
      expect_truth(in_pose.value(), gap, "in pose at " + std::to_string(base) + " gap " + std::to_string(gap));
    }
  }
}

TEST(CadPairVerdict, CylindersSideBySide) {
  for (double base : {0.0, 5e4}) {
    auto cyl = cad_part(BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 20.0, 80.0).Shape());
    for (double gap : kGaps) {
      // Tilted axes: the closest points are interior to the cylindrical faces.
      const RigidTransform pa = RigidTransform::from_axis_angle(Vec3(1, 0, 0), 0.3, Vec3(base, base, 0.0));
      const RigidTransform pb = RigidTransform::from_axis_angle(Vec3(1, 0, 0), 0.3, Vec3(base + 40.0 + gap, base, 0.0));
      auto v = decide_pair({cyl.get(), pa}, {cyl.get(), pb});
      ASSERT_TRUE(v.ok()) << v.error().to_string();
      if (gap == 0.0) {
        // Line contact along the whole length: touching (or, never, CLEAR).
        EXPECT_NE(v.value().result.verdict, Verdict::kClear) << describe(v.value());
        continue;
      }
      expect_truth(v.value(), gap, "cylinders at " + std::to_string(base) + " gap " + std::to_string(gap));
    }
  }
}

TEST(CadPairVerdict, ASolidInsideAnotherCollidesWithItsBoundariesApart) {
  auto big = cad_part(sphere(Vec3(5e4, 0, 0), 50.0));
  auto small = cad_part(sphere(Vec3(5e4 + 10.0, 0, 0), 5.0));
  auto v = decide_pair({big.get(), {}}, {small.get(), {}});
  ASSERT_TRUE(v.ok());
  EXPECT_EQ(v.value().result.verdict, Verdict::kCollision) << describe(v.value());
  EXPECT_TRUE(v.value().result.contained);
  EXPECT_NEAR(v.value().result.containment_point.x(), 5e4 + 10.0, 6.0);
}

TEST(CadPairVerdict, PolyhedralPartsAreExactOnTheirTriangles) {
  auto box = cad_part(BRepPrimAPI_MakeBox(gp_Pnt(5e4, 0, 0), gp_Pnt(5e4 + 100, 100, 100)).Shape());
  EXPECT_EQ(box->deflection_mm, 0.0);
  auto plate = cad_part(BRepPrimAPI_MakeBox(gp_Pnt(5e4 - 50, -50, -10), gp_Pnt(5e4 + 150, 150, 0)).Shape());
  auto v = decide_pair({box.get(), {}}, {plate.get(), {}});
  ASSERT_TRUE(v.ok());
  EXPECT_EQ(v.value().result.verdict, Verdict::kTouching) << describe(v.value());
  EXPECT_FALSE(v.value().decided_on_brep);
  auto apart = decide_pair({box.get(), RigidTransform::from_translation(Vec3(0, 0, 0.001))}, {plate.get(), {}});
  ASSERT_TRUE(apart.ok());
  EXPECT_EQ(apart.value().result.verdict, Verdict::kClear);
  EXPECT_NEAR(apart.value().result.distance_mm, 0.001, apart.value().error_bound_mm);
}

TEST(CadPairVerdict, ACadPartAgainstAMeshIsNeverWronglyClear) {
  auto ball = cad_part(sphere(Vec3(5e4, 0, 0), 50.0));
  // A small box mesh whose corner points at the sphere: its corner enters first.
  auto probe = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), gp_Pnt(5, 5, 5)).Shape());
  const Vec3 corner_dir = Vec3(-1, -1, -1).normalized();
  for (double gap : kGaps) {
    // Box corner (0,0,0) at distance 50 + gap from the centre along +diagonal, box extending outwards.
    const Vec3 corner = Vec3(5e4, 0, 0) - corner_dir * (50.0 + gap);
    auto v = decide_pair({ball.get(), {}}, {probe.get(), RigidTransform::from_translation(corner)});
    ASSERT_TRUE(v.ok());
    SCOPED_TRACE("gap " + std::to_string(gap) + ": " + describe(v.value()));
    if (gap > 0.0) {
      expect_truth(v.value(), gap, "mesh corner");
    } else if (gap < 0.0) {
      // The corner is a mesh vertex inside the exact sphere: proven.
      EXPECT_EQ(v.value().result.verdict, Verdict::kCollision);
    } else {
      EXPECT_NE(v.value().result.verdict, Verdict::kClear);
    }
  }
  // A face of a large mesh box cutting a cap off the sphere: no mesh vertex is inside, so the
  // exact faces cannot be told touching from crossing: INCONCLUSIVE, typed, never CLEAR.
  auto slab = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(0, -100, -100), gp_Pnt(20, 100, 100)).Shape());
  for (double gap : {-0.01, -0.001}) {
    auto v = decide_pair({ball.get(), {}}, {slab.get(), RigidTransform::from_translation(Vec3(5e4 + 50.0 + gap, 0, 0))});
    ASSERT_TRUE(v.ok());
    EXPECT_TRUE(v.value().result.verdict == Verdict::kCollision || v.value().result.verdict == Verdict::kInconclusive)
        << describe(v.value());
    if (v.value().result.verdict == Verdict::kInconclusive) {
      EXPECT_EQ(v.value().result.inconclusive_reason, InconclusiveReason::kTessellationUnresolved);
    }
  }
}

// A depth found on the tessellations frees the tessellations; moved by what check_depth_on_brep
// reports, the exact spheres are free too (their analytic distance is >= 0).
TEST(CadDepth, TheReportedDepthFreesTheExactSolids) {
  auto ball = cad_part(sphere(Vec3::Zero(), 50.0));
  for (double base : {0.0, 5e4}) {
    for (double overlap : {0.02, 2.0}) {
      const Vec3 dir = Vec3(1, 0.3, -0.2).normalized();
      const RigidTransform pa = RigidTransform::from_translation(Vec3(base, 0, 0));
      const RigidTransform pb = RigidTransform::from_translation(Vec3(base, 0, 0) + (100.0 - overlap) * dir);
      auto found = penetration_vector(*ball->bvh, pa, *ball->bvh, pb, 162, 1e-4);
      ASSERT_TRUE(found.ok());
      auto checked = check_depth_on_brep({ball.get(), pa}, {ball.get(), pb}, found.value().direction, found.value().depth_mm);
      ASSERT_TRUE(checked.ok()) << checked.error().to_string();
      EXPECT_TRUE(checked.value().checked);
      const Vec3 moved_centre = pb.translation + checked.value().depth_mm * found.value().direction.normalized();
      EXPECT_GE((moved_centre - pa.translation).norm(), 100.0 - 1e-4)
          << "overlap " << overlap << " depth " << checked.value().depth_mm << " extensions " << checked.value().extensions;
      EXPECT_GE(checked.value().depth_mm, overlap - 1e-4);
    }
  }
}

}  // namespace
}  // namespace gk::engine
