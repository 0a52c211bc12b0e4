// Checkpoints of running audits in the daemon's SQLite database (beside the archive of ended
// ones): each job's snapshot and options when it begins, then one row per finished tile with its
// clashes, written and synced before the tile counts as kept. A restarted daemon reads them back
// and resumes each audit from its finished tiles (engine/audits/audit_checkpoints.h).
#pragma once

#include "engine/audits/audit_checkpoints.h"
#include "server/engine_names.h"

#include <memory>
#include <string>
#include <vector>

struct sqlite3;

namespace gk::server {

class AuditCheckpointStore final : public engine::AuditCheckpoints {
 public:
  static Result<std::unique_ptr<AuditCheckpointStore>> open(const std::string& directory);
  ~AuditCheckpointStore() override;

  Result<bool> begin(const std::string& job_id, const SceneRecord& scene, const AuditOptions& options,
                     const std::string& baseline_job_id) override;
  Result<bool> tile_done(const std::string& job_id, std::size_t tile, const std::vector<PairClash>& clashes) override;
  Result<bool> cancelled(const std::string& job_id) override;
  Result<bool> forget(const std::string& job_id) override;
  // Tolerant of damage: a job whose record cannot be read comes back `unreadable` (it ends FAILED),
  // a tile that cannot be read is left out (computed again), a row without an id is skipped.
  Result<std::vector<engine::UnfinishedAudit>> unfinished() const override;

 private:
  AuditCheckpointStore() = default;
  sqlite3* db_ = nullptr;
};

// A tile's clashes as stored and back (exposed for the round-trip test); decoding checks every
// enumeration and direction, an error names what is wrong.
std::string encode_tile(const std::vector<PairClash>& clashes);
Result<std::vector<PairClash>> decode_tile(const std::string& bytes);

}  // namespace gk::server
