// One object against its neighbours in a scene: what a move (PutObject, MoveObject, each frame
// of a drag) is answered with.
#pragma once

#include "engine/parts/part_registry.h"
#include "engine/scenes/scene_store.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/core/stop_token.h"

#include <string>
#include <vector>

namespace gk::engine {

struct ObjectContactResult {
  std::string other;
  Verdict verdict = Verdict::kClear;
  double distance_mm = 0.0;
  Vec3 point = Vec3::Zero(), other_point = Vec3::Zero();
  InconclusiveReason inconclusive_reason = InconclusiveReason::kNone;
  bool decided_on_brep = false;
};

struct MoveOutcome {
  Verdict verdict = Verdict::kClear;  // the worst over the neighbours
  std::vector<ObjectContactResult> contacts;
  unsigned candidates = 0;
};

// The object against every other object of the scene: those whose boxes (grown by clearance_mm)
// meet get an exact verdict; colliding, touching or closer-than-clearance ones are reported.
// `stop`: a caller that gave up (deadline, cancel) ends the work (kStopped).
Result<MoveOutcome> object_contacts(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                    PartRegistry& parts, const StopToken& stop = {});

}  // namespace gk::engine
