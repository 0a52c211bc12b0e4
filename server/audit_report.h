// Audit requests and reports between the proto and the audit job: the request checked field by
// field, and the report with its clashes grouped by object, by category pair and by floor cell.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "server/scene_queries.h"

namespace gk::server {

namespace pb = ::gatekeeper::v1;

// default_threads replaces threads = 0; tile_mm = 0 becomes 50 m.
Result<AuditOptions> to_audit_options(const pb::StartAuditRequest& in, int default_threads);

void progress_to_proto(const std::string& job_id, const AuditSnapshot& s, pb::AuditProgress* out);

// Clashes, their groups and the job's statistics (the progress is filled separately).
void report_to_proto(const AuditSnapshot& snapshot, pb::AuditReport* out);

// The other way, for a finished audit kept on disk: the snapshot its report describes.
AuditSnapshot snapshot_from_report(const pb::AuditReport& report);

}  // namespace gk::server
