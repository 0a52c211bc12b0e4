// The BVH queries against the all-pairs oracle on random meshes and poses: the contact pair set is
// the same set exactly, the distance the same minimum to 1e-12 relative.
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/tolerances.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "kernel/query/triangle_distance.h"
#include "tests/support/brute_force.h"
#include "tests/support/near_contact_poses.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <thread>

namespace gk {
namespace {

using testing::PairSet;
using testing::Rng;

struct Scenario {
  std::shared_ptr<MeshBvh> a, b;
  RigidTransform pose_a, pose_b;
};

Scenario make_scenario(Rng& rng, int round) {
  Scenario s;
  // Alternate closed blobs and soups, leaf sizes 1 and 3, near and far poses.
  const bool soups = round % 2 == 1;
  auto ma = soups ? testing::random_soup(rng, 120, 6.0, 2.0) : testing::random_closed_blob(rng, 2, 6.0, 0.5, Vec3::Zero());
  auto mb = soups ? testing::random_soup(rng, 80, 5.0, 2.5) : testing::random_closed_blob(rng, 2, 5.0, 0.5, Vec3::Zero());
  s.a = MeshBvh::build(testing::share(std::move(ma)), {1 + 2 * (round % 2)}).value();
  s.b = MeshBvh::build(testing::share(std::move(mb)), {1 + 2 * ((round / 2) % 2)}).value();
  s.pose_a = testing::random_pose(rng, 100.0);
  // B near A: within a few mesh radii, so some poses collide and some do not.
  const RigidTransform offset = testing::random_pose(rng, 14.0);
  s.pose_b = s.pose_a * offset;
  return s;
}

PairSet as_set(const CollisionResult& r) {
  PairSet out;
  for (const Contact& c : r.contacts) out.insert({c.triangle_a, c.triangle_b});
  return out;
}

TEST(MeshQueriesBruteForce, ContactPairsFirstHitAndDistanceAgree) {
  Rng rng(2024);
  int colliding = 0, separate = 0;
  for (int round = 0; round < 60; ++round) {
    const Scenario s = make_scenario(rng, round);
    const PairSet truth = testing::brute_force_contacts(s.a->mesh(), s.pose_a, s.b->mesh(), s.pose_b);

    CollisionRequest all;
    all.all_contacts = true;
    const CollisionResult got = collide(*s.a, s.pose_a, *s.b, s.pose_b, all).value();
    EXPECT_EQ(as_set(got), truth) << "round " << round;

    const CollisionResult first = collide(*s.a, s.pose_a, *s.b, s.pose_b).value();
    EXPECT_EQ(first.colliding, !truth.empty()) << "round " << round;
    if (first.colliding) {
      ASSERT_EQ(first.contacts.size(), 1u);
      EXPECT_EQ(truth.count({first.contacts[0].triangle_a, first.contacts[0].triangle_b}), 1u);
    }
    (truth.empty() ? separate : colliding) += 1;

    const double expected = testing::brute_force_distance(s.a->mesh(), s.pose_a, s.b->mesh(), s.pose_b);
    const DistanceResult d = distance(*s.a, s.pose_a, *s.b, s.pose_b).value();
    ASSERT_TRUE(d.found);
    // Same triangle-distance routine on the same doubles: equal up to 1e-12 relative.
    EXPECT_NEAR(d.distance_mm, expected, 1e-12 * std::max(1.0, expected)) << "round " << round;
    // Witnesses are in world coordinates and as far apart as the distance (1e-9 relative).
    EXPECT_NEAR((d.point_a - d.point_b).norm(), d.distance_mm, 1e-9 * std::max(1.0, d.distance_mm));
    if (truth.empty()) {
      EXPECT_GT(d.distance_mm, 0.0);
    } else {
      EXPECT_EQ(d.distance_mm, 0.0);
    }
  }
  // The random poses must exercise both outcomes, or the test proves little.
  EXPECT_GT(colliding, 10);
  EXPECT_GT(separate, 10);
}

TEST(MeshQueriesBruteForce, ThresholdQueryAndPairsWithinDelta) {
  Rng rng(99);
  for (int round = 0; round < 40; ++round) {
    const Scenario s = make_scenario(rng, round);
    const double truth = testing::brute_force_distance(s.a->mesh(), s.pose_a, s.b->mesh(), s.pose_b);
    for (double delta : {0.05, 0.5, 2.0}) {
      DistanceRequest req;
      req.upper_bound_mm = delta;
      req.stop_below_mm = delta;
      const DistanceResult d = distance(*s.a, s.pose_a, *s.b, s.pose_b, req).value();
      EXPECT_EQ(d.found, truth < delta) << "round " << round << " delta " << delta << " truth " << truth;
      if (d.found) {
        EXPECT_LT(d.distance_mm, delta);
      }

      const PairSet within = testing::brute_force_pairs_within(s.a->mesh(), s.pose_a, s.b->mesh(), s.pose_b, delta);
      const ProximityResult got = pairs_within(*s.a, s.pose_a, *s.b, s.pose_b, delta).value();
      PairSet got_set;
      for (const ProximityPair& p : got.pairs) got_set.insert({p.triangle_a, p.triangle_b});
      EXPECT_EQ(got_set, within) << "round " << round << " delta " << delta;
    }
  }
}

// A box's few large triangles against a dense mesh driven into it, across them or just beside
// them: the traversal drops a leaf-node pair when each leaf triangle is apart from the node's box
// along its own normal; every contact pair must survive that, at factory offsets too, and the
// distance of the poses that do not touch must be the all-pairs minimum.
TEST(MeshQueriesBruteForce, ADenseMeshDrivenIntoLargeFlatTrianglesKeepsEveryContact) {
  Rng rng(77);
  int colliding = 0, apart = 0;
  for (int leaf_box : {1, 4, 7}) {
    for (int leaf_blob : {1, 4}) {
      const auto box = MeshBvh::build(testing::share(testing::box_mesh(Vec3(-450, -40, 0), Vec3(450, 40, 90))), {leaf_box}).value();
      const auto blob =
          MeshBvh::build(testing::share(testing::random_closed_blob(rng, 3, 30.0, 0.3, Vec3::Zero())), {leaf_blob}).value();
      for (double offset : {0.0, 25000.0, 1.0e6}) {
        for (int k = 0; k < 12; ++k) {
          const RigidTransform place = RigidTransform::from_translation(Vec3(offset, -offset, 0.5 * offset));
          // The blob's centre near one of the box's faces (inside, across or outside it).
          const RigidTransform turn = testing::random_pose(rng, 0.0);
          const Vec3 at(std::uniform_real_distribution<double>(-480, 480)(rng), std::uniform_real_distribution<double>(-75, 75)(rng),
                        std::uniform_real_distribution<double>(-35, 125)(rng));
          const RigidTransform pose_b = place * RigidTransform{turn.rotation, at};
          const PairSet truth = testing::brute_force_contacts(box->mesh(), place, blob->mesh(), pose_b);
          CollisionRequest all;
          all.all_contacts = true;
          const CollisionResult got = collide(*box, place, *blob, pose_b, all).value();
          EXPECT_EQ(as_set(got), truth) << "leaves " << leaf_box << "/" << leaf_blob << " offset " << offset << " pose " << k;
          if (truth.empty()) {
            ++apart;
            const double d = distance(*box, place, *blob, pose_b).value().distance_mm;
            const double expected = testing::brute_force_distance(box->mesh(), place, blob->mesh(), pose_b);
            EXPECT_NEAR(d, expected, 1e-9 * std::max(1.0, offset)) << "offset " << offset << " pose " << k;
          } else {
            ++colliding;
          }
        }
      }
    }
  }
  EXPECT_GT(colliding, 40);
  EXPECT_GT(apart, 40);
}

// A pose's rotation is accepted within 1e-9 of orthonormal (written with 9 decimals, say). The
// node tests assume an orthonormal rotation, so at factory coordinates their error (1e-9 of 10^7
// mm) once put boxes beside their triangles: crossings of a few micrometres were missed and a
// piercing pair came out CLEAR. A box far out on a random diagonal, one large triangle cutting
// into it by 1 nm to 10 um, the triangle's pose a rotation rounded to 9..11 decimals.
TEST(MeshQueriesBruteForce, RotationsRoundedToNineDecimalsKeepEveryContactAtFactoryCoordinates) {
  Rng rng(909);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int accepted = 0, crossing = 0;
  for (int digits : {9, 10, 11}) {
    for (int t = 0; t < 120; ++t) {
      Mat3 r = testing::random_pose(rng, 0.0).rotation;
      const double scale = std::pow(10.0, digits);
      for (int i = 0; i < 9; ++i) r.data()[i] = std::round(r.data()[i] * scale) / scale;
      const RigidTransform pose_b{r, Vec3::Zero()};
      if (!pose_b.is_rigid()) continue;
      ++accepted;
      const Vec3 direction(unit(rng) < 0.5 ? -1 : 1, unit(rng) < 0.5 ? -1 : 1, unit(rng) < 0.5 ? -1 : 1);
      const Vec3 lo = (direction * std::round(3e6 + 2.5e6 * unit(rng))).array().round();  // rotated, still within 1e7
      const auto box = MeshBvh::build(testing::share(testing::box_mesh(lo, lo + Vec3(10, 10, 10)))).value();
      const double depth = std::pow(10.0, -6.0 + 4.0 * unit(rng));
      const bool bottom = unit(rng) < 0.5;
      Vec3 c = lo + Vec3(5, 5, 0);
      c.z() = bottom ? lo.z() + depth : lo.z() + 10.0 - depth;
      // The triangle's vertices in its own frame, so that pose_b puts them where wanted.
      const Mat3 inverse = r.inverse();
      auto triangle = TriangleMesh::create({inverse * (c + Vec3(-100, -100, 0)), inverse * (c + Vec3(100, -100, 0)),
                                            inverse * (c + Vec3(0, 100, 0))},
                                           {{0, 1, 2}});
      ASSERT_TRUE(triangle.ok());
      const auto plane = MeshBvh::build(testing::share(std::move(triangle).value())).value();
      const PairSet truth = testing::brute_force_contacts(box->mesh(), {}, plane->mesh(), pose_b);
      CollisionRequest all;
      all.all_contacts = true;
      const CollisionResult got = collide(*box, {}, *plane, pose_b, all).value();
      EXPECT_EQ(as_set(got), truth) << digits << " decimals, trial " << t << ", depth " << depth;
      if (!truth.empty()) ++crossing;
      const double d = distance(*box, {}, *plane, pose_b).value().distance_mm;
      EXPECT_NEAR(d, testing::brute_force_distance(box->mesh(), {}, plane->mesh(), pose_b), 1e-9)
          << digits << " decimals, trial " << t;
    }
  }
  EXPECT_GT(accepted, 150);
  EXPECT_GT(crossing, 100);
}

// Meshes of thousands of triangles have node slabs (kernel/bvh/node_slabs.h), which collision,
// distance and pairs_within queries prune with, and leaf pairs skip triangles by their bound
// against the other leaf. Both meshes with slabs or one, near contact (gaps -1...3 mm) and random poses, at the
// origin and at factory offsets: the all-pairs minimum and pair set, no tree involved.
TEST(MeshQueriesBruteForce, ContactsDistanceAndPairsWithinPrunedBySlabsEqualTheAllPairsAnswers) {
  Rng rng(77);
  const auto big_a = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 5, 60.0, 0.6, Vec3::Zero()))).value();
  const auto big_b = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 5, 35.0, 0.6, Vec3::Zero()))).value();
  const auto small = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 2, 20.0, 0.5, Vec3::Zero()))).value();
  ASSERT_NE(big_a->node_slabs(), nullptr);
  ASSERT_NE(big_b->node_slabs(), nullptr);
  ASSERT_EQ(small->node_slabs(), nullptr);
  const std::vector<RigidTransform> near_big = testing::near_contact_poses(*big_a, *big_b, 5u, 6);
  const std::vector<RigidTransform> near_small = testing::near_contact_poses(*big_a, *small, 6u, 6);
  int apart = 0, touching = 0;
  for (int round = 0; round < 18; ++round) {
    const bool with_small = round % 3 == 2;
    const MeshBvh& b = with_small ? *small : *big_b;
    RigidTransform relative;
    if (round < 12) {
      relative = (with_small ? near_small : near_big)[static_cast<std::size_t>(round / 2)];
    } else {
      relative = testing::random_pose(rng, 110.0);
    }
    RigidTransform pose_a = testing::random_pose(rng, 50.0);
    if (round % 2 == 1) pose_a.translation += Vec3(1.0e6, -3.3e5, 1.4e5);
    const RigidTransform pose_b = pose_a * relative;
    // The small mesh as A every other time it is used: slabs on B's side only.
    const bool small_first = with_small && round % 2 == 0;
    const MeshBvh& first = small_first ? b : *big_a;
    const MeshBvh& second = small_first ? *big_a : b;
    const RigidTransform& pose_first = small_first ? pose_b : pose_a;
    const RigidTransform& pose_second = small_first ? pose_a : pose_b;

    const double truth = testing::brute_force_distance_pruned(first.mesh(), pose_first, second.mesh(), pose_second);
    const DistanceResult d = distance(first, pose_first, second, pose_second).value();
    ASSERT_TRUE(d.found);
    EXPECT_NEAR(d.distance_mm, truth, 1e-12 * std::max(1.0, truth) + 1e-12 * pose_a.translation.norm()) << "round " << round;
    (truth > 0.0 ? apart : touching) += 1;

    CollisionRequest all;
    all.all_contacts = true;
    const CollisionResult contacts = collide(first, pose_first, second, pose_second, all).value();
    EXPECT_EQ(as_set(contacts), testing::brute_force_contacts_pruned(first.mesh(), pose_first, second.mesh(), pose_second))
        << "round " << round;

    const double delta = 1.0;
    const PairSet within = testing::brute_force_pairs_within_pruned(first.mesh(), pose_first, second.mesh(), pose_second, delta);
    const ProximityResult got = pairs_within(first, pose_first, second, pose_second, delta).value();
    PairSet got_set;
    for (const ProximityPair& p : got.pairs) got_set.insert({p.triangle_a, p.triangle_b});
    EXPECT_EQ(got_set, within) << "round " << round;
  }
  // Both outcomes, or the test proves little.
  EXPECT_GT(apart, 5);
  EXPECT_GE(touching, 2);
}

// A pin `off` mm off its hole's axis towards a random turn, tilted up to 0.01 rad, 10 mm in, the
// hole turned and, every other round, 1e7 mm out: (pin's pose, hole's pose).
std::pair<RigidTransform, RigidTransform> pin_and_hole_poses(Rng& rng, int round, double off) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double tilt = 0.01 * (2.0 * unit(rng) - 1.0), turn = 6.3 * unit(rng);
  RigidTransform pose_hole = RigidTransform::from_axis_angle(Vec3::UnitZ(), turn);
  if (round % 2 == 1) pose_hole.translation = Vec3(9.9e6, -2.5e6, 3.0e5);
  const RigidTransform pin_in_hole =
      RigidTransform::from_axis_angle(Vec3(1, 0, 0), tilt, Vec3(off * std::cos(turn), off * std::sin(turn), -10.0));
  return {pose_hole * pin_in_hole, pose_hole};
}

// A pin in a hole, line to line on one side: two curved surfaces whose leaf boxes overlap all
// round while few triangle pairs are near (small meshes: no slabs, boxes only). The pairs within
// the contact distance, with each leaf pair's triangles bounded one by one, must be the
// all-pairs set: tilted, turned, at factory offsets, touching and crossing by the facets' sag.
TEST(MeshQueriesBruteForce, APinInItsHoleLineToLineKeepsEveryPairWithinTheContactDistance) {
  Rng rng(31);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto pin = MeshBvh::build(testing::share(testing::cylinder_mesh(6.0, 30.0, 96))).value();
  const auto hole = MeshBvh::build(testing::share(testing::cylinder_mesh(6.3, 12.0, 24))).value();
  int found = 0;
  for (int round = 0; round < 24; ++round) {
    // The hole's polygon has its inradius 6.3 cos(7.5 deg) = 6.246: a pin 0.25-0.3 mm off its
    // axis reaches its facets on one side.
    const double off = 0.25 + 0.05 * unit(rng);
    const auto [pose_pin, pose_hole] = pin_and_hole_poses(rng, round, off);
    const double delta = tolerances::kContactMm;
    const PairSet within = testing::brute_force_pairs_within(pin->mesh(), pose_pin, hole->mesh(), pose_hole, delta);
    const ProximityResult got = pairs_within(*pin, pose_pin, *hole, pose_hole, delta).value();
    PairSet got_set;
    for (const ProximityPair& p : got.pairs) got_set.insert({p.triangle_a, p.triangle_b});
    EXPECT_EQ(got_set, within) << "round " << round;
    found += static_cast<int>(within.size());
  }
  EXPECT_GT(found, 50);  // the pin does reach the hole's facets
}

// The same pin and hole built with slabs although they are small (BvhBuildOptions::
// slabs_at_any_size, what a fixture's elements get): the slabs of two coaxial curved surfaces a
// fraction of a millimetre apart prune what their boxes cannot, and must never prune a pair that
// is near. Pairs within the contact distance and within 0.2 mm, the minimum distance and every
// contact (the pin passes through the closed hole's end caps), against all pairs: the pin's side
// from line to line with the hole's facets (crossing by their sag) to 0.3 mm from them.
TEST(MeshQueriesBruteForce, SmallMeshesWithSlabsKeepEveryNearPairOfAPinInItsHole) {
  Rng rng(32);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  BvhBuildOptions with_slabs;
  with_slabs.slabs_at_any_size = true;
  const auto pin = MeshBvh::build(testing::share(testing::cylinder_mesh(6.0, 30.0, 96)), with_slabs).value();
  const auto hole = MeshBvh::build(testing::share(testing::cylinder_mesh(6.3, 12.0, 24)), with_slabs).value();
  ASSERT_NE(pin->node_slabs(), nullptr);
  ASSERT_NE(hole->node_slabs(), nullptr);
  int at_contact = 0, within_02 = 0;
  for (int round = 0; round < 32; ++round) {
    const double off = 0.3 * unit(rng);  // line to line at about 0.25
    const auto [pose_pin, pose_hole] = pin_and_hole_poses(rng, round, off);
    for (const double delta : {tolerances::kContactMm, 0.2}) {
      const PairSet within = testing::brute_force_pairs_within(pin->mesh(), pose_pin, hole->mesh(), pose_hole, delta);
      const ProximityResult got = pairs_within(*pin, pose_pin, *hole, pose_hole, delta).value();
      PairSet got_set;
      for (const ProximityPair& p : got.pairs) got_set.insert({p.triangle_a, p.triangle_b});
      EXPECT_EQ(got_set, within) << "round " << round << ", within " << delta;
      (delta < 0.1 ? at_contact : within_02) += static_cast<int>(within.size());
    }
    const double truth = testing::brute_force_distance_pruned(pin->mesh(), pose_pin, hole->mesh(), pose_hole);
    const DistanceResult d = distance(*pin, pose_pin, *hole, pose_hole).value();
    EXPECT_NEAR(d.distance_mm, truth, 1e-12 * std::max(1.0, truth) + 1e-12 * pose_hole.translation.norm()) << "round " << round;
    CollisionRequest all;
    all.all_contacts = true;
    const CollisionResult contacts = collide(*pin, pose_pin, *hole, pose_hole, all).value();
    EXPECT_EQ(as_set(contacts), testing::brute_force_contacts_pruned(pin->mesh(), pose_pin, hole->mesh(), pose_hole)) << "round " << round;
  }
  // Near pairs at both distances, or the test proves little.
  EXPECT_GT(at_contact, 50);
  EXPECT_GT(within_02, at_contact);
}

// A spare thread for the test: each start runs its job on a new std::thread.
class TestSpareThread final : public SpareThread {
 public:
  void start(std::function<void()> job) override {
    ++started;
    thread_ = std::thread(std::move(job));
  }
  void wait() override { thread_.join(); }
  int started = 0;  // jobs dealt out to it

 private:
  std::thread thread_;
};

// A distance query finished on two threads (the frontier dealt out, the best distance shared)
// gives the same minimum as on one and as the all-pairs oracle, with a witness pair at that
// distance: near contact and at random poses, unbounded and bounded, at the origin and 1e6 mm out.
TEST(MeshQueriesBruteForce, ADistanceQueryFinishedOnTwoThreadsEqualsTheAllPairsMinimum) {
  Rng rng(4321);
  const auto a = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 5, 60.0, 0.6, Vec3::Zero()))).value();
  const auto b = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 5, 35.0, 0.6, Vec3::Zero()))).value();
  const std::vector<RigidTransform> near = testing::near_contact_poses(*a, *b, 17u, 7);
  int split = 0;
  for (int round = 0; round < 14; ++round) {
    const RigidTransform relative = round < 7 ? near[static_cast<std::size_t>(round)] : testing::random_pose(rng, 150.0);
    RigidTransform pose_a = testing::random_pose(rng, 50.0);
    if (round % 2 == 1) pose_a.translation += Vec3(1.0e6, -3.3e5, 1.4e5);
    const RigidTransform pose_b = pose_a * relative;
    for (const double bound : {std::numeric_limits<double>::infinity(), 20.0}) {
      DistanceRequest one;
      one.upper_bound_mm = bound;
      DistanceRequest two = one;
      TestSpareThread spare;
      two.spare = &spare;
      const DistanceResult d1 = distance(*a, pose_a, *b, pose_b, one).value();
      const DistanceResult d2 = distance(*a, pose_a, *b, pose_b, two).value();
      ASSERT_EQ(d1.found, d2.found) << "round " << round;
      if (!d1.found) continue;
      EXPECT_EQ(d1.distance_mm, d2.distance_mm) << "round " << round;
      const double truth = testing::brute_force_distance_pruned(a->mesh(), pose_a, b->mesh(), pose_b);
      EXPECT_NEAR(d2.distance_mm, truth, 1e-12 * std::max(1.0, truth) + 1e-12 * pose_a.translation.norm()) << "round " << round;
      // The witnesses lie on the triangles they name, that distance apart.
      Triangle ta = a->mesh().triangle(d2.triangle_a), tb = b->mesh().triangle(d2.triangle_b);
      for (Vec3& v : ta) v = pose_a.apply(v);
      for (Vec3& v : tb) v = pose_b.apply(v);
      EXPECT_NEAR(triangle_distance(ta, tb).distance, d2.distance_mm, 1e-9) << "round " << round;
      EXPECT_NEAR((d2.point_a - d2.point_b).norm(), d2.distance_mm, 1e-9) << "round " << round;
      // (Counted by the jobs started, not by the work done: a loaded machine may let the first
      // thread finish before the second one runs.)
      split += spare.started > 0 ? 1 : 0;
    }
  }
  EXPECT_GT(split, 6) << "most of these queries must have been dealt out to the second thread";
}

// A mesh whose own coordinates are near 1e7 mm, posed by a rotation written with 9 decimals
// (accepted: within kRotationOrthonormality of orthonormal, but not orthonormal): B's triangle
// pierces A's world triangle by 0.002 mm either way. The queries used to map B into A's frame with
// the rotation's transpose, which misplaced it by 0.002-0.012 mm here: no contact, apart by 2 um
// (found by an adversarial review with exact rational posing). The world triangle is placed here
// with the pose as given (rounding about 1e-9 mm at these coordinates, far below the piercing).
TEST(MeshQueriesBruteForce, ARotationWrittenWithNineDecimalsOnFactoryCoordinatesKeepsItsContacts) {
  Mat3 nine_decimals;
  nine_decimals << 1.0, 0.0, 0.0, 0.0, 0.866025404, -0.5, 0.0, 0.5, 0.866025404;
  const Vec3 stretch_axis = Vec3(1, 1, 1).normalized();
  for (double stretch : {0.0, 0.6e-9}) {
    const Mat3 r = nine_decimals * (Mat3::Identity() + (std::sqrt(1.0 + 3.0 * stretch) - 1.0) * stretch_axis * stretch_axis.transpose());
    RigidTransform pose_a{r, Vec3::Zero()};
    ASSERT_TRUE(pose_a.is_rigid()) << "stretch " << stretch;
    const Vec3 local(7e6, 0.0, 9.9e6);
    pose_a.translation = -(r * local);  // the part's world place near the origin
    const Triangle ta{local + Vec3(-10, -10, 0), local + Vec3(10, -10, 0), local + Vec3(0, 10, 0)};
    const Vec3 centre = (pose_a.apply(ta[0]) + pose_a.apply(ta[1]) + pose_a.apply(ta[2])) / 3.0;
    const Vec3 normal = (pose_a.apply(ta[1]) - pose_a.apply(ta[0])).cross(pose_a.apply(ta[2]) - pose_a.apply(ta[0])).normalized();
    const Vec3 across = normal.cross(Vec3::UnitX()).normalized();
    for (double side : {1.0, -1.0}) {
      // B pierces A's plane: from 0.002 mm on one side to 5 mm on the other.
      const Triangle tb{centre - side * 0.002 * normal - across, centre - side * 0.002 * normal + across, centre + side * 5.0 * normal};
      const auto a = MeshBvh::build(testing::share(TriangleMesh::create({ta[0], ta[1], ta[2]}, {{0, 1, 2}}).value())).value();
      const auto b = MeshBvh::build(testing::share(TriangleMesh::create({tb[0], tb[1], tb[2]}, {{0, 1, 2}}).value())).value();
      const CollisionResult hit = collide(*a, pose_a, *b, RigidTransform::identity()).value();
      EXPECT_TRUE(hit.colliding) << "stretch " << stretch << " side " << side;
      EXPECT_EQ(distance(*a, pose_a, *b, RigidTransform::identity()).value().distance_mm, 0.0) << "stretch " << stretch;
    }
  }
}

TEST(MeshQueriesBruteForce, BadPosesAndRequestsAreErrorsNamingTheField) {
  Rng rng(5);
  const Scenario s = make_scenario(rng, 0);
  RigidTransform nan_pose;
  nan_pose.translation.x() = std::nan("");
  auto c = collide(*s.a, nan_pose, *s.b, s.pose_b);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().field, "pose_a");
  RigidTransform sheared;
  sheared.rotation(0, 1) = 0.5;
  auto d = distance(*s.a, s.pose_a, *s.b, sheared);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.error().field, "pose_b");
  DistanceRequest bad;
  bad.upper_bound_mm = -1.0;
  auto e = distance(*s.a, s.pose_a, *s.b, s.pose_b, bad);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.error().field, "upper_bound_mm");
  auto f = pairs_within(*s.a, s.pose_a, *s.b, s.pose_b, std::nan(""));
  ASSERT_FALSE(f.ok());
  EXPECT_EQ(f.error().field, "delta_mm");
}

}  // namespace
}  // namespace gk
