#include "server/proto_convert.h"

#include "kernel/core/tolerances.h"
#include "kernel/core/units.h"

#include <cctype>
#include <cmath>
#include <tuple>

namespace gk::server {
namespace {


Result<bool> finite(double v, const std::string& field) {
  if (!std::isfinite(v)) return invalid_argument(field, "must be a finite number");
  return true;
}

}  // namespace

grpc::Status to_status(const Error& error) {
  // Messages quote what the client sent (an id, a name): a client's 20 KB id quoted back would
  // exceed the client's own metadata limit and arrive as RESOURCE_EXHAUSTED instead of the error.
  constexpr std::size_t kMaxMessageBytes = 1024;
  std::string message = error.to_string();
  if (message.size() > kMaxMessageBytes) {
    std::size_t cut = kMaxMessageBytes;
    while (cut > 0 && (static_cast<unsigned char>(message[cut]) & 0xC0) == 0x80) --cut;  // not inside a UTF-8 character
    message = message.substr(0, cut) + "... (" + std::to_string(message.size()) + " bytes)";
  }
  switch (error.code) {
    case ErrorCode::kInvalidArgument: return {grpc::StatusCode::INVALID_ARGUMENT, message};
    case ErrorCode::kNotFound: return {grpc::StatusCode::NOT_FOUND, message};
    case ErrorCode::kFailedPrecondition: return {grpc::StatusCode::FAILED_PRECONDITION, message};
    case ErrorCode::kInternal: return {grpc::StatusCode::INTERNAL, message};
    case ErrorCode::kStopped: return {grpc::StatusCode::DEADLINE_EXCEEDED, message};
    case ErrorCode::kResourceExhausted: return {grpc::StatusCode::RESOURCE_EXHAUSTED, message};
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

p4::MachineState to_state(const pb::MachineState& in) {
  p4::MachineState s;
  s.engaged_segments.assign(in.engaged_segments().begin(), in.engaged_segments().end());
  s.clamp_z_mm = in.clamp_z_mm();
  s.manipulator_x_mm = in.manipulator_x_mm();
  s.manipulator_y_mm = in.manipulator_y_mm();
  s.manipulator_rotation_deg = in.manipulator_rotation_deg();
  s.lower_blade_z_offset_mm = in.lower_blade_z_offset_mm();
  return s;
}

Result<engine::StepQuestion> to_question(const pb::ValidateStepRequest& request, const pb::SheetPart* default_part,
                                         const std::string& default_machine) {
  engine::StepQuestion q;
  q.machine_id = request.machine_id().empty() ? default_machine : request.machine_id();
  auto part = to_step_part(request.has_part() || !default_part ? request.part() : *default_part);
  if (!part.ok()) return part.error();
  q.part = std::move(part).value();
  auto step = to_step(request.step());
  if (!step.ok()) return step.error();
  q.step = step.value();
  if (request.has_state()) q.state = to_state(request.state());
  q.with_corrections = !request.skip_corrections();
  return q;
}

Result<engine::StepPart> to_step_part(const pb::SheetPart& in) {
  engine::StepPart out;
  out.part_id = in.part_id();
  out.deflection_mm = in.deflection_mm();
  out.spec.thickness_mm = in.thickness_mm();
  if (!in.part_id().empty()) return out;
  out.spec.width_mm = in.width_mm();
  out.spec.depth_mm = in.depth_mm();
  for (const pb::Flange& f : in.flanges()) {
    p4::Side side;
    switch (f.side()) {
      case pb::X_MIN: side = p4::Side::kXMin; break;
      case pb::X_MAX: side = p4::Side::kXMax; break;
      case pb::Y_MIN: side = p4::Side::kYMin; break;
      case pb::Y_MAX: side = p4::Side::kYMax; break;
      default: return invalid_argument("part.flanges.side", "missing or unknown side");
    }
    out.spec.flanges.push_back({side, f.height_mm(), f.angle_deg(), f.start_mm(), f.length_mm()});
  }
  for (const pb::Tab& t : in.tabs()) out.spec.tabs.push_back({t.x_min_mm(), t.x_max_mm(), t.y_mm(), t.height_mm()});
  return out;
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
    case InconclusiveReason::kSweepBudgetExhausted: return pb::SWEEP_BUDGET_EXHAUSTED;
    case InconclusiveReason::kTooManyContacts: return pb::TOO_MANY_CONTACTS;
  }
  return pb::PAIR_FAILED;
}

void to_proto(const Vec3& v, pb::Vec3* out) {
  out->set_x_mm(v.x());
  out->set_y_mm(v.y());
  out->set_z_mm(v.z());
}

void to_proto(const Direction& d, pb::Direction* out) {
  out->set_x(d.x());
  out->set_y(d.y());
  out->set_z(d.z());
}

void to_proto(const Direction& d, pb::Direction* out, pb::Vec3* old_field) {
  to_proto(d, out);
  to_proto(d.vector(), old_field);
}

void to_proto(const engine::ContactPlace& place, pb::ContactRegion* out) {
  out->set_min_distance_mm(place.min_distance_mm);
  to_proto(place.point_a, out->mutable_point_a());
  to_proto(place.point_b, out->mutable_point_b());
  out->set_triangle_pairs(place.triangle_pairs);
  to_proto(place.bounds.min, out->mutable_bounds_min());
  to_proto(place.bounds.max, out->mutable_bounds_max());
  for (int f : place.faces_a) out->add_faces_a(static_cast<std::uint32_t>(f));
  for (int f : place.faces_b) out->add_faces_b(static_cast<std::uint32_t>(f));
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
  out->set_deciding_stage(to_proto(a.decided_by));
  out->set_inconclusive_reason(to_proto(a.denial));
  out->set_limit(to_proto(a.limit));
  for (const p4::StepCollision& c : a.collisions) {
    pb::Collision* col = out->add_collisions();
    col->set_organ(c.organ);
    col->set_body(c.body);
    to_proto(c.point_mm, col->mutable_point());
    to_proto(c.organ_point_mm, col->mutable_organ_point());
    to_proto(c.normal, col->mutable_normal());
    if (const auto normal = Direction::of(c.normal)) to_proto(*normal, col->mutable_normal_direction());
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

StoredPose to_stored_pose(const pb::Pose& in) {
  StoredPose p;
  p.translation = Vec3(in.translation().x_mm(), in.translation().y_mm(), in.translation().z_mm());
  p.axis = Vec3(in.rotation_axis().x_mm(), in.rotation_axis().y_mm(), in.rotation_axis().z_mm());
  p.angle_deg = in.rotation_deg();
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
    // Checked when it was stored.
    out.objects[o.object_id()] = {o.object_id(), o.name(), o.category(), o.part_id(), to_stored_pose(o.pose()), o.group()};
  }
  return out;
}

InconclusiveReason from_proto(pb::InconclusiveReason r) {
  switch (r) {
    case pb::DEGENERATE_TRIANGLES: return InconclusiveReason::kDegenerateTriangles;
    case pb::TESSELLATION_UNRESOLVED: return InconclusiveReason::kTessellationUnresolved;
    case pb::BREP_UNDECIDED: return InconclusiveReason::kBrepUndecided;
    case pb::PAIR_FAILED: return InconclusiveReason::kPairFailed;
    case pb::SWEEP_BUDGET_EXHAUSTED: return InconclusiveReason::kSweepBudgetExhausted;
    case pb::TOO_MANY_CONTACTS: return InconclusiveReason::kTooManyContacts;
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

pb::DecidingStage to_proto(p4::Stage stage) {
  switch (stage) {
    case p4::Stage::kCache: return pb::DECIDING_STAGE_CACHE;
    case p4::Stage::kLimits: return pb::DECIDING_STAGE_LIMITS;
    case p4::Stage::kStatic: return pb::DECIDING_STAGE_STATIC;
    case p4::Stage::kGlobalBox: return pb::DECIDING_STAGE_GLOBAL_BOX;
    case p4::Stage::kBroadPhase: return pb::DECIDING_STAGE_BROAD_PHASE;
    case p4::Stage::kHullLod: return pb::DECIDING_STAGE_HULL_LOD;
    case p4::Stage::kNarrow: return pb::DECIDING_STAGE_NARROW;
  }
  return pb::DECIDING_STAGE_UNSPECIFIED;
}

pb::DepthMethod to_proto(engine::DepthMethod m) {
  switch (m) {
    case engine::DepthMethod::kNone: return pb::DEPTH_METHOD_UNSPECIFIED;
    case engine::DepthMethod::kAlongRequested: return pb::DEPTH_METHOD_ALONG_REQUESTED;
    case engine::DepthMethod::kPieceOrPartAxis: return pb::DEPTH_METHOD_PIECE_OR_PART_AXIS;
    case engine::DepthMethod::kLatticeDirection: return pb::DEPTH_METHOD_LATTICE_DIRECTION;
    case engine::DepthMethod::kBetweenCentres: return pb::DEPTH_METHOD_BETWEEN_CENTRES;
  }
  return pb::DEPTH_METHOD_UNSPECIFIED;
}

pb::VolumeMethod to_proto(engine::SharedVolumeMethod m) {
  switch (m) {
    case engine::SharedVolumeMethod::kNone: return pb::VOLUME_METHOD_UNSPECIFIED;
    case engine::SharedVolumeMethod::kApart: return pb::VOLUME_METHOD_APART;
    case engine::SharedVolumeMethod::kBrepBooleanCommon: return pb::VOLUME_METHOD_BREP_BOOLEAN_COMMON;
    case engine::SharedVolumeMethod::kMeshExactCorefinement: return pb::VOLUME_METHOD_MESH_EXACT_COREFINEMENT;
    case engine::SharedVolumeMethod::kMeshRayCast: return pb::VOLUME_METHOD_MESH_RAY_CAST;
  }
  return pb::VOLUME_METHOD_UNSPECIFIED;
}

Result<engine::ClearanceRequest> to_clearance_request(const pb::ClearanceQueryRequest& in) {
  engine::ClearanceRequest out;
  for (auto [side, from] : {std::pair{&out.a, &in.a()}, std::pair{&out.b, &in.b()}}) {
    side->part_id = from->part_id();
    side->scene_id = from->scene_id();
    side->object_id = from->object_id();
    side->pose = to_stored_pose(from->pose());  // checked by the engine, named "a.pose" / "b.pose"
  }
  out.safety_gap_mm = in.safety_gap_mm();
  out.region_merge_mm = in.region_merge_mm();
  out.compute_depth = in.compute_depth();
  out.depth_along = Vec3(in.depth_along().x_mm(), in.depth_along().y_mm(), in.depth_along().z_mm());
  if (in.has_depth_along_direction()) {
    const pb::Direction& d = in.depth_along_direction();
    if (in.has_depth_along()) return invalid_argument("depth_along_direction", "give depth_along or depth_along_direction, not both");
    const auto along = Direction::of(Vec3(d.x(), d.y(), d.z()));
    if (!along) return invalid_argument("depth_along_direction", "must be a finite, non-zero vector");
    out.depth_along = along->vector();
  }
  out.compute_volume = in.compute_volume();
  return out;
}

void to_proto(const engine::ClearanceResult& r, pb::ClearanceQueryResponse* out) {
  out->set_verdict(to_proto(r.verdict));
  out->set_inconclusive_reason(to_proto(r.inconclusive_reason));
  out->set_reason(r.reason);
  out->set_distance_mm(r.distance_mm);
  to_proto(r.point_a, out->mutable_point_a());
  to_proto(r.point_b, out->mutable_point_b());
  out->set_triangle_a(r.triangle_a);
  out->set_triangle_b(r.triangle_b);
  out->set_face_a(r.face_a);
  out->set_face_b(r.face_b);
  out->set_refined_on_brep(r.refined_on_brep);
  out->set_exact_faces_us(r.exact_faces_us);
  out->set_error_bound_mm(r.error_bound_mm);
  out->set_pairs_within_gap(r.pairs_within_gap);
  out->set_pairs_truncated(r.pairs_truncated);
  for (const engine::ContactPlace& place : r.regions) to_proto(place, out->add_regions());
  out->set_gap_violated(r.gap_violated);
  out->set_depth_mm(r.depth_mm);
  if (r.depth_direction) to_proto(*r.depth_direction, out->mutable_depth_axis(), out->mutable_depth_direction());
  out->set_depth_exact(r.depth_exact);
  out->set_depth_method(r.depth_method);
  out->set_depth_method_kind(to_proto(r.depth_method_kind));
  out->set_depth_max_angle_deg(r.depth_max_angle_deg);
  out->set_depth_pieces_a(r.depth_pieces_a);
  out->set_depth_pieces_b(r.depth_pieces_b);
  out->set_interference_volume_mm3(r.interference_volume_mm3);
  out->set_volume_error_bound_mm3(r.volume_error_bound_mm3);
  out->set_volume_cell_mm(r.volume_cell_mm);
  out->set_volume_method(r.volume_method);
  out->set_volume_method_kind(to_proto(r.volume_method_kind));
  out->set_not_computed(r.not_computed);
  out->set_elapsed_us(r.elapsed_us);
}

void to_proto(const MoveOutcome& outcome, pb::MoveResult* out) {
  out->set_verdict(to_proto(outcome.verdict));
  out->set_candidates(outcome.candidates);
  for (const ObjectContactResult& c : outcome.contacts) {
    pb::ObjectContact* o = out->add_contacts();
    o->set_other_object_id(c.other);
    o->set_verdict(to_proto(c.verdict));
    o->set_distance_mm(c.distance_mm);
    to_proto(c.point, o->mutable_point());
    to_proto(c.other_point, o->mutable_other_point());
    o->set_inconclusive_reason(to_proto(c.inconclusive_reason));
    o->set_decided_on_brep(c.decided_on_brep);
  }
}

}  // namespace gk::server
