// One object against its neighbours in a scene, the one path for every move: a drag's frames,
// MoveObject and PutObject (a session used for one frame). The layout session
// (engine/scenes/layout_session) finds the neighbours and decides each pair on the triangles; a
// pair with a CAD part is decided again on its exact faces (engine/verdicts/pair_verdict's
// decide_contact, the rule audits use too).
#pragma once

#include "engine/parts/part_registry.h"
#include "engine/scenes/object_contacts.h"
#include "engine/scenes/scene_store.h"
#include "engine/scenes/layout_session.h"
#include "kernel/core/stop_token.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace gk::engine {

// A drag stream's session: built on the first move of an object, kept while the stream drags the
// same object with the same clearance and nobody else edits the scene, rebuilt otherwise.
class DragSession {
 public:
  // After the move is stored: the scene's version then, and how to read the whole scene (only
  // called when the session must be rebuilt: a copy of 10,000 objects costs milliseconds).
  // `stop`: a caller that gave up (deadline, cancel) ends the frame (kStopped).
  Result<MoveOutcome> move(const std::string& scene_id, std::uint64_t scene_version,
                           const std::function<Result<SceneRecord>()>& read_scene, const std::string& object_id,
                           double clearance_mm, const RigidTransform& pose, PartRegistry& parts, const StopToken& stop = {});

  // Whether a frame for this object and clearance would reuse the session as it is (no scene to
  // place again, unless another client edited the scene meanwhile) and decide every pair on the
  // triangles alone (no CAD part, whose exact faces take long and do not stop on a cancel): such a
  // frame is short, what the server may answer on gRPC's own thread.
  bool answers_on_triangles(const std::string& scene_id, const std::string& object_id, double clearance_mm) const;

  // The object at its stored pose against the scene as it is: one frame of a fresh session.
  static Result<MoveOutcome> once(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                  PartRegistry& parts, const StopToken& stop = {});

 private:
  Result<bool> rebuild(const SceneRecord& scene, const std::string& object_id, double clearance_mm, PartRegistry& parts);
  Result<MoveOutcome> frame(const RigidTransform& pose, const StopToken& stop);

  std::unique_ptr<LayoutSession> session_;
  std::vector<std::shared_ptr<const LoadedPart>> parts_;  // object index -> part
  bool meshes_only_ = false;  // no part is CAD (set with parts_: asked every frame, not recounted)
  std::vector<std::string> ids_;  // object index -> id
  std::string scene_id_, object_id_;
  double clearance_mm_ = -1.0;
  std::uint64_t version_ = 0;     // the scene version the session reflects
};

}  // namespace gk::engine
