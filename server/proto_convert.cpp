#include "server/proto_convert.h"

#include "kernel/tolerances.h"

#include <cctype>
#include <cmath>

namespace gk::server {
namespace {

constexpr double kPi = 3.14159265358979323846;

Result<bool> finite(double v, const std::string& field) {
  if (!std::isfinite(v)) return invalid_argument(field, "must be a finite number");
  return true;
}

}  // namespace

grpc::Status to_status(const Error& error) {
  const std::string message = error.to_string();
  switch (error.code) {
    case ErrorCode::kInvalidArgument: return {grpc::StatusCode::INVALID_ARGUMENT, message};
    case ErrorCode::kNotFound: return {grpc::StatusCode::NOT_FOUND, message};
    case ErrorCode::kFailedPrecondition: return {grpc::StatusCode::FAILED_PRECONDITION, message};
    case ErrorCode::kInternal: return {grpc::StatusCode::INTERNAL, message};
    case ErrorCode::kStopped: return {grpc::StatusCode::DEADLINE_EXCEEDED, message};
  }
  return {grpc::StatusCode::INTERNAL, message};
}

Result<p4::BendStep> to_step(const pb::Step& in) {
  p4::BendStep s;
  switch (in.kind()) {
    case pb::CLAMP: s.kind = p4::StepKind::kClamp; break;
    case pb::BEND_UP: s.kind = p4::StepKind::kBendUp; break;
    case pb::BEND_DOWN: s.kind = p4::StepKind::kBendDown; break;
    case pb::ROTATE: s.kind = p4::StepKind::kRotate; break;
    case pb::APPROACH: s.kind = p4::StepKind::kApproach; break;
    case pb::RETRACT: s.kind = p4::StepKind::kRetract; break;
    default: return invalid_argument("step.kind", "missing or unknown step kind");
  }
  s.bend_point_mm = Vec2(in.bend_point().x_mm(), in.bend_point().y_mm());
  s.bend_direction = in.has_bend_direction() ? Vec2(in.bend_direction().x_mm(), in.bend_direction().y_mm()) : Vec2::UnitX();
  s.target_angle_deg = in.target_angle_deg();
  s.rotate_angle_deg = in.rotate_angle_deg();
  s.travel_mm = Vec3(in.travel().x_mm(), in.travel().y_mm(), in.travel().z_mm());
  s.lateral_shift_mm = in.lateral_shift_mm();
  s.retract_mm = in.retract_mm();
  s.turned_deg = in.turned_deg();
  for (auto [v, f] : {std::pair{s.target_angle_deg, "step.target_angle_deg"}, std::pair{s.rotate_angle_deg, "step.rotate_angle_deg"},
                      std::pair{s.lateral_shift_mm, "step.lateral_shift_mm"}, std::pair{s.retract_mm, "step.retract_mm"},
                      std::pair{s.turned_deg, "step.turned_deg"}}) {
    auto ok = finite(v, f);
    if (!ok.ok()) return ok.error();
  }
  return s;
}

Result<p4::MachineState> to_state(const pb::MachineState& in, const p4::MachineModel& model) {
  p4::MachineState s;
  s.engaged_segments.assign(in.engaged_segments().begin(), in.engaged_segments().end());
  s.clamp_z_mm = in.clamp_z_mm();
  s.manipulator_x_mm = in.manipulator_x_mm();
  s.manipulator_y_mm = in.manipulator_y_mm();
  s.manipulator_rotation_deg = in.manipulator_rotation_deg();
  s.lower_blade_z_offset_mm = in.lower_blade_z_offset_mm();
  auto valid = p4::validate_state(model, s);
  if (!valid.ok()) return invalid_argument("state." + valid.error().field, valid.error().message);
  return s;
}

Result<p4::SheetPart> to_part(const pb::SheetPart& in, PartRegistry& parts) {
  if (!(in.deflection_mm() >= 0.0) || !(in.deflection_mm() <= 1000.0))
    return invalid_argument("part.deflection_mm", "must be in [0, 1000] mm (0: the default)");
  if (!in.part_id().empty()) {
    const double deflection = in.deflection_mm() > 0.0 ? in.deflection_mm() : kPartDeflectionMm;
    auto loaded = parts.load(in.part_id(), deflection);
    if (!loaded.ok()) return Error{loaded.error().code, "part.part_id", loaded.error().message};
    auto part = p4::SheetPart::from_surface(*loaded.value()->mesh, in.thickness_mm(), loaded.value()->deflection_mm);
    if (!part.ok()) return invalid_argument("part." + part.error().field, part.error().message);
    return part;
  }
  p4::SheetPartSpec spec{in.width_mm(), in.depth_mm(), in.thickness_mm(), {}, {}};
  for (const pb::Flange& f : in.flanges()) {
    p4::Side side;
    switch (f.side()) {
      case pb::X_MIN: side = p4::Side::kXMin; break;
      case pb::X_MAX: side = p4::Side::kXMax; break;
      case pb::Y_MIN: side = p4::Side::kYMin; break;
      case pb::Y_MAX: side = p4::Side::kYMax; break;
      default: return invalid_argument("part.flanges.side", "missing or unknown side");
    }
    spec.flanges.push_back({side, f.height_mm(), f.angle_deg(), f.start_mm(), f.length_mm()});
  }
  for (const pb::Tab& t : in.tabs()) spec.tabs.push_back({t.x_min_mm(), t.x_max_mm(), t.y_mm(), t.height_mm()});
  auto part = p4::SheetPart::create(spec);
  if (!part.ok()) return invalid_argument("part." + part.error().field, part.error().message);
  return part;
}

Result<RigidTransform> to_pose(const pb::Pose& in, const std::string& field) {
  const Vec3 t(in.translation().x_mm(), in.translation().y_mm(), in.translation().z_mm());
  const Vec3 axis(in.rotation_axis().x_mm(), in.rotation_axis().y_mm(), in.rotation_axis().z_mm());
  if (!t.allFinite()) return invalid_argument(field + ".translation", "must be finite");
  if (!std::isfinite(in.rotation_deg())) return invalid_argument(field + ".rotation_deg", "must be finite");
  if (t.cwiseAbs().maxCoeff() > tolerances::kMaxCoordinateMm)
    return invalid_argument(field + ".translation", "beyond 1e7 mm from the origin");
  if (in.rotation_deg() == 0.0) return RigidTransform::from_translation(t);
  const double largest = axis.allFinite() ? axis.cwiseAbs().maxCoeff() : 0.0;
  if (!(largest > 0.0)) return invalid_argument(field + ".rotation_axis", "must be a finite, non-zero vector");
  // Scaled before normalising: (1e200, 0, 1) squared would overflow to infinity.
  const RigidTransform pose = RigidTransform::from_axis_angle(axis / largest, in.rotation_deg() * kPi / 180.0, t);
  if (!pose.is_rigid()) return invalid_argument(field + ".rotation_axis", "does not give a rigid rotation");
  return pose;
}

Result<bool> check_id(const std::string& id, const std::string& field) {
  if (id.empty() || id.size() > kMaxIdLength)
    return invalid_argument(field, "must be 1 to " + std::to_string(kMaxIdLength) + " characters");
  for (char c : id)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' || c == ':'))
      return invalid_argument(field, "may hold only letters, digits and - _ . :");
  return true;
}

Result<bool> check_label(const std::string& text, const std::string& field) {
  if (text.size() > kMaxLabelLength) return invalid_argument(field, "longer than " + std::to_string(kMaxLabelLength) + " bytes");
  const auto byte = [&](std::size_t i) { return i < text.size() ? static_cast<unsigned char>(text[i]) : 0u; };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const unsigned c = byte(i);
    // C0 controls and DEL; in UTF-8 the C1 controls (U+0080-U+009F), the line and paragraph
    // separators (U+2028, U+2029) and the bidirectional overrides and isolates (U+202A-U+202E,
    // U+2066-U+2069), which make a name read differently from what it holds.
    const bool c1 = c == 0xC2 && byte(i + 1) >= 0x80 && byte(i + 1) <= 0x9F;
    const bool separator_or_bidi = c == 0xE2 && ((byte(i + 1) == 0x80 && byte(i + 2) >= 0xA8 && byte(i + 2) <= 0xAE) ||
                                                 (byte(i + 1) == 0x81 && byte(i + 2) >= 0xA6 && byte(i + 2) <= 0xA9));
    if (c < 0x20 || c == 0x7F || c1 || separator_or_bidi)
      return invalid_argument(field, "holds a control or bidirectional formatting character (NUL, newline, DEL, U+202E, ...)");
  }
  return true;
}

pb::Verdict to_proto(Verdict v) {
  switch (v) {
    case Verdict::kClear: return pb::CLEAR;
    case Verdict::kTouching: return pb::TOUCHING;
    case Verdict::kCollision: return pb::COLLISION;
    case Verdict::kInconclusive: return pb::INCONCLUSIVE;
  }
  return pb::INCONCLUSIVE;
}

pb::InconclusiveReason to_proto(InconclusiveReason r) {
  switch (r) {
    case InconclusiveReason::kNone: return pb::INCONCLUSIVE_REASON_UNSPECIFIED;
    case InconclusiveReason::kDegenerateTriangles: return pb::DEGENERATE_TRIANGLES;
    case InconclusiveReason::kTessellationUnresolved: return pb::TESSELLATION_UNRESOLVED;
    case InconclusiveReason::kBrepUndecided: return pb::BREP_UNDECIDED;
    case InconclusiveReason::kPairFailed: return pb::PAIR_FAILED;
  }
  return pb::PAIR_FAILED;
}

void to_proto(const Vec3& v, pb::Vec3* out) {
  out->set_x_mm(v.x());
  out->set_y_mm(v.y());
  out->set_z_mm(v.z());
}

void to_proto(const p4::MachineState& s, pb::MachineState* out) {
  out->clear_engaged_segments();
  for (bool e : s.engaged_segments) out->add_engaged_segments(e);
  out->set_clamp_z_mm(s.clamp_z_mm);
  out->set_manipulator_x_mm(s.manipulator_x_mm);
  out->set_manipulator_y_mm(s.manipulator_y_mm);
  out->set_manipulator_rotation_deg(s.manipulator_rotation_deg);
  out->set_lower_blade_z_offset_mm(s.lower_blade_z_offset_mm);
}

void to_proto(const PartRecord& r, pb::PartInfo* out) {
  out->set_part_id(r.id);
  out->set_name(r.name);
  out->set_format(r.format);
  out->set_size_bytes(r.size_bytes);
  out->set_triangles(r.triangles);
  to_proto(r.bounds_min, out->mutable_bounds_min());
  to_proto(r.bounds_max, out->mutable_bounds_max());
  out->set_closed(r.closed);
}

void to_proto(const p4::BendStep& s, pb::Step* out) {
  switch (s.kind) {
    case p4::StepKind::kClamp: out->set_kind(pb::CLAMP); break;
    case p4::StepKind::kBendUp: out->set_kind(pb::BEND_UP); break;
    case p4::StepKind::kBendDown: out->set_kind(pb::BEND_DOWN); break;
    case p4::StepKind::kRotate: out->set_kind(pb::ROTATE); break;
    case p4::StepKind::kApproach: out->set_kind(pb::APPROACH); break;
    case p4::StepKind::kRetract: out->set_kind(pb::RETRACT); break;
  }
  out->mutable_bend_point()->set_x_mm(s.bend_point_mm.x());
  out->mutable_bend_point()->set_y_mm(s.bend_point_mm.y());
  out->mutable_bend_direction()->set_x_mm(s.bend_direction.x());
  out->mutable_bend_direction()->set_y_mm(s.bend_direction.y());
  out->set_target_angle_deg(s.target_angle_deg);
  out->set_rotate_angle_deg(s.rotate_angle_deg);
  to_proto(s.travel_mm, out->mutable_travel());
  out->set_lateral_shift_mm(s.lateral_shift_mm);
  out->set_retract_mm(s.retract_mm);
  out->set_turned_deg(s.turned_deg);
}

namespace {

pb::InconclusiveReason to_proto(p4::DenialReason r) {
  switch (r) {
    case p4::DenialReason::kNone: return pb::INCONCLUSIVE_REASON_UNSPECIFIED;
    case p4::DenialReason::kMachineLimit: return pb::MACHINE_LIMIT;
    case p4::DenialReason::kSweepBudget: return pb::SWEEP_BUDGET_EXHAUSTED;
  }
  return pb::INCONCLUSIVE_REASON_UNSPECIFIED;
}

pb::MachineLimit to_proto(p4::MachineLimit l) {
  switch (l) {
    case p4::MachineLimit::kNone: return pb::MACHINE_LIMIT_NONE;
    case p4::MachineLimit::kManipulatorTravelX: return pb::MANIPULATOR_TRAVEL_X;
    case p4::MachineLimit::kManipulatorTravelY: return pb::MANIPULATOR_TRAVEL_Y;
    case p4::MachineLimit::kGripNotOnPart: return pb::GRIP_NOT_ON_PART;
    case p4::MachineLimit::kNoClampingSegment: return pb::NO_CLAMPING_SEGMENT;
    case p4::MachineLimit::kBendAngle: return pb::BEND_ANGLE;
    case p4::MachineLimit::kThickness: return pb::THICKNESS;
    case p4::MachineLimit::kBendLength: return pb::BEND_LENGTH;
  }
  return pb::MACHINE_LIMIT_NONE;
}

}  // namespace

void to_proto(const p4::StepAnswer& a, pb::ValidateStepResponse* out) {
  out->set_verdict(to_proto(a.verdict));
  out->set_reason(a.reason);
  out->set_decided_by(p4::to_string(a.decided_by));
  out->set_inconclusive_reason(to_proto(a.denial));
  out->set_limit(to_proto(a.limit));
  for (const p4::StepCollision& c : a.collisions) {
    pb::Collision* col = out->add_collisions();
    col->set_organ(c.organ);
    col->set_body(c.body);
    to_proto(c.point_mm, col->mutable_point());
    to_proto(c.organ_point_mm, col->mutable_organ_point());
    to_proto(c.normal, col->mutable_normal());
    col->set_depth_mm(c.depth_mm);
    col->set_first_contact_deg(c.first_contact_deg);
    col->set_first_contact_fraction(c.first_contact_fraction);
  }
  out->set_min_clearance_mm(a.min_clearance_mm);
  out->set_min_clearance_lower_mm(a.min_clearance_lower_mm);
  out->set_clearance_organ(a.clearance_organ);
  to_proto(a.clearance_point_mm, out->mutable_clearance_point());
  pb::Correction* c = out->mutable_correction();
  switch (a.correction.kind) {
    case p4::CorrectionKind::kNone: c->set_kind(pb::CORRECTION_NONE); break;
    case p4::CorrectionKind::kRepoShift: c->set_kind(pb::REPO); break;
    case p4::CorrectionKind::kChangeAba: c->set_kind(pb::CHANGE_ABA); break;
    case p4::CorrectionKind::kRetract: c->set_kind(pb::RETRACT_FIRST); break;
    case p4::CorrectionKind::kFlip: c->set_kind(pb::FLIP); break;
  }
  c->set_lateral_shift_mm(a.correction.lateral_shift_mm);
  c->set_retract_mm(a.correction.retract_mm);
  for (bool e : a.correction.engaged_segments) c->add_engaged_segments(e);
  c->set_verified(a.correction.verified);
  c->set_description(a.correction.description);
  c->set_shift_design_mm(a.correction.shift_design_mm);
  c->set_shift_range_min_mm(a.correction.shift_range_mm[0]);
  c->set_shift_range_max_mm(a.correction.shift_range_mm[1]);
  for (const p4::CorrectionStep& s : a.correction.steps) {
    pb::CorrectionStep* cs = c->add_steps();
    to_proto(s.step, cs->mutable_step());
    to_proto(s.state, cs->mutable_state());
    cs->set_part_turned_over(s.part_turned_over);
  }
  pb::StageTimes* t = out->mutable_times();
  t->set_cache_us(a.times.cache_us);
  t->set_prepare_us(a.times.prepare_us);
  t->set_global_box_us(a.times.global_box_us);
  t->set_broad_us(a.times.broad_us);
  t->set_hull_us(a.times.hull_us);
  t->set_narrow_us(a.times.narrow_us);
  t->set_static_us(a.times.static_us);
  t->set_clearance_us(a.times.clearance_us);
  t->set_total_us(a.times.total_us);
}

Result<StoredPose> to_stored_pose(const pb::Pose& in, const std::string& field) {
  auto checked = to_pose(in, field);  // validates finiteness and the axis
  if (!checked.ok()) return checked.error();
  StoredPose p;
  p.translation = Vec3(in.translation().x_mm(), in.translation().y_mm(), in.translation().z_mm());
  if (in.rotation_deg() != 0.0) {
    // Stored as the rotation it was checked as (scaled so that its largest component is 1).
    const Vec3 axis(in.rotation_axis().x_mm(), in.rotation_axis().y_mm(), in.rotation_axis().z_mm());
    p.axis = axis / axis.cwiseAbs().maxCoeff();
    p.angle_deg = in.rotation_deg();
  }
  return p;
}

void scene_to_proto(const SceneRecord& scene, pb::SceneInfo* out) {
  out->set_scene_id(scene.id);
  out->set_name(scene.name);
  for (const auto& [id, o] : scene.objects) {
    pb::SceneObject* p = out->add_objects();
    p->set_object_id(o.id);
    p->set_name(o.name);
    p->set_category(o.category);
    p->set_part_id(o.part_id);
    p->set_group(o.group);
    to_proto(o.pose.translation, p->mutable_pose()->mutable_translation());
    to_proto(o.pose.axis, p->mutable_pose()->mutable_rotation_axis());
    p->mutable_pose()->set_rotation_deg(o.pose.angle_deg);
  }
}

Result<SceneRecord> scene_from_proto(const pb::SceneInfo& in) {
  SceneRecord out;
  out.id = in.scene_id();
  out.name = in.name();
  for (int i = 0; i < in.objects_size(); ++i) {
    const pb::SceneObject& o = in.objects(i);
    auto pose = to_stored_pose(o.pose(), "objects[" + std::to_string(i) + "].pose");
    if (!pose.ok()) return pose.error();
    out.objects[o.object_id()] = {o.object_id(), o.name(), o.category(), o.part_id(), pose.value(), o.group()};
  }
  return out;
}

InconclusiveReason from_proto(pb::InconclusiveReason r) {
  switch (r) {
    case pb::DEGENERATE_TRIANGLES: return InconclusiveReason::kDegenerateTriangles;
    case pb::TESSELLATION_UNRESOLVED: return InconclusiveReason::kTessellationUnresolved;
    case pb::BREP_UNDECIDED: return InconclusiveReason::kBrepUndecided;
    case pb::PAIR_FAILED: return InconclusiveReason::kPairFailed;
    default: return InconclusiveReason::kNone;
  }
}

Verdict from_proto(pb::Verdict v) {
  switch (v) {
    case pb::CLEAR: return Verdict::kClear;
    case pb::TOUCHING: return Verdict::kTouching;
    case pb::COLLISION: return Verdict::kCollision;
    default: return Verdict::kInconclusive;
  }
}

}  // namespace gk::server
