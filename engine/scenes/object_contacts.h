// What a move is answered with: one object against its neighbours in a scene (PutObject,
// MoveObject, each frame of a drag). Every move is decided by engine/scenes/drag_session.
#pragma once

#include "kernel/query/contact_verdict.h"

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
  std::vector<ObjectContactResult> contacts;  // colliding, touching or closer than the clearance, by object id
  unsigned candidates = 0;            // neighbours whose boxes (grown by the clearance) met the object's
};

}  // namespace gk::engine
