// ClearanceQuery end to end, on the real daemon: micrometre gaps and overlaps 50 m from the
// origin in many orientations, the distance +/- epsilon invariant on real parts, the B-Rep
// interference volume, and the B-Rep faces of each contact region.
#include "kernel/measure/interference_volume.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/bvh/mesh_bvh.h"
#include "occt_adapters/exact_measures.h"
#include "occt_adapters/shape_builders.h"
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"
#include "tests/server/daemon_fixture.h"
#include "tests/support/sanitized_build.h"
#include "tests/support/random_meshes.h"
#include "kernel/core/units.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;


void set_pose(const Eigen::AngleAxisd& rotation, const Vec3& translation, pb::Pose* out) {
  out->mutable_translation()->set_x_mm(translation.x());
  out->mutable_translation()->set_y_mm(translation.y());
  out->mutable_translation()->set_z_mm(translation.z());
  out->mutable_rotation_axis()->set_x_mm(rotation.axis().x());
  out->mutable_rotation_axis()->set_y_mm(rotation.axis().y());
  out->mutable_rotation_axis()->set_z_mm(rotation.axis().z());
  out->set_rotation_deg(rotation.angle() * 180.0 / kPi);
}

Vec3 vec(const pb::Vec3& v) { return Vec3(v.x_mm(), v.y_mm(), v.z_mm()); }

pb::ClearanceQueryResponse query(pb::Gatekeeper::Stub& stub, const pb::ClearanceQueryRequest& request) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
  pb::ClearanceQueryResponse response;
  const grpc::Status status = stub.ClearanceQuery(&ctx, request, &response);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return response;
}

std::string upload(pb::Gatekeeper::Stub& stub, const std::string& bytes, const std::string& format) {
  return testing::upload_part_id(stub, bytes, format);
}

// A closed 100 mm cube centred on its origin, as OBJ text.
std::string cube_obj() { return testing::box_obj(-50, -50, -50, 50, 50, 50); }

TEST(ClearanceE2E, MicrometreGapsAndOverlapsFiftyMetresOutAreDecidedInEveryOrientation) {
  Daemon daemon(testing::temp_dir("clearance-precision"));
  auto stub = daemon.stub();
  const std::string cube = upload(*stub, cube_obj(), "obj");
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Vec3 far(5.0e4, -3.7e4, 4.2e4);
  for (int orientation = 0; orientation < 40; ++orientation) {
    const Eigen::AngleAxisd rot_a(std::abs(unit(rng)) * kPi, Vec3(unit(rng), unit(rng), unit(rng)).normalized());
    const Mat3 ra = rot_a.toRotationMatrix();
    for (int contact = 0; contact < 2; ++contact) {
      // Face on face (B turned like A), or B turned 45 degrees about A's z: B's edge faces A's face.
      const Eigen::AngleAxisd rot_b = contact == 0 ? rot_a : Eigen::AngleAxisd(Eigen::Quaterniond(ra * Eigen::AngleAxisd(kPi / 4, Vec3::UnitZ()).toRotationMatrix()));
      const double touching_x = contact == 0 ? 100.0 : 50.0 + 50.0 * std::sqrt(2.0);
      for (double gap : {0.003, -0.003}) {
        pb::ClearanceQueryRequest request;
        request.mutable_a()->set_part_id(cube);
        request.mutable_b()->set_part_id(cube);
        set_pose(rot_a, far, request.mutable_a()->mutable_pose());
        set_pose(rot_b, far + ra * Vec3(touching_x + gap, 0, 0), request.mutable_b()->mutable_pose());
        request.set_safety_gap_mm(0.01);
        const pb::ClearanceQueryResponse r = query(*stub, request);
        if (gap > 0) {
          ASSERT_EQ(r.verdict(), pb::CLEAR) << "orientation " << orientation << " contact " << contact;
          EXPECT_NEAR(r.distance_mm(), gap, 1e-6);
          EXPECT_TRUE(r.gap_violated());
        } else {
          ASSERT_EQ(r.verdict(), pb::COLLISION) << "orientation " << orientation << " contact " << contact;
        }
        EXPECT_LT(r.error_bound_mm(), 1e-6);
      }
    }
  }
}

TEST(ClearanceE2E, MovingByTheDistancePlusOrMinusEpsilonAlongTheWitnessFlipsTheVerdict) {
  Daemon daemon(testing::temp_dir("clearance-invariant"));
  auto stub = daemon.stub();
  // Both in millimetres (the KUKA meshes are in metres): FCL's robot (1,000 mm) and the TR12J part.
  const std::string base = upload(*stub, testing::read_file(testing::shared_data("meshes/fcl/rob.obj")), "obj");
  const std::string tr12j = upload(*stub, testing::read_file(testing::shared_data("meshes/occt/TR12J_OCC64K.stl")), "stl");
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  constexpr double kEpsilon = 1e-3;
  int checked = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const Eigen::AngleAxisd rot_b(std::abs(unit(rng)) * kPi, Vec3(unit(rng), unit(rng), unit(rng)).normalized());
    Vec3 t_b = 1500.0 * Vec3(unit(rng), unit(rng), unit(rng)).normalized() + Vec3(2e4, 1e4, 0);
    pb::ClearanceQueryRequest request;
    request.mutable_a()->set_part_id(base);
    request.mutable_b()->set_part_id(tr12j);
    set_pose(Eigen::AngleAxisd(0.0, Vec3::UnitZ()), Vec3(2e4, 1e4, 0), request.mutable_a()->mutable_pose());
    // Walk B towards A along the witnesses until it is a random 0.01-5 mm away.
    pb::ClearanceQueryResponse r;
    for (int approach = 0; approach < 4; ++approach) {
      set_pose(rot_b, t_b, request.mutable_b()->mutable_pose());
      r = query(*stub, request);
      if (r.verdict() != pb::CLEAR) break;
      const double target = 0.01 + 5.0 * std::abs(unit(rng));
      if (r.distance_mm() < 6.0) break;
      t_b += (r.distance_mm() - target) * (vec(r.point_a()) - vec(r.point_b())).normalized();
    }
    if (r.verdict() != pb::CLEAR || r.distance_mm() < 0.005) continue;
    const double d = r.distance_mm();
    const Vec3 u = (vec(r.point_a()) - vec(r.point_b())).normalized();
    set_pose(rot_b, t_b + (d - kEpsilon) * u, request.mutable_b()->mutable_pose());
    const pb::ClearanceQueryResponse short_of = query(*stub, request);
    EXPECT_EQ(short_of.verdict(), pb::CLEAR) << "trial " << trial;
    EXPECT_NEAR(short_of.distance_mm(), kEpsilon, 1e-8) << "trial " << trial;
    set_pose(rot_b, t_b + (d + kEpsilon) * u, request.mutable_b()->mutable_pose());
    EXPECT_EQ(query(*stub, request).verdict(), pb::COLLISION) << "trial " << trial << " d=" << d;
    ++checked;
  }
  EXPECT_GE(checked, 8);
}

TEST(ClearanceE2E, CadPartsGetTheBooleanVolumeAndRegionsNameTheirFaces) {
  Daemon daemon(testing::temp_dir("clearance-brep"));
  auto stub = daemon.stub();
  const std::string path = testing::shared_data("step/occt/Pump_Nut.brep");
  const std::string nut = upload(*stub, testing::read_file(path), "brep");
  const occt::Shape shape = occt::read_shape_file(path).value();
  // Overlapping by a 2 mm shift: the service's volume is OCCT's Boolean common of the placed
  // solids; the ray-cast volume of the tessellations (an independent method) agrees within 1 %.
  pb::ClearanceQueryRequest request;
  request.mutable_a()->set_part_id(nut);
  request.mutable_b()->set_part_id(nut);
  request.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(2.0);
  request.set_compute_volume(true);
  request.set_compute_depth(true);
  const pb::ClearanceQueryResponse deep = query(*stub, request);
  ASSERT_EQ(deep.verdict(), pb::COLLISION);
  EXPECT_EQ(deep.volume_method(), "brep boolean common");
  const RigidTransform shift = RigidTransform::from_translation(Vec3(2, 0, 0));
  const double boolean = occt::interference_volume(shape, occt::place(shape, shift).value()).value();
  EXPECT_NEAR(deep.interference_volume_mm3(), boolean, 1e-6 * boolean);
  const auto meshed = occt::mesh_shape(shape, 0.05).value();
  const auto bvh = MeshBvh::build(testing::share(meshed.mesh)).value();
  const double rays = interference_volume(*bvh, {}, *bvh, shift, 256).value().volume_mm3;
  EXPECT_NEAR(deep.interference_volume_mm3(), rays, 0.01 * rays);
  // The depth frees B (a certified upper bound: checked here on the kernel), and is no more than
  // sliding B off along one of the box's axes: its width plus the 2 mm along x, its extent along y or z.
  const Aabb box = meshed.mesh.bounds();
  const Vec3 direction = vec(deep.depth_direction());
  RigidTransform freed = shift;
  freed.translation += (deep.depth_mm() + 1e-3) * direction;
  EXPECT_FALSE(collide(*bvh, {}, *bvh, freed).value().colliding);
  EXPECT_GT(deep.depth_mm(), 0.0);
  // How good a depth the 2 s search finds is a matter of speed, not judged in the slow sanitizer build.
  if (!testing::kSanitizedBuild) {
    EXPECT_LE(deep.depth_mm(), std::min({box.diagonal().x() + 2.0, box.diagonal().y(), box.diagonal().z()}) + 1e-3);
  }
  EXPECT_FALSE(deep.depth_exact());  // a nut is not convex
  // A copy moved along x by its box's width plus 3 mm, with a 10 mm gap: every region names the
  // faces it lies on, and the refined witnesses' faces are among them.
  request.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(box.diagonal().x() + 3.0);
  request.set_safety_gap_mm(10.0);
  const pb::ClearanceQueryResponse apart = query(*stub, request);
  ASSERT_EQ(apart.verdict(), pb::CLEAR);
  ASSERT_TRUE(apart.refined_on_brep());
  ASSERT_GT(apart.regions_size(), 0);
  std::set<std::uint32_t> faces_a, faces_b;
  for (const pb::ContactRegion& region : apart.regions()) {
    EXPECT_GT(region.faces_a_size(), 0);
    EXPECT_GT(region.faces_b_size(), 0);
    faces_a.insert(region.faces_a().begin(), region.faces_a().end());
    faces_b.insert(region.faces_b().begin(), region.faces_b().end());
  }
  EXPECT_EQ(faces_a.count(apart.face_a()), 1u) << apart.face_a();
  EXPECT_EQ(faces_b.count(apart.face_b()), 1u) << apart.face_b();
}

}  // namespace
}  // namespace gk
