// The engine's types under the names the server's translation code uses.
#pragma once

#include "engine/gatekeeper_engine.h"

namespace gk::server {

using engine::AuditedObject;
using engine::AuditOptions;
using engine::PairClash;
using engine::AuditJob;
using engine::AuditSnapshot;
using engine::AuditStatus;
using engine::ClashRecord;
using engine::DragSession;
using engine::Engine;
using engine::MachineSnapshot;
using engine::MoveOutcome;
using engine::ObjectContactResult;
using engine::PartRecord;
using engine::PartUpload;
using engine::SceneObjectRecord;
using engine::SceneRecord;
using engine::StoredPose;
using engine::WorkPool;

}  // namespace gk::server
