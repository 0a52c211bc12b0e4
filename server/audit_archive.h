// Finished audit jobs kept in the daemon's SQLite database (beside parts and scenes), so their
// reports, pages and re-audit baselines survive a restart. A job still running when the daemon
// stops is not kept.
#pragma once

#include "server/engine_names.h"

#include <memory>
#include <string>
#include <utility>
#include <vector>

struct sqlite3;

namespace gk::server {

class AuditArchive final : public engine::EndedAudits {
 public:
  static Result<std::unique_ptr<AuditArchive>> open(const std::string& directory);
  ~AuditArchive() override;

  // Stores the job with its final state.
  Result<bool> save(const std::string& job_id, const AuditJob& job, const AuditSnapshot& final_state) override;
  // One stored job, ended (NOT_FOUND when there is none). The daemon reads them on demand: ended
  // jobs beyond a few are not kept in memory (AuditJobs).
  Result<std::shared_ptr<AuditJob>> load(const std::string& job_id) const override;

 private:
  AuditArchive() = default;
  sqlite3* db_ = nullptr;
};

}  // namespace gk::server
