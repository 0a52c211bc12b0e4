// Safety of the P4 pipeline's shortcuts, on thousands of random cases:
//  - the hull level of detail never clears an organ that the exact sweep reaches;
//  - conservative advancement agrees with the OCCT swept solid (MakeRevol, meshed);
//  - refitting the organ tree answers exactly like rebuilding it.
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "machine_models/p4/machine_scene.h"
#include "machine_models/p4/manipulator_geometry.h"
#include "machine_models/p4/motion_sweep.h"
#include "machine_models/p4/plate_shapes.h"
#include "machine_models/p4/step_validator.h"
#include "occt_adapters/shape_builders.h"
#include "occt_adapters/shape_mesher.h"
#include "tests/support/random_meshes.h"
#include "tests/support/sanitized_build.h"
#include "kernel/core/units.h"

#include <gtest/gtest.h>

#include <map>
#include <random>

namespace gk::p4 {
namespace {


struct RandomBend {
  SheetPart part = SheetPart::from_plates({}, 1.0);
  BendStep step;
  MachineState state;
};

RandomBend random_bend(testing::Rng& rng, const MachineModel& model) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RandomBend r;
  const double t = 0.5 + 2.5 * u(rng);
  SheetPartSpec spec{200.0 + 1300.0 * u(rng), 300.0 + 600.0 * u(rng), t, {}, {}};
  const double flange = 20.0 + 330.0 * u(rng);
  const double line = spec.depth_mm - flange;
  // Side flanges that stop short of the bend line, up or down, and a tab under the blankholder.
  for (Side side : {Side::kXMin, Side::kXMax})
    if (u(rng) < 0.5)
      spec.flanges.push_back({side, 10.0 + 150.0 * u(rng), (u(rng) < 0.7 ? 1.0 : -1.0) * (30.0 + 100.0 * u(rng)), 0.0,
                              std::max(1.0, line - 10.0)});
  if (u(rng) < 0.5) spec.flanges.push_back({Side::kYMax, 10.0 + 100.0 * u(rng), (u(rng) < 0.5 ? 1.0 : -1.0) * 90.0, 0.0, 0.0});
  r.part = SheetPart::create(spec).value();
  r.step.kind = u(rng) < 0.6 ? StepKind::kBendUp : StepKind::kBendDown;
  r.step.bend_point_mm = Vec2(0.0, line);
  r.step.bend_direction = Vec2(1.0, 0.0);
  r.step.target_angle_deg = 10.0 + 125.0 * u(rng);
  r.step.lateral_shift_mm = -300.0 + 600.0 * u(rng);
  r.state.clamp_z_mm = t;
  r.state.engaged_segments.resize(model.aba.segment_widths_mm.size());
  for (std::size_t i = 0; i < r.state.engaged_segments.size(); ++i) r.state.engaged_segments[i] = u(rng) < 0.7;
  return r;
}

// Plates (machine coordinates) as one moving body.
MovingBody body_of(const std::vector<Plate>& plates) {
  MovingBody body;
  TriangleMesh mesh = plates_mesh(plates);
  body.points = mesh.vertices();
  body.mesh = MeshBvh::build(std::make_shared<const TriangleMesh>(std::move(mesh))).value();
  return body;
}

// The moving body and motion of a bend, built here the way the validator builds them.
bool bend_body(const MachineModel& model, const RandomBend& r, MovingBody& body, Motion& motion,
               std::vector<Plate>& plates) {
  std::vector<Plate> moving, fixed;
  if (!r.part.split(r.step.bend_point_mm, r.step.bend_direction, model.bend_zone_mm, moving, fixed).ok() || moving.empty())
    return false;
  const RigidTransform placement = part_placement(r.part, r.step);
  plates.clear();
  for (const Plate& p : moving) plates.push_back(p.transformed(placement));
  body = body_of(plates);
  const double t = r.part.thickness_mm();
  const bool up = r.step.kind == StepKind::kBendUp;
  motion = {true, Vec3(0, 0, up ? t : 0.0), Vec3::UnitX(), (up ? 1.0 : -1.0) * r.step.target_angle_deg * kPi / 180.0,
            Vec3::Zero()};
  return true;
}

// Every organ the flange of a bend meets: all of them, supports and the parked blade included.
std::vector<SweepOrgan> sweep_organs(const MachineScene& scene) {
  std::vector<SweepOrgan> out;
  for (std::size_t i = 0; i < scene.organs().size(); ++i) {
    const Organ& o = scene.organs()[i];
    out.push_back({static_cast<int>(i), o.mesh.get(), o.pose});
  }
  return out;
}

TEST(P4Safety, HullLevelOfDetailNeverClearsWhatTheExactSweepReaches) {
  const MachineModel model = default_machine_model().value();
  auto scene = MachineScene::build(model).value();
  testing::Rng rng(314);
  int cases = 0, organs_cleared_by_hull = 0, exact_collisions = 0;
  AdvanceOptions adv;
  adv.required_clearance_mm = 0.1;
  for (int trial = 0; trial < testing::samples(1000); ++trial) {
    const RandomBend r = random_bend(rng, model);
    ASSERT_TRUE(scene->apply_state(r.state).ok());
    MovingBody body;
    Motion motion;
    std::vector<Plate> plates;
    if (!bend_body(model, r, body, motion, plates)) continue;
    ++cases;
    const std::vector<SweepOrgan> organs = sweep_organs(*scene);
    // A coarse sampling step makes the sagitta matter.
    const HullLodResult lod = hull_lod({body}, motion, organs, adv.required_clearance_mm, 40.0 * kPi / 180.0).value();
    std::vector<char> remaining(organs.size(), 0);
    for (int i : lod.remaining) remaining[i] = 1;
    for (std::size_t i = 0; i < organs.size(); ++i) {
      const SweepOutcome exact = conservative_advance({body}, motion, {organs[i]}, adv).value();
      ASSERT_FALSE(exact.budget_exceeded);
      if (exact.collided) ++exact_collisions;
      if (remaining[i]) continue;
      ++organs_cleared_by_hull;
      ASSERT_FALSE(exact.collided) << "trial " << trial << ": the hull cleared " << scene->organs()[organs[i].index].name
                                   << " but the sweep reaches it at s = " << exact.contact_s;
    }
  }
  // The test must exercise both sides of the question.
  EXPECT_GT(cases, testing::samples(750));
  EXPECT_GT(organs_cleared_by_hull, testing::samples(5000));
  EXPECT_GT(exact_collisions, testing::samples(100));
  RecordProperty("cases", cases);
  RecordProperty("organs_cleared_by_hull", organs_cleared_by_hull);
  RecordProperty("exact_collisions", exact_collisions);
}

TEST(P4Safety, VerticalPrismHullNeverClearsWhatARotationReaches) {
  // ROTATE steps bound the sweep by a prism over the 2D hull of the sampled footprints.
  const MachineModel model = default_machine_model().value();
  auto scene = MachineScene::build(model).value();
  testing::Rng rng(1618);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int cleared_pairs = 0, collisions = 0;
  AdvanceOptions adv;
  adv.required_clearance_mm = 0.1;
  for (int trial = 0; trial < 300; ++trial) {
    RandomBend r = random_bend(rng, model);
    r.state.manipulator_y_mm = -200.0 - 1500.0 * u(rng);
    ASSERT_TRUE(scene->apply_state(r.state).ok());
    BendStep place = r.step;
    place.kind = StepKind::kRotate;
    const RigidTransform placement = part_placement(r.part, place);
    std::vector<Plate> plates;
    for (const Plate& p : r.part.plates()) plates.push_back(p.transformed(placement));
    const MovingBody body = body_of(plates);
    const double angle = (u(rng) < 0.5 ? -1.0 : 1.0) * (10.0 + 170.0 * u(rng));
    const Motion motion{true, Vec3(-300.0 + 600.0 * u(rng), r.state.manipulator_y_mm, 0.0), Vec3::UnitZ(),
                        angle * kPi / 180.0, Vec3::Zero()};
    std::vector<SweepOrgan> organs;
    for (std::size_t i = 0; i < scene->organs().size(); ++i)
      if (!scene->organs()[i].support) organs.push_back({static_cast<int>(i), scene->organs()[i].mesh.get(), scene->organs()[i].pose});
    const HullLodResult lod = hull_lod({body}, motion, organs, adv.required_clearance_mm, 30.0 * kPi / 180.0).value();
    std::vector<char> remaining(organs.size(), 0);
    for (int i : lod.remaining) remaining[i] = 1;
    for (std::size_t i = 0; i < organs.size(); ++i) {
      const SweepOutcome exact = conservative_advance({body}, motion, {organs[i]}, adv).value();
      if (exact.collided) ++collisions;
      if (remaining[i]) continue;
      ++cleared_pairs;
      ASSERT_FALSE(exact.collided) << "trial " << trial << ": the prism cleared " << scene->organs()[organs[i].index].name;
    }
  }
  EXPECT_GT(cleared_pairs, 3000);
  EXPECT_GT(collisions, 100);
}

TEST(P4Safety, ConservativeAdvancementAgreesWithTheOcctSweptSolid) {
  const MachineModel model = default_machine_model().value();
  auto scene = MachineScene::build(model).value();
  testing::Rng rng(2718);
  const double deflection = 0.05;  // [mm] tessellation of the swept solid
  int compared = 0, colliding = 0, clear = 0;
  AdvanceOptions adv;
  adv.required_clearance_mm = 1e-3;
  for (int trial = 0; trial < 60; ++trial) {
    const RandomBend r = random_bend(rng, model);
    ASSERT_TRUE(scene->apply_state(r.state).ok());
    MovingBody body;
    Motion motion;
    std::vector<Plate> plates;
    if (!bend_body(model, r, body, motion, plates)) continue;
    // The swept solid: every moving plate revolved about the bend axis, then meshed.
    const occt::Shape part = plates_shape(plates).value();
    auto swept = occt::revolve(part, motion.axis_point, motion.axis_direction, motion.angle_rad * 180.0 / kPi);
    ASSERT_TRUE(swept.ok()) << swept.error().to_string();
    auto meshed = occt::mesh_shape(swept.value(), deflection);
    ASSERT_TRUE(meshed.ok()) << meshed.error().to_string();
    const auto sweep_bvh = MeshBvh::build(std::make_shared<const TriangleMesh>(meshed.value().mesh)).value();
    for (const SweepOrgan& organ : sweep_organs(*scene)) {
      const SweepOutcome ca = conservative_advance({body}, motion, {organ}, adv).value();
      const double d = distance(*sweep_bvh, {}, *organ.mesh, organ.pose).value().distance_mm;
      const bool mesh_hits = collide(*sweep_bvh, {}, *organ.mesh, organ.pose).value().colliding;
      if (ca.collided) {
        // Advancement found contact: the swept surface comes within the tessellation error.
        EXPECT_LE(d, deflection + 2e-3) << "trial " << trial << " organ " << scene->organs()[organ.index].name;
        ++colliding;
      } else if (ca.min_clearance_mm > 2.0 * deflection) {
        // Clear by more than the tessellation error: the meshed sweep must not touch the organ.
        EXPECT_FALSE(mesh_hits) << "trial " << trial << " organ " << scene->organs()[organ.index].name;
        ++clear;
      }
      ++compared;
    }
  }
  EXPECT_GT(compared, 1000);
  EXPECT_GT(colliding, 20);
  EXPECT_GT(clear, 500);
}

TEST(P4Safety, ValidatorAgreesWithPlainAdvancementOnTheWholeBody) {
  // The validator cuts bodies into radial bands and filters organs by boxes and hulls; none of
  // that may change the answer of advancing the whole moving body against every organ.
  const MachineModel model = default_machine_model().value();
  auto scene = MachineScene::build(model).value();
  ValidatorOptions options;
  options.compute_corrections = false;
  StepValidator validator(scene, options);
  testing::Rng rng(4242);
  int collisions = 0, clears = 0;
  AdvanceOptions adv;
  adv.required_clearance_mm = options.required_clearance_mm;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int compared = 0;
  std::map<std::string, int> skipped;
  for (int trial = 0; trial < testing::samples(1200); ++trial) {
    RandomBend r = random_bend(rng, model);
    // The manipulator somewhere over the held side (its limits and static checks are tested
    // elsewhere: only answers decided by the sweep are compared here).
    const double line = r.step.bend_point_mm.y();
    r.state.manipulator_y_mm = std::max(-2200.0, -line * (0.5 + 0.5 * u(rng)));
    r.state.manipulator_x_mm = -100.0 + 200.0 * u(rng);
    if (r.state.manipulator_y_mm > -50.0) continue;
    ASSERT_TRUE(validator.set_state(r.state).ok());
    MovingBody body;
    Motion motion;
    std::vector<Plate> plates;
    if (!bend_body(model, r, body, motion, plates)) continue;
    std::vector<SweepOrgan> organs = sweep_organs(*scene);
    std::vector<std::shared_ptr<MeshBvh>> manipulator;
    for (const Plate& p : manipulator_plates(model.manipulator, Vec2(r.state.manipulator_x_mm, r.state.manipulator_y_mm), 0.0,
                                             r.part.thickness_mm())) {
      manipulator.push_back(MeshBvh::build(std::make_shared<const TriangleMesh>(plates_mesh({p}))).value());
      organs.push_back({-1, manipulator.back().get(), RigidTransform{}});
    }
    const SweepOutcome plain = conservative_advance({body}, motion, organs, adv).value();
    auto answer = validator.validate(r.part, r.step);
    ASSERT_TRUE(answer.ok()) << answer.error().to_string();
    const StepAnswer& a = answer.value();
    if (a.decided_by == Stage::kLimits || a.decided_by == Stage::kStatic) {
      ++skipped[a.collisions.empty() ? std::string(to_string(a.limit)) : a.collisions.front().body + "/" + a.collisions.front().organ];
      continue;
    }
    ++compared;
    ASSERT_EQ(a.verdict == Verdict::kCollision, plain.collided) << "trial " << trial << ": " << a.reason;
    if (plain.collided) {
      ++collisions;
      // Both stop within the contact resolution of the required clearance: the angles agree to
      // the angle that resolution spans at the slowest approach (0.05 degrees here).
      EXPECT_NEAR(a.collisions.front().first_contact_deg, plain.contact_s * r.step.target_angle_deg, 0.05) << "trial " << trial;
    } else {
      ++clears;
    }
  }
  for (const auto& [why, n] : skipped) RecordProperty("skipped " + why, n);
  EXPECT_GT(compared, testing::samples(100));
  EXPECT_GT(collisions, testing::samples(30));
  EXPECT_GT(clears, testing::samples(30));
}

TEST(P4Safety, RefitAnswersExactlyLikeRebuild) {
  const MachineModel model = default_machine_model().value();
  auto refitted = MachineScene::build(model).value();
  auto rebuilt = MachineScene::build(model).value();
  StepValidator a(refitted), b(rebuilt);
  testing::Rng rng(99);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const RandomBend r = random_bend(rng, model);
    ASSERT_TRUE(refitted->apply_state(r.state).ok());
    ASSERT_TRUE(rebuilt->apply_state(r.state).ok());
    rebuilt->rebuild_tree();
    for (int q = 0; q < 5; ++q) {
      const Vec3 c(-1500 + 3000 * u(rng), -800 + 1200 * u(rng), -300 + 900 * u(rng));
      const Vec3 h(5 + 400 * u(rng), 5 + 300 * u(rng), 5 + 300 * u(rng));
      const Aabb box{c - h, c + h};
      EXPECT_EQ(refitted->organs_overlapping(box), rebuilt->organs_overlapping(box)) << "trial " << trial;
    }
    auto x = a.validate(r.part, r.step);
    auto y = b.validate(r.part, r.step);
    ASSERT_EQ(x.ok(), y.ok());
    if (!x.ok()) continue;
    EXPECT_EQ(x.value().verdict, y.value().verdict) << "trial " << trial;
    EXPECT_EQ(x.value().collisions.size(), y.value().collisions.size());
    if (!x.value().collisions.empty() && !y.value().collisions.empty()) {
      EXPECT_EQ(x.value().collisions[0].first_contact_deg, y.value().collisions[0].first_contact_deg);
    }
  }
}

}  // namespace
}  // namespace gk::p4
