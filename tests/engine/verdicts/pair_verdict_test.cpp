// The CAD verdict decided on the exact faces (issue: geometry truth §2), against analytic solids:
// spheres, cylinders and boxes whose true distance is known in closed form, posed to overlap or
// part by less than the 0.05 mm tessellation — at the origin and at 5e4 mm, with the offset written
// into the file and with it in the pose. The shapes are built with OCCT's primitives, written to
// BREP bytes and read back through the project's reader, as an upload would be.
#include "engine/verdicts/exact_depth.h"
#include "engine/verdicts/pair_verdict.h"
#include "kernel/measure/exact_interference_volume.h"
#include "kernel/measure/interference_volume.h"
#include "kernel/measure/penetration_depth.h"
#include "kernel/core/tolerances.h"
#include "tests/support/random_meshes.h"
#include "occt_adapters/brep_contact.h"
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"
#include "kernel/core/units.h"

#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRepTools.hxx>
#include <gp_Ax2.hxx>

#include <gtest/gtest.h>

#include <sstream>

namespace gk::engine {
namespace {

constexpr double kDeflectionMm = 0.05;
constexpr double kDegree = 3.14159265358979323846 / 180.0;

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
  part->deflection_mm = part->shape.is_polyhedral() ? 0.0 : meshed.value().deflection_mm;  // as the part registry takes it
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

// Exactly tangent spheres of unequal radii, written at factory coordinates or posed there with
// rotations: the distance function is flat at the contact (it grows with the square of the offset
// along the surfaces), so a search that stops a few hundredths of a millimetre early reports a
// gap of micrometres — a wrong CLEAR. They touch.
TEST(CadPairVerdict, TangentSpheresOfUnequalSizeTouch) {
  const double radii[][2] = {{150.0, 1.0}, {150.0, 0.3}, {50.0, 5.0}, {5.0, 50.0}, {20.0, 0.3}};
  const Vec3 directions[] = {Vec3(0, 0, 1), Vec3(0.3, -0.8, 0.52), Vec3(-0.6, 0.2, -0.77), Vec3(0.1, 0.99, -0.05)};
  const Vec3 centres[] = {Vec3::Zero(), Vec3(-7344.769087, 39279.28726, -9900.210908), Vec3(49922.41103, 31124.31498, 1300.79623)};
  int cases = 0, touching = 0;
  for (const auto& r : radii) {
    auto at_origin_a = cad_part(sphere(Vec3::Zero(), r[0]));
    auto at_origin_b = cad_part(sphere(Vec3::Zero(), r[1]));
    const Vec3 written(50000.0, 31234.5, 1234.25);
    auto a_far = cad_part(sphere(written, r[0]));
    auto b_far = cad_part(sphere(written, r[1]));
    for (const Vec3& c : centres) {
      auto a = cad_part(sphere(c, r[0]));
      for (const Vec3& d : directions) {
        const Vec3 cb = c + (r[0] + r[1]) * d.normalized();
        auto b = cad_part(sphere(cb, r[1]));
        const std::string where = "r " + std::to_string(r[0]) + "/" + std::to_string(r[1]) + " at " + std::to_string(c.x());
        auto in_file = decide_pair({a.get(), {}}, {b.get(), {}});
        ASSERT_TRUE(in_file.ok()) << in_file.error().to_string();
        EXPECT_NE(in_file.value().result.verdict, Verdict::kClear) << where << " in file: " << describe(in_file.value());
        // In the pose, rotated: the parameterisation no longer lines up with the contact.
        const RigidTransform pa = RigidTransform::from_axis_angle(Vec3(0.94, 0.24, 0.24), -2.47, c);
        const RigidTransform pb = RigidTransform::from_axis_angle(Vec3(0.71, 0.71, 0), 1.51, cb);
        auto in_pose = decide_pair({at_origin_a.get(), pa}, {at_origin_b.get(), pb});
        ASSERT_TRUE(in_pose.ok()) << in_pose.error().to_string();
        EXPECT_NE(in_pose.value().result.verdict, Verdict::kClear) << where << " in pose: " << describe(in_pose.value());
        // Both: written far from the origin and posed back there, rotated (a part exported in
        // another cell's coordinates and placed by the layout).
        const RigidTransform ra = RigidTransform::from_axis_angle(Vec3(0.942809, 0.235702, 0.235702), -141.7 * kDegree, Vec3::Zero());
        const RigidTransform rb = RigidTransform::from_axis_angle(Vec3(0.707107, 0.707107, 0), 86.5 * kDegree, Vec3::Zero());
        const RigidTransform qa = RigidTransform::from_translation(c) * ra * RigidTransform::from_translation(-written);
        const RigidTransform qb = RigidTransform::from_translation(cb) * rb * RigidTransform::from_translation(-written);
        auto both = decide_pair({a_far.get(), qa}, {b_far.get(), qb});
        ASSERT_TRUE(both.ok()) << both.error().to_string();
        EXPECT_NE(both.value().result.verdict, Verdict::kClear) << where << " in file and pose: " << describe(both.value());
        for (const auto* v : {&in_file.value(), &in_pose.value(), &both.value()}) touching += v->result.verdict == Verdict::kTouching;
        cases += 3;
      }
    }
  }
  EXPECT_EQ(cases, 180);
  // INCONCLUSIVE would be safe, but a tangency is decidable: nearly all are found touching.
  EXPECT_GE(touching, 171) << touching << " of " << cases << " touching";
  // Found by the review: written at (50000, 31234.5, 1234.25), posed rotated, radii 150 and 1.
  const Vec3 written(50000.0, 31234.5, 1234.25);
  auto big = cad_part(sphere(written, 150.0));
  auto small = cad_part(sphere(written, 1.0));
  const RigidTransform pa = RigidTransform::from_axis_angle(Vec3(0.942809, 0.235702, 0.235702), -141.7 * kDegree,
                                                            Vec3(-7344.769087, 39279.28726, -9900.210908));
  // B's centre 151 mm from A's, towards where the review found the contact.
  const Vec3 towards = Vec3(-137.196, 6.3723, 60.26255).normalized();
  const RigidTransform turn_b = RigidTransform::from_axis_angle(Vec3(0.707107, 0.707107, 0), 86.5 * kDegree, Vec3::Zero());
  const RigidTransform pb = RigidTransform::from_translation(pa.apply(written) + 151.0 * towards - turn_b.apply(written)) * turn_b;
  const double between = (pa.apply(written) - pb.apply(written)).norm();
  ASSERT_NEAR(between, 151.0, 1e-9);
  auto v = decide_pair({big.get(), pa}, {small.get(), pb});
  ASSERT_TRUE(v.ok()) << v.error().to_string();
  EXPECT_EQ(v.value().result.verdict, Verdict::kTouching) << "true gap " << between - 151.0 << ": " << describe(v.value());
}

// A small ball a few micrometres into a torus (found by the review: 3-12 um overlaps answered
// TOUCHING because the lens they share holds less than 1e-9 mm^3): crossing by more than the
// contact tolerance is a collision whatever the volume; exactly tangent, it touches.
TEST(CadPairVerdict, MicrometreOverlapsOfSmallCurvedPartsCollide) {
  const Vec3 centre(0.0, 0.0, 0.0);
  const Vec3 axis = Vec3(0.23091, -0.93086, 0.28318).normalized();
  const double big_r = 13.4695, tube = 6.5799, ball = 1.53655;
  auto torus = cad_part(BRepPrimAPI_MakeTorus(gp_Ax2(gp_Pnt(centre.x(), centre.y(), centre.z()), gp_Dir(axis.x(), axis.y(), axis.z())),
                                              big_r, tube).Shape());
  const Vec3 u = axis.cross(Vec3(1, 0, 0)).normalized();
  const Vec3 w = axis.cross(u);
  int cases = 0;
  for (double around : {0.3, 2.1, 4.4}) {
    const Vec3 radial = std::cos(around) * u + std::sin(around) * w;
    const Vec3 tube_centre = centre + big_r * radial;
    for (double phi : {0.2, 1.3, 2.9}) {
      const Vec3 normal = std::cos(phi) * radial + std::sin(phi) * axis;
      const Vec3 on_surface = tube_centre + tube * normal;
      for (double overlap : {0.0, 0.0002, 0.0005, 0.001, 0.003, 0.006, 0.012}) {
        auto b = cad_part(sphere(on_surface + (ball - overlap) * normal, ball));
        auto v = decide_pair({torus.get(), {}}, {b.get(), {}});
        ASSERT_TRUE(v.ok()) << v.error().to_string();
        SCOPED_TRACE("around " + std::to_string(around) + " phi " + std::to_string(phi) + " overlap " + std::to_string(overlap) +
                     ": " + describe(v.value()));
        // Between the contact tolerance and 5e-4 mm a lens this small can be lost by both the
        // Boolean common and the section (one of these nine spots at 2e-4 mm): TOUCHING there is
        // the documented limit; never CLEAR.
        if (overlap >= tolerances::kCurvedCrossingDetectedMm) EXPECT_EQ(v.value().result.verdict, Verdict::kCollision);
        else EXPECT_NE(v.value().result.verdict, Verdict::kClear);
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 63);
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
  // A face of a large mesh box cutting a cap off the sphere: no mesh vertex is inside; the
  // triangles themselves enter the solid (Boolean common), and a point of them inside proves it.
  // Tangent, they touch; apart, the exact distance. The sphere written at 5e4 mm, or posed there.
  auto slab = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(0, -100, -100), gp_Pnt(20, 100, 100)).Shape());
  auto ball_at_origin = cad_part(sphere(Vec3::Zero(), 50.0));
  const RigidTransform ball_pose = RigidTransform::from_translation(Vec3(5e4, 0, 0));
  for (double gap : kGaps) {
    for (int posed = 0; posed < 2; ++posed) {
      const PosedPart cad = posed ? PosedPart{ball_at_origin.get(), ball_pose} : PosedPart{ball.get(), {}};
      auto v = decide_pair(cad, {slab.get(), RigidTransform::from_translation(Vec3(5e4 + 50.0 + gap, 0, 0))});
      ASSERT_TRUE(v.ok());
      expect_truth(v.value(), gap, "slab face, gap " + std::to_string(gap) + (posed ? " (posed)" : " (in the file)"));
      if (gap < 0.0) {
        // The proof is a point of the slab's face (x = 5e4 + 50 + gap) inside the exact sphere.
        const Vec3 p = v.value().result.point_a;
        EXPECT_NEAR(p.x(), 5e4 + 50.0 + gap, 1e-6);
        EXPECT_LT((p - Vec3(5e4, 0, 0)).norm(), 50.0);
      }
    }
  }
  // The ball inside a closed mesh box, touching its wall from within: inside, so colliding.
  auto crate = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), gp_Pnt(200, 200, 200)).Shape());
  auto inner = decide_pair({ball_at_origin.get(), RigidTransform::from_translation(Vec3(50, 100, 100))}, {crate.get(), {}});
  ASSERT_TRUE(inner.ok());
  EXPECT_EQ(inner.value().result.verdict, Verdict::kCollision) << describe(inner.value());
  EXPECT_TRUE(inner.value().result.contained);
}

// A mesh slab turned at random, its face at a random signed gap of -0.05..0.05 mm from an exact
// sphere (below the deflection): the verdict is the analytic truth or INCONCLUSIVE, never a wrong
// CLEAR, and INCONCLUSIVE stays rare.
TEST(CadPairVerdict, RandomSlabsAgainstASphereWithinTheDeflection) {
  auto ball = cad_part(sphere(Vec3::Zero(), 50.0));
  auto slab = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(0, -100, -100), gp_Pnt(20, 100, 100)).Shape());
  testing::Rng rng(5);
  std::uniform_real_distribution<double> gap_of(-0.05, 0.05);
  int inconclusive = 0, decided = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const double gap = gap_of(rng);
    RigidTransform turn = testing::random_pose(rng, 0.0);
    // The slab's face x = 0 (normal -x) faces the sphere from direction turn * (+x).
    const Vec3 offset = trial % 2 ? Vec3(5e4, -5e4, 5e4) : Vec3::Zero();
    turn.translation = offset + turn.rotation * Vec3(50.0 + gap, 0, 0);
    auto v = decide_pair({ball.get(), RigidTransform::from_translation(offset)}, {slab.get(), turn});
    ASSERT_TRUE(v.ok());
    SCOPED_TRACE("trial " + std::to_string(trial) + " gap " + std::to_string(gap) + ": " + describe(v.value()));
    if (v.value().result.verdict == Verdict::kInconclusive) {
      ++inconclusive;
      continue;
    }
    ++decided;
    if (std::fabs(gap) <= tolerances::kContactMm) {
      EXPECT_NE(v.value().result.verdict, Verdict::kClear);
    } else {
      expect_truth(v.value(), gap, "random slab");
    }
  }
  EXPECT_LE(inconclusive, 2);
  EXPECT_GE(decided, 38);
}

// Found by review: every tessellation vertex of a cylinder whose caps are flush with a closed mesh
// box's faces lies on the box's walls, so a vertex could not tell inside from outside; a cone
// standing in a box likewise. Inside is a collision.
TEST(CadPairVerdict, ACadPartInsideAClosedMeshWithItsFacesFlushCollides) {
  auto cylinder = cad_part(BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 10.0, 40.0).Shape());
  const TopoDS_Shape boxes[] = {BRepPrimAPI_MakeBox(gp_Pnt(-40, -40, 0), gp_Pnt(40, 40, 40)).Shape(),
                                BRepPrimAPI_MakeBox(gp_Pnt(-10, -40, 0), gp_Pnt(40, 40, 40)).Shape(),  // side tangent too
                                BRepPrimAPI_MakeBox(gp_Pnt(-40, -40, 0), gp_Pnt(40, 40, 50)).Shape()};
  for (const TopoDS_Shape& shape : boxes) {
    auto crate = mesh_part(shape);
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(5e4, 5e4, -5e4)}) {
      const RigidTransform at = RigidTransform::from_translation(offset);
      auto v = decide_pair({cylinder.get(), at}, {crate.get(), at});
      ASSERT_TRUE(v.ok());
      EXPECT_EQ(v.value().result.verdict, Verdict::kCollision) << describe(v.value());
      auto swapped = decide_pair({crate.get(), at}, {cylinder.get(), at});
      ASSERT_TRUE(swapped.ok());
      EXPECT_EQ(swapped.value().result.verdict, Verdict::kCollision) << describe(swapped.value());
    }
  }
  // The same cylinder standing on the box's top face from outside only touches.
  auto under = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(-40, -40, -40), gp_Pnt(40, 40, 0)).Shape());
  auto touch = decide_pair({cylinder.get(), {}}, {under.get(), {}});
  ASSERT_TRUE(touch.ok());
  EXPECT_EQ(touch.value().result.verdict, Verdict::kTouching) << describe(touch.value());
}

// Found by review: a flat mesh face cutting a torus where its seams meet lost the cut in the
// Boolean common (TOUCHING at 0.005-0.049 mm deep); the section rings find it.
TEST(CadPairVerdict, AFlatFaceCuttingATorusAtItsSeamsCollides) {
  auto torus = cad_part(BRepPrimAPI_MakeTorus(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 20.0, 5.0).Shape());
  auto slab = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(0, -30, -30), gp_Pnt(10, 30, 30)).Shape());
  for (double gap : {-0.049, -0.03, -0.02, -0.005, -0.001, 0.0, 0.003, 0.03}) {
    auto v = decide_pair({torus.get(), {}}, {slab.get(), RigidTransform::from_translation(Vec3(25.0 + gap, 0, 0))});
    ASSERT_TRUE(v.ok());
    expect_truth(v.value(), gap, "torus seam, gap " + std::to_string(gap));
  }
  // The second review: away from the seam (turned about the torus's axis) both the Boolean and the
  // section lost caps near 0.049 mm deep; the foot of the solid's extreme point beyond the face finds them.
  for (double azimuth_deg : {15.0, 45.0, 90.0, 135.0, 270.0, 345.0}) {
    for (double gap : {-0.0505, -0.049, -0.0485, -0.01}) {
      const RigidTransform turn = RigidTransform::from_axis_angle(Vec3::UnitZ(), azimuth_deg * kDegree);
      RigidTransform pose = turn;
      pose.translation = turn.rotation * Vec3(25.0 + gap, 0, 0);
      auto v = decide_pair({torus.get(), {}}, {slab.get(), pose});
      ASSERT_TRUE(v.ok());
      expect_truth(v.value(), gap, "torus at azimuth " + std::to_string(azimuth_deg) + ", gap " + std::to_string(gap));
    }
  }
}

// A shared volume measured on a CAD part's tessellation is the triangles' volume; the band bound
// added for the deflection covers the way to the exact solid's (analytic caps of a ball).
TEST(CadVolume, TheTessellationBandCoversTheExactSolidsVolume) {
  const double r = 10.0;
  auto ball = cad_part(sphere(Vec3::Zero(), r));
  for (double h : {-30.0, -5.0, 0.0, 9.8}) {  // the box z >= h cuts a cap of height r - h (all of it below -r)
    const double cap = r - std::max(h, -r);
    const double exact = kPi * cap * cap * (3.0 * r - cap) / 3.0;
    const TriangleMesh box = testing::box_mesh(Vec3(-50, -50, h), Vec3(50, 50, 50));
    const double on_triangles = exact_interference_volume(*ball->mesh, {}, box, {}).value().volume_mm3;
    const Aabb region{ball->mesh->bounds().min.cwiseMax(box.bounds().min), ball->mesh->bounds().max.cwiseMin(box.bounds().max)};
    const double band = tessellation_band_volume(*ball->mesh, {}, kDeflectionMm, region);
    SCOPED_TRACE("h " + std::to_string(h) + ": triangles " + std::to_string(on_triangles) + " exact " + std::to_string(exact) +
                 " band " + std::to_string(band));
    EXPECT_GT(std::fabs(on_triangles - exact), 0.0);
    EXPECT_LE(std::fabs(on_triangles - exact), band);
  }
}

// A depth found on the tessellations frees the tessellations; moved by what check_depth_on_brep
// reports, the exact spheres are apart (their analytic distance is > 0) — including overlaps far
// below the deflection, where the tessellations do not overlap at all and the depth on them is 0.
TEST(CadDepth, TheReportedDepthFreesTheExactSolids) {
  const double radii[][2] = {{50.0, 50.0}, {0.3, 150.0}, {20.0, 1.0}};
  for (const auto& r : radii) {
    auto a = cad_part(sphere(Vec3::Zero(), r[0]));
    auto b = cad_part(sphere(Vec3::Zero(), r[1]));
    const double touching = r[0] + r[1];
    for (double base : {0.0, 5e4}) {
      for (double overlap : {0.0005, 0.003, 0.02, 2.0}) {
        if (overlap > 0.5 * std::min(r[0], r[1])) continue;
        const Vec3 dir = Vec3(1, 0.3, -0.2).normalized();
        const RigidTransform pa = RigidTransform::from_translation(Vec3(base, 0, 0));
        const RigidTransform pb = RigidTransform::from_translation(Vec3(base, 0, 0) + (touching - overlap) * dir);
        auto found = penetration_vector(*a->bvh, pa, *b->bvh, pb, 162, 1e-4);
        ASSERT_TRUE(found.ok());
        // As the service does: no direction from the triangles (they are free) -> the centres' line.
        const Vec3 along = found.value().depth_mm > 0.0 ? found.value().direction : dir;
        auto checked = check_depth_on_brep({a.get(), pa}, {b.get(), pb}, along, found.value().depth_mm);
        ASSERT_TRUE(checked.ok()) << checked.error().to_string();
        EXPECT_TRUE(checked.value().checked);
        const Vec3 moved_centre = pb.translation + checked.value().depth_mm * along.normalized();
        EXPECT_GT((moved_centre - pa.translation).norm(), touching)
            << "radii " << r[0] << "/" << r[1] << " overlap " << overlap << " depth " << checked.value().depth_mm
            << " added " << checked.value().added_mm;
        EXPECT_GE(checked.value().depth_mm, overlap - 1e-4);
      }
    }
  }
}

// A CAD part against a mesh part (found by a review: the depth was the tessellation's, and the
// exact sphere moved by it still overlapped the box by 0.025 mm^3). Analytic oracle: a ball of
// radius 10 at the centre of the box [-50, 50]^3 is free of it once moved 60 mm along +y; a cube
// [-1, 1]^3 at the centre of the ball is free of the ball once moved 11 mm along +x.
TEST(CadDepth, ACadPartAgainstAMeshIsFreedOnItsExactFaces) {
  auto ball = cad_part(sphere(Vec3::Zero(), 10.0));
  auto box = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(-50, -50, -50), gp_Pnt(50, 50, 50)).Shape());
  auto cube = mesh_part(BRepPrimAPI_MakeBox(gp_Pnt(-1, -1, -1), gp_Pnt(1, 1, 1)).Shape());
  for (double base : {0.0, 5e4}) {
    const RigidTransform at = RigidTransform::from_translation(Vec3(base, 0, 0));
    for (const auto& [fixed, moving, along, free_at] :
         {std::tuple{box.get(), ball.get(), Vec3(0, 1, 0), 60.0}, {ball.get(), cube.get(), Vec3(1, 0, 0), 11.0}}) {
      auto found = penetration_along(*fixed->bvh, at, *moving->bvh, at, along, 1e-4);
      ASSERT_TRUE(found.ok()) << found.error().to_string();
      auto checked = check_depth_on_brep({fixed, at}, {moving, at}, along, found.value().depth_mm);
      ASSERT_TRUE(checked.ok()) << checked.error().to_string();
      EXPECT_TRUE(checked.value().checked);
      EXPECT_GE(checked.value().depth_mm, free_at) << "triangles' depth " << found.value().depth_mm << ", base " << base;
      EXPECT_LE(checked.value().depth_mm, free_at + 8.0 * kDeflectionMm);
    }
  }
}

// The shared volume of two exact solids comes with a bound that holds (OCCT's own estimate of its
// integration error did not: 2e-16 mm^3 claimed, 1.4e-7 mm^3 off on a torus lens). Oracle: the
// closed-form lens of two equal balls, V = pi (4r + d)(2r - d)^2 / 12 at centre distance d.
TEST(CadVolume, TheBooleanCommonsBoundHoldsOnLensesOfEveryDepth) {
  const double r = 10.0;
  auto a = cad_part(sphere(Vec3::Zero(), r));
  auto b = cad_part(sphere(Vec3::Zero(), r));
  for (double base : {0.0, 5e4})
    for (double d : {19.999, 19.95, 19.0, 12.0}) {
      const RigidTransform pa = RigidTransform::from_translation(Vec3(base, 0, 0));
      const Vec3 dir = Vec3(0.6, -0.64, 0.48);  // unit
      const RigidTransform pb = RigidTransform::from_translation(Vec3(base, 0, 0) + d * dir);
      auto shared = occt::shared_volume(a->shape, pa, b->shape, pb, pa.translation + 0.5 * d * dir, /*bound_error=*/true);
      ASSERT_TRUE(shared.ok()) << shared.error().to_string();
      const double exact = kPi * (4.0 * r + d) * (2.0 * r - d) * (2.0 * r - d) / 12.0;
      SCOPED_TRACE("d " + std::to_string(d) + " base " + std::to_string(base));
      EXPECT_LE(std::fabs(shared.value().volume_mm3 - exact), shared.value().error_bound_mm3) << shared.value().volume_mm3 << " vs " << exact;
      EXPECT_LT(shared.value().error_bound_mm3, (d > 19.99 ? 0.25 : 0.05) * exact);  // and it says something
    }
}

}  // namespace
}  // namespace gk::engine
