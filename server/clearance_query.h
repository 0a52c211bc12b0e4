// ClearanceQuery: the certified distance, the places closer than the safety gap, and for
// interpenetrating parts the depth and the shared volume, between two uploaded parts at poses or
// two scene objects. The geometry is the kernel's; CAD parts are refined on their exact faces.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "kernel/stop_token.h"
#include "server/part_registry.h"
#include "server/scene_store.h"

#include <grpcpp/support/status.h>

namespace gk::server {

namespace pb = ::gatekeeper::v1;

// Long parts (depth, volume) ask `stop` as they go.
grpc::Status answer_clearance(const pb::ClearanceQueryRequest& request, PartRegistry& parts, SceneStore& scenes, const StopToken& stop,
                              pb::ClearanceQueryResponse* response);

}  // namespace gk::server
