// The P4 engine on scenarios whose answers are derived by hand, the safety of the hull level of
// detail, refit against rebuild, corrections that verify, and bad input.
#include "machine_models/p4/machine_model.h"
#include "machine_models/p4/machine_scene.h"
#include "machine_models/p4/plate_shapes.h"
#include "machine_models/p4/step_validator.h"
#include "tests/machine_models/p4_test_engine.h"
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"
#include "tests/support/random_meshes.h"
#include "kernel/core/units.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gk::p4 {
namespace {

double deg(double rad) { return rad * 180.0 / kPi; }

using namespace testing_engine;

TEST(P4Model, DefaultModelLoadsWithFiftySegmentsOverTheBendLength) {
  auto model = default_machine_model();
  ASSERT_TRUE(model.ok()) << model.error().to_string();
  const MachineModel& m = model.value();
  ASSERT_EQ(m.aba.segment_widths_mm.size(), 50u);
  double total = 0.0;
  for (double w : m.aba.segment_widths_mm) total += w;
  EXPECT_DOUBLE_EQ(total, m.max_bend_length_mm);
  EXPECT_DOUBLE_EQ(m.slot_x_min(0), -1250.0);
  EXPECT_DOUBLE_EQ(m.slot_x_max(49), 1250.0);
  for (double w : m.aba.segment_widths_mm) EXPECT_EQ(std::fmod(w, 5.0), 0.0);
}

TEST(P4Model, BadModelFilesNameTheKey) {
  const std::string good = embedded_default_model_toml();
  auto broken = parse_machine_model("[machine\nname = 1");
  ASSERT_FALSE(broken.ok());
  EXPECT_NE(broken.error().field.find("line"), std::string::npos);
  std::string bad_rel = good;
  bad_rel.replace(bad_rel.find("relative_to = \"clamp\""), 21, "relative_to = \"floor\"");
  auto r = parse_machine_model(bad_rel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().field, "organ[0].relative_to");
  std::string concave = good;
  concave.replace(concave.find("[[-0.5, 0.0], [-60.0, 0.0]"), 26, "[[-0.5, 0.0], [-30.0, 90.0]");
  auto c = parse_machine_model(concave);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().field, "aba.profile_yz_mm");
  EXPECT_FALSE(load_machine_model_file("/nonexistent.toml").ok());
}

TEST(P4Scenarios, FlangeTallerThanTheAbaClearanceHitsTheBeamAtTheComputedAngle) {
  const double t = 1.5, flange = 300.0;
  Engine e = make_engine(t);
  const SheetPart part = flat_part(1000.0, 800.0, t);
  auto a = e.validator->validate(part, bend(StepKind::kBendUp, 800.0 - flange, 90.0));
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  ASSERT_EQ(a.value().verdict, Verdict::kCollision) << a.value().reason;
  ASSERT_FALSE(a.value().collisions.empty());
  const StepCollision& c = a.value().collisions.front();
  EXPECT_EQ(c.organ, "upper_beam");
  // The flange's upper far edge turns about the bend axis (Y 0, Z t) with radius `flange`; the
  // beam's underside is 203 mm above the axis; contact when flange * sin(angle) = 203 - 0.1.
  const double expected = deg(std::asin((203.0 - 0.1) / flange));
  EXPECT_NEAR(c.first_contact_deg, expected, 0.01);  // tolerance: contact resolution 1e-3 mm
  EXPECT_NEAR(c.point_mm.z(), t + 203.0 - 0.1, 0.01);
  EXPECT_LT(c.normal.z(), -0.9);  // the beam pushes the flange down
  EXPECT_GT(c.depth_mm, 0.0);
  // A flange lower than the clearance bends freely.
  auto low = e.validator->validate(part, bend(StepKind::kBendUp, 800.0 - 150.0, 90.0));
  ASSERT_TRUE(low.ok());
  EXPECT_EQ(low.value().verdict, Verdict::kClear) << low.value().reason;
}

TEST(P4Scenarios, LongFlangeBendingDownHitsTheBedAndFlippingClearsIt) {
  const double t = 1.5, flange = 190.0;
  Engine e = make_engine(t);
  const SheetPart part = flat_part(1000.0, 800.0, t);
  auto a = e.validator->validate(part, bend(StepKind::kBendDown, 800.0 - flange, 90.0));
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  ASSERT_EQ(a.value().verdict, Verdict::kCollision) << a.value().reason;
  const StepCollision& c = a.value().collisions.front();
  EXPECT_EQ(c.organ, "bed");
  // The lower far edge turns down about (Y 0, Z 0); the bed is 180 mm below.
  EXPECT_NEAR(c.first_contact_deg, deg(std::asin((180.0 - 0.1) / flange)), 0.01);
  const Correction& fix = a.value().correction;
  EXPECT_EQ(fix.kind, CorrectionKind::kFlip);
  EXPECT_TRUE(fix.verified);
  // Verify the correction independently: the part turned over, bent up.
  const SheetPart flipped = part.turned_over(Vec2(0.0, 800.0 - flange), Vec2(0.0, 1.0));
  auto up = e.validator->validate(flipped, bend(StepKind::kBendUp, 800.0 - flange, 90.0));
  ASSERT_TRUE(up.ok());
  EXPECT_EQ(up.value().verdict, Verdict::kClear);
  // A short flange bends down freely.
  auto short_down = e.validator->validate(part, bend(StepKind::kBendDown, 800.0 - 120.0, 90.0));
  ASSERT_TRUE(short_down.ok());
  EXPECT_EQ(short_down.value().verdict, Verdict::kClear) << short_down.value().reason;
  // The lowest-point check: the 120 mm flange's lower far edge ends straight below the axis.
  EXPECT_NEAR(short_down.value().lowest_point_mm, -120.0, 1e-9);
  EXPECT_NEAR(a.value().lowest_point_mm, -flange, 1e-9);
}

SheetPart box_part(double t) {
  // 800 x 600 blank; flanges 50 mm up on both X sides, stopping 10 mm before the next bend line.
  SheetPartSpec spec{800.0, 600.0, t, {}, {}};
  spec.flanges.push_back({Side::kXMin, 50.0, 90.0, 0.0, 490.0});
  spec.flanges.push_back({Side::kXMax, 50.0, 90.0, 0.0, 490.0});
  return SheetPart::create(spec).value();
}

TEST(P4Scenarios, BoxWithSideFlangesBlocksATooLongBlankholderAtClamp) {
  const double t = 1.2;
  Engine e = make_engine(t);
  const SheetPart part = box_part(t);
  BendStep clamp = bend(StepKind::kClamp, 500.0, 90.0);
  auto a = e.validator->validate(part, clamp);
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  ASSERT_EQ(a.value().verdict, Verdict::kCollision) << a.value().reason;
  // The side flanges stand at X = +-400 (part centred): the segments over them are hit.
  for (const StepCollision& c : a.value().collisions) EXPECT_EQ(c.organ.rfind("aba.segment.", 0), 0u) << c.organ;
  const Correction& fix = a.value().correction;
  EXPECT_EQ(fix.kind, CorrectionKind::kChangeAba);
  ASSERT_TRUE(fix.verified) << fix.description;
  // Engaging only the segments between the flanges clamps cleanly (the others rise 120 mm, over
  // the 50 mm flanges).
  MachineState fitted = MachineState::with_aba_span(e.model, -395.0, 395.0, t);
  fitted.manipulator_y_mm = -400.0;
  ASSERT_TRUE(e.validator->set_state(fitted).ok());
  auto b = e.validator->validate(part, clamp);
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(b.value().verdict, Verdict::kClear) << b.value().reason;
  // And the correction's own segment set clears too.
  MachineState corrected = fitted;
  corrected.engaged_segments = fix.engaged_segments;
  ASSERT_TRUE(e.validator->set_state(corrected).ok());
  EXPECT_EQ(e.validator->validate(part, clamp).value().verdict, Verdict::kClear);
}

TEST(P4Scenarios, InnerTabPassesThroughAGapAndHitsAnEngagedSegment) {
  const double t = 1.0;
  Engine e = make_engine(t);
  // A 30 mm tab 20 mm behind the bend line, centred on the part (machine X in [-10, 10]).
  SheetPartSpec spec{800.0, 600.0, t, {}, {}};
  spec.tabs.push_back({390.0, 410.0, 480.0, 30.0});
  const SheetPart part = SheetPart::create(spec).value();
  const BendStep clamp = bend(StepKind::kClamp, 500.0, 90.0);
  // Wrong segments: all engaged; the 100 mm slot over X = 0 comes down on the tab.
  auto wrong = e.validator->validate(part, clamp);
  ASSERT_TRUE(wrong.ok());
  ASSERT_EQ(wrong.value().verdict, Verdict::kCollision);
  std::size_t slot = 0;
  for (std::size_t i = 0; i < e.model.aba.segment_widths_mm.size(); ++i)
    if (e.model.slot_x_min(i) <= -10.0 && e.model.slot_x_max(i) >= 10.0) slot = i;
  EXPECT_EQ(wrong.value().collisions.front().organ, "aba.segment." + std::to_string(slot));
  // Right segments: that slot left out, so the tab stands in the gap.
  MachineState right = MachineState::with_aba_span(e.model, -1250.0, 1250.0, t);
  right.manipulator_y_mm = -400.0;
  right.engaged_segments[slot] = false;
  ASSERT_TRUE(e.validator->set_state(right).ok());
  auto ok = e.validator->validate(part, clamp);
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ(ok.value().verdict, Verdict::kClear) << ok.value().reason;
}

TEST(P4Scenarios, RotationNearATowerCollidesAndTheComputedRetractClearsIt) {
  const double t = 1.5;
  Engine e = make_engine(t);
  MachineState s;
  s.clamp_z_mm = t;
  s.manipulator_y_mm = -400.0;
  ASSERT_TRUE(e.validator->set_state(s).ok());
  // 2800 x 800: its corners reach 1456 mm from the rotation axis; the tower starts at X = 1450.
  const SheetPart part = flat_part(2800.0, 800.0, t);
  BendStep rotate = bend(StepKind::kRotate, 800.0, 90.0);
  rotate.rotate_angle_deg = 90.0;
  auto a = e.validator->validate(part, rotate);
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  ASSERT_EQ(a.value().verdict, Verdict::kCollision) << a.value().reason;
  EXPECT_EQ(a.value().collisions.front().organ.rfind("tower.", 0), 0u) << a.value().collisions.front().organ;
  const Correction& fix = a.value().correction;
  ASSERT_EQ(fix.kind, CorrectionKind::kRetract);
  ASSERT_TRUE(fix.verified) << fix.description;
  BendStep retracted = rotate;
  retracted.retract_mm = fix.retract_mm;
  EXPECT_EQ(e.validator->validate(part, retracted).value().verdict, Verdict::kClear);
  // The retract is the smallest to 8 mm: 9 mm less still collides.
  retracted.retract_mm = fix.retract_mm - 9.0;
  EXPECT_EQ(e.validator->validate(part, retracted).value().verdict, Verdict::kCollision);
}

TEST(P4Pipeline, EveryAnswerNamesItsStageAndTheMemoAnswersRepeats) {
  const double t = 1.5;
  Engine e = make_engine(t);
  const SheetPart part = flat_part(1000.0, 800.0, t);
  const BendStep step = bend(StepKind::kBendUp, 700.0, 90.0);
  auto first = e.validator->validate(part, step).value();
  EXPECT_NE(first.decided_by, Stage::kCache);
  EXPECT_GT(first.times.total_us, 0.0);
  auto again = e.validator->validate(part, step).value();
  EXPECT_EQ(again.decided_by, Stage::kCache);
  EXPECT_EQ(again.verdict, first.verdict);
  // A different state is a different key.
  MachineState s = e.scene->state();
  s.engaged_segments.assign(50, true);
  s.engaged_segments[3] = false;
  ASSERT_TRUE(e.validator->set_state(s).ok());
  EXPECT_NE(e.validator->validate(part, step).value().decided_by, Stage::kCache);
}

TEST(P4Pipeline, BadInputGivesErrorsNamingTheField) {
  Engine e = make_engine(1.5);
  const SheetPart part = flat_part(1000.0, 800.0, 1.5);
  BendStep s = bend(StepKind::kBendUp, 700.0, std::nan(""));
  auto nan = e.validator->validate(part, s);
  ASSERT_FALSE(nan.ok());
  EXPECT_EQ(nan.error().field, "target_angle_deg");
  s.target_angle_deg = 180.0;  // not a bend at all
  auto absurd = e.validator->validate(part, s);
  ASSERT_FALSE(absurd.ok());
  EXPECT_EQ(absurd.error().field, "target_angle_deg");
  s.target_angle_deg = 150.0;  // a bend, but past the machine's 135 degrees: denied with the limit named
  auto over = e.validator->validate(part, s);
  ASSERT_TRUE(over.ok());
  EXPECT_EQ(over.value().verdict, Verdict::kInconclusive);
  EXPECT_EQ(over.value().denial, DenialReason::kMachineLimit);
  EXPECT_EQ(over.value().limit, MachineLimit::kBendAngle);
  s = bend(StepKind::kBendUp, 700.0, 90.0);
  s.bend_direction = Vec2::Zero();
  auto zero = e.validator->validate(part, s);
  ASSERT_FALSE(zero.ok());
  EXPECT_EQ(zero.error().field, "bend_direction");
  s = bend(StepKind::kBendUp, 900.0, 90.0);  // beyond the part: nothing moves
  auto nothing = e.validator->validate(part, s);
  ASSERT_FALSE(nothing.ok());
  EXPECT_EQ(nothing.error().field, "bend_point");
  MachineState bad;
  bad.engaged_segments.assign(7, true);
  auto state = e.validator->set_state(bad);
  ASSERT_FALSE(state.ok());
  EXPECT_EQ(state.error().field, "engaged_segments");
  bad = MachineState{};
  bad.manipulator_y_mm = 5000.0;
  EXPECT_EQ(e.validator->set_state(bad).error().field, "manipulator_y_mm");
  auto thick = e.validator->validate(flat_part(1000.0, 800.0, 5.0), bend(StepKind::kBendUp, 700.0, 90.0));
  ASSERT_TRUE(thick.ok());
  EXPECT_EQ(thick.value().limit, MachineLimit::kThickness);
  EXPECT_EQ(thick.value().verdict, Verdict::kInconclusive);
  // Absurd magnitudes are errors naming the field, never answers.
  EXPECT_EQ(SheetPart::create({1e8, 800.0, 1.0, {}, {}}).error().field, "width_mm");
  s = bend(StepKind::kBendUp, 700.0, 90.0);
  s.bend_point_mm.x() = 1e308;
  EXPECT_EQ(e.validator->validate(part, s).error().field, "bend_point");
  EXPECT_FALSE(SheetPart::create({1000.0, 800.0, 1.0, {{Side::kXMax, 50.0, 200.0, 0.0, 0.0}}, {}}).ok());
}

}  // namespace
}  // namespace gk::p4

namespace gk::p4 {
namespace {
using namespace testing_engine;

// A parametric part as its B-Rep tessellation: what a STEP part looks like to the engine.
SheetPart as_surface_part(const SheetPart& part, double deflection) {
  const occt::Shape brep = plates_shape(part.plates()).value();
  auto meshed = occt::mesh_shape(brep, deflection).value();
  return SheetPart::from_surface(std::move(meshed.mesh), part.thickness_mm(), deflection).value();
}

TEST(P4SurfaceParts, ATessellatedPartAnswersLikeItsParametricTwin) {
  const double t = 1.5;
  Engine e = make_engine(t);
  const SheetPart plates = flat_part(1000.0, 800.0, t);
  const SheetPart surface = as_surface_part(plates, 0.01);
  for (const BendStep& step : {bend(StepKind::kBendUp, 500.0, 90.0), bend(StepKind::kBendDown, 610.0, 90.0),
                               bend(StepKind::kBendUp, 700.0, 135.0), bend(StepKind::kBendDown, 700.0, 90.0)}) {
    auto a = e.validator->validate(plates, step);
    auto b = e.validator->validate(surface, step);
    ASSERT_TRUE(a.ok() && b.ok()) << (a.ok() ? b.error().to_string() : a.error().to_string());
    EXPECT_EQ(a.value().verdict, b.value().verdict) << to_string(step.kind) << " at " << step.bend_point_mm.y();
    if (!a.value().collisions.empty() && !b.value().collisions.empty()) {
      EXPECT_EQ(a.value().collisions[0].organ, b.value().collisions[0].organ);
      // The surface part keeps 0.01 mm more clearance (its deflection): contact a hair earlier.
      EXPECT_NEAR(a.value().collisions[0].first_contact_deg, b.value().collisions[0].first_contact_deg, 0.05);
    }
  }
}

TEST(P4SurfaceParts, ARealStepSheetMetalPartGoesThroughThePipeline) {
  Engine e = make_engine(1.0);
  auto shape = occt::read_shape_file(testing::shared_data("step/sheetmetal/Heatsink_AAVID_573300D00010G_TO-263.step"));
  ASSERT_TRUE(shape.ok()) << shape.error().to_string();
  auto meshed = occt::mesh_shape(shape.value(), 0.05);
  ASSERT_TRUE(meshed.ok());
  auto part = SheetPart::from_surface(std::move(meshed.value().mesh), 1.0, 0.05);
  ASSERT_TRUE(part.ok());
  // The heatsink spans Y [-6.2, 6.6]: bend what lies beyond Y = 2 up by 45 degrees. A 27 mm part
  // cannot be held by a manipulator whose travel stops 50 mm behind the bend line: denied, with
  // the limit named, never CLEAR.
  BendStep step = bend(StepKind::kBendUp, 2.0, 45.0);
  auto a = e.validator->validate(part.value(), step);
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  EXPECT_EQ(a.value().verdict, Verdict::kInconclusive) << a.value().reason;
  EXPECT_EQ(a.value().limit, MachineLimit::kGripNotOnPart);
  step.kind = StepKind::kClamp;
  ASSERT_TRUE(e.validator->validate(part.value(), step).ok());
  step = bend(StepKind::kBendUp, 20.0, 45.0);  // beyond the part
  auto none = e.validator->validate(part.value(), step);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().field, "bend_point");
}

}  // namespace
}  // namespace gk::p4

namespace gk::p4 {
namespace {
using namespace testing_engine;

TEST(P4Scenarios, RetractingWithAFlangeTallerThanTheOpenBlankholderCatchesIt) {
  const double t = 1.5;
  Engine e = make_engine(t);
  // The y_max flange stands 250 mm at the bend line; the blankholder opens 220 mm while the part
  // moves, its nose 0.5 mm behind the bend line: pulling the part back 100 mm catches the flange
  // after (0.5 - 0.1) mm of travel.
  SheetPartSpec spec{1000.0, 800.0, t, {{Side::kYMax, 250.0, 90.0, 0.0, 0.0}}, {}};
  const SheetPart tall = SheetPart::create(spec).value();
  BendStep retract = bend(StepKind::kRetract, 800.0, 90.0);
  retract.travel_mm = Vec3(0.0, -100.0, 0.0);
  auto a = e.validator->validate(tall, retract);
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  ASSERT_EQ(a.value().verdict, Verdict::kCollision) << a.value().reason;
  EXPECT_EQ(a.value().collisions.front().organ.rfind("aba.segment.", 0), 0u);
  EXPECT_NEAR(a.value().collisions.front().first_contact_fraction * 100.0, 0.4, 0.01);  // mm of travel
  // A 150 mm flange passes under the open blankholder; approaching forward is clear too.
  spec.flanges[0].height_mm = 150.0;
  const SheetPart low = SheetPart::create(spec).value();
  EXPECT_EQ(e.validator->validate(low, retract).value().verdict, Verdict::kClear);
  BendStep approach = retract;
  approach.kind = StepKind::kApproach;
  approach.travel_mm = Vec3(0.0, 100.0, 0.0);
  EXPECT_EQ(e.validator->validate(tall, approach).value().verdict, Verdict::kClear);
  approach.travel_mm = Vec3::Zero();
  EXPECT_EQ(e.validator->validate(tall, approach).error().field, "travel");
}

}  // namespace
}  // namespace gk::p4
