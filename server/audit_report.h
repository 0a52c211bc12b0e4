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
// Only the clashes [begin, end) (the groups and statistics always cover every clash).
// `scene_id`: the audited scene's (each clash's id is derived from it and the pair).
void report_to_proto(const AuditSnapshot& snapshot, const std::string& scene_id, pb::AuditReport* out, std::size_t begin = 0,
                     std::size_t end = static_cast<std::size_t>(-1));

// A page of a report: the clashes [begin, end) and the token of the next page (empty: the last).
struct ReportPage {
  std::size_t begin = 0, end = 0;
  std::string next_token;
};
// The page a request asks for; an error names page_size or page_token.
Result<ReportPage> report_page(const pb::GetAuditReportRequest& request, std::size_t clashes);

// Review statuses: each clash of the report gets its pair's status now (UNSPECIFIED for a pair
// no finished audit has recorded: a running or cancelled audit's); a status record and a
// request's status.
void add_clash_statuses(const std::vector<engine::ClashStatusRecord>& statuses, pb::AuditReport* report);
void status_to_proto(const engine::ClashStatusRecord& r, pb::ClashStatusInfo* out);
Result<engine::ClashStatus> clash_status_from_proto(pb::ClashStatus status);

// The other way, for a finished audit kept on disk: the snapshot its report describes.
AuditSnapshot snapshot_from_report(const pb::AuditReport& report);

}  // namespace gk::server
