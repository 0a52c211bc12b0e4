#include "engine/gatekeeper_engine.h"

#include "engine/audits/audit_request.h"
#include "engine/input_checks.h"
#include "kernel/core/tolerances.h"

#include <cmath>
#include <set>
#include <spdlog/spdlog.h>

namespace gk::engine {
namespace {

Result<bool> check_clearance(double clearance_mm) {
  if (!std::isfinite(clearance_mm) || clearance_mm < 0.0 || clearance_mm > tolerances::kMaxCoordinateMm)
    return invalid_argument("clearance_mm", "must be a distance from 0 to 1e7 mm");
  return true;
}

}  // namespace

Engine::Engine(MachineRegistry& machines, PartRegistry& parts, SceneStore& scenes, EndedAudits* archive, EngineOptions options,
               AuditCheckpoints* checkpoints, ClashStatuses* statuses)
    : machines_(machines), parts_(parts), scenes_(scenes), options_(options), steps_(machines, parts, options.step_answers_kept),
      audits_(parts, archive, options.audits, checkpoints, statuses), statuses_(statuses) {}

Result<ClearanceResult> Engine::clearance(const ClearanceRequest& request, const StopToken& stop) {
  return clearance_query(request, parts_, scenes_, stop);
}

Result<std::unique_ptr<PartUpload>> Engine::begin_upload(const std::string& name, const std::string& format,
                                                         std::uint64_t size_bytes, const std::string& sha256_hex) {
  if (auto bad = check_label(name, "header.name"); !bad.ok()) return bad.error();
  return parts_.store().begin(name, format, size_bytes, sha256_hex);
}

Result<PartRecord> Engine::finish_upload(std::unique_ptr<PartUpload> upload) {
  auto record = parts_.store().finish(std::move(upload), [](const std::string& path, PartRecord r) -> Result<PartRecord> {
    auto mesh = PartRegistry::read_any(path, r.format, kPartDeflectionMm);
    if (!mesh.ok()) return mesh.error();
    r.triangles = static_cast<std::uint32_t>(mesh.value().triangle_count());
    r.bounds_min = mesh.value().bounds().min;
    r.bounds_max = mesh.value().bounds().max;
    r.closed = mesh.value().is_closed_oriented();
    return r;
  });
  if (record.ok())
    spdlog::info("stored part {} ({} bytes, {} triangles)", record.value().id, record.value().size_bytes, record.value().triangles);
  return record;
}

Result<PartRecord> Engine::part(const std::string& part_id) const { return parts_.store().get(part_id); }

Result<MachineSnapshot> Engine::machine(const std::string& machine_id) const { return machines_.get(machine_id); }

Result<MachineSnapshot> Engine::set_machine_state(const std::string& machine_id, const p4::MachineState& state) {
  auto m = machines_.get(machine_id);
  if (!m.ok()) return m.error();
  if (auto valid = p4::validate_state(m.value().model, state); !valid.ok())
    return invalid_argument("state." + valid.error().field, valid.error().message);
  auto set = machines_.set_state(machine_id, state);
  if (!set.ok()) return set.error();
  return machines_.get(machine_id);
}

Result<MachineSnapshot> Engine::put_machine_model(const std::string& machine_id, const std::string& model_toml) {
  if (auto bad = check_id(machine_id, "machine_id"); !bad.ok()) return bad.error();
  return machines_.put_model(machine_id, model_toml);
}

Result<SceneRecord> Engine::create_scene(const std::string& name) {
  if (auto bad = check_label(name, "name"); !bad.ok()) return bad.error();
  return scenes_.create(name);
}

Result<bool> Engine::check_object(SceneObjectRecord& o, const std::string& field, std::set<std::string>* known_parts) const {
  if (!o.id.empty())
    if (auto bad = check_id(o.id, field + ".object_id"); !bad.ok()) return bad;
  for (const auto& [text, name] : {std::pair<const std::string*, const char*>{&o.name, ".name"}, {&o.category, ".category"},
                                   {&o.group, ".group"}})
    if (auto bad = check_label(*text, field + name); !bad.ok()) return bad;
  auto pose = checked_pose(o.pose.translation, o.pose.axis, o.pose.angle_deg, field + ".pose");
  if (!pose.ok()) return pose.error();
  o.pose = pose.value();  // as checked: the axis scaled to a largest component of 1
  if (known_parts && known_parts->count(o.part_id)) return true;  // a batch looks each part up once
  auto part = parts_.store().get(o.part_id);
  if (!part.ok()) return Error{part.error().code, field + ".part_id", part.error().message};
  if (known_parts) known_parts->insert(o.part_id);
  return true;
}

Result<PlacedMove> Engine::put_object(const std::string& scene_id, SceneObjectRecord object, double clearance_mm,
                                      const StopToken& stop) {
  if (auto bad = check_object(object, "object"); !bad.ok()) return bad.error();
  if (auto bad = check_clearance(clearance_mm); !bad.ok()) return bad.error();
  std::optional<SceneObjectRecord> previous;
  auto stored = scenes_.put(scene_id, std::move(object), &previous);
  if (!stored.ok()) return stored.error();
  auto outcome = answer_stored_edit(scene_id, stored.value(), previous, clearance_mm, stop);
  if (!outcome.ok()) return outcome.error();
  return PlacedMove{stored.value().id, std::move(outcome).value()};
}

Result<std::vector<SceneObjectRecord>> Engine::put_objects(const std::string& scene_id, std::vector<SceneObjectRecord> objects) {
  std::set<std::string> known_parts, ids;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string field = "objects[" + std::to_string(i) + "]";
    if (auto bad = check_object(objects[i], field, &known_parts); !bad.ok()) return bad.error();
    // Two objects of one batch under one id: one would silently replace the other.
    if (!objects[i].id.empty() && !ids.insert(objects[i].id).second)
      return invalid_argument(field + ".object_id", "'" + objects[i].id + "' appears twice in the batch");
  }
  return scenes_.put_many(scene_id, std::move(objects));
}

Result<MoveOutcome> Engine::move_object(const std::string& scene_id, const std::string& object_id, const StoredPose& asked_pose,
                                        double clearance_mm, DragSession* drag, const StopToken& stop) {
  auto checked = checked_pose(asked_pose.translation, asked_pose.axis, asked_pose.angle_deg, "pose");
  if (!checked.ok()) return checked.error();
  const StoredPose& pose = checked.value();
  if (auto bad = check_clearance(clearance_mm); !bad.ok()) return bad.error();
  std::optional<SceneObjectRecord> previous;
  // A drag's frames are logged, not synced one by one (engine/scenes/scene_store's WriteDurability);
  // end_drag syncs them.
  auto moved = scenes_.move(scene_id, object_id, pose, &previous, drag ? WriteDurability::kLogged : WriteDurability::kSynced);
  if (!moved.ok()) return moved.error();
  if (!drag) return answer_stored_edit(scene_id, moved.value(), previous, clearance_mm, stop);
  // A drag's session stays valid while the scene's version advances by this stream's own moves
  // only (engine/scenes/drag_session); its frame answers for this pose of the object.
  auto version = scenes_.version(scene_id);
  if (!version.ok()) return version.error();
  auto frame = drag->move(scene_id, version.value(), [&] { return scenes_.get(scene_id); }, object_id, clearance_mm,
                          pose.transform(), parts_, stop);
  if (!frame.ok()) (void)scenes_.revert(scene_id, moved.value(), previous);
  return frame;
}

// Every edit is stored first and answered after, on the scene as it is then with the object as
// this edit stored it: of two concurrent edits the one answered later sees the other (answering
// first and storing after let two objects be told CLEAR and stored overlapping), and an answer is
// always for what its own edit stored, never for another client's pose or part of the same
// object. An edit whose answer fails (a deadline, a cancel) is taken back unless edited since.
Result<MoveOutcome> Engine::answer_stored_edit(const std::string& scene_id, const SceneObjectRecord& stored,
                                               const std::optional<SceneObjectRecord>& previous, double clearance_mm,
                                               const StopToken& stop) {
  auto scene = scenes_.get(scene_id);
  Result<MoveOutcome> outcome = Error{};
  if (scene.ok()) {
    scene.value().objects[stored.id] = stored;
    outcome = DragSession::once(scene.value(), stored.id, clearance_mm, parts_, stop);
  } else {
    outcome = scene.error();
  }
  if (!outcome.ok()) (void)scenes_.revert(scene_id, stored, previous);
  return outcome;
}

Result<bool> Engine::end_drag() { return scenes_.sync(); }

Result<SceneRecord> Engine::delete_object(const std::string& scene_id, const std::string& object_id) {
  return scenes_.remove(scene_id, object_id);
}

Result<std::string> Engine::start_audit(const std::string& scene_id, const AuditOptions& asked, const std::string& baseline_job_id) {
  auto options = checked_audit_options(asked, options_.audit_threads);
  if (!options.ok()) return options.error();
  auto scene = scenes_.get(scene_id);
  if (!scene.ok()) return scene.error();
  return audits_.start(scene.value(), options.value(), baseline_job_id);
}

Result<ClashStatusRecord> Engine::set_clash_status(const std::string& scene_id, const std::string& clash_id, ClashStatus status) {
  if (!statuses_) return Error{ErrorCode::kFailedPrecondition, "clash_id", "this daemon keeps no clash statuses"};
  if (auto scene = scenes_.version(scene_id); !scene.ok()) return scene.error();
  return statuses_->set(scene_id, clash_id, status);
}

Result<std::vector<ClashStatusRecord>> Engine::clash_statuses(const std::string& scene_id) const {
  if (auto scene = scenes_.version(scene_id); !scene.ok()) return scene.error();
  if (!statuses_) return std::vector<ClashStatusRecord>{};
  return statuses_->list(scene_id);
}

Result<FixtureElement> Engine::fixture_element(const std::string& element_id, const std::string& part_id, const StoredPose& pose,
                                               std::vector<CylinderFeature> declared, const std::string& field,
                                               std::vector<SlotFeature> declared_slots) {
  if (auto bad = check_id(element_id, field + ".element_id"); !bad.ok()) return bad.error();
  auto checked = checked_pose(pose.translation, pose.axis, pose.angle_deg, field + ".pose");
  if (!checked.ok()) return checked.error();
  if (auto known = parts_.store().get(part_id); !known.ok()) return Error{known.error().code, field + ".part_id", known.error().message};
  auto loaded = parts_.load(part_id, kPartDeflectionMm);
  if (!loaded.ok()) return Error{loaded.error().code, field + ".part_id", loaded.error().message};
  return element_from_part(loaded.value(), element_id, checked.value().transform(), std::move(declared), field, std::move(declared_slots));
}

Result<DisplayMesh> Engine::display_mesh(const std::string& part_id, std::size_t max_triangles) {
  auto loaded = parts_.load(part_id, kPartDeflectionMm);
  if (!loaded.ok()) return loaded.error();
  return decimate_for_display(*loaded.value()->mesh, max_triangles);
}

}  // namespace gk::engine
