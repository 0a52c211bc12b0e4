// The motion between two poses (kernel/query/rigid_sweep.h) is the screw motion: it starts and
// ends at the poses, keeps a pivot fixed when the two poses turn about one, and no point moves
// farther than the rate bound or strays from its chord more than the sagitta bound - checked by
// following points along the motion in fine steps, on random pose pairs up to half turns and at
// factory offsets.
#include "kernel/query/rigid_sweep.h"

#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace gk {
namespace {

using testing::Rng;

TEST(RigidSweep, TheScrewMotionEndsAtItsPosesAndItsPointsKeepWithinTheBounds) {
  Rng rng(31);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto box = MeshBvh::build(testing::share(testing::box_mesh(Vec3(-30, -10, -5), Vec3(40, 20, 15)))).value();
  int turned = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double offset = trial % 3 == 0 ? 1.0e6 : 0.0;
    RigidTransform from = testing::random_pose(rng, 200.0), to = testing::random_pose(rng, 200.0);
    from.translation.x() += offset;
    to.translation.x() += offset;
    if (trial % 4 == 0) to.rotation = from.rotation;  // some without a turn
    const MotionBound bound = motion_bound(*box, from, to);
    turned += bound.angle_rad > 0.1 ? 1 : 0;
    const double scale = 1e-9 * (1.0 + offset);
    EXPECT_LT((pose_between(from, to, 0.0).translation - from.translation).norm(), scale);
    EXPECT_LT((pose_between(from, to, 1.0).translation - to.translation).norm(), scale) << "trial " << trial;
    EXPECT_LT((pose_between(from, to, 1.0).rotation - to.rotation).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
    // Points of the box (its corners and random inner points), followed in 2,000 steps.
    for (int k = 0; k < 12; ++k) {
      const Vec3 p = k < 8 ? Vec3((k & 1) ? 40 : -30, (k & 2) ? 20 : -10, (k & 4) ? 15 : -5)
                           : Vec3(5 + 35 * unit(rng), 5 + 15 * unit(rng), 5 + 10 * unit(rng));
      const Vec3 start = from.apply(p), end = to.apply(p);
      const Vec3 chord = end - start;
      double length = 0.0, stray = 0.0;
      Vec3 last = start;
      for (int i = 1; i <= 2000; ++i) {
        const Vec3 x = pose_between(from, to, i / 2000.0).apply(p);
        length += (x - last).norm();
        last = x;
        const double t = chord.squaredNorm() > 0.0 ? std::clamp((x - start).dot(chord) / chord.squaredNorm(), 0.0, 1.0) : 0.0;
        stray = std::max(stray, (x - (start + t * chord)).norm());
      }
      EXPECT_LE(length, bound.rate() * (1.0 + 1e-9) + scale) << "trial " << trial << " point " << k;
      EXPECT_LE(stray, bound.sagitta_mm * (1.0 + 1e-9) + scale) << "trial " << trial << " point " << k;
    }
  }
  EXPECT_GT(turned, 150);
}

// A mesh written at factory coordinates (its vertices 9.9e6 mm from its own origin) turned by
// 1e-3 rad about its middle and slid 1 mm: its points move about 1 mm, and the rate says so (it
// was measured from the mesh's origin: 1.7e4 mm, and a clear frame ran out of steps).
TEST(RigidSweep, AMeshWrittenAtFactoryCoordinatesMovesAtTheRateOfItsOwnSize) {
  const Vec3 far(9.9e6, 9.9e6, 9.9e6);
  const auto cube = MeshBvh::build(testing::share(testing::box_mesh(far, far + Vec3(10, 10, 10)))).value();
  const Vec3 middle = far + Vec3(5, 5, 5);
  const Mat3 turn = Eigen::AngleAxisd(1e-3, Vec3(0.3, 0.5, 0.8).normalized()).toRotationMatrix();
  const RigidTransform from = RigidTransform::from_translation(-far);
  RigidTransform to{turn, Vec3::Zero()};
  to.translation = (Vec3(5, 5, 5) + Vec3(1, 0, 0)) - turn * middle;  // the middle moved by 1 mm
  const MotionBound bound = motion_bound(*cube, from, to);
  EXPECT_LT(bound.rate(), 1.1) << "travel " << bound.travel_mm << ", reach " << bound.reach_mm;
  // And it is a bound: every corner's path, followed in 2,000 steps, is no longer.
  for (int k = 0; k < 8; ++k) {
    const Vec3 p = far + Vec3((k & 1) ? 10 : 0, (k & 2) ? 10 : 0, (k & 4) ? 10 : 0);
    double length = 0.0;
    Vec3 last = from.apply(p);
    for (int i = 1; i <= 2000; ++i) {
      const Vec3 x = pose_between(from, to, i / 2000.0).apply(p);
      length += (x - last).norm();
      last = x;
    }
    EXPECT_LE(length, bound.rate() * (1.0 + 1e-9) + 1e-6) << "corner " << k;
  }
}

// A part tipped over an edge: the second pose turns the first about a line through a point q of
// that edge. Every pose between keeps q where it was (a turn about the part's own origin with the
// origin moving straight would dip it by up to lever x (1 - cos(angle / 2))).
TEST(RigidSweep, APivotStaysWhereItIsAllAlongTheMotion) {
  Rng rng(8);
  for (int trial = 0; trial < 100; ++trial) {
    const RigidTransform from = testing::random_pose(rng, 500.0);
    const Vec3 q_local(10.0, -5.0, 0.0);
    const Vec3 q = from.apply(q_local);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const Vec3 axis = Vec3(unit(rng), unit(rng), unit(rng)).normalized();
    const double angle = 3.0 * unit(rng);
    const Mat3 turn = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    const RigidTransform to{turn * from.rotation, turn * (from.translation - q) + q};
    for (int i = 0; i <= 20; ++i)
      EXPECT_LT((pose_between(from, to, i / 20.0).apply(q_local) - q).norm(), 1e-9) << "trial " << trial << " s " << i / 20.0;
  }
}

}  // namespace
}  // namespace gk
