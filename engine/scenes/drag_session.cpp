#include "engine/scenes/drag_session.h"

#include "engine/scenes/placed_scene.h"
#include "engine/verdicts/pair_verdict.h"

#include <algorithm>
#include <cmath>

namespace gk::engine {

Result<MoveOutcome> DragSession::move(const std::string& scene_id, std::uint64_t scene_version,
                                      const std::function<Result<SceneRecord>()>& read_scene, const std::string& object_id,
                                      double clearance_mm, const RigidTransform& pose, PartRegistry& parts,
                                      const StopToken& stop) {
  // Still valid when only this stream's own moves happened since (one version each).
  const bool same = session_ && scene_id == scene_id_ && object_id == object_id_ && clearance_mm == clearance_mm_ &&
                    scene_version == version_ + 1;
  if (!same) {
    auto read = read_scene();
    if (!read.ok()) return read.error();
    auto built = rebuild(read.value(), object_id, clearance_mm, parts);
    if (!built.ok()) return built.error();
    scene_version = read.value().version;
  }
  version_ = scene_version;
  return frame(pose, stop);
}

bool DragSession::answers_on_triangles(const std::string& scene_id, const std::string& object_id, double clearance_mm) const {
  return session_ && meshes_only_ && scene_id == scene_id_ && object_id == object_id_ && clearance_mm == clearance_mm_;
}

Result<MoveOutcome> DragSession::once(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                      PartRegistry& parts, const StopToken& stop) {
  auto self = scene.objects.find(object_id);
  if (self == scene.objects.end()) return Error{ErrorCode::kNotFound, "object_id", "no object '" + object_id + "'"};
  DragSession session;
  auto built = session.rebuild(scene, object_id, clearance_mm, parts);
  if (!built.ok()) return built.error();
  return session.frame(self->second.pose.transform(), stop);
}

Result<bool> DragSession::rebuild(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                  PartRegistry& parts) {
  if (!std::isfinite(clearance_mm) || clearance_mm < 0.0) return invalid_argument("clearance_mm", "must be >= 0");
  session_.reset();
  auto placed = place_scene(scene, parts);
  if (!placed.ok()) return placed.error();
  auto it = placed.value().index_of.find(object_id);
  if (it == placed.value().index_of.end()) return Error{ErrorCode::kNotFound, "object_id", "no object '" + object_id + "'"};
  auto session = LayoutSession::create(std::move(placed.value().objects), it->second, clearance_mm);
  if (!session.ok()) return session.error();
  session_ = std::move(session).value();
  ids_.clear();
  for (const SceneObjectRecord* r : placed.value().records) ids_.push_back(r->id);
  parts_ = placed.value().parts;
  meshes_only_ = std::none_of(parts_.begin(), parts_.end(), [](const std::shared_ptr<const LoadedPart>& p) { return p->deflection_mm > 0.0; });
  scene_id_ = scene.id;
  object_id_ = object_id;
  clearance_mm_ = clearance_mm;
  return true;
}

Result<MoveOutcome> DragSession::frame(const RigidTransform& pose, const StopToken& stop) {
  auto frame = session_->move_to(pose, stop);
  if (!frame.ok()) return frame.error();
  MoveOutcome out;
  out.candidates = frame.value().candidates;
  const std::shared_ptr<const LoadedPart>& self = parts_[session_->moving_index()];
  for (const FrameContact& c : frame.value().contacts) {
    const std::shared_ptr<const LoadedPart>& other = parts_[c.other];
    ObjectContactResult contact{ids_[c.other], c.verdict, c.distance_mm, c.point, c.other_point};
    if (self->deflection_mm + other->deflection_mm > 0.0) {
      // The triangles of a CAD part cannot tell within its deflection: the exact faces decide.
      auto exact = decide_contact({self.get(), pose}, {other.get(), session_->pose_of(c.other)}, clearance_mm_, stop);
      if (!exact.ok()) return exact.error();
      if (!exact.value()) continue;
      const engine::PairVerdict& v = *exact.value();
      contact = {ids_[c.other], v.result.verdict, v.result.distance_mm, v.result.point_a, v.result.point_b,
                 v.result.inconclusive_reason, v.decided_on_brep};
    }
    if (severity(contact.verdict) > severity(out.verdict)) out.verdict = contact.verdict;
    out.contacts.push_back(std::move(contact));
  }
  return out;
}

}  // namespace gk::engine
