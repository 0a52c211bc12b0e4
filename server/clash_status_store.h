// Clashes' review statuses in the daemon's SQLite database, one row per scene and clash id
// (engine/audits/clash_statuses.h has the rules), synced before a change is acknowledged.
#pragma once

#include "engine/audits/clash_statuses.h"

#include <memory>
#include <mutex>
#include <string>
#include <vector>

struct sqlite3;

namespace gk::server {

class ClashStatusStore final : public engine::ClashStatuses {
 public:
  static Result<std::unique_ptr<ClashStatusStore>> open(const std::string& directory);
  ~ClashStatusStore() override;

  Result<bool> record_audit(const std::string& scene_id, const std::string& job_id,
                            const std::vector<engine::FoundClash>& found) override;
  Result<engine::ClashStatusRecord> set(const std::string& scene_id, const std::string& clash_id,
                                        engine::ClashStatus status) override;
  Result<std::vector<engine::ClashStatusRecord>> list(const std::string& scene_id) const override;

 private:
  ClashStatusStore() = default;
  sqlite3* db_ = nullptr;
  mutable std::mutex mutex_;  // one transaction at a time on the connection
};

}  // namespace gk::server
