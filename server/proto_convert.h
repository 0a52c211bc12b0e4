// Between the wire (gatekeeper.v1) and the engine: every malformed field becomes an
// INVALID_ARGUMENT that names it.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "kernel/query/contact_verdict.h"
#include "machine_models/p4/step_validator.h"
#include "server/engine_names.h"

#include <grpcpp/support/status.h>

namespace gk::server {

namespace pb = ::gatekeeper::v1;

grpc::Status to_status(const Error& error);

Result<p4::BendStep> to_step(const pb::Step& step);
p4::MachineState to_state(const pb::MachineState& state);
Result<engine::StepPart> to_step_part(const pb::SheetPart& part);
// A ValidateStep request as the engine's question; a request without a part (or machine) of its
// own takes the batch's (ValidateSteps).
Result<engine::StepQuestion> to_question(const pb::ValidateStepRequest& request, const pb::SheetPart* default_part = nullptr,
                                         const std::string& default_machine = "");

void to_proto(const p4::StepAnswer& answer, pb::ValidateStepResponse* out);
Result<engine::ClearanceRequest> to_clearance_request(const pb::ClearanceQueryRequest& in);
void to_proto(const engine::ClearanceResult& result, pb::ClearanceQueryResponse* out);
void to_proto(const MoveOutcome& outcome, pb::MoveResult* out);
void to_proto(const p4::MachineState& state, pb::MachineState* out);
void to_proto(const p4::BendStep& step, pb::Step* out);
void to_proto(const Vec3& v, pb::Vec3* out);
void to_proto(const Direction& d, pb::Direction* out);
// A direction in both fields of an answer: the Direction, and the older Vec3 beside it.
void to_proto(const Direction& d, pb::Direction* out, pb::Vec3* old_field);
void to_proto(const engine::ContactPlace& place, pb::ContactRegion* out);
void to_proto(const PartRecord& record, pb::PartInfo* out);

pb::Verdict to_proto(Verdict v);
pb::DecidingStage to_proto(p4::Stage stage);
pb::DepthMethod to_proto(engine::DepthMethod m);
pb::VolumeMethod to_proto(engine::SharedVolumeMethod m);
pb::InconclusiveReason to_proto(InconclusiveReason r);
Verdict from_proto(pb::Verdict v);
InconclusiveReason from_proto(pb::InconclusiveReason r);

// Scenes: a pose as stored (axis and angle kept as given), and a scene both ways.
// A pose as the client wrote it (the engine checks it: engine::checked_pose).
StoredPose to_stored_pose(const pb::Pose& in);
void scene_to_proto(const SceneRecord& scene, pb::SceneInfo* out);
Result<SceneRecord> scene_from_proto(const pb::SceneInfo& in);

}  // namespace gk::server
