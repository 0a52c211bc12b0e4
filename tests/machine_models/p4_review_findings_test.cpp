// What an adversarial review of ValidateStep found (a black-box tester with an oracle of its own),
// each case as it was sent, with the answer it must get now.
#include "machine_models/p4/convex_polytope.h"
#include "machine_models/p4/manipulator_geometry.h"
#include "machine_models/p4/step_validator.h"
#include "tests/machine_models/p4_test_engine.h"

#include <gtest/gtest.h>

namespace gk::p4 {
namespace {

using namespace testing_engine;

MachineState state_at(double t, double manipulator_y, double blade_offset = 0.0) {
  MachineState s = default_state(t);
  s.manipulator_y_mm = manipulator_y;
  s.lower_blade_z_offset_mm = blade_offset;
  return s;
}

TEST(P4Review, TheParkedLowerBladeIsAnObstacleInABendUpToo) {
  Engine e = make_engine(1.5);
  // A flange bent down at the moving edge swings into the parked blade (Y 210..265, Z -175..-120)
  // from about 3.3 degrees of a bend up.
  SheetPartSpec spec{1000.0, 600.0, 1.5, {{Side::kYMax, 150.0, -90.0, 0.0, 0.0}}, {}};
  ASSERT_TRUE(e.validator->set_state(state_at(1.5, -380.0)).ok());
  auto a = e.validator->validate(SheetPart::create(spec).value(), bend(StepKind::kBendUp, 400.0, 30.0), false).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  EXPECT_EQ(a.collisions.front().organ, "blade.lower");
  EXPECT_LT(a.collisions.front().first_contact_deg, 4.0);
  // A blade raised 125 mm stands in the flange: the bend up starts inside it, like the clamp.
  ASSERT_TRUE(e.validator->set_state(state_at(2.0, -380.0, 125.0)).ok());
  const SheetPart flat = flat_part(1000.0, 620.0, 2.0);
  for (StepKind kind : {StepKind::kClamp, StepKind::kBendUp}) {
    auto b = e.validator->validate(flat, bend(kind, 400.0, 30.0), false).value();
    ASSERT_EQ(b.verdict, Verdict::kCollision) << to_string(kind) << ": " << b.reason;
    EXPECT_EQ(b.collisions.front().organ, "blade.lower") << to_string(kind);
  }
}

TEST(P4Review, AFlipIsNotVerifiedWhenTheBladeStandsInTheTurnedPart) {
  Engine e = make_engine(1.5);
  ASSERT_TRUE(e.validator->set_state(state_at(1.5, -380.0, 150.0)).ok());
  const SheetPart part = flat_part(1000.0, 630.0, 1.5);
  auto a = e.validator->validate(part, bend(StepKind::kBendDown, 400.0, 45.0)).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  EXPECT_FALSE(a.correction.verified) << to_string(a.correction.kind) << ": " << a.correction.description;
}

TEST(P4Review, WhatStandsInTheBendZoneIsCheckedWhereItStands) {
  // A 250 mm tab 1 mm in front of the bend line (inside the 3 mm bend zone) reaches the upper beam.
  Engine e = make_engine(1.5);
  SheetPartSpec spec{1000.0, 700.0, 1.5, {}, {{400.0, 600.0, 501.0, 250.0}}};
  const SheetPart part = SheetPart::create(spec).value();
  for (StepKind kind : {StepKind::kClamp, StepKind::kBendUp, StepKind::kBendDown}) {
    auto a = e.validator->validate(part, bend(kind, 500.0, 30.0), false).value();
    ASSERT_EQ(a.verdict, Verdict::kCollision) << to_string(kind) << ": " << a.reason;
    EXPECT_EQ(a.collisions.front().organ, "upper_beam") << to_string(kind);
    EXPECT_NEAR(a.collisions.front().depth_mm, 250.0 - 203.0, 1e-6) << to_string(kind);
  }
}

TEST(P4Review, AManipulatorCollisionNamesThePartThatHitsWithItsOwnDepth) {
  Engine e = make_engine(1.5);
  ASSERT_TRUE(e.validator->set_state(state_at(1.5, -100.0)).ok());
  auto a = e.validator->validate(flat_part(1000.0, 800.0, 1.5), bend(StepKind::kClamp, 500.0, 90.0), false).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  const auto plates = manipulator_plates(e.model.manipulator, Vec2(0.0, -100.0), 0.0, 1.5);
  int checked = 0;
  for (const StepCollision& c : a.collisions) {
    if (c.body.rfind("manipulator.", 0) != 0) continue;
    const Organ* organ = nullptr;
    for (const Organ& o : e.scene->organs())
      if (o.name == c.organ) organ = &o;
    ASSERT_NE(organ, nullptr);
    const ConvexPolytope shape = ConvexPolytope::prism(organ->profile_yz, organ->x_min, organ->x_max).transformed(organ->pose);
    for (const Plate& p : plates)
      if (p.label == c.body) {
        EXPECT_NEAR(c.depth_mm, penetration_depth(ConvexPolytope::plate(p), shape), 1e-9) << c.body << " in " << c.organ;
        ++checked;
      }
  }
  EXPECT_GT(checked, 0);
}

TEST(P4Review, TheManipulatorMustNotStandInThePartItHolds) {
  // A 30 mm tab under a suction cup (cup 0 at X -120, Y -480: the tab at machine X [-140, -100]).
  Engine e = make_engine(1.5);
  SheetPartSpec spec{1000.0, 700.0, 1.5, {}, {{360.0, 400.0, 20.0, 30.0}}};
  const SheetPart part = SheetPart::create(spec).value();
  for (StepKind kind : {StepKind::kClamp, StepKind::kBendUp, StepKind::kRotate}) {
    BendStep step = bend(kind, 500.0, 90.0);
    step.rotate_angle_deg = 30.0;
    auto a = e.validator->validate(part, step, false).value();
    ASSERT_EQ(a.verdict, Verdict::kCollision) << to_string(kind) << ": " << a.reason;
    EXPECT_EQ(a.collisions.front().body.rfind("manipulator.cup.", 0), 0u) << a.collisions.front().body;
    EXPECT_EQ(a.collisions.front().organ, "part.tab.0");
  }
  // Moved aside (the cup clears the tab by more than the clearance) it holds the part again.
  SheetPartSpec aside = spec;
  aside.tabs[0].x_min_mm = 200.0;
  aside.tabs[0].x_max_mm = 240.0;
  EXPECT_EQ(e.validator->validate(SheetPart::create(aside).value(), bend(StepKind::kClamp, 500.0, 90.0), false).value().verdict,
            Verdict::kClear);
}

TEST(P4Review, ATabOnTheFlangeGetsACorrectionByTheFeatureItIs) {
  // Segments 24 and 25 are open; a tab on the flange meets segment 26 as it turns up.
  Engine e = make_engine(1.5);
  MachineState s = default_state(1.5);
  s.engaged_segments.assign(50, true);
  s.engaged_segments[24] = s.engaged_segments[25] = false;
  ASSERT_TRUE(e.validator->set_state(s).ok());
  SheetPartSpec spec{1000.0, 700.0, 1.5, {}, {{600.0, 700.0, 520.0, 80.0}}};
  const SheetPart part = SheetPart::create(spec).value();
  auto a = e.validator->validate(part, bend(StepKind::kBendUp, 500.0, 90.0)).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  EXPECT_TRUE(a.correction.verified) << to_string(a.correction.kind) << ": " << a.correction.description;
}

TEST(P4Review, AbsurdValuesAreErrorsNamingTheFieldNotExceptions) {
  Engine e = make_engine(1.5);
  SheetPartSpec spec{1000.0, 800.0, 1.5, {{Side::kYMin, 20.0, 90.0, 0.0, 0.0}}, {{100.0, 200.0, 100.0, 20.0}}};
  SheetPartSpec tall_flange = spec, tall_tab = spec, negative_length = spec;
  tall_flange.flanges[0].height_mm = 1e7;
  tall_tab.tabs[0].height_mm = 1e7;
  negative_length.flanges[0].length_mm = -1e308;
  EXPECT_EQ(SheetPart::create(tall_flange).error().field, "flanges[0].height_mm");
  EXPECT_EQ(SheetPart::create(tall_tab).error().field, "tabs[0].height_mm");
  EXPECT_EQ(SheetPart::create(negative_length).error().field, "flanges[0].length_mm");
  SheetPartSpec many = spec;
  many.tabs.assign(5000, spec.tabs[0]);
  EXPECT_EQ(SheetPart::create(many).error().field, "tabs");
  MachineState spun = default_state(1.5);
  spun.manipulator_rotation_deg = 1e308;
  EXPECT_EQ(e.validator->set_state(spun).error().field, "manipulator_rotation_deg");
  BendStep rotate = bend(StepKind::kRotate, 650.0, 90.0);
  rotate.rotate_angle_deg = 10.0;
  rotate.retract_mm = 1e7;
  EXPECT_EQ(e.validator->validate(SheetPart::create(spec).value(), rotate).error().field, "retract_mm");
  // Fields the step's kind does not use are checked all the same.
  BendStep clamp = bend(StepKind::kClamp, 650.0, 90.0);
  clamp.travel_mm.x() = std::nan("");
  EXPECT_EQ(e.validator->validate(SheetPart::create(spec).value(), clamp).error().field, "travel");
  clamp = bend(StepKind::kClamp, 650.0, 90.0);
  clamp.rotate_angle_deg = 1e308;
  EXPECT_EQ(e.validator->validate(SheetPart::create(spec).value(), clamp).error().field, "rotate_angle_deg");
  rotate.retract_mm = 0.0;
  rotate.target_angle_deg = 1e308;
  EXPECT_EQ(e.validator->validate(SheetPart::create(spec).value(), rotate).error().field, "target_angle_deg");
  std::string toml = embedded_default_model_toml();
  toml.replace(toml.find("x_mm = [-1400.0, 1400.0]"), 24, "x_mm = [-1e300, 1e300]");
  auto model = parse_machine_model(toml);
  ASSERT_FALSE(model.ok());
  EXPECT_NE(model.error().field.find("x_mm"), std::string::npos) << model.error().to_string();
}

TEST(P4Review, ABodyThatStartsInsideAnOrganIsReportedWhereTheyOverlap) {
  // A 175 mm flange hanging down at the bend line stands in the parked blade (Z -175..-120) before
  // a 3 degree rotation begins.
  Engine e = make_engine(1.5);
  ASSERT_TRUE(e.validator->set_state(state_at(1.5, -380.0)).ok());
  SheetPartSpec spec{1000.0, 740.0, 1.5, {{Side::kYMax, 175.0, -90.0, 0.0, 0.0}}, {}};
  BendStep rotate = bend(StepKind::kRotate, 500.0, 90.0);
  rotate.rotate_angle_deg = 3.0;
  auto a = e.validator->validate(SheetPart::create(spec).value(), rotate, false).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  const StepCollision& c = a.collisions.front();
  const Organ* organ = nullptr;
  for (const Organ& o : e.scene->organs())
    if (o.name == c.organ) organ = &o;
  ASSERT_NE(organ, nullptr);
  EXPECT_TRUE(organ->box.expanded(1e-6).contains(Aabb{c.point_mm, c.point_mm})) << c.organ << " " << c.point_mm.transpose();
}

}  // namespace
}  // namespace gk::p4
