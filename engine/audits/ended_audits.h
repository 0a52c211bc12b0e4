// Where ended audit jobs are kept, so that their reports and re-audit baselines outlive the
// daemon (the daemon keeps them in its database: server/audit_archive). The engine only asks.
#pragma once

#include "engine/audits/audit_job.h"

#include <memory>
#include <string>

namespace gk::engine {

class EndedAudits {
 public:
  virtual ~EndedAudits() = default;
  // Stores the job with its final state.
  virtual Result<bool> save(const std::string& job_id, const AuditJob& job, const AuditSnapshot& final_state) = 0;
  // One stored job, ended (NOT_FOUND when there is none).
  virtual Result<std::shared_ptr<AuditJob>> load(const std::string& job_id) const = 0;
};

}  // namespace gk::engine
