#include "clients/gatekeeper_client/audit_report.h"

namespace gk::client {

grpc::Status read_audit_report(::gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& job_id,
                               ::gatekeeper::v1::AuditReport* report, const ReportOptions& options) {
  ::gatekeeper::v1::GetAuditReportRequest request;
  request.set_job_id(job_id);
  request.set_page_size(options.page_size);
  report->Clear();
  // A running audit lists its clashes as found and sorts them when it ends: pages read across its
  // end would overlap and miss some. Then the report is read again from its first page.
  int restarts = 0;
  for (;;) {
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + options.deadline);
    ::gatekeeper::v1::AuditReport page;
    const grpc::Status status = stub.GetAuditReport(&ctx, request, &page);
    if (!status.ok()) return status;
    // The first page brings the groups and statistics; later ones add their clashes.
    if (request.page_token().empty()) {
      *report = page;
    } else if (page.progress().state() != report->progress().state()) {
      if (++restarts > 3) return grpc::Status(grpc::StatusCode::ABORTED, "the report kept changing while it was read; try again");
      request.clear_page_token();
      report->Clear();
      continue;
    } else {
      for (auto& clash : *page.mutable_clashes()) *report->add_clashes() = std::move(clash);
      *report->mutable_progress() = page.progress();
    }
    if (page.next_page_token().empty()) break;
    request.set_page_token(page.next_page_token());
  }
  report->clear_next_page_token();
  // A running audit's first page counted fewer clashes than the pages read after it brought.
  report->set_clashes_total(static_cast<std::uint64_t>(report->clashes_size()));
  return grpc::Status::OK;
}

}  // namespace gk::client
