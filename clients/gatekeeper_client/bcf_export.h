// BCF 2.1 (buildingSMART's BIM Collaboration Format: what clash tools exchange) from an audit
// report: one topic per clash, its Guid the clash's stable id (so a re-audit's export updates the
// same topics), titled with the verdict and both objects, described with the verdict's figures,
// TopicStatus its review status (New, Active, Reviewed, Approved, Resolved), and one viewpoint
// that looks at the clash from a distance sized to it and selects both objects
// by their scene object ids. BCF's coordinates are metres; the report's are millimetres.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"

#include <cstdint>
#include <string>

namespace gk::client {

struct BcfOptions {
  std::string author = "gatekeeperd";  // every topic's CreationAuthor
  std::int64_t created_unix_s = 0;     // every topic's CreationDate (0: now)
};

// The .bcfzip bytes in `archive`; false with `error` set when a clash carries no clash_id (a
// report from a daemon older than the field).
bool write_bcf(const ::gatekeeper::v1::AuditReport& report, const BcfOptions& options, std::string* archive,
               std::string* error);

}  // namespace gk::client
