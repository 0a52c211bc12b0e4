// Audit requests and reports between the proto and the audit job: the request checked field by
// field, and the report with its clashes grouped by object, by category pair and by floor cell.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "server/engine_names.h"

namespace gk::server {

namespace pb = ::gatekeeper::v1;

// The request as asked (the engine checks it and fills in the defaults).
Result<AuditOptions> to_audit_options(const pb::StartAuditRequest& in);

void progress_to_proto(const std::string& job_id, const AuditSnapshot& s, pb::AuditProgress* out);

// Clashes, their groups and the job's statistics (the progress is filled separately).
void report_to_proto(const AuditSnapshot& snapshot, pb::AuditReport* out);

// The other way, for a finished audit kept on disk: the snapshot its report describes.
AuditSnapshot snapshot_from_report(const pb::AuditReport& report);

}  // namespace gk::server
