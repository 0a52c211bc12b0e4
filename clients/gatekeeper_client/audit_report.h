// Reading an audit's report page by page (a whole factory's report exceeds gRPC's default 4 MiB
// receive limit): the clashes of every page, in order, with the groups and statistics.
#pragma once

#include "gatekeeper/v1/gatekeeper.grpc.pb.h"

#include <chrono>
#include <cstdint>
#include <string>

namespace gk::client {

struct ReportOptions {
  std::uint32_t page_size = 5000;  // clashes a reply
  std::chrono::seconds deadline{120};  // each page's
};

// The whole report (every clash, in the report's order). The HTML page is fetched on its own
// (GetAuditReport with html): it holds every clash and can be large.
grpc::Status read_audit_report(::gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& job_id,
                               ::gatekeeper::v1::AuditReport* report, const ReportOptions& options = {});

}  // namespace gk::client
