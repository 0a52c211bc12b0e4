// Audit requests and reports between the proto and the audit job: the request checked field by
// field, and the report with its clashes grouped by object, by category pair and by floor cell.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "server/scene_queries.h"

namespace gk::server {

namespace pb = ::gatekeeper::v1;

// default_threads replaces threads = 0; tile_mm = 0 becomes 50 m.
Result<AuditOptions> to_audit_options(const pb::StartAuditRequest& in, int default_threads);

// Clashes, their groups and the job's statistics (the progress is filled separately).
void report_to_proto(const AuditSnapshot& snapshot, pb::AuditReport* out);

}  // namespace gk::server
