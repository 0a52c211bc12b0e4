// Between the wire (gatekeeper.v1) and the engine: every malformed field becomes an
// INVALID_ARGUMENT that names it.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "kernel/contact_verdict.h"
#include "machine_models/p4/step_validator.h"
#include "server/part_registry.h"
#include "server/scene_store.h"

#include <grpcpp/support/status.h>

namespace gk::server {

namespace pb = ::gatekeeper::v1;

grpc::Status to_status(const Error& error);

Result<p4::BendStep> to_step(const pb::Step& step);
Result<p4::MachineState> to_state(const pb::MachineState& state, const p4::MachineModel& model);
Result<p4::SheetPart> to_part(const pb::SheetPart& part, PartRegistry& parts);
Result<RigidTransform> to_pose(const pb::Pose& pose, const std::string& field);

void to_proto(const p4::StepAnswer& answer, pb::ValidateStepResponse* out);
void to_proto(const p4::MachineState& state, pb::MachineState* out);
void to_proto(const p4::BendStep& step, pb::Step* out);
void to_proto(const Vec3& v, pb::Vec3* out);
void to_proto(const PartRecord& record, pb::PartInfo* out);
// Ids a client names (objects, machines): 1-128 of [A-Za-z0-9-_.:], so that nothing stored is
// truncated or ambiguous (a NUL byte ended an id in storage). Names, categories and groups: at most
// 256 bytes, no control characters.
inline constexpr std::size_t kMaxIdLength = 128;
inline constexpr std::size_t kMaxLabelLength = 256;
Result<bool> check_id(const std::string& id, const std::string& field);
Result<bool> check_label(const std::string& text, const std::string& field);

pb::Verdict to_proto(Verdict v);
pb::InconclusiveReason to_proto(InconclusiveReason r);
Verdict from_proto(pb::Verdict v);
InconclusiveReason from_proto(pb::InconclusiveReason r);

// Scenes: a pose as stored (axis and angle kept as given), and a scene both ways.
Result<StoredPose> to_stored_pose(const pb::Pose& in, const std::string& field);
void scene_to_proto(const SceneRecord& scene, pb::SceneInfo* out);
Result<SceneRecord> scene_from_proto(const pb::SceneInfo& in);

}  // namespace gk::server
