// The P4 steps that used to be answered CLEAR while driving steel through steel, and the figures
// that claimed more than they knew: each case with its answer derived by hand from the default
// model (p4_default.toml). Supports and pressing segments are obstacles outside the intended
// contact layer; the manipulator is a body in every step; machine limits are denied by name;
// corrections are sub-sequences that the test runs itself, step by step.
#include "kernel/query/mesh_distance.h"
#include "machine_models/p4/step_validator.h"
#include "tests/machine_models/p4_test_engine.h"
#include "kernel/core/units.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gk::p4 {
namespace {

using namespace testing_engine;

bool is_segment(const std::string& organ) { return organ.rfind("aba.segment.", 0) == 0; }

// Validates the correction's steps one by one, each in its state; true when all are CLEAR.
void expect_steps_clear(StepValidator& v, const SheetPart& part, const Correction& fix) {
  ASSERT_FALSE(fix.steps.empty());
  for (std::size_t i = 0; i < fix.steps.size(); ++i) {
    ASSERT_TRUE(v.set_state(fix.steps[i].state).ok());
    auto a = v.validate(part, fix.steps[i].step, false);
    ASSERT_TRUE(a.ok()) << a.error().to_string();
    EXPECT_EQ(a.value().verdict, Verdict::kClear)
        << "step " << i << " (" << to_string(fix.steps[i].step.kind) << "): " << a.value().reason;
  }
}

// ---- supports ----------------------------------------------------------------------------------

TEST(P4Supports, ACounterbladeWithoutReliefStopsABendDownPastNinetyDegrees) {
  // The old square counterblade: its front face 0.5 mm behind the bend line. A 50 mm flange bent
  // down 92 degrees about (Y 0, Z 0) puts its lower far edge at Y = 50 cos 92 = -1.745: 1.245 mm
  // inside the counterblade.
  std::string toml = embedded_default_model_toml();
  const std::string relief = "profile_yz_mm = [[-150.0, -149.5], [-0.5, 0.0], [-150.0, 0.0]]";
  ASSERT_NE(toml.find(relief), std::string::npos);
  toml.replace(toml.find(relief), relief.size(), "profile_yz_mm = [[-80.0, -160.0], [-0.5, -160.0], [-0.5, 0.0], [-80.0, 0.0]]");
  const MachineModel square = parse_machine_model(toml).value();
  Engine e = make_engine(1.5, {}, &square);
  const SheetPart part = flat_part(1000.0, 600.0, 1.5);
  auto a = e.validator->validate(part, bend(StepKind::kBendDown, 550.0, 92.0));
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  ASSERT_EQ(a.value().verdict, Verdict::kCollision) << a.value().reason;
  EXPECT_EQ(a.value().collisions.front().organ, "counterblade");
  EXPECT_EQ(a.value().collisions.front().body, "flange");
  EXPECT_GT(a.value().collisions.front().depth_mm, 0.5);
  EXPECT_LE(a.value().collisions.front().depth_mm, 1.246);
  // 90 degrees keeps the flange's lower face at Y = 0, 0.5 mm in front of it: clear.
  EXPECT_EQ(e.validator->validate(part, bend(StepKind::kBendDown, 550.0, 90.0)).value().verdict, Verdict::kClear);
}

TEST(P4Supports, TheDefaultCounterbladesReliefLetsBendsDownReach135Degrees) {
  Engine e = make_engine(1.5);
  const SheetPart part = flat_part(1000.0, 600.0, 1.5);
  for (double flange : {50.0, 100.0, 170.0}) {
    auto a = e.validator->validate(part, bend(StepKind::kBendDown, 600.0 - flange, 135.0));
    ASSERT_TRUE(a.ok()) << a.error().to_string();
    EXPECT_EQ(a.value().verdict, Verdict::kClear) << flange << " mm: " << a.value().reason;
    // The relief face (z = y + 0.5) passes the flange's lower face (z = y) at 0.5 / sqrt(2).
    EXPECT_LE(a.value().min_clearance_lower_mm, 0.5 / std::sqrt(2.0) + 1e-6) << flange;
  }
}

TEST(P4Supports, WhatHangsBelowASupportsTopFaceIsACollisionWithinTheLayerIsContact) {
  Engine e = make_engine(1.5);
  // A flange bent down at the part's far edge (machine Y = -550, over the table).
  for (double h : {30.0, 0.05, 0.005}) {
    SheetPartSpec spec{1000.0, 600.0, 1.5, {{Side::kYMin, h, -90.0, 0.0, 0.0}}, {}};
    const SheetPart part = SheetPart::create(spec).value();
    auto a = e.validator->validate(part, bend(StepKind::kClamp, 550.0, 90.0));
    ASSERT_TRUE(a.ok()) << a.error().to_string();
    if (h > tolerances::kIntendedContactMm) {
      ASSERT_EQ(a.value().verdict, Verdict::kCollision) << h << ": " << a.value().reason;
      EXPECT_EQ(a.value().collisions.front().organ, "table");
      EXPECT_EQ(a.value().collisions.front().body, "part");
      EXPECT_NEAR(a.value().collisions.front().depth_mm, h, 1e-9) << "lifting the part by h frees it";
    } else {
      EXPECT_EQ(a.value().verdict, Verdict::kClear) << h << ": " << a.value().reason;
    }
  }
}

// ---- the blankholder at CLAMP ------------------------------------------------------------------

SheetPart part_with_tab(double x0, double x1, double y, double h) {
  SheetPartSpec spec{1000.0, 800.0, 1.5, {}, {{x0, x1, y, h}}};
  return SheetPart::create(spec).value();
}

TEST(P4Clamp, ATabUnderTheUpperBeamMustKeepItsClearance) {
  // The beam's underside is 203 mm above the clamp line (= the sheet's upper face); a tab 300 mm
  // behind the bend line stands under it, behind the segments.
  Engine e = make_engine(1.5);
  MachineState s = default_state(1.5);
  s.manipulator_x_mm = 380.0;  // away from the tab
  ASSERT_TRUE(e.validator->set_state(s).ok());
  const BendStep clamp = bend(StepKind::kClamp, 700.0, 90.0);
  for (auto [h, verdict] : {std::pair{203.05, Verdict::kCollision}, std::pair{202.95, Verdict::kCollision},
                            std::pair{202.85, Verdict::kClear}}) {
    auto a = e.validator->validate(part_with_tab(450.0, 550.0, 400.0, h), clamp);
    ASSERT_TRUE(a.ok()) << a.error().to_string();
    EXPECT_EQ(a.value().verdict, verdict) << h << ": " << a.value().reason;
    if (verdict == Verdict::kCollision) {
      EXPECT_EQ(a.value().collisions.front().organ, "upper_beam") << h;
      EXPECT_NEAR(a.value().collisions.front().depth_mm, std::max(0.0, h - 203.0), 1e-9) << h;
    } else {
      // Static: the clearance is measured exactly.
      EXPECT_NEAR(a.value().min_clearance_mm, 203.0 - h, 1e-9);
      EXPECT_NEAR(a.value().min_clearance_lower_mm, 203.0 - h, 1e-9);
      EXPECT_EQ(a.value().clearance_organ, "upper_beam");
    }
  }
}

TEST(P4Clamp, ATabUnderADisengagedSegmentIsCheckedEvenWithZeroClearance) {
  // Slot 24 spans X [-75, 25]; disengaged, it stands 120 mm above the clamp line. The tab stands
  // at X [-40, -10], 30 mm behind the bend line, under that segment's lower face.
  for (auto [required, h, verdict] : {std::tuple{0.0, 120.05, Verdict::kCollision}, std::tuple{0.0, 119.95, Verdict::kClear},
                                      std::tuple{0.1, 119.95, Verdict::kCollision}, std::tuple{0.1, 119.85, Verdict::kClear}}) {
    ValidatorOptions options;
    options.required_clearance_mm = required;
    Engine e = make_engine(1.5, options);
    MachineState s = default_state(1.5);
    s.engaged_segments.assign(50, true);
    s.engaged_segments[24] = false;
    ASSERT_TRUE(e.validator->set_state(s).ok());
    ASSERT_DOUBLE_EQ(e.model.slot_x_min(24), -75.0);
    auto a = e.validator->validate(part_with_tab(460.0, 490.0, 670.0, h), bend(StepKind::kClamp, 700.0, 90.0));
    ASSERT_TRUE(a.ok()) << a.error().to_string();
    EXPECT_EQ(a.value().verdict, verdict) << "clearance " << required << ", tab " << h << ": " << a.value().reason;
    if (verdict == Verdict::kCollision) {
      EXPECT_EQ(a.value().collisions.front().organ, "aba.segment.24");
    }
  }
}

TEST(P4Clamp, ABlankholderPressedIntoTheSheetIsACollisionAndOneAboveItClampsNothing) {
  const double t = 1.5;
  const SheetPart part = flat_part(1000.0, 800.0, t);
  const BendStep clamp = bend(StepKind::kClamp, 700.0, 90.0);
  Engine e = make_engine(t);
  auto at = [&](double clamp_z) {
    EXPECT_TRUE(e.validator->set_state(default_state(clamp_z)).ok());
    return e.validator->validate(part, clamp).value();
  };
  const StepAnswer pressed = at(t - 0.02);
  ASSERT_EQ(pressed.verdict, Verdict::kCollision) << pressed.reason;
  EXPECT_TRUE(is_segment(pressed.collisions.front().organ));
  EXPECT_NEAR(pressed.collisions.front().depth_mm, 0.02, 1e-9);
  EXPECT_EQ(at(t - 0.005).verdict, Verdict::kClear);  // within the intended contact layer
  EXPECT_EQ(at(t).verdict, Verdict::kClear);
  const StepAnswer open = at(t + 0.5);
  EXPECT_EQ(open.verdict, Verdict::kInconclusive);
  EXPECT_EQ(open.limit, MachineLimit::kNoClampingSegment);
}

// ---- the manipulator -----------------------------------------------------------------------------

TEST(P4Manipulator, StandingUnderTheBlankholderIsACollisionInClampAndBends) {
  // At Y = -50 (inside its travel) the gripper frame (Y [-150, 50], 40-60 mm above the sheet)
  // and the rotator column stand inside the segments, whose back faces recede to Y = -249 at the
  // top of the tool.
  Engine e = make_engine(1.5);
  MachineState s = default_state(1.5);
  s.manipulator_y_mm = -50.0;
  ASSERT_TRUE(e.validator->set_state(s).ok());
  const SheetPart part = flat_part(1000.0, 800.0, 1.5);
  for (StepKind kind : {StepKind::kClamp, StepKind::kBendUp, StepKind::kBendDown}) {
    auto a = e.validator->validate(part, bend(kind, 700.0, 90.0));
    ASSERT_TRUE(a.ok()) << a.error().to_string();
    ASSERT_EQ(a.value().verdict, Verdict::kCollision) << to_string(kind) << ": " << a.value().reason;
    EXPECT_EQ(a.value().collisions.front().body.rfind("manipulator.", 0), 0u) << a.value().collisions.front().body;
    EXPECT_TRUE(is_segment(a.value().collisions.front().organ)) << a.value().collisions.front().organ;
    EXPECT_GT(a.value().collisions.front().depth_mm, 0.0);
  }
  // 400 mm back it clears the tool.
  ASSERT_TRUE(e.validator->set_state(default_state(1.5)).ok());
  EXPECT_EQ(e.validator->validate(part, bend(StepKind::kClamp, 700.0, 90.0)).value().verdict, Verdict::kClear);
}

TEST(P4Manipulator, TheRotatorMovesWithThePartUnderTheOpenBlankholder) {
  // Approaching with the manipulator: the rotator column's top (200 mm above the sheet) passes
  // under the open segments (220 mm); a model whose segments open only 150 mm catches it.
  std::string toml = embedded_default_model_toml();
  const std::string lift = "aba_lift_for_rotation_mm = 220.0";
  ASSERT_NE(toml.find(lift), std::string::npos);
  toml.replace(toml.find(lift), lift.size(), "aba_lift_for_rotation_mm = 150.0");
  const MachineModel low_lift = parse_machine_model(toml).value();
  BendStep approach = bend(StepKind::kApproach, 700.0, 90.0);
  approach.travel_mm = Vec3(0.0, 550.0, 0.0);  // the column's front ends at Y = -10, under the segments
  const SheetPart part = flat_part(1000.0, 800.0, 1.5);
  MachineState s = default_state(1.5);
  s.manipulator_y_mm = -650.0;
  Engine ok = make_engine(1.5);
  ASSERT_TRUE(ok.validator->set_state(s).ok());
  EXPECT_EQ(ok.validator->validate(part, approach).value().verdict, Verdict::kClear);
  Engine caught = make_engine(1.5, {}, &low_lift);
  ASSERT_TRUE(caught.validator->set_state(s).ok());
  auto a = caught.validator->validate(part, approach).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  EXPECT_EQ(a.collisions.front().body, "manipulator.rotator");
}

// ---- machine limits ----------------------------------------------------------------------------

TEST(P4Limits, StepsTheMachineCannotMakeAreDeniedWithTheLimitNamed) {
  Engine e = make_engine(1.5);
  const SheetPart part = flat_part(1000.0, 800.0, 1.5);
  auto limit_of = [&](const SheetPart& p, const BendStep& step, const MachineState& state) {
    EXPECT_TRUE(e.validator->set_state(state).ok());
    auto a = e.validator->validate(p, step);
    EXPECT_TRUE(a.ok());
    EXPECT_EQ(a.value().verdict, Verdict::kInconclusive) << a.value().reason;
    EXPECT_EQ(a.value().denial, DenialReason::kMachineLimit);
    return a.value().limit;
  };
  BendStep approach = bend(StepKind::kApproach, 700.0, 90.0);
  approach.travel_mm = Vec3(1000.0, 0.0, 0.0);  // from X = 0; the travel ends at 800
  EXPECT_EQ(limit_of(part, approach, default_state(1.5)), MachineLimit::kManipulatorTravelX);
  BendStep retract = bend(StepKind::kRetract, 700.0, 90.0);
  retract.travel_mm = Vec3(0.0, -2000.0, 0.0);  // from Y = -400 to -2400; the travel ends at -2200
  EXPECT_EQ(limit_of(part, retract, default_state(1.5)), MachineLimit::kManipulatorTravelY);
  BendStep rotate = bend(StepKind::kRotate, 700.0, 90.0);
  rotate.retract_mm = 1900.0;
  EXPECT_EQ(limit_of(part, rotate, default_state(1.5)), MachineLimit::kManipulatorTravelY);
  MachineState off = default_state(1.5);
  off.manipulator_x_mm = 700.0;  // the part spans X [-500, 500]
  EXPECT_EQ(limit_of(part, bend(StepKind::kClamp, 700.0, 90.0), off), MachineLimit::kGripNotOnPart);
  MachineState on_flange = default_state(1.5);
  EXPECT_EQ(limit_of(part, bend(StepKind::kBendUp, 350.0, 90.0), on_flange), MachineLimit::kGripNotOnPart)
      << "held side is Y [-350, 0]: the manipulator at -400 is off it";
  MachineState far_segments = MachineState::with_aba_span(e.model, 600.0, 1250.0, 1.5);
  far_segments.manipulator_y_mm = -400.0;
  EXPECT_EQ(limit_of(part, bend(StepKind::kClamp, 700.0, 90.0), far_segments), MachineLimit::kNoClampingSegment);
  EXPECT_EQ(limit_of(part, bend(StepKind::kBendUp, 700.0, 90.0), far_segments), MachineLimit::kNoClampingSegment);
  EXPECT_EQ(limit_of(flat_part(2600.0, 800.0, 1.5), bend(StepKind::kBendUp, 700.0, 90.0), default_state(1.5)),
            MachineLimit::kBendLength);
  EXPECT_EQ(limit_of(flat_part(1000.0, 800.0, 0.3), bend(StepKind::kBendUp, 700.0, 90.0), default_state(0.3)),
            MachineLimit::kThickness);
  EXPECT_EQ(limit_of(part, bend(StepKind::kBendDown, 700.0, 136.0), default_state(1.5)), MachineLimit::kBendAngle);
  // Absurd magnitudes are errors naming the field.
  BendStep far = approach;
  far.travel_mm = Vec3(1e308, 0.0, 0.0);
  EXPECT_EQ(e.validator->validate(part, far).error().field, "travel");
  EXPECT_EQ(SheetPart::create({1000.0, 800.0, 1.5, {}, {{0.0, 10.0, 100.0, 1e9}}}).error().field, "tabs[0].height_mm");
}

// ---- corrections ---------------------------------------------------------------------------------

TEST(P4Corrections, RetractFirstIsARetractARotationAndAReapproachEachClear) {
  Engine e = make_engine(1.5);
  const SheetPart part = flat_part(2800.0, 800.0, 1.5);  // corners 1456 mm from the axis: the tower is at 1450
  BendStep rotate = bend(StepKind::kRotate, 800.0, 90.0);
  rotate.rotate_angle_deg = 90.0;
  auto a = e.validator->validate(part, rotate).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  // The part is 2800 mm long: also beyond the bend length, which a rotation does not need.
  ASSERT_EQ(a.correction.kind, CorrectionKind::kRetract);
  ASSERT_TRUE(a.correction.verified) << a.correction.description;
  ASSERT_EQ(a.correction.steps.size(), 3u);
  EXPECT_EQ(a.correction.steps[0].step.kind, StepKind::kRetract);
  EXPECT_EQ(a.correction.steps[1].step.kind, StepKind::kRotate);
  EXPECT_EQ(a.correction.steps[2].step.kind, StepKind::kApproach);
  EXPECT_DOUBLE_EQ(a.correction.steps[2].step.turned_deg, 90.0);
  expect_steps_clear(*e.validator, part, a.correction);
}

TEST(P4Corrections, ARetractThatItselfCollidesIsNeverOfferedAsVerified) {
  // A 250 mm flange stands at the bend line, 0.5 mm in front of the open segments' noses (they
  // open 220 mm): pulling the part back catches it after 0.4 mm, so no retract can be the fix.
  Engine e = make_engine(1.5);
  SheetPartSpec spec{1000.0, 800.0, 1.5, {{Side::kYMax, 250.0, 90.0, 0.0, 0.0}}, {}};
  const SheetPart part = SheetPart::create(spec).value();
  BendStep rotate = bend(StepKind::kRotate, 800.0, 90.0);
  rotate.rotate_angle_deg = 90.0;
  auto a = e.validator->validate(part, rotate).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  EXPECT_FALSE(a.correction.verified) << a.correction.description;
}

SheetPart box_part(double t) {
  // 800 x 600 blank; flanges 50 mm up on both X sides, stopping 10 mm before the next bend line.
  SheetPartSpec spec{800.0, 600.0, t, {}, {}};
  spec.flanges.push_back({Side::kXMin, 50.0, 90.0, 0.0, 490.0});
  spec.flanges.push_back({Side::kXMax, 50.0, 90.0, 0.0, 490.0});
  return SheetPart::create(spec).value();
}

TEST(P4Corrections, ChangeAbaAtABendLeavesTheSideFlangesFreeAndStillClamps) {
  // Every segment engaged: the side flanges at X = +-400 stand under segments when the part is
  // clamped for its Y_MAX bend. The new blankholder is validated with its clamp and the bend.
  Engine e = make_engine(1.2);
  const SheetPart part = box_part(1.2);
  auto a = e.validator->validate(part, bend(StepKind::kBendUp, 500.0, 90.0)).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  EXPECT_EQ(a.collisions.front().body, "part");
  ASSERT_EQ(a.correction.kind, CorrectionKind::kChangeAba) << a.correction.description;
  ASSERT_TRUE(a.correction.verified) << a.correction.description;
  ASSERT_EQ(a.correction.steps.size(), 2u);
  EXPECT_EQ(a.correction.steps[0].step.kind, StepKind::kClamp);
  expect_steps_clear(*e.validator, part, a.correction);
}

TEST(P4Corrections, AFullWidthTabGetsNoBlankholderThatClampsNothing) {
  // A tab across the whole part, 30 mm behind the bend line, under every segment over the part:
  // leaving it free leaves nothing pressing the part.
  Engine e = make_engine(1.5);
  const SheetPart part = part_with_tab(0.0, 1000.0, 670.0, 30.0);
  auto a = e.validator->validate(part, bend(StepKind::kClamp, 700.0, 90.0)).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  EXPECT_FALSE(a.correction.verified) << to_string(a.correction.kind) << ": " << a.correction.description;
}

TEST(P4Corrections, RepoShiftsTheFeatureUnderTheGapByTheDesignsRule) {
  // A 20 mm tab at X [-10, 10] under engaged slot 24; slot 26 ([125, 225]) is left out by the
  // sequencer: the design's shift is its centre minus the tab's, 175 mm. Shifts clear while the
  // tab stays 0.1 mm inside the gap: [125 + 10 + 0.1, 225 - 10 - 0.1], to 0.5 mm.
  Engine e = make_engine(1.5);
  MachineState s = default_state(1.5);
  s.engaged_segments.assign(50, true);
  s.engaged_segments[26] = false;
  ASSERT_DOUBLE_EQ(e.model.slot_x_min(26), 125.0);
  ASSERT_TRUE(e.validator->set_state(s).ok());
  const SheetPart part = part_with_tab(490.0, 510.0, 670.0, 30.0);
  const BendStep clamp = bend(StepKind::kClamp, 700.0, 90.0);
  auto a = e.validator->validate(part, clamp).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  const Correction& fix = a.correction;
  ASSERT_EQ(fix.kind, CorrectionKind::kRepoShift) << fix.description;
  ASSERT_TRUE(fix.verified);
  EXPECT_NEAR(fix.shift_design_mm, 175.0, 1e-9);
  EXPECT_NEAR(fix.lateral_shift_mm, 175.0, 1e-9) << "the design's shift clears: it is returned";
  EXPECT_NEAR(fix.shift_range_mm[0], 135.1, 0.6);
  EXPECT_NEAR(fix.shift_range_mm[1], 214.9, 0.6);
  ASSERT_EQ(fix.steps.size(), 2u);  // the lateral move (ABA open), the clamp at the new position
  EXPECT_EQ(fix.steps[0].step.kind, StepKind::kApproach);
  EXPECT_NEAR(fix.steps[0].step.travel_mm.x(), 175.0, 1e-9);
  EXPECT_NEAR(fix.steps[1].state.manipulator_x_mm, 175.0, 1e-9) << "the manipulator carries the part";
  expect_steps_clear(*e.validator, part, fix);
  // Just outside the range the tab meets a segment.
  BendStep outside = clamp;
  outside.lateral_shift_mm = fix.shift_range_mm[1] + 1.0;
  MachineState there = s;
  there.manipulator_x_mm = outside.lateral_shift_mm;
  ASSERT_TRUE(e.validator->set_state(there).ok());
  EXPECT_EQ(e.validator->validate(part, outside, false).value().verdict, Verdict::kCollision);
}

// ---- figures -------------------------------------------------------------------------------------

TEST(P4Figures, DepthIsTheDeepestOverTheMotionNotAtItsEnd) {
  // A 230 mm tab, 100 mm behind the bend line, approaches 150 mm under the open segments (their
  // lower faces 220 mm above the sheet): it passes through one 10 mm deep and ends in front of
  // it, where it overlaps nothing.
  Engine e = make_engine(1.5);
  MachineState s = default_state(1.5);
  s.manipulator_x_mm = 300.0;
  ASSERT_TRUE(e.validator->set_state(s).ok());
  const SheetPart part = part_with_tab(450.0, 550.0, 600.0, 230.0);
  BendStep approach = bend(StepKind::kApproach, 700.0, 90.0);
  approach.travel_mm = Vec3(0.0, 150.0, 0.0);
  auto a = e.validator->validate(part, approach).value();
  ASSERT_EQ(a.verdict, Verdict::kCollision) << a.reason;
  EXPECT_TRUE(is_segment(a.collisions.front().organ));
  EXPECT_EQ(a.collisions.front().body, "part");
  EXPECT_GT(a.collisions.front().first_contact_fraction, 0.1);
  EXPECT_NEAR(a.collisions.front().depth_mm, 10.0, 2e-3);
}

TEST(P4Figures, TheClearanceBracketHoldsTheDenselySampledMinimum) {
  // A 100 mm flange bent up 135 degrees ends 0.35 mm from the segments' noses: a near miss.
  Engine e = make_engine(1.5);
  const SheetPart part = flat_part(1000.0, 800.0, 1.5);
  const BendStep step = bend(StepKind::kBendUp, 700.0, 135.0);
  auto a = e.validator->validate(part, step).value();
  ASSERT_EQ(a.verdict, Verdict::kClear) << a.reason;
  // The oracle: the flange's plates at 4,001 angles against every organ, by mesh distance.
  std::vector<Plate> moving, held;
  ASSERT_TRUE(part.split(step.bend_point_mm, step.bend_direction, e.model.bend_zone_mm, moving, held).ok());
  const RigidTransform placement = part_placement(part, step);
  for (Plate& p : moving) p = p.transformed(placement);
  const auto flange = MeshBvh::build(std::make_shared<const TriangleMesh>(plates_mesh(moving))).value();
  double sampled = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 4000; ++k) {
    const double angle = 135.0 * k / 4000.0 * kPi / 180.0;
    const Vec3 axis(0.0, 0.0, 1.5);
    const RigidTransform pose = RigidTransform::from_translation(axis) * RigidTransform::from_axis_angle(Vec3::UnitX(), angle) *
                                RigidTransform::from_translation(-axis);
    for (const Organ& o : e.scene->organs())
      sampled = std::min(sampled, distance(*flange, pose, *o.mesh, o.pose).value().distance_mm);
  }
  EXPECT_LT(sampled, 1.0);
  EXPECT_LE(a.min_clearance_lower_mm, sampled + 1e-9) << "the lower end is proven";
  EXPECT_GE(a.min_clearance_mm, a.min_clearance_lower_mm);
  EXPECT_LE(a.min_clearance_mm - a.min_clearance_lower_mm,
            std::max(tolerances::kClearanceBracketMm, tolerances::kClearanceBracketRelative * a.min_clearance_mm) + 1e-9);
  EXPECT_LE(a.min_clearance_mm, sampled + 1e-6) << "measured where the dense sampling finds it";
}

}  // namespace
}  // namespace gk::p4
