// A clash's review status, kept per scene and pair of objects (its clash_id) across audits, as
// clash tools keep them: an audit that ends DONE records what it found, a user sets the rest. The
// daemon keeps them in its database (server/clash_status_store); the engine only asks.
#pragma once

#include "kernel/core/status.h"

#include <string>
#include <vector>

namespace gk::engine {

enum class ClashStatus { kNew, kActive, kReviewed, kApproved, kResolved };

struct FoundClash {
  std::string clash_id, object_a, object_b;
};

struct ClashStatusRecord {
  std::string scene_id, clash_id, object_a, object_b;
  ClashStatus status = ClashStatus::kNew;
  bool set_by_user = false;
  std::string first_job_id, last_job_id;
};

class ClashStatuses {
 public:
  virtual ~ClashStatuses() = default;
  // A DONE audit of the scene found these clashes (and no others), in one transaction: a pair
  // found the first time is NEW; found again, NEW becomes ACTIVE and RESOLVED becomes ACTIVE
  // (reopened); REVIEWED, APPROVED and ACTIVE stay; a pair no longer found becomes RESOLVED.
  virtual Result<bool> record_audit(const std::string& scene_id, const std::string& job_id,
                                    const std::vector<FoundClash>& found) = 0;
  // A user's status for a known clash of the scene (NOT_FOUND for a clash no audit found).
  virtual Result<ClashStatusRecord> set(const std::string& scene_id, const std::string& clash_id, ClashStatus status) = 0;
  // Every clash of the scene any audit found, in clash_id order.
  virtual Result<std::vector<ClashStatusRecord>> list(const std::string& scene_id) const = 0;
};

}  // namespace gk::engine
